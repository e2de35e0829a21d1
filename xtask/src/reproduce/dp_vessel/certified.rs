//! Certified position and heading: the nonlinear set-membership filter `smf-nl`
//! (docs/nonlinear-smf.md, Lagrange remainder with the vessel's Hessians) on the paper's Euler
//! model (16)–(20), beside the EKF on the same data, with a Monte Carlo count of the steps whose
//! truth leaves the published set.
//!
//! Not the paper's experiment. The truth is the filter's own model (what the guarantee covers),
//! driven open loop by smooth thrusts (`τ_i = τ̂_i sin(t/(5 + i))`, `τ̂ = (2e5 N, 5e4 N, 1e6 N m)`),
//! with every noise on the boundary of its ellipsoid: `w ∈ 𝓔(0, diag(1e−2, 1e−2, 1e−4, 1e−4,
//! 1e−4, 1e−6))`, `v ∈ 𝓔(0, diag(1 m², 1 m², 1e−2 rad²))`, `x0` on the boundary of
//! `𝓔(0, diag(4, 4, 1e−2, 1e−2, 1e−2, 1e−4))`. The certified intervals of `x`, `y`, `ψ` are the
//! published set's bounding box (N1). The EKF (first seed, for the figure) takes each shape as
//! nine covariances (its ±3σ box is the ellipsoid's box, as on the truck). The filter is told the
//! vessel's speed limits as state bounds (N1'); the same filter without them runs on the same
//! data to show why they matter. The constrained-zonotope filter `czf-nl`
//! (docs/constrained-zonotopes.md) runs beside them on the first seeds, on the ellipsoids' bounding
//! boxes (a weaker assumption: the same noise lies in them) and the same speed limits.

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
use vessel_dynamics::{DiscreteVessel, VesselParams};

use super::outputs::WriteFigure as _;
use crate::reproduce::runner::{bounding_boxes, median};

/// Seeds and steps per seed of the full run and of `--quick`.
const SIZES: [(usize, usize); 2] = [(20, 5000), (2, 1000)];

/// Seeds (the first ones) on which `czf-nl` runs beside `smf-nl`, full and `--quick` (a step costs
/// about 100 times `smf-nl`'s).
const ZONOTOPE_SEEDS: [usize; 2] = [4, 1];

/// The speed limits declared to the filter as state bounds (N1'): `|u|, |v| ≤ 2 m/s`,
/// `|r| ≤ 0.1 rad/s` — generous for a 76 m supply vessel holding station (the truth here stays
/// below 0.4 m/s and 0.01 rad/s; the run counts any step beyond them).
pub const SPEED_LIMITS: [f64; 3] = [2.0, 2.0, 0.1];

/// The certified vessel scenario in `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct CertifiedVessel {
    /// Seeds (`seed + 2000 + i`).
    pub seeds: usize,
    /// Certified steps taken.
    pub steps: usize,
    /// Steps whose truth is outside the published ellipsoid or a box interval (must be 0).
    pub misses: usize,
    /// Runs stopped by `GuaranteeLost`.
    pub guarantee_lost: usize,
    /// Steps whose true velocities exceed [`SPEED_LIMITS`] (must be 0: the guarantee assumes them).
    pub truth_beyond_speed_limits: usize,
    /// Median width of the certified `x` interval over every step \[m\].
    pub median_x_width_m: f64,
    /// Median width of the certified `y` interval \[m\].
    pub median_y_width_m: f64,
    /// Median width of the certified `ψ` interval \[°\].
    pub median_psi_width_deg: f64,
    /// Median `x` width over the first fifth of every run's steps and over the last fifth \[m\]:
    /// whether the sets grow with the horizon.
    pub x_width_first_last_fifth_m: (f64, f64),
    /// The same for `ψ` \[°\].
    pub psi_width_first_last_fifth_deg: (f64, f64),
    /// The same filter without the speed limits, on the same data.
    pub without_limits: Growth,
    /// `czf-nl` on the first seeds' data.
    pub zonotope: ZonotopeVessel,
    /// Median width of the EKF's ±3σ band of `x` \[m\] and `ψ` \[°\] (first seed).
    pub ekf_band_width: (f64, f64),
    /// Steps where the EKF's ±3σ band of `x`, `y` or `ψ` misses the truth, of the first seed's.
    pub ekf_band_misses: (usize, usize),
    /// The figure `(file, caption)`.
    pub figure: (String, String),
    /// Wall-clock seconds.
    pub seconds: f64,
}

