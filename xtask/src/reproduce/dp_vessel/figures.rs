//! The figures (the paper's Fig. 2: position and heading; Fig. 3: forces — both lost, redrawn
//! from this reconstruction) and the per-run CSV files.

use std::fmt::Write as _;
use std::path::Path;

use svg_plot::{Chart, Grid, PALETTE, Series};
use vessel_control::LoopRecord;

use super::ResultSummary;
use super::outputs;
use super::outputs::WriteFigure as _;
use super::run::{EstimatorSpec, Scenario, TARGET};

const DEG: f64 = 180.0 / std::f64::consts::PI;

/// Writes one run as CSV: `t` \[s\]; the true state `x, y, psi, u, v, r` (m, rad, m/s, rad/s);
/// the estimate (`_hat`); the measurement `z_x, z_y, z_psi`; the commanded thrust
/// `tau_x, tau_y, tau_n` (N, N m) and the reference `yd_x, yd_y, yd_psi` (empty at the last
/// instant).
///
/// # Errors
/// The file cannot be written.
pub fn write_csv(path: &Path, rec: &LoopRecord) -> std::io::Result<()> {
    let mut s = String::from(
        "t,x,y,psi,u,v,r,x_hat,y_hat,psi_hat,u_hat,v_hat,r_hat,z_x,z_y,z_psi,tau_x,tau_y,tau_n,yd_x,yd_y,yd_psi\n",
    );
    for k in 0..=rec.steps {
        let _ = write!(s, "{:.1}", rec.time(k));
        for v in rec.state(k).iter().chain(rec.estimate(k)).chain(rec.measurement(k)) {
            let _ = write!(s, ",{v:.9e}");
        }
        if k < rec.steps {
            for v in rec.input(k) {
                let _ = write!(s, ",{v:.6e}");
            }
            match rec.reference(k) {
                Some(r) => r.iter().for_each(|v| {
                    let _ = write!(s, ",{v:.9e}");
                }),
                None => s.push_str(",,,"),
            }
        } else {
            s.push_str(",,,,,,");
        }
        s.push('\n');
    }
    outputs::write_atomic(path, s.as_bytes())
}

fn panel(title: String, y_label: String) -> Chart {
    Chart { width: 620, height: 290, ..Chart::new(title, "time t [s]", y_label) }
}

/// Every `every`-th sample of `(t, v)` (measurements drawn as dots).
fn thin(t: &[f64], v: &[f64], every: usize) -> (Vec<f64>, Vec<f64>) {
    (t.iter().step_by(every).copied().collect(), v.iter().step_by(every).copied().collect())
}

