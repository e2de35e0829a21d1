//! Certified sideslip: the nonlinear set-membership filter `smf-nl` (docs/nonlinear-smf.md) on the
//! truck with bounded noise, beside the EKF on the same data.
//!
//! The truth here is the filter's own model (`TruckEkfModel`, Euler at 1 ms) — what the guarantee
//! covers — driven by the nominal slalom's inputs (`δ` and the six wheel speeds of the simulated
//! truth), with every noise on the boundary of its ellipsoid: process noise in
//! `𝓔(0, (3σ_w)²)`, `σ_w² = T·q_c`, measurement noise in `𝓔(0, (3σ)²)`, the initial state on the
//! boundary of `𝓔(x̂0, (3σ0)²)` (diagonal ellipsoids whose axis-aligned boxes are ±3σ of the
//! EKF's Gaussian settings). The certified sideslip interval is `atan([V_y]/[V_x])` over the
//! published set's bounding box (2), computed in interval arithmetic; the EKF's band is
//! `β̂ ± 3σ_β` (σ_β propagated from `P` to first order). A Monte Carlo run repeats the certified
//! filter alone over many seeds and counts the steps whose truth leaves the published set. In the
//! figure run the constrained-zonotope filter `czf-nl` (docs/constrained-zonotopes.md) runs beside
//! them on the ellipsoids' bounding boxes (±3σ: the same noise lies in them), its β interval
//! `atan([V_y]/[V_x])` over its published box.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use estimators::{
    ConstrainedZonotopeFilter, ConstrainedZonotopeSettings, Estimate, EstimatorError, ExtendedKalmanFilter,
    NonlinearSetMembershipFilter, Setup,
};
use models::{DiscreteModel, Interval, Noise, Xoshiro256StarStar};
use nalgebra::{DMatrix, DVector};
use serde::Serialize;
use svg_plot::{Chart, Grid, PALETTE, Series};
use truck_dynamics::{TruckEkfModel, TruthTrajectory};

use super::outputs::{self, WriteFigure as _};
use super::run::{P0_SIGMA, QC, SIGMA, StepTiming, X0};
use crate::reproduce::outputs::sig3;
use crate::reproduce::runner::{bounding_boxes, median};

/// Half-width of the noise boxes in standard deviations of the EKF's Gaussian settings.
pub const SIGMAS: f64 = 3.0;
/// Monte Carlo seeds of the full run (each the whole slalom): about 10⁶ certified steps.
pub const MONTE_CARLO_SEEDS: usize = 84;
/// Monte Carlo seeds of `--quick`.
pub const MONTE_CARLO_SEEDS_QUICK: usize = 2;

/// The noise description written to `summary.json` and the report.
pub const NOISE: &str = "diagonal ellipsoids whose axis-aligned boxes are ±3σ of the EKF's Gaussian settings: \
                         w ∈ 𝓔(0, 9·T·diag(q_c)), v ∈ 𝓔(0, 9·diag(σ²)), x0 ∈ 𝓔(x̂0, 9·diag(σ0²)); every noise \
                         drawn on the boundary of its ellipsoid (uniform direction)";

/// The Monte Carlo count of the certified filter.
#[derive(Debug, Clone, Serialize)]
pub struct MonteCarlo {
    /// Seeds (`seed + 1000 + i`).
    pub seeds: usize,
    /// Certified steps taken.
    pub steps: usize,
    /// Steps whose truth is outside the published ellipsoid.
    pub misses: usize,
    /// Runs stopped by `GuaranteeLost`.
    pub guarantee_lost: usize,
    /// Wall-clock seconds.
    pub seconds: f64,
}

