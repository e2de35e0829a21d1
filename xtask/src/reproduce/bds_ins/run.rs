//! The runs of the BDS/INS reproduction: the error-state truth, the BDS errors of a route, the
//! filters on identical data (`docs/bds-ins-fuzzy-kf.md` §3 "Experiments"), and per-epoch
//! accumulators over the Monte Carlo seeds.

use estimators::registry::names;
use estimators::{DataChecks, Setup};
use std::time::Instant;

use bds_ins_dynamics::{
    BdsSimulator, DiscreteInsModel, InsErrorModel, InsNoise, InsParams, Zone, idx, scenario, simulate_error_states,
};
use estimators::adaptive::ReceiverStatus;
use estimators::{AdaptiveError, AdaptiveKalmanFilter, FuzzyScaling, NoiseScaling, ScalingContext};
use models::{Xoshiro256StarStar, splitmix64};
use nalgebra::DVector;
use serde::Serialize;

/// How a filter chooses `t_k`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum Mode {
    /// `t ≡ 1`: the plain Kalman filter (the paper's KF).
    Unit,
    /// The true variance factor of the epoch's zone (a reference the paper does not have).
    Oracle,
    /// The FIS with `d_k` the horizontal innovation norm (online).
    FisOnline,
    /// The FIS with the scripted `d` (0.05 m up to 600 s, 0.5 m after).
    FisScripted,
}

/// One filter of an experiment.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Variant {
    /// Identifier (file names).
    pub id: &'static str,
    /// Label for tables and figures.
    pub label: &'static str,
    /// How `t_k` is chosen.
    pub mode: Mode,
    /// RTK status reported to the FIS after 600 s (experiment (a); the zone's own status in (b)).
    pub rtk_after: Option<u8>,
}

/// The filters of experiment (a), run on identical data.
pub const VARIANTS_A: [Variant; 6] = [
    Variant { id: names::KF, label: "KF (t ≡ 1)", mode: Mode::Unit, rtk_after: None },
    Variant { id: "fkf_scripted_float", label: "FKF, scripted d, float", mode: Mode::FisScripted, rtk_after: Some(4) },
    Variant { id: "fkf_online_float", label: "FKF, online d, float", mode: Mode::FisOnline, rtk_after: Some(4) },
    Variant {
        id: "fkf_scripted_single",
        label: "FKF, scripted d, single",
        mode: Mode::FisScripted,
        rtk_after: Some(1),
    },
    Variant { id: "fkf_online_single", label: "FKF, online d, single", mode: Mode::FisOnline, rtk_after: Some(1) },
    Variant { id: "oracle", label: "KF with the true R (reference)", mode: Mode::Oracle, rtk_after: None },
];

/// The filters of experiment (b).
pub const VARIANTS_B: [Variant; 2] = [
    Variant { id: names::KF, label: "KF (t ≡ 1)", mode: Mode::Unit, rtk_after: None },
    Variant { id: names::FKF, label: "FKF (online d)", mode: Mode::FisOnline, rtk_after: None },
];

/// The scaling of one variant: the FIS of the workspace (`FuzzyScaling::bds_ins_default`,
/// `σ0 = 0.2 m`), fed per epoch by the runner.
struct RunScaling {
    mode: Mode,
    fis: FuzzyScaling,
    /// The epoch being updated (scripted `d`, oracle).
    epoch: usize,
    /// Variance factor of the epoch's zone (oracle).
    variance_factor: f64,
}

impl NoiseScaling for RunScaling {
    fn scale(&mut self, c: &ScalingContext<'_>) -> Result<f64, AdaptiveError> {
        match self.mode {
            Mode::Unit => Ok(1.0),
            Mode::Oracle => Ok(self.variance_factor),
            Mode::FisOnline => self.fis.scale(c),
            Mode::FisScripted => {
                let distance = if self.epoch > scenario::PAPER_SWITCH_EPOCH {
                    scenario::SCRIPTED_D_AFTER
                } else {
                    scenario::SCRIPTED_D_BEFORE
                };
                self.fis.scale(&ScalingContext { distance, ..*c })
            }
        }
    }
}

/// The models: the truth's (biases exactly constant) and the filters' (a tiny bias random walk so
/// that `Q` is positive definite; the same `Φ`).
pub fn models() -> Result<(DiscreteInsModel, DiscreteInsModel), String> {
    let build = |noise| {
        InsErrorModel::new(InsParams::digest(), noise)
            .and_then(|m| m.discretize(scenario::PAPER_PERIOD))
            .map_err(|e| format!("INS error model: {e}"))
    };
    Ok((build(InsNoise::digest())?, build(InsNoise::digest_filter())?))
}

