//! Figures (truth and estimate of `V_x`, `γ`, `β` and their errors; comparisons across cases) and
//! the per-case CSV files.

use std::fmt::Write as _;
use std::path::Path;

use svg_plot::{BarChart, Bars, Chart, Grid, PALETTE, Series};

use super::cases::Case;
use super::outputs::WriteFigure as _;
use super::run::Trace;
use super::{CaseSummary, outputs};

/// The plotted signals: index into `[V_x, V_y, γ, β]`, name, unit and the factor from SI.
const SIGNALS: [(usize, &str, &str, f64); 3] =
    [(0, "Vx", "m/s", 1.0), (2, "γ", "°/s", 180.0 / std::f64::consts::PI), (3, "β", "°", 180.0 / std::f64::consts::PI)];

const TRUTH: &str = PALETTE[0];
const ESTIMATE: &str = PALETTE[1];
const ERROR: &str = PALETTE[2];

/// Writes one run as CSV: `t` \[s\], then for `vx` \[m/s\], `vy` \[m/s\], `gamma` \[rad/s\] and
/// `beta` \[rad\] the truth, the estimate (`_hat`) and its standard deviation (`_sigma`).
///
/// # Errors
/// The file cannot be written.
pub fn write_csv(path: &Path, trace: &Trace) -> std::io::Result<()> {
    let mut s =
        String::from("t,vx,vx_hat,vx_sigma,vy,vy_hat,vy_sigma,gamma,gamma_hat,gamma_sigma,beta,beta_hat,beta_sigma\n");
    for k in 0..trace.t.len() {
        let _ = write!(s, "{:.3}", trace.t[k]);
        for i in 0..4 {
            let _ = write!(s, ",{:.9e},{:.9e},{:.4e}", trace.truth[k][i], trace.estimate[k][i], trace.sigma[k][i]);
        }
        s.push('\n');
    }
    outputs::write_atomic(path, s.as_bytes())
}

fn column(trace: &Trace, f: impl Fn(usize) -> f64) -> Vec<f64> {
    (0..trace.t.len()).map(f).collect()
}

fn panel(title: String, y_label: String) -> Chart {
    Chart { width: 620, height: 290, ..Chart::new(title, "time t [s]", y_label) }
}

/// The 2σ band of the initial covariance dwarfs everything after the first updates: vertical
/// ranges take the band into account only from this time on \[s\] (the estimate and the error
/// themselves are always fully shown).
const BAND_FROM: f64 = 0.1;

/// `(min, max)` of the finite values with a 5 % margin (`None` if there is none).
fn padded(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) =
        values.filter(|v| v.is_finite()).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    if lo > hi {
        return None;
    }
    let pad = 0.05 * (hi - lo).max(1e-12 * hi.abs().max(1.0));
    Some((lo - pad, hi + pad))
}

/// The six-panel figure of one case (first seed): truth and estimate with its ±2σ band (left),
/// error with the ±2σ band (right), for `V_x`, `γ` and `β`. Returns `(file, caption)`.
///
/// # Errors
/// The file cannot be written.
pub fn case_figure(dir: &Path, case: &Case, trace: &Trace, seed: u64) -> std::io::Result<Vec<(String, String)>> {
    let mut grid = Grid::new(2);
    grid.title = format!("Truck slalom, case “{}”: truth and EKF estimate (seed {seed})", case.title);
    let t = trace.t.clone();
    let late: Vec<bool> = t.iter().map(|&t| t >= BAND_FROM).collect();
    for (i, name, unit, scale) in SIGNALS {
        let truth = column(trace, |k| trace.truth[k][i] * scale);
        let est = column(trace, |k| trace.estimate[k][i] * scale);
        let sd = column(trace, |k| 2.0 * trace.sigma[k][i] * scale);
        let lo: Vec<f64> = est.iter().zip(&sd).map(|(e, s)| e - s).collect();
        let hi: Vec<f64> = est.iter().zip(&sd).map(|(e, s)| e + s).collect();
        let band_late = |v: &[f64]| v.iter().zip(&late).filter(|(_, l)| **l).map(|(v, _)| *v).collect::<Vec<_>>();
        let mut c = panel(format!("{name}: truth and estimate"), format!("{name} [{unit}]"));
        c.y_range = padded(truth.iter().chain(&est).chain(&band_late(&lo)).chain(&band_late(&hi)).copied());
        c.add(Series::band("estimate ± 2σ", t.clone(), lo, hi, ESTIMATE));
        c.add(Series::line("estimate", t.clone(), est.clone(), ESTIMATE));
        c.add(Series::line("truth", t.clone(), truth.clone(), TRUTH));
        grid.add(c);
        let err: Vec<f64> = est.iter().zip(&truth).map(|(e, x)| e - x).collect();
        let neg: Vec<f64> = sd.iter().map(|s| -s).collect();
        let reach = err.iter().map(|e| e.abs()).chain(band_late(&sd)).filter(|v| v.is_finite()).fold(0.0, f64::max);
        let mut c = panel(format!("{name}: error (estimate − truth)"), format!("error in {name} [{unit}]"));
        if reach > 0.0 {
            c.y_range = Some((-1.1 * reach, 1.1 * reach));
        }
        c.add(Series::band("± 2σ", t.clone(), neg, sd, ESTIMATE));
        c.add(Series::line("error", t.clone(), err, ERROR));
        grid.add(c);
    }
    let file = format!("{}_states.svg", case.id);
    grid.write(&dir.join(&file))?;
    Ok(vec![(file, format!("Case “{}”: truth and estimate of Vx, γ, β and their errors", case.title))])
}