/// `czf-nl` on the bounding boxes of the same ellipsoids, with the speed limits.
#[derive(Debug, Clone, Serialize)]
pub struct ZonotopeVessel {
    /// Seeds (the first of the Monte Carlo's).
    pub seeds: usize,
    /// Steps taken.
    pub steps: usize,
    /// Steps with `x`, `y`, `ψ`, `u`, `v` or `r` outside its published interval (must be 0).
    pub misses: usize,
    /// Runs stopped by an error (`GuaranteeLost`, a refused measurement): must be 0.
    pub stopped: usize,
    /// Steps marked diverging.
    pub diverging_steps: usize,
    /// Median width of the certified `x`, `y` interval \[m\] and of `ψ` \[°\].
    pub median_widths: (f64, f64, f64),
    /// Median `x` width over the first and the last fifth of the steps \[m\].
    pub x_width_first_last_fifth_m: (f64, f64),
    /// The same for `ψ` \[°\].
    pub psi_width_first_last_fifth_deg: (f64, f64),
    /// Median width of `smf-nl`'s `x` interval over the same seeds \[m\] (the ratio's other side).
    pub smf_median_x_width_m: f64,
}

/// The widths of the filter without state bounds.
#[derive(Debug, Clone, Serialize)]
pub struct Growth {
    /// Certified steps taken.
    pub steps: usize,
    /// Steps whose truth is outside the published set (must be 0).
    pub misses: usize,
    /// Median `x` width over the first and the last fifth of the steps \[m\].
    pub x_width_first_last_fifth_m: (f64, f64),
    /// The same for `ψ` \[°\].
    pub psi_width_first_last_fifth_deg: (f64, f64),
    /// Median width of the velocity `u` over the last fifth \[m/s\].
    pub u_width_last_fifth: f64,
}

fn diag(v: &[f64]) -> DMatrix<f64> {
    DMatrix::from_diagonal(&DVector::from_column_slice(v))
}

/// One step of the figure run: `t`, then per coordinate (`x`, `y`, `ψ`) the certified interval
/// and the EKF's band `[x̂ − 3σ, x̂ + 3σ]`, both relative to the truth; then per coordinate
/// `czf-nl`'s interval relative to the truth.
type Row = [f64; 19];

/// What one Monte Carlo run counts.
#[derive(Default)]
struct Tally {
    steps: usize,
    misses: usize,
    lost: usize,
    beyond_limits: usize,
    /// Widths of `x`, `y`, `ψ`, `u` at every step.
    widths: [Vec<f64>; 4],
    /// Widths of `x`, `ψ`, `u` over the first (0) and the last (1) fifth of the steps.
    ends: [[Vec<f64>; 2]; 3],
    /// `czf-nl`'s counts (first seeds only).
    zonotope: ZonotopeTally,
}

/// What `czf-nl` counts.
#[derive(Default)]
struct ZonotopeTally {
    seeds: usize,
    steps: usize,
    misses: usize,
    stopped: usize,
    diverging: usize,
    /// Widths of `x`, `y`, `ψ`, and `smf-nl`'s `x` on the same steps.
    widths: [Vec<f64>; 4],
    /// Widths of `x`, `ψ` over the first and the last fifth.
    ends: [[Vec<f64>; 2]; 2],
}

