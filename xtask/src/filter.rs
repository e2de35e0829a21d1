//! `cargo xtask filter --model MODEL.toml --input DATA.csv --output OUT.csv
//! [--estimator smf|kf|yang-li] [--solver NAME]`: run an estimator over logged data.
//!
//! * `MODEL.toml`: discrete-time `a` (n×n), `b` (n×p), `c` (m×n), `q` (n×n), `r` (m×m), `p0` (n×n)
//!   as arrays of rows, and `x0` (length n). For `--estimator yang-li` (the reconstruction of
//!   [17] that does not use the input) also `u_lower` and `u_upper` (length p): the known input
//!   range. For the Kalman filter `q`, `r`, `p0` are covariances; for the set-membership
//!   filters, ellipsoid shapes.
//! * `DATA.csv`: header `k,u1,…,up,y1,…,ym`; row `k` holds the input `u_k` and the measurement
//!   `y_{k+1}` taken after it.
//! * `OUT.csv`: header `k,xhat1,…,xhatn,lo1,…,lon,hi1,…,hin,trace` (plus `tau1,tau2,tau3` for the
//!   set-membership filters), one row per step, labelled `k+1`.
//!
//! `--solver` picks how the set-membership filters solve (29): `two-multiplier` (default, exact)
//! or an SDP backend name (`faer-ipm`, `clarabel` when built with it).

use std::fmt::Write as _;
use std::path::Path;

use estimators::{
    KalmanFilter, SdpUpdateSolver, SetMembershipFilter, StepModel, TwoMultiplierSolver, UpdateSolver, yang_li,
};
use lmi::SolverSettings;
use nalgebra::{DMatrix, DVector};
use serde::Deserialize;
use toml::Spanned;

use crate::args::Args;

/// The model file, as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ModelFile {
    a: Spanned<Vec<Vec<f64>>>,
    b: Spanned<Vec<Vec<f64>>>,
    c: Spanned<Vec<Vec<f64>>>,
    q: Spanned<Vec<Vec<f64>>>,
    r: Spanned<Vec<Vec<f64>>>,
    p0: Spanned<Vec<Vec<f64>>>,
    x0: Spanned<Vec<f64>>,
    u_lower: Option<Spanned<Vec<f64>>>,
    u_upper: Option<Spanned<Vec<f64>>>,
}

/// A validated model.
#[derive(Debug, Clone)]
pub struct Model {
    /// `A` (n×n).
    pub a: DMatrix<f64>,
    /// `B` (n×p).
    pub b: DMatrix<f64>,
    /// `C` (m×n).
    pub c: DMatrix<f64>,
    /// `Q` (n×n).
    pub q: DMatrix<f64>,
    /// `R` (m×m).
    pub r: DMatrix<f64>,
    /// `P₀` (n×n).
    pub p0: DMatrix<f64>,
    /// `x₀` (n).
    pub x0: DVector<f64>,
    /// Known input range, if given.
    pub input_range: Option<(DVector<f64>, DVector<f64>)>,
}

/// 1-based line and column of a byte offset.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let mut end = offset.min(text.len());
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    let before = &text[..end];
    let line = before.matches('\n').count() + 1;
    let col = before[before.rfind('\n').map_or(0, |i| i + 1)..].chars().count() + 1;
    (line, col)
}

fn matrix(
    text: &str,
    path: &Path,
    name: &str,
    v: &Spanned<Vec<Vec<f64>>>,
    rows: Option<usize>,
    cols: Option<usize>,
) -> Result<DMatrix<f64>, String> {
    let (line, col) = line_col(text, v.span().start);
    let at = |msg: String| format!("{}:{line}:{col}: `{name}`: {msg}", path.display());
    let m = v.get_ref();
    if m.is_empty() {
        return Err(at("empty matrix".into()));
    }
    if let Some(r) = rows {
        if m.len() != r {
            return Err(at(format!("expected {r} rows, found {}", m.len())));
        }
    }
    let width = cols.unwrap_or(m[0].len());
    for (i, row) in m.iter().enumerate() {
        if row.len() != width {
            return Err(at(format!("row {} has {} entries, expected {width}", i + 1, row.len())));
        }
        if let Some(j) = row.iter().position(|x| !x.is_finite()) {
            return Err(at(format!("entry ({}, {}) is not finite", i + 1, j + 1)));
        }
    }
    if width == 0 && name != "b" {
        return Err(at("rows are empty".into()));
    }
    Ok(DMatrix::from_fn(m.len(), width, |i, j| m[i][j]))
}

