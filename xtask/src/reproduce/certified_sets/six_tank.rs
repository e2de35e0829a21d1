//! CORA's six-tank observer benchmark (examples/six-tank, its README for the provenance): `czf-nl`
//! with the model file's boxes on CORA's published inputs and measurements, its final certified
//! widths against CORA's saved final hulls (examples/six-tank/cora_hulls.csv), and the step time —
//! at the order the model file's `[estimator.czf-nl]` table chose, and at the default order (20, 8
//! constraints) beside it.

use std::path::Path;
use std::time::Instant;

use equation_models::EquationModel;
use estimators::{ConstrainedZonotopeFilter, ConstrainedZonotopeSettings, Estimate, Setup};
use nalgebra::DVector;
use serde::Serialize;

use crate::reproduce::runner::StepTiming;

/// CORA's first measurement (at t = 0), which the log's rows cannot hold (examples/six-tank/README.md).
pub const Y1: [f64; 3] = [18.587107801413037, 20.225990245627816, 19.112251238495777];

/// Repetitions of the 19-step log for the step time.
const TIMING_REPEATS: [usize; 2] = [50, 3];

/// The comparison.
#[derive(Debug, Clone, Serialize)]
pub struct SixTank {
    /// `czf-nl`'s final widths (t = 9.5 s) at the chosen order.
    pub widths: Vec<f64>,
    /// Their mean.
    pub mean: f64,
    /// CORA's saved final hull widths per observer: `(name, widths)`.
    pub cora: Vec<(String, Vec<f64>)>,
    /// Per state, the least of CORA's widths.
    pub cora_best: Vec<f64>,
    /// Their mean.
    pub cora_best_mean: f64,
    /// Steps whose status was not clean (must be 0 on CORA's data), at either order.
    pub unclean_steps: usize,
    /// The chosen order and constraints (the model file's `[estimator.czf-nl]` table).
    pub order: (usize, usize),
    /// One step at the chosen order.
    pub step_time: StepTiming,
    /// The same run at the default order (20, 8 constraints).
    pub default_order: OrderRun,
}

/// The filter on CORA's data at one order.
#[derive(Debug, Clone, Serialize)]
pub struct OrderRun {
    /// Generators per state and constraints kept.
    pub order: (usize, usize),
    /// Final widths (t = 9.5 s).
    pub widths: Vec<f64>,
    /// Their mean.
    pub mean: f64,
    /// One step.
    pub step_time: StepTiming,
    /// Steps whose status was not clean.
    pub unclean_steps: usize,
}

fn read(path: &Path) -> Result<String, String> {
    std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))
}

fn number(path: &Path, line: usize, cell: &str) -> Result<f64, String> {
    cell.trim().parse().map_err(|_| format!("{}:{}: not a number: {cell:?}", path.display(), line + 1))
}

/// One row of the log: `(u_k, y_{k+1})`.
pub type Row = (DVector<f64>, DVector<f64>);

/// The log of examples/six-tank/data.csv.
///
/// # Errors
/// A file that cannot be read, or a row that is not seven numbers (named by `file:line`).
pub fn log(path: &Path) -> Result<Vec<Row>, String> {
    let text = read(path)?;
    let mut rows = Vec::new();
    for (line, l) in text.lines().enumerate().skip(1) {
        let v = l.split(',').map(|c| number(path, line, c)).collect::<Result<Vec<f64>, String>>()?;
        if v.len() != 7 {
            return Err(format!("{}:{}: expected 7 columns, found {}", path.display(), line + 1, v.len()));
        }
        rows.push((DVector::from_column_slice(&v[1..4]), DVector::from_column_slice(&v[4..7])));
    }
    Ok(rows)
}