/// The Monte Carlo over `seeds` × `horizon` steps, the filter bounded by `limits` (or not); the
/// EKF's figure rows of the first seed into `rows` when given.
fn monte_carlo(
    seed: u64,
    (seeds, horizon): (usize, usize),
    limits: Option<[f64; 3]>,
    zonotope_seeds: usize,
    mut rows: Option<&mut Vec<Row>>,
) -> Result<Tally, String> {
    let model = DiscreteVessel::paper(VesselParams::paper()).map_err(|e| format!("vessel: {e}"))?;
    let setup = Setup {
        x0: DVector::zeros(6),
        p0: diag(&[4.0, 4.0, 1e-2, 1e-2, 1e-2, 1e-4]),
        process_noise: diag(&[1e-2, 1e-2, 1e-4, 1e-4, 1e-4, 1e-6]),
        measurement_noise: diag(&[1.0, 1.0, 1e-2]),
        inputs: 3,
    };
    let ninth = |m: &DMatrix<f64>| m / 9.0;
    let ekf_setup = Setup {
        p0: ninth(&setup.p0),
        process_noise: ninth(&setup.process_noise),
        measurement_noise: ninth(&setup.measurement_noise),
        ..setup.clone()
    };
    let noise = |shape: &DMatrix<f64>| Noise::ellipsoid_boundary(shape.clone()).map_err(|e| format!("noise: {e}"));
    let (w, v, x0) = (noise(&setup.process_noise)?, noise(&setup.measurement_noise)?, noise(&setup.p0)?);
    // czf-nl: the bounding boxes of the same ellipsoids (half-widths √P_ii), as generator matrices.
    let boxes = bounding_boxes(&setup);
    let inf = f64::INFINITY;
    let zonotope_settings = ConstrainedZonotopeSettings {
        state_bounds: limits.map(|l| {
            (
                DVector::from_column_slice(&[-inf, -inf, -inf, -l[0], -l[1], -l[2]]),
                DVector::from_column_slice(&[inf, inf, inf, l[0], l[1], l[2]]),
            )
        }),
        ..ConstrainedZonotopeSettings::default()
    };
    let mut tally = Tally::default();
    let (mut u, mut next, mut y) = (DVector::zeros(3), DVector::zeros(6), DVector::zeros(3));
    for i in 0..seeds {
        let mut rng = Xoshiro256StarStar::seed_from_u64(seed.wrapping_add(2000 + i as u64));
        let mut x = &setup.x0 + x0.sample(&mut rng);
        let mut smf = NonlinearSetMembershipFilter::new(setup.clone()).map_err(|e| format!("smf-nl: {e}"))?;
        if let Some(l) = limits {
            let inf = f64::INFINITY;
            smf = smf
                .with_state_bounds(&[-inf, -inf, -inf, -l[0], -l[1], -l[2]], &[inf, inf, inf, l[0], l[1], l[2]])
                .map_err(|e| format!("smf-nl: {e}"))?;
        }
        let mut ekf = ExtendedKalmanFilter::new(ekf_setup.clone()).map_err(|e| format!("EKF: {e}"))?;
        let mut czf = if i < zonotope_seeds {
            tally.zonotope.seeds += 1;
            Some(
                ConstrainedZonotopeFilter::new(boxes.clone(), zonotope_settings.clone())
                    .map_err(|e| format!("czf-nl: {e}"))?,
            )
        } else {
            None
        };
        for k in 0..horizon {
            let t = k as f64 * model.ts();
            for (j, amp) in [2e5, 5e4, 1e6].into_iter().enumerate() {
                u[j] = amp * (t / (5.0 + j as f64)).sin();
            }
            model.f(&x, &u, &mut next).map_err(|e| format!("vessel truth: {e}"))?;
            x = &next + w.sample(&mut rng);
            model.h(&x, &u, &mut y).map_err(|e| format!("vessel truth: {e}"))?;
            y += v.sample(&mut rng);
            tally.beyond_limits += usize::from((0..3).any(|j| x[3 + j].abs() > SPEED_LIMITS[j]));
            let est = match smf.step(&model, &u, &y) {
                Ok(est) => est,
                Err(EstimatorError::GuaranteeLost { .. }) => {
                    tally.lost += 1;
                    break;
                }
                Err(e) => return Err(format!("smf-nl, seed {i}, step {k}: {e}")),
            };
            tally.steps += 1;
            let e = &x - &est.center;
            let d = est.shape.clone().cholesky().map_or(f64::INFINITY, |c| e.dot(&c.solve(&e)));
            tally.misses += usize::from(d.is_nan() || d > 1.0);
            let boxes: [Interval; 4] = std::array::from_fn(|j| {
                Interval::centered(est.center[j], Interval::point(est.shape[(j, j)].max(0.0)).sqrt().hi())
            });
            for (j, b) in boxes.iter().enumerate() {
                tally.misses += usize::from(!b.contains(x[j]));
                tally.widths[j].push(b.width());
            }
            let fifth = if 5 * k < horizon {
                Some(0)
            } else if 5 * k >= 4 * horizon {
                Some(1)
            } else {
                None
            };
            if let Some(end) = fifth {
                for (slot, j) in [0, 2, 3].into_iter().enumerate() {
                    tally.ends[slot][end].push(boxes[j].width());
                }
            }
            let mut zonotope_rows = [f64::NAN; 6];
            if let Some(f) = czf.as_mut() {
                let z = &mut tally.zonotope;
                match f.step(&model, &u, &y) {
                    Ok(e) => {
                        z.steps += 1;
                        z.diverging += usize::from(!e.status().is_clean());
                        let b: Vec<(f64, f64)> = (0..6).map(|j| e.bounds(j).unwrap_or((f64::NAN, f64::NAN))).collect();
                        z.misses += usize::from((0..6).any(|j| !(b[j].0 <= x[j] && x[j] <= b[j].1)));
                        for (slot, j) in [0, 1, 2].into_iter().enumerate() {
                            z.widths[slot].push(b[j].1 - b[j].0);
                            zonotope_rows[2 * slot] = b[j].0 - x[j];
                            zonotope_rows[2 * slot + 1] = b[j].1 - x[j];
                        }
                        z.widths[3].push(boxes[0].width());
                        if let Some(end) = fifth {
                            z.ends[0][end].push(b[0].1 - b[0].0);
                            z.ends[1][end].push(b[2].1 - b[2].0);
                        }
                    }
                    Err(e @ (EstimatorError::GuaranteeLost { .. } | EstimatorError::SetMissed { .. })) => {
                        eprintln!("czf-nl stopped, seed {i}, step {k}: {e}");
                        z.stopped += 1;
                        czf = None;
                    }
                    Err(e) => return Err(format!("czf-nl, seed {i}, step {k}: {e}")),
                }
            }
            if let (0, Some(rows)) = (i, rows.as_deref_mut()) {
                let e = ekf.step(&model, &u, &y).map_err(|e| format!("EKF, step {k}: {e}"))?;
                let mut row = [0.0; 19];
                row[13..].copy_from_slice(&zonotope_rows);
                row[0] = t + model.ts();
                for j in 0..3 {
                    let s = 3.0 * e.covariance[(j, j)].max(0.0).sqrt();
                    row[1 + 4 * j..5 + 4 * j].copy_from_slice(&[
                        boxes[j].lo() - x[j],
                        boxes[j].hi() - x[j],
                        e.center[j] - s - x[j],
                        e.center[j] + s - x[j],
                    ]);
                }
                rows.push(row);
            }
        }
    }
    Ok(tally)
}