/// The certified scenario in `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct CertifiedSummary {
    /// The noise sets.
    pub noise: String,
    /// Steps of the figure run (first seed).
    pub steps: usize,
    /// Steps whose truth is outside the published ellipsoid (must be 0).
    pub misses: usize,
    /// Whether the figure run stopped on `GuaranteeLost`.
    pub guarantee_lost: bool,
    /// Steps whose truth `β` is outside the certified interval (must be 0).
    pub beta_misses: usize,
    /// Largest `(x − x̂)ᵀ P⁻¹ (x − x̂)` of the truth over the run (≤ 1 when contained).
    pub max_distance: f64,
    /// Median width of the certified `β` interval \[°\].
    pub median_beta_width_deg: f64,
    /// Largest width of the certified `β` interval \[°\].
    pub max_beta_width_deg: f64,
    /// Median width of the EKF's `β̂ ± 3σ_β` band (`6σ_β`) \[°\].
    pub median_ekf_band_width_deg: f64,
    /// Steps whose truth `β` is outside the EKF's ±3σ band.
    pub ekf_outside_band: usize,
    /// Median of the certified interval's width over the EKF band's width.
    pub median_width_ratio: f64,
    /// Wall time of `NonlinearSetMembershipFilter::step` in the figure run.
    pub timing: StepTiming,
    /// The Monte Carlo count.
    pub monte_carlo: MonteCarlo,
    /// `czf-nl` in the figure run.
    pub zonotope: ZonotopeBeta,
    /// The figure `(file, caption)`.
    pub figure: (String, String),
    /// The CSV file (relative to `csv/`).
    pub csv: String,
}

/// `czf-nl` on the figure run's data.
#[derive(Debug, Clone, Serialize)]
pub struct ZonotopeBeta {
    /// Steps taken.
    pub steps: usize,
    /// Steps with a state or `β` outside its published interval (must be 0).
    pub misses: usize,
    /// Why it stopped, if it did (`GuaranteeLost` or a refused measurement).
    pub stopped: Option<String>,
    /// Median / largest width of its certified `β` interval \[°\].
    pub median_beta_width_deg: f64,
    /// Largest width \[°\].
    pub max_beta_width_deg: f64,
    /// Median of its `β` width over `smf-nl`'s on the same steps.
    pub median_ratio_to_smf: f64,
    /// Wall time of its step.
    pub timing: StepTiming,
}

/// One run's outcome; with `record`, the per-step series of the figure.
#[derive(Debug, Default)]
struct SeedRun {
    steps: usize,
    misses: usize,
    beta_misses: usize,
    max_distance: f64,
    lost: bool,
    step_ns: Vec<u64>,
    /// `[t, β, β_lo, β_hi, β̂_EKF, σ_β,EKF, β_lo,czf, β_hi,czf]` per step.
    rows: Vec<Row>,
    czf_steps: usize,
    czf_misses: usize,
    czf_stopped: Option<String>,
    czf_ns: Vec<u64>,
}

/// One step of the figure run.
type Row = [f64; 8];

fn diag(v: [f64; 3]) -> DMatrix<f64> {
    DMatrix::from_diagonal(&DVector::from_row_slice(&v))
}

/// The certified filter's sets: ±3σ boxes of the EKF's settings as their ellipsoids' boxes.
fn certified_setup(ts: f64) -> Setup {
    let k2 = SIGMAS * SIGMAS;
    Setup {
        x0: DVector::from_row_slice(&X0),
        p0: diag(P0_SIGMA.map(|s| k2 * s * s)),
        process_noise: diag(QC.map(|q| k2 * q * ts)),
        measurement_noise: diag(SIGMA.map(|s| k2 * s * s)),
        inputs: 7,
    }
}

/// The EKF's Gaussian settings (digest §4).
fn ekf_setup(ts: f64) -> Setup {
    Setup {
        x0: DVector::from_row_slice(&X0),
        p0: diag(P0_SIGMA.map(|s| s * s)),
        process_noise: diag(QC.map(|q| q * ts)),
        measurement_noise: diag(SIGMA.map(|s| s * s)),
        inputs: 7,
    }
}

/// `(x − c)ᵀ P⁻¹ (x − c)`, `∞` when `P` is not positive definite.
fn distance(c: &DVector<f64>, p: &DMatrix<f64>, x: &DVector<f64>) -> f64 {
    let e = x - c;
    p.clone().cholesky().map_or(f64::INFINITY, |ch| e.dot(&ch.solve(&e)))
}

/// The certified `β` interval `atan([V_y]/[V_x])` over the set's bounding box (N1), (2).
fn beta_interval(c: &DVector<f64>, p: &DMatrix<f64>) -> Interval {
    let b = |i: usize| {
        let s = Interval::point(p[(i, i)].max(0.0)).sqrt().hi();
        Interval::centered(c[i], s)
    };
    (b(1) / b(0)).atan()
}