/// CORA's widths per observer at t = 9.5 s (the test's `tFinal == 10` branch), states in order.
fn cora(path: &Path) -> Result<Vec<(String, Vec<f64>)>, String> {
    let text = read(path)?;
    let mut out: Vec<(String, Vec<f64>)> = Vec::new();
    for (line, l) in text.lines().enumerate().skip(1) {
        let cells: Vec<&str> = l.split(',').collect();
        if cells.len() != 5 {
            return Err(format!("{}:{}: expected 5 columns", path.display(), line + 1));
        }
        if cells[0].contains("tFinal") {
            // The test's other branch: hulls at another horizon, not this comparison's.
            continue;
        }
        let width = number(path, line, cells[4])?;
        match out.iter_mut().find(|(name, _)| name == cells[0]) {
            Some((_, w)) => w.push(width),
            None => out.push((cells[0].to_owned(), vec![width])),
        }
    }
    if out.is_empty() || out.iter().any(|(_, w)| w.len() != 6) {
        return Err(format!("{}: expected six states per observer", path.display()));
    }
    Ok(out)
}

/// `czf-nl` with `settings` on CORA's data, `repeats` times for the step time.
fn run_at(
    tanks: &EquationModel,
    setup: &Setup,
    rows: &[Row],
    settings: &ConstrainedZonotopeSettings,
    repeats: usize,
) -> Result<OrderRun, String> {
    let mut ns = Vec::new();
    let mut widths = Vec::new();
    let mut unclean_steps = 0;
    for repeat in 0..repeats {
        let mut f =
            ConstrainedZonotopeFilter::new(setup.clone(), settings.clone()).map_err(|e| format!("czf-nl: {e}"))?;
        f.update(tanks, &DVector::from_column_slice(&Y1)).map_err(|e| format!("czf-nl, y_1: {e}"))?;
        for (k, (u, y)) in rows.iter().enumerate() {
            let t0 = Instant::now();
            let e = f.step(tanks, u, y).map_err(|e| format!("czf-nl, row {k}: {e}"))?;
            ns.push(u64::try_from(t0.elapsed().as_nanos()).unwrap_or(u64::MAX));
            if repeat == 0 {
                unclean_steps += usize::from(!e.status().is_clean());
                widths = (0..6).map(|i| e.bounds(i).map_or(f64::NAN, |(l, h)| h - l)).collect();
            }
        }
    }
    Ok(OrderRun {
        order: (settings.order, settings.max_constraints),
        mean: widths.iter().sum::<f64>() / 6.0,
        widths,
        step_time: StepTiming::of(ns),
        unclean_steps,
    })
}

/// Runs the comparison from the files under `root`.
///
/// # Errors
/// A file that cannot be read or parsed, or a filter error.
pub fn run(root: &Path, quick: bool) -> Result<SixTank, String> {
    let dir = root.join("examples/six-tank");
    let model = port_est::model::read_model(&dir.join("model.toml")).map_err(|e| format!("six-tank model: {e}"))?;
    let setup = model.setup(estimators::EstimateKind::GuaranteedConstrainedZonotope);
    let port_est::model::Dynamics::Equations(tanks) = &model.dynamics else {
        return Err("examples/six-tank/model.toml: not a model written as equations".into());
    };
    let chosen = super::czf_settings(&model)?;
    let rows = log(&dir.join("data.csv"))?;
    let cora = cora(&dir.join("cora_hulls.csv"))?;
    let repeats = TIMING_REPEATS[usize::from(quick)];
    let at_chosen = run_at(tanks, &setup, &rows, &chosen, repeats)?;
    // The default order with every other setting the file's (like for like).
    let d = ConstrainedZonotopeSettings::default();
    let default = ConstrainedZonotopeSettings { order: d.order, max_constraints: d.max_constraints, ..chosen.clone() };
    let default_order = run_at(tanks, &setup, &rows, &default, repeats)?;
    let cora_best: Vec<f64> = (0..6).map(|i| cora.iter().map(|(_, w)| w[i]).fold(f64::INFINITY, f64::min)).collect();
    Ok(SixTank {
        mean: at_chosen.mean,
        widths: at_chosen.widths,
        cora_best_mean: cora_best.iter().sum::<f64>() / 6.0,
        cora_best,
        cora,
        unclean_steps: at_chosen.unclean_steps + default_order.unclean_steps,
        order: at_chosen.order,
        step_time: at_chosen.step_time,
        default_order,
    })
}