fn vector(text: &str, path: &Path, name: &str, v: &Spanned<Vec<f64>>, len: usize) -> Result<DVector<f64>, String> {
    let (line, col) = line_col(text, v.span().start);
    let x = v.get_ref();
    if x.len() != len {
        return Err(format!("{}:{line}:{col}: `{name}`: expected {len} entries, found {}", path.display(), x.len()));
    }
    if let Some(j) = x.iter().position(|x| !x.is_finite()) {
        return Err(format!("{}:{line}:{col}: `{name}`: entry {} is not finite", path.display(), j + 1));
    }
    Ok(DVector::from_column_slice(x))
}

/// Reads and validates `MODEL.toml` (dimensions are checked against `a`; errors give
/// `file:line:column`).
pub fn read_model(path: &Path, text: &str) -> Result<Model, String> {
    let f: ModelFile = toml::from_str(text).map_err(|e| {
        let loc = e.span().map(|s| line_col(text, s.start));
        match loc {
            Some((l, c)) => format!("{}:{l}:{c}: {}", path.display(), e.message()),
            None => format!("{}: {}", path.display(), e.message()),
        }
    })?;
    let a = matrix(text, path, "a", &f.a, None, None)?;
    let n = a.nrows();
    if a.ncols() != n {
        let (l, c) = line_col(text, f.a.span().start);
        return Err(format!("{}:{l}:{c}: `a` must be square, is {n}x{}", path.display(), a.ncols()));
    }
    let b = matrix(text, path, "b", &f.b, Some(n), None)?;
    let c = matrix(text, path, "c", &f.c, None, Some(n))?;
    let m = c.nrows();
    let q = matrix(text, path, "q", &f.q, Some(n), Some(n))?;
    let r = matrix(text, path, "r", &f.r, Some(m), Some(m))?;
    let p0 = matrix(text, path, "p0", &f.p0, Some(n), Some(n))?;
    let x0 = vector(text, path, "x0", &f.x0, n)?;
    let p = b.ncols();
    let input_range = match (&f.u_lower, &f.u_upper) {
        (Some(lo), Some(hi)) => Some((vector(text, path, "u_lower", lo, p)?, vector(text, path, "u_upper", hi, p)?)),
        (None, None) => None,
        (Some(v), None) | (None, Some(v)) => {
            let (l, c) = line_col(text, v.span().start);
            return Err(format!("{}:{l}:{c}: give both `u_lower` and `u_upper`, or neither", path.display()));
        }
    };
    Ok(Model { a, b, c, q, r, p0, x0, input_range })
}

/// One row of `DATA.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct DataRow {
    /// 1-based line of the row in the file.
    pub line: usize,
    /// The row's `k`.
    pub k: u64,
    /// `u_k`.
    pub u: DVector<f64>,
    /// `y_{k+1}`.
    pub y: DVector<f64>,
}

