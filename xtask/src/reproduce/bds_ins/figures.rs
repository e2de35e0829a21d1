//! Figures 7–9 of experiment (a) (errors, `√P11`, `√P22`), the scale `t_k`, the field analogue's
//! errors and Table 1 as bars, and the CSV files.

use estimators::registry::names;
use std::fmt::Write as _;
use std::path::Path;

use svg_plot::{BarChart, Bars, Chart, Grid, PALETTE, Series};

use super::outputs;
use super::outputs::WriteFigure as _;
use super::run::{Accumulator, VARIANTS_A, VARIANTS_B};

/// The variants of (a) drawn in Figs 7–9: KF, FKF scripted/online (float), the reference.
const DRAWN_A: [&str; 4] = [names::KF, "fkf_scripted_float", "fkf_online_float", "oracle"];

/// The first `skip` epochs (convergence from the 2 m initial error) are left out of automatic
/// vertical ranges.
const SKIP: usize = 50;

fn color(id: &str) -> &'static str {
    match id {
        names::KF => PALETTE[0],
        "fkf_scripted_float" | names::FKF => PALETTE[2],
        "fkf_online_float" => PALETTE[1],
        "fkf_scripted_single" => PALETTE[5],
        "fkf_online_single" => PALETTE[4],
        _ => PALETTE[3],
    }
}

fn times(n: usize) -> Vec<f64> {
    (0..n).map(|k| k as f64).collect()
}

/// `(min, max)` of the finite values from `SKIP` on, with a 5 % margin.
fn range_after(series: &[&[f64]], symmetric: bool) -> Option<(f64, f64)> {
    let vals = series.iter().flat_map(|s| s.iter().skip(SKIP)).filter(|v| v.is_finite());
    let (lo, hi) = vals.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    if lo > hi {
        return None;
    }
    if symmetric {
        let m = 1.05 * lo.abs().max(hi.abs());
        return Some((-m, m));
    }
    let pad = 0.05 * (hi - lo).max(1e-12);
    Some((lo.min(0.0), hi + pad))
}

/// Writes experiment (a) of one reading: `k`, then for every variant of [`VARIANTS_A`] the first
/// seed's `ex`, `ey` \[m\], and over the seeds the RMS of `e_x`, `e_y`, the mean `√P11`, `√P22`
/// \[m\] and the mean `t_k`.
///
/// # Errors
/// The file cannot be written.
pub fn write_reading_csv(path: &Path, acc: &[Accumulator]) -> std::io::Result<()> {
    let mut s = String::from("k");
    for v in &VARIANTS_A {
        for c in ["ex_seed0", "ey_seed0", "rms_ex", "rms_ey", "sigma_x", "sigma_y", "t_mean"] {
            let _ = write!(s, ",{}_{c}", v.id);
        }
    }
    s.push('\n');
    let per: Vec<_> = acc.iter().map(Accumulator::per_epoch).collect();
    let n = per.first().map_or(0, |p| p.rms_ex.len());
    for k in 0..n {
        let _ = write!(s, "{k}");
        for (a, p) in acc.iter().zip(&per) {
            let (ex, ey) = a.first.as_ref().map_or((f64::NAN, f64::NAN), |t| (t.ex[k], t.ey[k]));
            let _ = write!(
                s,
                ",{ex:.6e},{ey:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e}",
                p.rms_ex[k], p.rms_ey[k], p.mean_sx[k], p.mean_sy[k], p.mean_scale[k]
            );
        }
        s.push('\n');
    }
    outputs::write_atomic(path, s.as_bytes())
}