/// `β̂ = atan(V̂_y/V̂_x)` and its first-order standard deviation from `P`.
fn ekf_beta(c: &DVector<f64>, p: &DMatrix<f64>) -> (f64, f64) {
    let (vx, vy) = (c[0], c[1]);
    let d = vx * vx + vy * vy;
    let (gx, gy) = (-vy / d, vx / d);
    let var = gx * gx * p[(0, 0)] + 2.0 * gx * gy * p[(0, 1)] + gy * gy * p[(1, 1)];
    ((vy / vx).atan(), var.max(0.0).sqrt())
}

/// One run over the inputs of `truth`: the model-truth with boundary noise, `smf-nl`, and with
/// `record` the EKF on the same data and the per-step series.
fn run_seed(truth: &TruthTrajectory, model: &TruckEkfModel, seed: u64, record: bool) -> Result<SeedRun, String> {
    let ts = model.ts();
    let setup = certified_setup(ts);
    let noise = |shape: &DMatrix<f64>| Noise::ellipsoid_boundary(shape.clone()).map_err(|e| format!("noise: {e}"));
    let (w, v, x0) = (noise(&setup.process_noise)?, noise(&setup.measurement_noise)?, noise(&setup.p0)?);
    let mut rng = Xoshiro256StarStar::seed_from_u64(seed);
    let mut x = &setup.x0 + x0.sample(&mut rng);
    let mut smf = NonlinearSetMembershipFilter::new(setup).map_err(|e| format!("smf-nl: {e}"))?;
    let mut ekf = ExtendedKalmanFilter::new(ekf_setup(ts)).map_err(|e| format!("EKF: {e}"))?;
    let mut czf = if record {
        Some(
            ConstrainedZonotopeFilter::new(
                bounding_boxes(&certified_setup(ts)),
                ConstrainedZonotopeSettings::default(),
            )
            .map_err(|e| format!("czf-nl: {e}"))?,
        )
    } else {
        None
    };
    let mut run = SeedRun::default();
    let (mut u, mut next, mut y) = (DVector::zeros(7), DVector::zeros(3), DVector::zeros(3));
    for k in 0..truth.len().saturating_sub(1) {
        let input = truth.estimator_input(k).ok_or("missing truth input")?;
        u[0] = input.delta;
        for j in 0..6 {
            u[1 + j] = input.omega[j];
        }
        model.f(&x, &u, &mut next).map_err(|e| format!("model truth, step {k}: {e}"))?;
        x = &next + w.sample(&mut rng);
        model.h(&x, &u, &mut y).map_err(|e| format!("model truth, step {k}: {e}"))?;
        y += v.sample(&mut rng);
        let t0 = Instant::now();
        let result = smf.step(model, &u, &y);
        let ns = t0.elapsed().as_nanos();
        let est = match result {
            Ok(est) => est,
            Err(EstimatorError::GuaranteeLost { .. }) => {
                run.lost = true;
                break;
            }
            Err(e) => return Err(format!("smf-nl, seed {seed}, step {k}: {e}")),
        };
        run.steps += 1;
        let d = distance(&est.center, &est.shape, &x);
        run.max_distance = run.max_distance.max(d);
        run.misses += usize::from(d.is_nan() || d > 1.0);
        let beta = beta_interval(&est.center, &est.shape);
        run.beta_misses += usize::from(!beta.contains((x[1] / x[0]).atan()));
        if record {
            run.step_ns.push(u64::try_from(ns).unwrap_or(u64::MAX));
            let e = ekf.step(model, &u, &y).map_err(|e| format!("EKF, step {k}: {e}"))?;
            let (b, s) = ekf_beta(&e.center, &e.covariance);
            let mut zonotope_beta = (f64::NAN, f64::NAN);
            if let Some(f) = czf.as_mut() {
                let t0 = Instant::now();
                match f.step(model, &u, &y) {
                    Ok(z) => {
                        run.czf_ns.push(u64::try_from(t0.elapsed().as_nanos()).unwrap_or(u64::MAX));
                        run.czf_steps += 1;
                        let b: Vec<Interval> = (0..3)
                            .map(|i| z.bounds(i).map_or(Interval::ENTIRE, |(l, h)| Interval::new(l, h)))
                            .collect();
                        let zb = (b[1] / b[0]).atan();
                        let outside = (0..3).any(|i| !b[i].contains(x[i])) || !zb.contains((x[1] / x[0]).atan());
                        run.czf_misses += usize::from(outside);
                        zonotope_beta = (zb.lo(), zb.hi());
                    }
                    Err(e @ (EstimatorError::GuaranteeLost { .. } | EstimatorError::SetMissed { .. })) => {
                        run.czf_stopped = Some(format!("step {k}: {e}"));
                        czf = None;
                    }
                    Err(e) => return Err(format!("czf-nl, seed {seed}, step {k}: {e}")),
                }
            }
            run.rows.push([
                (k + 1) as f64 * ts,
                (x[1] / x[0]).atan(),
                beta.lo(),
                beta.hi(),
                b,
                s,
                zonotope_beta.0,
                zonotope_beta.1,
            ]);
        }
    }
    Ok(run)
}