/// Comparison figures across cases: the `β` error of the first seed of every case over time, and
/// bars of the RMSE (mean over seeds) of `V_x`, `γ`, `β` per case over the whole run and after
/// 2 s. Returns `(file, caption)` pairs.
///
/// # Errors
/// A file cannot be written.
pub fn comparison_figures(
    dir: &Path,
    cases: &[CaseSummary],
    traces: &[Trace],
) -> std::io::Result<Vec<(String, String)>> {
    let mut files = Vec::new();
    let deg = 180.0 / std::f64::consts::PI;
    let zoom = 0.05;
    let mut full = Chart::new(
        format!("β error of every case (first seed); vertical range set by t ≥ {BAND_FROM} s"),
        "time t [s]",
        "error in β [°]",
    );
    let mut early = Chart::new(format!("β error in the first {} ms", zoom * 1e3), "time t [s]", "error in β [°]");
    early.x_range = Some((0.0, zoom));
    let mut reach = 0.0f64;
    for (j, (c, tr)) in cases.iter().zip(traces).enumerate() {
        let e = column(tr, |k| (tr.estimate[k][3] - tr.truth[k][3]) * deg);
        reach = tr.t.iter().zip(&e).filter(|(t, _)| **t >= BAND_FROM).map(|(_, e)| e.abs()).fold(reach, f64::max);
        let n = tr.t.iter().take_while(|t| **t <= zoom + 1e-9).count();
        early.add(Series::line(c.title.clone(), tr.t[..n].to_vec(), e[..n].to_vec(), PALETTE[j % 7]));
        full.add(Series::line(c.title.clone(), tr.t.clone(), e, PALETTE[j % 7]));
    }
    if reach > 0.0 {
        full.y_range = Some((-1.1 * reach, 1.1 * reach));
    }
    let mut grid = Grid::new(1);
    grid.add(full).add(early);
    let file = "beta_error_cases.svg".to_owned();
    grid.write(&dir.join(&file))?;
    files.push((file, "β error of every case over time, and its first 50 ms (first seed)".to_owned()));

    let groups: Vec<String> = cases.iter().map(|c| c.short.clone()).collect();
    let mut grid = Grid::new(1);
    grid.title = "RMSE per case (mean over seeds)".into();
    type Pick = fn(&CaseSummary) -> &super::run::SignalSpread;
    let signals: [(&str, &str, Pick); 3] = [
        ("Vx", "m/s", |c| &c.aggregate.vx_mps),
        ("γ", "°/s", |c| &c.aggregate.gamma_degps),
        ("β", "°", |c| &c.aggregate.beta_deg),
    ];
    for (name, unit, pick) in signals {
        let mut b = BarChart::new(format!("{name} RMSE"), "", format!("RMSE of {name} [{unit}]"), groups.clone());
        b.height = 260;
        b.add(Bars::new("whole run", cases.iter().map(|c| pick(c).whole.rmse.mean).collect(), PALETTE[1]));
        b.add(Bars::new("after 2 s", cases.iter().map(|c| pick(c).after_2s.rmse.mean).collect(), PALETTE[5]));
        grid.add(b);
    }
    let file = "rmse_cases.svg".to_owned();
    grid.write(&dir.join(&file))?;
    files.push((file, "RMSE of Vx, γ, β per case, whole run and after 2 s (mean over seeds)".to_owned()));
    Ok(files)
}