/// Reads `DATA.csv` for `p` inputs and `m` outputs (errors give `file:line:column`).
pub fn read_data(path: &Path, text: &str, p: usize, m: usize) -> Result<Vec<DataRow>, String> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text); // a UTF-8 byte-order mark (spreadsheet exports)
    let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty());
    let Some((hl, header)) = lines.next() else {
        return Err(format!("{}:1:1: empty file, expected the header `k,u1,…,y1,…`", path.display()));
    };
    let expected: Vec<String> = std::iter::once("k".to_owned())
        .chain((1..=p).map(|i| format!("u{i}")))
        .chain((1..=m).map(|i| format!("y{i}")))
        .collect();
    let raw: Vec<&str> = header.split(',').collect();
    let cols: Vec<&str> = raw.iter().map(|c| c.trim()).collect();
    let mut col_pos = 1;
    for (j, want) in expected.iter().enumerate() {
        // Point at the cell's first non-blank character.
        let here = col_pos + raw.get(j).map_or(0, |c| c.chars().take_while(|ch| ch.is_whitespace()).count());
        match cols.get(j) {
            Some(got) if got == want => {}
            got => {
                return Err(format!(
                    "{}:{}:{here}: header column {} is {:?}, expected {want:?} (model has p = {p} inputs, m = {m} outputs)",
                    path.display(),
                    hl + 1,
                    j + 1,
                    got.unwrap_or(&"<missing>")
                ));
            }
        }
        col_pos += raw[j].chars().count() + 1;
    }
    if cols.len() > expected.len() {
        return Err(format!(
            "{}:{}:{col_pos}: unexpected extra header column {:?}",
            path.display(),
            hl + 1,
            cols[expected.len()]
        ));
    }
    let mut rows = Vec::new();
    for (li, line) in lines {
        let mut fields = Vec::with_capacity(expected.len());
        let mut col = 1;
        for f in line.split(',') {
            let lead = f.chars().take_while(|ch| ch.is_whitespace()).count();
            fields.push((col + lead, f.trim()));
            col += f.chars().count() + 1;
        }
        if fields.len() != expected.len() {
            return Err(format!(
                "{}:{}:1: {} fields, expected {}",
                path.display(),
                li + 1,
                fields.len(),
                expected.len()
            ));
        }
        let (kc, ks) = fields[0];
        let k: u64 = ks
            .parse()
            .map_err(|_| format!("{}:{}:{kc}: k = {ks:?} is not a nonnegative integer", path.display(), li + 1))?;
        let mut vals = Vec::with_capacity(p + m);
        for (j, &(c, s)) in fields.iter().enumerate().skip(1) {
            let v: f64 = s
                .parse()
                .map_err(|_| format!("{}:{}:{c}: {} = {s:?} is not a number", path.display(), li + 1, expected[j]))?;
            if !v.is_finite() {
                return Err(format!("{}:{}:{c}: {} = {s} is not finite", path.display(), li + 1, expected[j]));
            }
            vals.push(v);
        }
        rows.push(DataRow {
            line: li + 1,
            k,
            u: DVector::from_column_slice(&vals[..p]),
            y: DVector::from_column_slice(&vals[p..]),
        });
    }
    if rows.is_empty() {
        return Err(format!("{}:{}:1: no data rows after the header", path.display(), hl + 2));
    }
    Ok(rows)
}

/// Runs an estimator over the data and returns the output CSV text.
pub fn run_filter(model: &Model, data: &[DataRow], estimator: &str, solver: &str) -> Result<String, String> {
    let (n, p) = (model.a.nrows(), model.b.ncols());
    let cols = |pfx: &str| (1..=n).map(|i| format!("{pfx}{i}")).collect::<Vec<_>>().join(",");
    let mut out = format!("k,{},{},{},trace", cols("xhat"), cols("lo"), cols("hi"));
    let sm = StepModel::new(&model.a, &model.b, &model.c);
    let e = |e: estimators::EstimatorError| e.to_string();
    match estimator {
        "kf" => {
            out.push('\n');
            let mut kf = KalmanFilter::new(model.x0.clone(), model.p0.clone(), model.q.clone(), model.r.clone(), p)
                .map_err(e)?;
            for row in data {
                let est =
                    kf.step(&sm, &row.u, &row.y).map_err(|err| format!("line {} (k = {}): {err}", row.line, row.k))?;
                let _ = write!(out, "{}", next_k(row)?);
                for v in est.mean.iter() {
                    let _ = write!(out, ",{v:e}");
                }
                for sign in [-1.0, 1.0] {
                    for (x, s) in est.mean.iter().zip(est.std_dev.iter()) {
                        let _ = write!(out, ",{:e}", x + sign * s);
                    }
                }
                let _ = writeln!(out, ",{:e}", est.covariance.trace());
            }
            Ok(out)
        }
        "smf" | "yang-li" => {
            out.push_str(",tau1,tau2,tau3\n");
            if solver == "two-multiplier" {
                run_set(model, data, estimator, TwoMultiplierSolver::new(), &mut out)?;
            } else {
                let s = SdpUpdateSolver::by_name(solver, SolverSettings::default()).map_err(e)?;
                run_set(model, data, estimator, s, &mut out)?;
            }
            Ok(out)
        }
        other => Err(format!("unknown estimator {other:?}: use smf, kf or yang-li")),
    }
}

/// An estimator's complaint about the model, in the model file's terms.
fn model_err(e: estimators::EstimatorError) -> String {
    format!("model: {e} (Q, R, P0, x0 are the model file's `q`, `r`, `p0`, `x0`)")
}