/// Runs the scenario over the nominal `truth`: the figure run (seed `seed`) and the Monte Carlo
/// count (seeds `seed + 1000 + i`), writing the figure and the CSV.
///
/// # Errors
/// A filter error other than `GuaranteeLost`, or an output that cannot be written.
pub fn run(
    truth: &TruthTrajectory,
    model: &TruckEkfModel,
    seed: u64,
    quick: bool,
    out: &Path,
) -> Result<CertifiedSummary, String> {
    let first = run_seed(truth, model, seed, true)?;
    let deg = 180.0 / std::f64::consts::PI;
    let widths: Vec<f64> = first.rows.iter().map(|r| (r[3] - r[2]) * deg).collect();
    let bands: Vec<f64> = first.rows.iter().map(|r| 2.0 * SIGMAS * r[5] * deg).collect();
    let ratios: Vec<f64> = widths.iter().zip(&bands).map(|(w, b)| w / b).collect();
    let ekf_outside_band = first.rows.iter().filter(|r| (r[1] - r[4]).abs() > SIGMAS * r[5]).count();
    let csv = "certified_beta.csv".to_owned();
    write_csv(&out.join("csv").join(&csv), &first.rows).map_err(|e| format!("writing {csv}: {e}"))?;
    let figure =
        figure(&out.join("figures"), &first.rows, seed).map_err(|e| format!("writing the certified figure: {e}"))?;
    let seeds = if quick { MONTE_CARLO_SEEDS_QUICK } else { MONTE_CARLO_SEEDS };
    let t0 = Instant::now();
    let bar = crate::reproduce::progress_bar(seeds as u64, "truck smf-nl Monte Carlo");
    let mut mc = MonteCarlo { seeds, steps: 0, misses: 0, guarantee_lost: 0, seconds: 0.0 };
    for i in 0..seeds {
        let r = run_seed(truth, model, seed.wrapping_add(1000 + i as u64), false)?;
        mc.steps += r.steps;
        mc.misses += r.misses + r.beta_misses;
        mc.guarantee_lost += usize::from(r.lost);
        bar.inc(1);
    }
    bar.finish_and_clear();
    mc.seconds = t0.elapsed().as_secs_f64();
    let zonotope_widths: Vec<f64> = first.rows.iter().map(|r| (r[7] - r[6]) * deg).filter(|w| w.is_finite()).collect();
    let zonotope = ZonotopeBeta {
        steps: first.czf_steps,
        misses: first.czf_misses,
        stopped: first.czf_stopped.clone(),
        median_beta_width_deg: median(zonotope_widths.clone()),
        max_beta_width_deg: zonotope_widths.iter().copied().fold(0.0, f64::max),
        median_ratio_to_smf: median(
            first.rows.iter().map(|r| (r[7] - r[6]) / (r[3] - r[2])).filter(|v| v.is_finite()).collect(),
        ),
        timing: StepTiming::of(first.czf_ns.clone()),
    };
    Ok(CertifiedSummary {
        noise: NOISE.to_owned(),
        steps: first.steps,
        misses: first.misses,
        guarantee_lost: first.lost,
        beta_misses: first.beta_misses,
        max_distance: first.max_distance,
        median_beta_width_deg: median(widths.clone()),
        max_beta_width_deg: widths.iter().copied().fold(0.0, f64::max),
        median_ekf_band_width_deg: median(bands),
        ekf_outside_band,
        median_width_ratio: median(ratios),
        timing: StepTiming::of(first.step_ns),
        monte_carlo: mc,
        zonotope,
        figure,
        csv,
    })
}