/// Figs 7–9 and the scale of one reading. Returns `(file, caption)` pairs.
///
/// # Errors
/// A file cannot be written.
pub fn reading_figures(
    dir: &Path,
    id: &str,
    label: &str,
    acc: &[Accumulator],
    seed: u64,
) -> std::io::Result<Vec<(String, String)>> {
    let mut files = Vec::new();
    let pick = |vid: &str| VARIANTS_A.iter().position(|v| v.id == vid).map(|j| (&VARIANTS_A[j], &acc[j]));
    let n = acc.first().map_or(0, |a| a.sum_h.len());
    let t = times(n);
    // Fig. 7: position errors of the first seed.
    let mut grid = Grid::new(1);
    grid.title = format!("Fig. 7 (reconstruction), noise {label}: position errors, seed {seed}");
    for (axis, name) in [(0, "east e_x"), (1, "north e_y")] {
        let mut c = Chart::new(format!("{name} = estimate − truth"), "time t [s]", format!("{name} [m]"));
        c.height = 300;
        let mut ranges: Vec<Vec<f64>> = Vec::new();
        for vid in [names::KF, "fkf_scripted_float", "fkf_online_float"] {
            if let Some((v, a)) = pick(vid)
                && let Some(tr) = &a.first
            {
                let e = if axis == 0 { tr.ex.clone() } else { tr.ey.clone() };
                ranges.push(e.clone());
                c.add(Series::line(v.label, t.clone(), e, color(vid)));
            }
        }
        c.y_range = range_after(&ranges.iter().map(Vec::as_slice).collect::<Vec<_>>(), true);
        grid.add(c);
    }
    let file = format!("fig7_errors_{id}.svg");
    grid.write(&dir.join(&file))?;
    files.push((file, format!("Fig. 7: e_x and e_y of the KF and the FKF, first seed (noise {label})")));
    // Figs 8–9: the filters' σ, and the actual RMS error over the seeds.
    let mut grid = Grid::new(1);
    grid.title = format!("Figs 8–9 (reconstruction), noise {label}: σ (solid), RMS error (dashed)");
    for (axis, name) in [(0, "√P11 (east)"), (1, "√P22 (north)")] {
        let mut c = Chart::new(name.to_owned(), "time t [s]", "σ, RMS error [m]");
        c.height = 300;
        let mut ranges: Vec<Vec<f64>> = Vec::new();
        for vid in DRAWN_A {
            if let Some((v, a)) = pick(vid) {
                let p = a.per_epoch();
                let (sig, rms) = if axis == 0 { (p.mean_sx, p.rms_ex) } else { (p.mean_sy, p.rms_ey) };
                ranges.push(sig.clone());
                c.add(Series::line(format!("σ {}", v.label), t.clone(), sig, color(vid)));
                if vid != "oracle" {
                    ranges.push(rms.clone());
                    c.add(Series::dashed(format!("RMS error {}", v.label), t.clone(), rms, color(vid)));
                }
            }
        }
        c.y_range = range_after(&ranges.iter().map(Vec::as_slice).collect::<Vec<_>>(), false);
        grid.add(c);
    }
    let file = format!("fig8_9_sigma_{id}.svg");
    grid.write(&dir.join(&file))?;
    files.push((
        file,
        format!("Figs 8–9: √P11, √P22 (mean over seeds) against the actual RMS error over seeds (noise {label})"),
    ));
    // The scale t_k.
    let mut c = Chart::new(format!("Noise scale t_k, mean over seeds (noise {label})"), "time t [s]", "t_k");
    for (v, a) in VARIANTS_A.iter().zip(acc) {
        if v.id == names::KF {
            continue;
        }
        c.add(Series::line(v.label, t.clone(), a.per_epoch().mean_scale, color(v.id)));
    }
    let file = format!("scale_{id}.svg");
    c.write(&dir.join(&file))?;
    files.push((file, format!("t_k of every FKF variant and of the reference, mean over seeds (noise {label})")));
    Ok(files)
}