/// The output label `k + 1` of a row.
fn next_k(row: &DataRow) -> Result<u64, String> {
    row.k.checked_add(1).ok_or_else(|| format!("line {}: k = {} is too large", row.line, row.k))
}

fn run_set<S: UpdateSolver>(
    model: &Model,
    data: &[DataRow],
    estimator: &str,
    solver: S,
    out: &mut String,
) -> Result<(), String> {
    let (x0, p0, q, r) = (model.x0.clone(), model.p0.clone(), model.q.clone(), model.r.clone());
    let mut f = if estimator == "yang-li" {
        let (lo, hi) = model
            .input_range
            .as_ref()
            .ok_or("--estimator yang-li needs the input range `u_lower`, `u_upper` in the model file")?;
        yang_li::without_input(x0, p0, q, r, lo, hi, solver).map_err(model_err)?
    } else {
        SetMembershipFilter::new(x0, p0, q, r, model.b.ncols(), solver).map_err(model_err)?
    };
    let sm = StepModel::new(&model.a, &model.b, &model.c);
    for row in data {
        let est = f.step(&sm, &row.u, &row.y).map_err(|err| format!("line {} (k = {}): {err}", row.line, row.k))?;
        let _ = write!(out, "{}", next_k(row)?);
        for v in est.center.iter().chain(est.lower.iter()).chain(est.upper.iter()) {
            let _ = write!(out, ",{v:e}");
        }
        let t = est.report.tau;
        let _ = writeln!(out, ",{:e},{:e},{:e},{:e}", est.trace(), t[0], t[1], t[2]);
    }
    Ok(())
}