fn write_csv(path: &Path, rows: &[Row]) -> std::io::Result<()> {
    let mut s =
        String::from("t,beta,beta_certified_lo,beta_certified_hi,beta_ekf,beta_ekf_sigma,beta_czf_lo,beta_czf_hi\n");
    for r in rows {
        let _ = writeln!(
            s,
            "{:.3},{:.9e},{:.9e},{:.9e},{:.9e},{:.4e},{:.9e},{:.9e}",
            r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7]
        );
    }
    outputs::write_atomic(path, s.as_bytes())
}

/// The truth's `β`, the certified interval and the EKF's ±3σ band over the slalom, a zoom on one
/// half-period, and both widths over time.
fn figure(dir: &Path, rows: &[Row], seed: u64) -> std::io::Result<(String, String)> {
    let deg = 180.0 / std::f64::consts::PI;
    let col = |f: &dyn Fn(&Row) -> f64| rows.iter().map(f).collect::<Vec<f64>>();
    let t = col(&|r| r[0]);
    let mut grid = Grid::new(1);
    grid.title = format!("Truck slalom, bounded noise: certified β (smf-nl) and the EKF's ±3σ band (seed {seed})");
    for (title, range) in [("β over the slalom", None), ("β, zoom on 2.5–3.5 s", Some((2.5, 3.5)))] {
        let mut c = Chart::new(title, "time t [s]", "β [°]");
        c.width = 900;
        c.x_range = range;
        c.add(Series::band(
            "EKF β̂ ± 3σ",
            t.clone(),
            col(&|r| (r[4] - SIGMAS * r[5]) * deg),
            col(&|r| (r[4] + SIGMAS * r[5]) * deg),
            PALETTE[1],
        ));
        c.add(Series::band("certified β (smf-nl)", t.clone(), col(&|r| r[2] * deg), col(&|r| r[3] * deg), PALETTE[2]));
        c.add(Series::band("certified β (czf-nl)", t.clone(), col(&|r| r[6] * deg), col(&|r| r[7] * deg), PALETTE[3]));
        c.add(Series::line("truth (model with bounded noise)", t.clone(), col(&|r| r[1] * deg), PALETTE[0]));
        if let Some((a, b)) = range {
            let inside = rows.iter().filter(|r| r[0] >= a && r[0] <= b);
            let (lo, hi) = inside.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), r| {
                (lo.min(r[2]).min(r[4] - SIGMAS * r[5]), hi.max(r[3]).max(r[4] + SIGMAS * r[5]))
            });
            if lo < hi {
                let pad = 0.05 * (hi - lo);
                c.y_range = Some(((lo - pad) * deg, (hi + pad) * deg));
            }
        } else {
            c.y_range = rows.iter().filter(|r| r[0] >= 0.2).fold(None, |acc: Option<(f64, f64)>, r| {
                let (lo, hi) = (r[2].min(r[4] - SIGMAS * r[5]) * deg, r[3].max(r[4] + SIGMAS * r[5]) * deg);
                Some(acc.map_or((lo, hi), |(a, b)| (a.min(lo), b.max(hi))))
            });
        }
        grid.add(c);
    }
    let mut c = Chart::new("Widths", "time t [s]", "width [°]");
    c.width = 900;
    c.add(Series::line("certified interval (smf-nl)", t.clone(), col(&|r| (r[3] - r[2]) * deg), PALETTE[2]));
    c.add(Series::line("certified interval (czf-nl)", t.clone(), col(&|r| (r[7] - r[6]) * deg), PALETTE[3]));
    c.add(Series::line("EKF ±3σ band (6σ_β)", t, col(&|r| 2.0 * SIGMAS * r[5] * deg), PALETTE[1]));
    c.y_range = rows.iter().filter(|r| r[0] >= 0.2).fold(None, |acc: Option<(f64, f64)>, r| {
        let hi = ((r[3] - r[2]).max(2.0 * SIGMAS * r[5]) * deg) * 1.1;
        Some(acc.map_or((0.0, hi), |(_, b)| (0.0, b.max(hi))))
    });
    grid.add(c);
    let file = "certified_beta.svg".to_owned();
    grid.write(&dir.join(&file))?;
    Ok((
        file,
        "Certified β intervals of smf-nl and czf-nl beside the EKF's ±3σ band, bounded noise on the boundary (first \
         seed)"
            .into(),
    ))
}