/// Median of the first and the last fifth.
fn ends(v: [Vec<f64>; 2], scale: f64) -> (f64, f64) {
    let [first, last] = v;
    (median(first) * scale, median(last) * scale)
}

/// Runs the Monte Carlo count with the speed limits and without, and writes the figure into
/// `figures`.
///
/// # Errors
/// The model cannot be built, a filter error other than `GuaranteeLost`, or the figure cannot be
/// written.
pub fn run(seed: u64, quick: bool, figures: &Path) -> Result<CertifiedVessel, String> {
    let sizes = SIZES[usize::from(quick)];
    let t0 = Instant::now();
    let mut rows: Vec<Row> = Vec::new();
    let bounded = monte_carlo(seed, sizes, Some(SPEED_LIMITS), ZONOTOPE_SEEDS[usize::from(quick)], Some(&mut rows))?;
    let free = monte_carlo(seed, sizes, None, 0, None)?;
    let ekf_misses = rows.iter().filter(|r| (0..3).any(|j| r[3 + 4 * j] > 0.0 || r[4 + 4 * j] < 0.0)).count();
    let ekf_width = |j: usize| median(rows.iter().map(|r| r[4 + 4 * j] - r[3 + 4 * j]).collect());
    let figure = figure(figures, &rows, seed).map_err(|e| format!("writing the certified vessel figure: {e}"))?;
    let [wx, wy, wpsi, _] = bounded.widths;
    let [x_ends, psi_ends, _] = bounded.ends;
    let z = bounded.zonotope;
    let [zx, zy, zpsi, smf_x] = z.widths;
    let [zx_ends, zpsi_ends] = z.ends;
    let zonotope = ZonotopeVessel {
        seeds: z.seeds,
        steps: z.steps,
        misses: z.misses,
        stopped: z.stopped,
        diverging_steps: z.diverging,
        median_widths: (median(zx), median(zy), median(zpsi).to_degrees()),
        x_width_first_last_fifth_m: ends(zx_ends, 1.0),
        psi_width_first_last_fifth_deg: ends(zpsi_ends, 180.0 / std::f64::consts::PI),
        smf_median_x_width_m: median(smf_x),
    };
    let [free_x, free_psi, [_, free_u]] = free.ends;
    Ok(CertifiedVessel {
        seeds: sizes.0,
        steps: bounded.steps,
        misses: bounded.misses,
        guarantee_lost: bounded.lost,
        truth_beyond_speed_limits: bounded.beyond_limits,
        median_x_width_m: median(wx),
        median_y_width_m: median(wy),
        median_psi_width_deg: median(wpsi).to_degrees(),
        x_width_first_last_fifth_m: ends(x_ends, 1.0),
        psi_width_first_last_fifth_deg: ends(psi_ends, 180.0 / std::f64::consts::PI),
        without_limits: Growth {
            steps: free.steps,
            misses: free.misses,
            x_width_first_last_fifth_m: ends(free_x, 1.0),
            psi_width_first_last_fifth_deg: ends(free_psi, 180.0 / std::f64::consts::PI),
            u_width_last_fifth: median(free_u),
        },
        zonotope,
        ekf_band_width: (ekf_width(0), ekf_width(2).to_degrees()),
        ekf_band_misses: (ekf_misses, rows.len()),
        figure,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// Per coordinate, the certified interval and the EKF's ±3σ band minus the truth (a band holds the
/// truth where it holds 0), over the first seed.
fn figure(dir: &Path, rows: &[Row], seed: u64) -> std::io::Result<(String, String)> {
    let col = |c: usize, scale: f64| rows.iter().map(|r| r[c] * scale).collect::<Vec<f64>>();
    let t = col(0, 1.0);
    let mut grid = Grid::new(1);
    grid.title = format!(
        "Supply vessel, bounded noise: certified intervals (smf-nl, czf-nl) and the EKF's ±3σ band, minus the \
         truth (seed {})",
        seed + 2000
    );
    for (j, (name, unit, scale)) in
        [("x", "m", 1.0), ("y", "m", 1.0), ("ψ", "°", 180.0 / std::f64::consts::PI)].into_iter().enumerate()
    {
        let mut c = Chart::new(format!("{name} − truth"), "time t [s]", format!("{name} − {name}_true [{unit}]"));
        c.width = 900;
        let base = 1 + 4 * j;
        c.add(Series::band("EKF ±3σ band", t.clone(), col(base + 2, scale), col(base + 3, scale), PALETTE[1]));
        c.add(Series::band(
            "certified interval (smf-nl)",
            t.clone(),
            col(base, scale),
            col(base + 1, scale),
            PALETTE[2],
        ));
        let zb = 13 + 2 * j;
        c.add(Series::band("certified interval (czf-nl)", t.clone(), col(zb, scale), col(zb + 1, scale), PALETTE[3]));
        c.add(Series::line("truth", t.clone(), vec![0.0; t.len()], PALETTE[0]));
        grid.add(c);
    }
    let file = "certified_vessel.svg".to_owned();
    grid.write(&dir.join(&file))?;
    Ok((
        file,
        "Certified x, y, ψ intervals of smf-nl and czf-nl beside the EKF's ±3σ band, minus the truth (first seed)"
            .into(),
    ))
}

/// The report's section.
#[must_use]
pub fn markdown(c: &CertifiedVessel) -> String {
    let mut md = String::from("## Certified position and heading (smf-nl, bounded noise)\n\n");
    let (x_first, x_last) = c.x_width_first_last_fifth_m;
    let (psi_first, psi_last) = c.psi_width_first_last_fifth_deg;
    let g = &c.without_limits;
    let trend = |first: f64, last: f64| {
        if last > 1.5 * first {
            "grow with the horizon"
        } else if last < first / 1.5 {
            "contract over the horizon"
        } else {
            "stay of one size over the horizon"
        }
    };
    let _ = writeln!(
        md,
        "Not the paper's experiment: the nonlinear set-membership filter `smf-nl` on the Euler model (16)–(20) \
         (Lagrange remainder: the vessel encloses its Hessians). The truth is the filter's own model driven open \
         loop by smooth thrusts, every noise on the boundary of its ellipsoid (w: diag(1e−2, 1e−2, 1e−4, 1e−4, \
         1e−4, 1e−6), v: diag(1 m², 1 m², 1e−2 rad²)); the certified intervals of x, y, ψ are the published set's \
         bounding box. The filter is told the vessel's speed limits as state bounds (N1'): |u|, |v| ≤ {} m/s, \
         |r| ≤ {} rad/s. The EKF beside it (first seed) takes each shape as nine covariances, so that its ±3σ box \
         is the ellipsoid's box.\n\n\
         | quantity | value |\n|---|---|\n\
         | seeds × steps | {} seeds, {} steps |\n\
         | truth outside the published ellipsoid or a box interval | **{}** |\n\
         | steps whose true velocities exceed the speed limits | {} |\n\
         | runs stopped by GuaranteeLost | {} |\n\
         | median certified width of x / y / ψ | {:.3} m / {:.3} m / {:.3}° |\n\
         | median certified x width, first / last fifth of the steps | {:.3} m / {:.3} m |\n\
         | median certified ψ width, first / last fifth of the steps | {:.3}° / {:.3}° |\n\
         | without the speed limits: misses; x width first / last fifth | **{}** of {} steps; {:.3} m / {:.3} m |\n\
         | without the speed limits: ψ width first / last fifth; u width, last fifth | {:.3}° / {:.3}°; {:.3} m/s |\n\
         | median EKF ±3σ band width of x / ψ (first seed) | {:.3} m / {:.3}° |\n\
         | steps where the EKF's band misses x, y or ψ (first seed) | {} of {} |\n\
         | wall time (both Monte Carlo runs) | {:.1} s |\n\n\
         With the speed limits the sets {} (x: {x_first:.2} m → {x_last:.2} m, with ±1 m position noise); the \
         certified intervals are {:.1} times as wide as the EKF's ±3σ band in x. Without them the sets {} (x: \
         {:.2} m → {:.2} m): the velocities are not measured, so the set's velocity interval is wide (the linear \
         filter on the vessel linearised at rest already holds ±4 m/s); the kinematics' remainder grows with \
         (velocity width) × (heading width), enters the position's process noise, makes the velocity less \
         observable, and so on — a loop whose gain rises at oblique headings, where both velocities feed both \
         positions (docs/nonlinear-smf.md, \"The vessel\"). Declared speed limits cut the loop; they are an \
         assumption of the guarantee like the noise bounds.\n\n![{}](figures/{})\n",
        SPEED_LIMITS[0],
        SPEED_LIMITS[2],
        c.seeds,
        c.steps,
        c.misses,
        c.truth_beyond_speed_limits,
        c.guarantee_lost,
        c.median_x_width_m,
        c.median_y_width_m,
        c.median_psi_width_deg,
        x_first,
        x_last,
        psi_first,
        psi_last,
        g.misses,
        g.steps,
        g.x_width_first_last_fifth_m.0,
        g.x_width_first_last_fifth_m.1,
        g.psi_width_first_last_fifth_deg.0,
        g.psi_width_first_last_fifth_deg.1,
        g.u_width_last_fifth,
        c.ekf_band_width.0,
        c.ekf_band_width.1,
        c.ekf_band_misses.0,
        c.ekf_band_misses.1,
        c.seconds,
        trend(x_first, x_last),
        c.median_x_width_m / c.ekf_band_width.0,
        trend(g.x_width_first_last_fifth_m.0, g.x_width_first_last_fifth_m.1),
        g.x_width_first_last_fifth_m.0,
        g.x_width_first_last_fifth_m.1,
        c.figure.1,
        c.figure.0
    );
    let z = &c.zonotope;
    let _ = writeln!(
        md,
        "\n### The constrained-zonotope filter beside it\n\n\
         `czf-nl` (docs/constrained-zonotopes.md) on the first {} seeds' data, with the ellipsoids' bounding boxes \
         (half-widths √P_ii: a weaker assumption, the same noise lies in them) and the same speed limits.\n\n\
         | quantity | value |\n|---|---|\n\
         | steps | {} |\n\
         | truth outside a published interval (any state) | **{}** |\n\
         | runs stopped (GuaranteeLost or a refused measurement) | {} |\n\
         | steps marked diverging (an unmeasured velocity's interval spans its declared limit) | {} |\n\
         | median certified width of x / y / ψ | {:.3} m / {:.3} m / {:.3}° |\n\
         | `smf-nl`'s median x width on the same steps | {:.3} m |\n\
         | median x width, first / last fifth of the steps | {:.3} m / {:.3} m |\n\
         | median ψ width, first / last fifth of the steps | {:.3}° / {:.3}° |\n",
        z.seeds,
        z.steps,
        z.misses,
        z.stopped,
        z.diverging_steps,
        z.median_widths.0,
        z.median_widths.1,
        z.median_widths.2,
        z.smf_median_x_width_m,
        z.x_width_first_last_fifth_m.0,
        z.x_width_first_last_fifth_m.1,
        z.psi_width_first_last_fifth_deg.0,
        z.psi_width_first_last_fifth_deg.1,
    );
    md
}