/// Runs `cargo xtask filter` with the given arguments.
pub fn run(args: &[String]) -> Result<(), String> {
    let args = Args::parse(args, &["model", "input", "output", "estimator", "solver"], &[])?;
    let need = |k: &str| args.value(k).ok_or(format!("--{k} is required (see `cargo xtask help`)"));
    let (model_path, input_path, output_path) =
        (Path::new(need("model")?), Path::new(need("input")?), Path::new(need("output")?));
    let read = |p: &Path| std::fs::read_to_string(p).map_err(|e| format!("{}: {e}", p.display()));
    let model = read_model(model_path, &read(model_path)?)?;
    let data = read_data(input_path, &read(input_path)?, model.b.ncols(), model.c.nrows())?;
    let estimator = args.value("estimator").unwrap_or("smf");
    let solver = args.value("solver").unwrap_or("two-multiplier");
    if estimator == "kf" && args.value("solver").is_some() {
        return Err("--solver applies to the set-membership filters (smf, yang-li), not kf".into());
    }
    let csv = run_filter(&model, &data, estimator, solver)?;
    std::fs::write(output_path, csv).map_err(|e| format!("{}: {e}", output_path.display()))?;
    eprintln!("{} steps of {estimator} written to {}", data.len(), output_path.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const MODEL: &str = "a = [[1.0, 0.01], [0.0, 0.99]]\nb = [[0.0], [0.01]]\nc = [[1.0, 0.0]]\nq = [[1e-4, 0.0], [0.0, 1e-4]]\nr = [[1e-2]]\np0 = [[1.0, 0.0], [0.0, 1.0]]\nx0 = [0.0, 0.0]\n";

    #[test]
    fn model_errors_name_line_and_column() {
        let p = Path::new("m.toml");
        assert!(read_model(p, MODEL).is_ok());
        let bad = MODEL.replace("b = [[0.0], [0.01]]", "b = [[0.0]]");
        let err = read_model(p, &bad).unwrap_err();
        assert!(err.starts_with("m.toml:2:5: `b`: expected 2 rows, found 1"), "{err}");
        let bad = MODEL.replace("x0 = [0.0, 0.0]", "x0 = [0.0]");
        assert!(read_model(p, &bad).unwrap_err().contains("m.toml:7:6: `x0`: expected 2 entries"));
        let bad = MODEL.replace("r = [[1e-2]]", "r = [[1e-2, 0.0]]");
        assert!(read_model(p, &bad).unwrap_err().contains("`r`: row 1 has 2 entries, expected 1"));
        let bad = MODEL.replace("q = ", "qq = ");
        let err = read_model(p, &bad).unwrap_err();
        assert!(err.starts_with("m.toml:4:"), "{err}");
        let bad = format!("{MODEL}u_lower = [0.0]\n");
        assert!(read_model(p, &bad).unwrap_err().starts_with("m.toml:8:11: give both `u_lower` and `u_upper`"));
    }

    #[test]
    fn data_errors_name_line_and_column() {
        let p = Path::new("d.csv");
        let ok = "k,u1,y1\n0,1.0,0.5\n1,1.0,0.6\n";
        assert_eq!(read_data(p, ok, 1, 1).unwrap().len(), 2);
        let err = read_data(p, "k,u1,z1\n", 1, 1).unwrap_err();
        assert!(err.starts_with("d.csv:1:6: header column 3 is \"z1\""), "{err}");
        let err = read_data(p, "k,u1,y1\n0,1.0,abc\n", 1, 1).unwrap_err();
        assert!(err.starts_with("d.csv:2:7: y1 = \"abc\" is not a number"), "{err}");
        let err = read_data(p, "k,u1,y1\n0,1.0\n", 1, 1).unwrap_err();
        assert!(err.starts_with("d.csv:2:1: 2 fields, expected 3"), "{err}");
        let err = read_data(p, "k,u1,y1\n-1,1.0,2\n", 1, 1).unwrap_err();
        assert!(err.contains("d.csv:2:1: k = \"-1\""), "{err}");
        let err = read_data(p, "k,u1,y1\n0,NaN,2\n", 1, 1).unwrap_err();
        assert!(err.contains("d.csv:2:3: u1 = NaN is not finite"), "{err}");
        assert!(read_data(p, "", 1, 1).unwrap_err().contains("empty file"));
        assert!(read_data(p, "k,u1,y1\n", 1, 1).unwrap_err().starts_with("d.csv:2:1: no data rows"));
        // Columns point at the cell's text even with padding; a byte-order mark is skipped.
        let err = read_data(p, " k , u1 , z1 \n", 1, 1).unwrap_err();
        assert!(err.starts_with("d.csv:1:11: header column 3 is \"z1\""), "{err}");
        assert_eq!(read_data(p, "\u{feff}k,u1,y1\n0,1,2\n", 1, 1).unwrap()[0].line, 2);
    }

    #[test]
    fn every_estimator_runs_and_the_set_contains_what_the_centre_implies() {
        let model = read_model(Path::new("m.toml"), MODEL).unwrap();
        let data: Vec<DataRow> = (0..50)
            .map(|k| DataRow {
                line: k as usize + 2,
                k,
                u: DVector::from_element(1, 1.0),
                y: DVector::from_element(1, 0.01 * k as f64),
            })
            .collect();
        for (est, solver) in [("smf", "two-multiplier"), ("smf", "faer-ipm"), ("kf", "")] {
            let csv = run_filter(&model, &data, est, solver).unwrap();
            let lines: Vec<&str> = csv.lines().collect();
            assert_eq!(lines.len(), 51, "{est}");
            assert!(lines[0].starts_with("k,xhat1,xhat2,lo1,lo2,hi1,hi2,trace"));
            assert!(lines[1].starts_with("1,"));
            let last: Vec<f64> = lines[50].split(',').map(|v| v.parse().unwrap()).collect();
            assert!(last[3] <= last[1] && last[1] <= last[5], "{est}: lo ≤ xhat ≤ hi");
        }
        assert!(run_filter(&model, &data, "yang-li", "two-multiplier").unwrap_err().contains("u_lower"));
        assert!(run_filter(&model, &data, "ukf", "").unwrap_err().contains("unknown estimator"));
        // k + 1 overflowing is an error naming the line, not a panic.
        let big =
            [DataRow { line: 2, k: u64::MAX, u: DVector::from_element(1, 1.0), y: DVector::from_element(1, 0.0) }];
        for est in ["smf", "kf"] {
            let err = run_filter(&model, &big, est, "two-multiplier").unwrap_err();
            assert!(err.contains("line 2: k = 18446744073709551615 is too large"), "{err}");
        }
        // A model the estimator rejects names the file's keys.
        let mut bad = model.clone();
        bad.q[(0, 0)] = -1.0;
        assert!(run_filter(&bad, &data, "smf", "two-multiplier").unwrap_err().contains("the model file's `q`"));
    }
}