/// Fig. 2 (position and heading: truth, estimate, measurements, reference; and the track) and
/// Fig. 3 (the three thrust components with their limits) of one run. Returns `(file, caption)`.
///
/// # Errors
/// A file cannot be written.
pub fn run_figures(
    dir: &Path,
    scenario: &Scenario,
    spec: &EstimatorSpec,
    rec: &LoopRecord,
    seed: u64,
) -> std::io::Result<Vec<(String, String)>> {
    let n = rec.steps + 1;
    let t: Vec<f64> = (0..n).map(|k| rec.time(k)).collect();
    let mut grid = Grid::new(2);
    grid.title = format!("Fig. 2 (redrawn): position and heading — {} / {} (seed {seed})", scenario.id, spec.label);
    for (i, name, unit, scale) in [(0, "north x", "m", 1.0), (1, "east y", "m", 1.0), (2, "heading ψ", "°", DEG)] {
        let truth: Vec<f64> = (0..n).map(|k| rec.state(k)[i] * scale).collect();
        let est: Vec<f64> = (0..n).map(|k| rec.estimate(k)[i] * scale).collect();
        let z: Vec<f64> = (0..n).map(|k| rec.measurement(k)[i] * scale).collect();
        let mut c = panel(name.to_string(), format!("{name} [{unit}]"));
        let (tz, zz) = thin(&t, &z, 20);
        c.add(Series::markers("measurement (every 2 s)", tz, zz, PALETTE[6]));
        if rec.reference_dim > 0 {
            let yd: Vec<f64> = (0..rec.steps).map(|k| rec.reference(k).map_or(f64::NAN, |r| r[i] * scale)).collect();
            c.add(Series::dashed("reference y_d", t[..rec.steps].to_vec(), yd, PALETTE[3]));
        }
        c.add(Series::line("estimate", t.clone(), est, PALETTE[1]));
        c.add(Series::line("truth", t.clone(), truth, PALETTE[0]));
        if i == 2 {
            // The measurements (σ up to 18°) would hide the heading: range from truth and estimate.
            let (lo, hi) = (0..n).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), k| {
                let a = rec.state(k)[2] * DEG;
                let b = rec.estimate(k)[2] * DEG;
                (lo.min(a).min(b), hi.max(a).max(b))
            });
            let pad = 0.1 * (hi - lo).max(0.1);
            c.y_range = Some((lo - pad, hi + pad));
        }
        grid.add(c);
    }
    let mut track = Chart::xy("track (east, north)", "east y [m]", "north x [m]");
    track.width = 620;
    track.height = 290;
    track.add(Series::markers("target", vec![TARGET[1]], vec![TARGET[0]], PALETTE[2]));
    track.add(Series::track(
        "truth",
        (0..n).map(|k| rec.state(k)[1]).collect(),
        (0..n).map(|k| rec.state(k)[0]).collect(),
        PALETTE[0],
    ));
    grid.add(track);
    let file2 = format!("fig2_{}_{}.svg", scenario.id, spec.id);
    grid.write(&dir.join(&file2))?;

    let mut grid = Grid::new(1);
    grid.title = format!("Fig. 3 (redrawn): thrust — {} / {} (seed {seed})", scenario.id, spec.id.to_uppercase());
    let tt = t[..rec.steps].to_vec();
    let limits = vessel_dynamics::ThrustLimits::paper().max;
    for (i, name, unit, scale) in
        [(0, "surge force τ_X", "kN", 1e-3), (1, "sway force τ_Y", "kN", 1e-3), (2, "yaw moment τ_N", "kN·m", 1e-3)]
    {
        let tau: Vec<f64> = (0..rec.steps).map(|k| rec.input(k)[i] * scale).collect();
        let mut c =
            Chart { width: 900, height: 260, ..Chart::new(name.to_string(), "time t [s]", format!("{name} [{unit}]")) };
        let lim = limits[i] * scale;
        c.add(Series::dashed("limit", vec![0.0, tt[tt.len() - 1]], vec![lim, lim], PALETTE[2]));
        c.add(Series::dashed("", vec![0.0, tt[tt.len() - 1]], vec![-lim, -lim], PALETTE[2]));
        c.add(Series::line("commanded (after saturation)", tt.clone(), tau, PALETTE[1]));
        c.y_range = Some((-1.1 * lim, 1.1 * lim));
        grid.add(c);
    }
    let file3 = format!("fig3_{}_{}.svg", scenario.id, spec.id);
    grid.write(&dir.join(&file3))?;
    Ok(vec![
        (file2, format!("Fig. 2 (redrawn): north, east, heading and track — {}, {}", scenario.title, spec.label)),
        (file3, format!("Fig. 3 (redrawn): thrust and limits — {}, {}", scenario.title, spec.label)),
    ])
}

/// The distance `√((x − 50)² + (y − 50)²)` to the target of the first seed of every (scenario,
/// estimator) with figures, over time, as `log10` (read back from the CSV files written before,
/// so that the runs' records need not stay in memory). Returns `(file, caption)`.
///
/// # Errors
/// A file cannot be written.
pub fn comparison_figures(dir: &Path, results: &[ResultSummary]) -> std::io::Result<Vec<(String, String)>> {
    let mut chart = Chart::new("Distance to the target (50 m, 50 m), first seed", "time t [s]", "log10 distance [m]");
    chart.width = 900;
    let file = "distance_to_target.svg".to_owned();
    let mut any = false;
    for (j, res) in results.iter().filter(|r| r.scenario.figures).enumerate() {
        let path = dir.join("..").join("csv").join(&res.csv);
        let Ok(text) = std::fs::read_to_string(&path) else { continue };
        let (mut t, mut d) = (Vec::new(), Vec::new());
        for line in text.lines().skip(1).step_by(5) {
            let mut f = line.split(',');
            let (Some(tk), Some(x), Some(y)) = (f.next(), f.next(), f.next()) else { continue };
            let (Ok(tk), Ok(x), Ok(y)) = (tk.parse::<f64>(), x.parse::<f64>(), y.parse::<f64>()) else { continue };
            t.push(tk);
            d.push((x - TARGET[0]).hypot(y - TARGET[1]).max(1e-3).log10());
        }
        chart.add(Series::line(
            format!("{} / {}", res.scenario.id, res.estimator.to_uppercase()),
            t,
            d,
            PALETTE[(j + 1) % 8],
        ));
        any = true;
    }
    if !any {
        return Ok(Vec::new());
    }
    chart.write(&dir.join(&file))?;
    Ok(vec![(file, "Distance to the target over time, runs A and B, each estimator (first seed)".to_owned())])
}