/// Writes experiment (b): `k`, then for KF and FKF the first seed's `ex`, `ey`, `t`, and the mean
/// horizontal error over the seeds.
///
/// # Errors
/// The file cannot be written.
pub fn write_field_csv(path: &Path, acc: &[Accumulator]) -> std::io::Result<()> {
    let mut s = String::from("k");
    for v in &VARIANTS_B {
        for c in ["ex_seed0", "ey_seed0", "t_seed0", "mean_horizontal"] {
            let _ = write!(s, ",{}_{c}", v.id);
        }
    }
    s.push('\n');
    let n = acc.first().map_or(0, |a| a.sum_h.len());
    for k in 0..n {
        let _ = write!(s, "{k}");
        for a in acc {
            let (ex, ey, t) =
                a.first.as_ref().map_or((f64::NAN, f64::NAN, f64::NAN), |t| (t.ex[k], t.ey[k], t.scale[k]));
            let _ = write!(s, ",{ex:.6e},{ey:.6e},{t:.6e},{:.6e}", a.sum_h[k] / a.runs.max(1) as f64);
        }
        s.push('\n');
    }
    outputs::write_atomic(path, s.as_bytes())
}

/// The field analogue: horizontal error over the route (first seed and mean over seeds), `t_k`,
/// and Table 1 as bars. Returns `(file, caption)` pairs.
///
/// # Errors
/// A file cannot be written.
pub fn field_figures(
    dir: &Path,
    acc: &[Accumulator],
    windows: &[(String, usize, usize)],
    seed: u64,
) -> std::io::Result<Vec<(String, String)>> {
    let mut files = Vec::new();
    let n = acc.first().map_or(0, |a| a.sum_h.len());
    let t = times(n);
    let mut grid = Grid::new(1);
    grid.title = format!("Field analogue, seed {seed}: open, fully occluded (300–420 s), half occluded (420–600 s)");
    let mut c = Chart::new("horizontal error of the corrected position", "time t [s]", "horizontal error [m]");
    c.height = 320;
    let mut ranges: Vec<Vec<f64>> = Vec::new();
    for (v, a) in VARIANTS_B.iter().zip(acc) {
        if let Some(tr) = &a.first {
            let h: Vec<f64> = (0..tr.len()).map(|k| tr.horizontal(k)).collect();
            ranges.push(h.clone());
            c.add(Series::line(v.label, t.clone(), h, color(v.id)));
        }
        let mean: Vec<f64> = a.sum_h.iter().map(|s| s / a.runs.max(1) as f64).collect();
        c.add(Series::dashed(format!("{} (mean over seeds)", v.label), t.clone(), mean, color(v.id)));
    }
    c.y_range = range_after(&ranges.iter().map(Vec::as_slice).collect::<Vec<_>>(), false);
    grid.add(c);
    let mut c = Chart::new("noise scale t_k of the FKF (first seed)", "time t [s]", "t_k");
    c.height = 240;
    if let Some((v, a)) = VARIANTS_B.iter().zip(acc).find(|(v, _)| v.id == names::FKF)
        && let Some(tr) = &a.first
    {
        c.add(Series::line(v.label, t.clone(), tr.scale.clone(), color(v.id)));
    }
    grid.add(c);
    let file = "field_errors.svg".to_owned();
    grid.write(&dir.join(&file))?;
    files.push((file, "Field analogue: horizontal error of KF and FKF along the route, and the FKF's t_k".to_owned()));
    let groups: Vec<String> = windows.iter().map(|w| w.0.clone()).collect();
    let mut b = BarChart::new(
        "Table 1 layout: mean horizontal error per zone (mean over seeds)",
        "",
        "mean horizontal error [m]",
        groups,
    );
    for (v, a) in VARIANTS_B.iter().zip(acc) {
        let vals = windows.iter().map(|w| a.window(w.1, w.2).mean_horizontal).collect();
        b.add(Bars::new(v.label, vals, color(v.id)));
    }
    let file = "field_table1.svg".to_owned();
    b.write(&dir.join(&file))?;
    files.push((file, "Mean horizontal error per zone, KF and FKF (the layout of the paper's Table 1)".to_owned()));
    Ok(files)
}