/// One filter's run: per epoch `k = 0..=N` (0: the initial estimate) the errors of the estimate
/// against the truth, its standard deviations and the scale used.
#[derive(Debug, Clone, Default)]
pub struct Trace {
    /// `δx̂ − δx` \[m\].
    pub ex: Vec<f64>,
    /// `δŷ − δy` \[m\].
    pub ey: Vec<f64>,
    /// `δψ̂ − δψ` \[rad\].
    pub epsi: Vec<f64>,
    /// `√P11` \[m\].
    pub sx: Vec<f64>,
    /// `√P22` \[m\].
    pub sy: Vec<f64>,
    /// `t_k` (1 for the plain KF; NaN at `k = 0` and on outages).
    pub scale: Vec<f64>,
    /// Nanoseconds of each filter step (update or prediction).
    pub step_ns: Vec<u64>,
}

impl Trace {
    fn push(&mut self, truth: &DVector<f64>, mean: &DVector<f64>, sd: &DVector<f64>, scale: f64) {
        self.ex.push(mean[idx::DX] - truth[idx::DX]);
        self.ey.push(mean[idx::DY] - truth[idx::DY]);
        self.epsi.push(mean[idx::DPSI] - truth[idx::DPSI]);
        self.sx.push(sd[idx::DX]);
        self.sy.push(sd[idx::DY]);
        self.scale.push(scale);
    }

    /// Horizontal error `√(e_x² + e_y²)` at epoch `k`.
    #[must_use]
    pub fn horizontal(&self, k: usize) -> f64 {
        self.ex[k].hypot(self.ey[k])
    }

    /// Number of epochs, the initial one included.
    #[must_use]
    pub fn len(&self) -> usize {
        self.ex.len()
    }

    /// Whether the trace is empty.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.ex.is_empty()
    }
}

/// The data of one seed: the truth and the BDS epochs of the route.
pub struct Data {
    /// `X_0 … X_N`.
    pub truth: Vec<DVector<f64>>,
    /// The BDS epochs `1 … N`.
    pub epochs: Vec<bds_ins_dynamics::BdsEpoch>,
}

/// The seed of the BDS stream derived from the run's seed (independent of the truth's stream).
fn bds_seed(seed: u64) -> u64 {
    let mut s = seed ^ 0xbd51_e5ee_d000_0003;
    splitmix64(&mut s)
}

/// Simulates the truth (from the digest's initial error) and the BDS errors of `zones`.
///
/// # Errors
/// A simulation error, named.
pub fn simulate(truth_model: &DiscreteInsModel, zones: Vec<Zone>, seed: u64) -> Result<Data, String> {
    let bds = BdsSimulator::new(zones, scenario::PAPER_PERIOD, bds_seed(seed)).map_err(|e| format!("BDS: {e}"))?;
    let steps = bds.len();
    let mut rng = Xoshiro256StarStar::seed_from_u64(seed);
    let truth = simulate_error_states(truth_model, &scenario::initial_error(), steps, &mut rng)
        .map_err(|e| format!("truth: {e}"))?;
    Ok(Data { truth, epochs: bds.collect() })
}

/// The status the filter is told at an epoch: the zone's, or in experiment (a) the variant's
/// status after 600 s.
fn status_of(v: &Variant, fix: &bds_ins_dynamics::BdsFix, epoch: usize) -> Result<ReceiverStatus, String> {
    let rtk = match v.rtk_after {
        Some(code) if epoch > scenario::PAPER_SWITCH_EPOCH => code,
        _ => fix.rtk.code(),
    };
    ReceiverStatus::new(f64::from(fix.satellites), f64::from(rtk)).map_err(|e| format!("receiver status: {e}"))
}

