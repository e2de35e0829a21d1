//! The carrier paper's Figures 3–10 for a scenario's runs.

use std::path::Path;

use nalgebra::DVector;
use svg_plot::{Chart, PALETTE, Series};

use super::scenarios::{STATES, TS};
use crate::reproduce::outputs::WriteFigure as _;
use crate::reproduce::runner::Run;

/// Colour of the `j`-th estimator: the palette without black (the truth) and the pale yellow.
fn series_color(j: usize) -> &'static str {
    PALETTE[1 + j % 6]
}

/// The paper's Figures 3–6 (per state: truth, bounds of the set filters, Kalman estimate) and
/// 7–10 (errors) for one scenario; returns the written file names (relative to `dir`).
pub fn write_figures(
    dir: &Path,
    scenario_id: &str,
    scenario_title: &str,
    truth: &[DVector<f64>],
    bound_runs: &[&Run],
    estimate_runs: &[&Run],
) -> std::io::Result<Vec<(String, String)>> {
    let mut files = Vec::new();
    let steps = bound_runs.iter().chain(estimate_runs).map(|r| r.snapshots.len()).min().unwrap_or(0);
    let t: Vec<f64> = (0..steps).map(|k| k as f64 * TS).collect();
    for (i, (id, name, unit)) in STATES.iter().enumerate() {
        let fig = 3 + i;
        let mut chart = Chart::new(
            format!("Fig. {fig} — {name}: truth and bounds ({scenario_title})"),
            "time t [s]",
            format!("{name} [{unit}]"),
        );
        for (j, run) in bound_runs.iter().enumerate() {
            let color = series_color(j);
            let lo: Vec<f64> =
                run.snapshots[..steps].iter().map(|s| s.centre[i] - s.shape[(i, i)].max(0.0).sqrt()).collect();
            let hi: Vec<f64> =
                run.snapshots[..steps].iter().map(|s| s.centre[i] + s.shape[(i, i)].max(0.0).sqrt()).collect();
            if j == 0 {
                chart.add(Series::band(format!("{} bounds", run.label), t.clone(), lo, hi, color));
            } else {
                chart.add(Series::dashed(format!("{} upper", run.label), t.clone(), hi, color));
                chart.add(Series::dashed(format!("{} lower", run.label), t.clone(), lo, color));
            }
        }
        for (j, run) in estimate_runs.iter().enumerate() {
            let color = series_color(bound_runs.len() + j);
            let y = run.snapshots[..steps].iter().map(|s| s.centre[i]).collect();
            chart.add(Series::line(format!("{} estimate", run.label), t.clone(), y, color));
        }
        chart.add(Series::line("truth", t.clone(), truth[..steps].iter().map(|x| x[i]).collect(), PALETTE[0]));
        let file = format!("{scenario_id}_fig{fig}_{id}.svg");
        chart.write(&dir.join(&file))?;
        files.push((file, format!("Fig. {fig}: {name}")));
    }
    for (i, (id, name, unit)) in STATES.iter().enumerate() {
        let fig = 7 + i;
        let mut chart = Chart::new(
            format!("Fig. {fig} — {name}: estimation error ({scenario_title})"),
            "time t [s]",
            format!("error in {name} [{unit}]"),
        );
        for (j, run) in bound_runs.iter().chain(estimate_runs).enumerate() {
            let color = series_color(j);
            let y = run.snapshots[..steps].iter().zip(truth).map(|(s, x)| s.centre[i] - x[i]).collect();
            let what = if run.is_set { "centre − truth" } else { "estimate − truth" };
            chart.add(Series::line(format!("{} {what}", run.label), t.clone(), y, color));
        }
        let file = format!("{scenario_id}_fig{fig}_{id}_error.svg");
        chart.write(&dir.join(&file))?;
        files.push((file, format!("Fig. {fig}: error in {name}")));
    }
    Ok(files)
}