/// The report's section.
#[must_use]
pub fn markdown(c: &CertifiedSummary) -> String {
    let mc = &c.monte_carlo;
    let mut md = String::from("## Certified sideslip (smf-nl, bounded noise)\n\n");
    let _ = writeln!(
        md,
        "Not the paper's experiment: the nonlinear set-membership filter `smf-nl` (docs/nonlinear-smf.md; the \
         truck's enclosures by interval forward-mode AD, mean-value remainder because the slip ratio has a kink at \
         free rolling) on the same slalom. The truth is the filter's own model (Euler at 1 ms, static loads) driven \
         by the nominal truth's δ and wheel speeds — the guarantee covers the model, not the richer simulation — \
         with bounded noise: {}. The certified β interval is atan([V_y]/[V_x]) over the published set's bounding \
         box, in interval arithmetic; the EKF (digest settings) runs on the same data.\n",
        c.noise
    );
    let _ = writeln!(
        md,
        "| quantity | value |\n|---|---|\n\
         | certified steps (figure run) | {} |\n\
         | truth outside the published ellipsoid | **{}** (largest distance {}) |\n\
         | truth β outside the certified interval | **{}** |\n\
         | median / largest certified β width | {}° / {}° |\n\
         | median EKF ±3σ band width (6σ_β) | {}° |\n\
         | median ratio certified / EKF width | {} |\n\
         | truth β outside the EKF's ±3σ band | {} of {} steps |\n\
         | Monte Carlo: seeds × steps, misses, GuaranteeLost | {} seeds, {} steps, **{}** misses, {} lost, {:.1} s |\n\
         | smf-nl step: median / p99 | {} µs / {} µs |\n",
        c.steps,
        c.misses,
        sig3(c.max_distance),
        c.beta_misses,
        sig3(c.median_beta_width_deg),
        sig3(c.max_beta_width_deg),
        sig3(c.median_ekf_band_width_deg),
        sig3(c.median_width_ratio),
        c.ekf_outside_band,
        c.steps,
        mc.seeds,
        mc.steps,
        mc.misses,
        mc.guarantee_lost,
        mc.seconds,
        sig3(c.timing.median_us),
        sig3(c.timing.p99_us),
    );
    let _ = writeln!(
        md,
        "The certified interval holds the β of every state of the model consistent with the data and the noise \
         bounds, whatever the noise does inside them, and is {} times as wide as the EKF's ±3σ band (median). The \
         EKF's band is a Gaussian statement: with this bounded noise of the same scale, drawn on the boundary, it \
         misses the truth in {} of {} steps ({:.1} %).\n\n![{}](figures/{})\n",
        sig3(c.median_width_ratio),
        c.ekf_outside_band,
        c.steps,
        100.0 * c.ekf_outside_band as f64 / c.steps.max(1) as f64,
        c.figure.1,
        c.figure.0
    );
    let z = &c.zonotope;
    let _ = writeln!(
        md,
        "The constrained-zonotope filter `czf-nl` (docs/constrained-zonotopes.md) on the figure run's data, with the \
         ellipsoids' bounding boxes (±3σ; the same noise lies in them): {} steps{}, **{}** steps with a state or β \
         outside its interval, certified β width {}° median, {}° largest — {} times `smf-nl`'s (median); step {} µs \
         median, {} µs p99.\n",
        z.steps,
        z.stopped.as_ref().map_or(String::new(), |s| format!(" (stopped at {s})")),
        z.misses,
        sig3(z.median_beta_width_deg),
        sig3(z.max_beta_width_deg),
        sig3(z.median_ratio_to_smf),
        sig3(z.timing.median_us),
        sig3(z.timing.p99_us),
    );
    md
}