/// Runs one variant over one seed's data. `variance_factor(k)` is the true noise factor of epoch
/// `k` (for the oracle).
///
/// # Errors
/// A rejected filter step, naming the variant and epoch.
pub fn run_filter(
    v: &Variant,
    model: &DiscreteInsModel,
    data: &Data,
    variance_factor: &dyn Fn(usize) -> f64,
) -> Result<Trace, String> {
    let scaling = RunScaling { mode: v.mode, fis: FuzzyScaling::bds_ins_default(), epoch: 0, variance_factor: 1.0 };
    let mut f = AdaptiveKalmanFilter::new(
        Setup {
            x0: DVector::zeros(bds_ins_dynamics::STATES),
            p0: scenario::initial_covariance(),
            process_noise: model.q.clone(),
            measurement_noise: scenario::nominal_r(),
            inputs: 0,
        },
        scaling,
    )
    .map_err(|e| format!("{}: {e}", v.id))?;
    // The paper's filters have no innovation gate.
    f.set_data_checks(DataChecks::OFF).map_err(|e| format!("{}: {e}", v.id))?;
    let n = data.epochs.len();
    let mut trace = Trace {
        ex: Vec::with_capacity(n + 1),
        ey: Vec::with_capacity(n + 1),
        epsi: Vec::with_capacity(n + 1),
        sx: Vec::with_capacity(n + 1),
        sy: Vec::with_capacity(n + 1),
        scale: Vec::with_capacity(n + 1),
        step_ns: Vec::with_capacity(n),
    };
    let e = f.estimate();
    trace.push(&data.truth[0], &e.center, &e.std_dev, f64::NAN);
    let u = DVector::zeros(0);
    let mut y = DVector::zeros(3);
    for epoch in &data.epochs {
        let k = epoch.k;
        let scale = match &epoch.fix {
            Some(fix) => {
                // z = INS − BDS = H X_k − e_BDS (13).
                let x = &data.truth[k];
                y[0] = x[idx::DX] - fix.error[0];
                y[1] = x[idx::DY] - fix.error[1];
                y[2] = bds_ins_dynamics::wrap_angle(x[idx::DPSI] - fix.error[2]);
                let status = status_of(v, fix, k)?;
                let s = f.scaling_mut();
                s.epoch = k;
                s.variance_factor = variance_factor(k);
                let t0 = Instant::now();
                let step = f.step_with_status(model, &u, &y, &status);
                trace.step_ns.push(t0.elapsed().as_nanos() as u64);
                step.map_err(|e| format!("{} at epoch {k}: {e}", v.id))?.scale
            }
            None => {
                let t0 = Instant::now();
                let step = f.predict(model, &u);
                trace.step_ns.push(t0.elapsed().as_nanos() as u64);
                step.map_err(|e| format!("{} (prediction) at epoch {k}: {e}", v.id))?;
                f64::NAN
            }
        };
        let e = f.estimate();
        trace.push(&data.truth[k], &e.center, &e.std_dev, scale);
    }
    Ok(trace)
}

/// Sums over the seeds, per epoch, of one variant's errors, and the first seed's trace.
#[derive(Debug, Clone, Default)]
pub struct Accumulator {
    /// Seeds added.
    pub runs: usize,
    /// `Σ √(e_x² + e_y²)` per epoch.
    pub sum_h: Vec<f64>,
    /// `Σ e_x²`.
    pub sum_ex2: Vec<f64>,
    /// `Σ e_y²`.
    pub sum_ey2: Vec<f64>,
    /// `Σ e_ψ²`.
    pub sum_epsi2: Vec<f64>,
    /// `Σ √P11`.
    pub sum_sx: Vec<f64>,
    /// `Σ √P22`.
    pub sum_sy: Vec<f64>,
    /// `Σ t_k` and the number of updates per epoch.
    pub sum_scale: Vec<f64>,
    /// Number of updates (not outages) per epoch.
    pub updates: Vec<usize>,
    /// `Σ |e_k − e_{k−1}|²` (horizontal; 0 at `k = 0`).
    pub sum_dh2: Vec<f64>,
    /// The first seed's trace.
    pub first: Option<Trace>,
    /// Step wall times of all seeds \[ns\].
    pub step_ns: Vec<u64>,
}

impl Accumulator {
    /// Adds one seed's trace.
    pub fn add(&mut self, t: Trace) {
        let n = t.len();
        if self.sum_h.is_empty() {
            for v in [
                &mut self.sum_h,
                &mut self.sum_ex2,
                &mut self.sum_ey2,
                &mut self.sum_epsi2,
                &mut self.sum_sx,
                &mut self.sum_sy,
                &mut self.sum_scale,
                &mut self.sum_dh2,
            ] {
                *v = vec![0.0; n];
            }
            self.updates = vec![0; n];
        }
        for k in 0..n.min(self.sum_h.len()) {
            self.sum_h[k] += t.horizontal(k);
            self.sum_ex2[k] += t.ex[k] * t.ex[k];
            self.sum_ey2[k] += t.ey[k] * t.ey[k];
            self.sum_epsi2[k] += t.epsi[k] * t.epsi[k];
            self.sum_sx[k] += t.sx[k];
            self.sum_sy[k] += t.sy[k];
            if t.scale[k].is_finite() {
                self.sum_scale[k] += t.scale[k];
                self.updates[k] += 1;
            }
            if k > 0 {
                self.sum_dh2[k] += (t.ex[k] - t.ex[k - 1]).powi(2) + (t.ey[k] - t.ey[k - 1]).powi(2);
            }
        }
        self.runs += 1;
        self.step_ns.extend_from_slice(&t.step_ns);
        if self.first.is_none() {
            self.first = Some(t);
        }
    }

    /// Statistics pooled over the seeds and the epochs `from..=to`.
    #[must_use]
    pub fn window(&self, from: usize, to: usize) -> WindowStats {
        let to = to.min(self.sum_h.len().saturating_sub(1));
        let count = ((to + 1).saturating_sub(from) * self.runs).max(1) as f64;
        let sum = |v: &[f64]| v[from..=to].iter().sum::<f64>();
        let updates: usize = self.updates[from..=to].iter().sum();
        let rms_ex = (sum(&self.sum_ex2) / count).sqrt();
        let rms_ey = (sum(&self.sum_ey2) / count).sqrt();
        let mean_sx = sum(&self.sum_sx) / count;
        let mean_sy = sum(&self.sum_sy) / count;
        WindowStats {
            mean_horizontal: sum(&self.sum_h) / count,
            rms_ex,
            rms_ey,
            rms_epsi_deg: (sum(&self.sum_epsi2) / count).sqrt().to_degrees(),
            mean_sigma_x: mean_sx,
            mean_sigma_y: mean_sy,
            consistency_x: rms_ex / mean_sx,
            consistency_y: rms_ey / mean_sy,
            mean_scale: if updates > 0 { sum(&self.sum_scale) / updates as f64 } else { f64::NAN },
            rms_step_change: (sum(&self.sum_dh2) / count).sqrt(),
        }
    }

    /// Per epoch over the seeds: RMS of `e_x` and of `e_y`, mean `√P11`, `√P22`, mean `t_k`.
    #[must_use]
    pub fn per_epoch(&self) -> PerEpoch {
        let r = self.runs.max(1) as f64;
        PerEpoch {
            rms_ex: self.sum_ex2.iter().map(|s| (s / r).sqrt()).collect(),
            rms_ey: self.sum_ey2.iter().map(|s| (s / r).sqrt()).collect(),
            mean_sx: self.sum_sx.iter().map(|s| s / r).collect(),
            mean_sy: self.sum_sy.iter().map(|s| s / r).collect(),
            mean_scale: self
                .sum_scale
                .iter()
                .zip(&self.updates)
                .map(|(s, &u)| if u > 0 { s / u as f64 } else { f64::NAN })
                .collect(),
        }
    }
}

/// Per-epoch Monte Carlo statistics of one variant.
#[derive(Debug, Clone)]
pub struct PerEpoch {
    /// RMS over seeds of `e_x` \[m\].
    pub rms_ex: Vec<f64>,
    /// RMS over seeds of `e_y` \[m\].
    pub rms_ey: Vec<f64>,
    /// Mean over seeds of `√P11` \[m\].
    pub mean_sx: Vec<f64>,
    /// Mean over seeds of `√P22` \[m\].
    pub mean_sy: Vec<f64>,
    /// Mean over seeds of `t_k`.
    pub mean_scale: Vec<f64>,
}

/// Accuracy and consistency over a window, pooled over seeds and epochs.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct WindowStats {
    /// Mean horizontal error `mean √(e_x² + e_y²)` \[m\].
    pub mean_horizontal: f64,
    /// `RMS(e_x)` \[m\].
    pub rms_ex: f64,
    /// `RMS(e_y)` \[m\].
    pub rms_ey: f64,
    /// `RMS(e_ψ)` \[°\].
    pub rms_epsi_deg: f64,
    /// Mean `√P11` \[m\].
    pub mean_sigma_x: f64,
    /// Mean `√P22` \[m\].
    pub mean_sigma_y: f64,
    /// `RMS(e_x) / mean √P11` (1: consistent; above 1: overconfident).
    pub consistency_x: f64,
    /// `RMS(e_y) / mean √P22`.
    pub consistency_y: f64,
    /// Mean `t_k` over the updates.
    pub mean_scale: f64,
    /// `RMS |e_k − e_{k−1}|` (horizontal): how much the corrected position jitters \[m\].
    pub rms_step_change: f64,
}
