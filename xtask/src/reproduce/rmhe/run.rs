//! The estimator variants, the simulated double lane change and the Monte Carlo runs.

use car_dynamics::{CarModel, CarParams, NoiseBounds, double_lane_change_inputs};
use estimators::mhe::{
    BlockingPreset, InnerSolver, MheCost, MheSettings, MovingHorizonEstimator, WindowSolver, WindowStatus,
};
use estimators::{DataChecks, Setup};
use models::{ConstantModel, LinearModel, Xoshiro256StarStar};
use nalgebra::{DMatrix, DVector};
use serde::Serialize;

/// `λv` of the default map `1/(1 − α)` at the paper's `α = 0.9`.
pub const LAMBDA_DEFAULT: f64 = 10.0;
/// `λv` of the alternative map `1/α` at `α = 0.9`.
pub const LAMBDA_ALTERNATIVE: f64 = 1.0 / 0.9;

/// One estimator of the experiment.
#[derive(Debug, Clone, Serialize)]
pub struct Variant {
    /// Identifier (tables, CSV).
    pub id: &'static str,
    /// Label.
    pub label: &'static str,
    /// Blocking preset.
    #[serde(skip)]
    pub preset: BlockingPreset,
    /// Cost.
    #[serde(skip)]
    pub cost: MheCost,
    /// Window solver.
    #[serde(skip)]
    pub solver: WindowSolver,
    /// `λv` (`inf` for plain MHE).
    pub lambda_v: f64,
    /// Solver description.
    pub solver_name: &'static str,
    /// Whether `y − C x ∈ V` is imposed too (the paper's (11) literally).
    pub output_constraint: bool,
}

fn cr(inner: InnerSolver) -> WindowSolver {
    WindowSolver::CoordinateRotation { max_sweeps: 10, tolerance: 1e-8, inner }
}

/// The variants: the paper's three, the controls, and the `λv = 1/α` pair.
#[must_use]
pub fn variants() -> Vec<Variant> {
    let minmax = MheCost::MinMax { lambda_v: LAMBDA_DEFAULT };
    let alt = MheCost::MinMax { lambda_v: LAMBDA_ALTERNATIVE };
    let v = |id, label, preset, cost, solver, lambda_v, solver_name| Variant {
        id,
        label,
        preset,
        cost,
        solver,
        lambda_v,
        solver_name,
        output_constraint: false,
    };
    vec![
        v(
            "rmhe",
            "RMHE",
            BlockingPreset::Rmhe,
            minmax,
            cr(InnerSolver::ActiveSet),
            LAMBDA_DEFAULT,
            "coordinate rotation",
        ),
        v(
            "rmhe-op",
            "RMHE-OP",
            BlockingPreset::RmheOp,
            minmax,
            cr(InnerSolver::ActiveSet),
            LAMBDA_DEFAULT,
            "coordinate rotation",
        ),
        v(
            "rmhe-of",
            "RMHE-OF",
            BlockingPreset::RmheOf,
            minmax,
            cr(InnerSolver::ActiveSet),
            LAMBDA_DEFAULT,
            "coordinate rotation",
        ),
        v(
            "mhe",
            "plain MHE",
            BlockingPreset::Rmhe,
            MheCost::LeastSquares,
            WindowSolver::exact_saddle(),
            f64::INFINITY,
            "least squares (one box QP)",
        ),
        v(
            "saddle",
            "exact saddle (RMHE)",
            BlockingPreset::Rmhe,
            minmax,
            WindowSolver::exact_saddle(),
            LAMBDA_DEFAULT,
            "exact saddle",
        ),
        v(
            "rmhe-alpha",
            "RMHE, λv = 1/α",
            BlockingPreset::Rmhe,
            alt,
            cr(InnerSolver::ActiveSet),
            LAMBDA_ALTERNATIVE,
            "coordinate rotation",
        ),
        v(
            "saddle-alpha",
            "exact saddle, λv = 1/α",
            BlockingPreset::Rmhe,
            alt,
            WindowSolver::exact_saddle(),
            LAMBDA_ALTERNATIVE,
            "exact saddle",
        ),
        Variant {
            output_constraint: true,
            ..v(
                "saddle-yc",
                "exact saddle (RMHE), with y − Cx ∈ V",
                BlockingPreset::Rmhe,
                minmax,
                WindowSolver::exact_saddle(),
                LAMBDA_DEFAULT,
                "exact saddle, Clarabel QPs",
            )
        },
    ]
}

/// The variant timed with Clarabel as the minimisation step (timing table only).
#[must_use]
pub fn clarabel_variant() -> Variant {
    Variant {
        id: "rmhe-clarabel",
        label: "RMHE, Clarabel inner QP",
        preset: BlockingPreset::Rmhe,
        cost: MheCost::MinMax { lambda_v: LAMBDA_DEFAULT },
        solver: cr(InnerSolver::Clarabel),
        lambda_v: LAMBDA_DEFAULT,
        solver_name: "coordinate rotation (Clarabel)",
        output_constraint: false,
    }
}

/// Truth noise: case (a) injects `w ~ U(W)`, case (b) none.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Case {
    /// Paper-literal: `w ~ U[−0.1, 0.1]⁴` in the truth.
    A,
    /// CarSim-like: `w = 0` in the truth; `W` is only the estimator's constraint.
    B,
}

/// Estimator prior: the correct `x̄0 = x(0)` or the confidently wrong `x̄0 = 0`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Prior {
    /// `x̄0 = [−2, 0, 0, 0]`.
    Correct,
    /// `x̄0 = 0` with `P0 = 0.01 I` (2 m error, 0.1 m standard deviation).
    Wrong,
}

/// The experiment's fixed data.
#[derive(Debug, Clone)]
pub struct Experiment {
    /// The ZOH car model at `Ts = 0.5 s`.
    pub model: ConstantModel,
    /// `δ_f(k)`, `k = 0..steps`.
    pub inputs: Vec<DVector<f64>>,
    /// Steps (40: k = 0..40, 20 s).
    pub steps: usize,
    /// Sampling period \[s\].
    pub ts: f64,
}

impl Experiment {
    /// The digest's experiment.
    ///
    /// # Errors
    /// The car model cannot be built (it can: the digest's parameters are valid).
    pub fn digest() -> Result<Self, String> {
        let ts = car_dynamics::DIGEST_SAMPLING_PERIOD;
        let steps = car_dynamics::DIGEST_STEPS;
        let car = CarModel::new(CarParams::digest_default()).map_err(|e| e.to_string())?;
        let model = car.discretize(ts).map_err(|e| e.to_string())?;
        let inputs = double_lane_change_inputs(ts, steps).map_err(|e| e.to_string())?;
        Ok(Self { model, inputs, steps, ts })
    }

    /// The estimator's setup (prior, weights) and settings of `variant` with `prior`.
    #[must_use]
    pub fn settings(&self, variant: &Variant, prior: Prior) -> (Setup, MheSettings) {
        let bounds = NoiseBounds::digest();
        let w = bounds.process_vector();
        let x0 = match prior {
            Prior::Correct => DVector::from_row_slice(&car_dynamics::DIGEST_INITIAL_STATE),
            Prior::Wrong => DVector::zeros(4),
        };
        let setup = Setup {
            x0,
            p0: DMatrix::identity(4, 4) * 0.01,
            process_noise: DMatrix::identity(4, 4) * 9e-4,
            measurement_noise: DMatrix::from_element(1, 1, 0.1),
            inputs: 1,
        };
        let mut s = MheSettings::new(
            (DVector::from_fn(4, |i, _| -w[i]), DVector::from_fn(4, |i, _| w[i])),
            (DVector::from_element(1, -1.0), DVector::from_element(1, 1.0)),
        );
        // tidy: invariant — the presets accept N = 6.
        s = s.with_preset(6, variant.preset).expect("N = 6 fits every preset");
        s.cost = variant.cost;
        s.solver = variant.solver;
        s.output_constraint = variant.output_constraint;
        (setup, s)
    }

    /// Simulates the truth `x_0..x_steps` and the measurements `y_0..y_steps` of one seed.
    ///
    /// # Errors
    /// A noise model cannot be built.
    pub fn simulate(&self, case: Case, seed: u64) -> Result<Simulated, String> {
        let bounds = NoiseBounds::digest();
        let wn = bounds.process_noise().map_err(|e| e.to_string())?;
        let vn = bounds.measurement_noise().map_err(|e| e.to_string())?;
        let mut rng = Xoshiro256StarStar::seed_from_u64(seed);
        let (a, b, c) = (self.model.a(), self.model.b(), self.model.c());
        let mut x = DVector::from_row_slice(&car_dynamics::DIGEST_INITIAL_STATE);
        let mut xs = Vec::with_capacity(self.steps + 1);
        let mut ys = Vec::with_capacity(self.steps + 1);
        for k in 0..=self.steps {
            // The same draws in both cases (w drawn and discarded in case (b)).
            let v = vn.sample(&mut rng);
            ys.push(c * &x + v);
            xs.push(x.clone());
            let w = wn.sample(&mut rng);
            if k < self.steps {
                x = a * &x + b * &self.inputs[k] + if case == Case::A { w } else { DVector::zeros(4) };
            }
        }
        Ok((xs, ys))
    }
}

/// A simulated run: the truth `x_0..x_steps` and the measurements `y_0..y_steps`.
pub type Simulated = (Vec<DVector<f64>>, Vec<DVector<f64>>);

/// One estimator run over one seed.
#[derive(Debug, Clone)]
pub struct Trace {
    /// `x̂_{k|k}`, `k = 0..=steps`.
    pub estimates: Vec<DVector<f64>>,
    /// Wall time of each update \[ns\] (the initial one included).
    pub update_ns: Vec<u64>,
    /// Sweeps (coordinate rotation) or Newton iterations (exact saddle) per update.
    pub sweeps: Vec<usize>,
    /// Whether each update's window solve converged.
    pub converged: Vec<bool>,
    /// Scalar unknowns of the last update.
    pub unknowns: usize,
    /// Vector unknowns of the last update.
    pub vector_unknowns: usize,
}

/// Runs `settings` over measurements `ys` (`y_0..y_steps`).
///
/// # Errors
/// An estimator error (named).
pub fn run(exp: &Experiment, (setup, settings): (Setup, MheSettings), ys: &[DVector<f64>]) -> Result<Trace, String> {
    let mut e = MovingHorizonEstimator::new(setup, settings).map_err(|e| e.to_string())?;
    // The paper's estimator, timed as published: without the window's data check.
    e.set_data_checks(DataChecks::OFF).map_err(|e| e.to_string())?;
    let n = exp.steps + 1;
    let mut t = Trace {
        estimates: Vec::with_capacity(n),
        update_ns: Vec::with_capacity(n),
        sweeps: Vec::with_capacity(n),
        converged: Vec::with_capacity(n),
        unknowns: 0,
        vector_unknowns: 0,
    };
    let model = &exp.model;
    e.measure_initial(model, &ys[0]).map_err(|e| format!("initial measurement: {e}"))?;
    record(&e, &mut t);
    for k in 0..exp.steps {
        estimators::Estimator::step(&mut e, model, &exp.inputs[k], &ys[k + 1])
            .map_err(|err| format!("step {k}: {err}"))?;
        record(&e, &mut t);
    }
    Ok(t)
}

fn record(e: &MovingHorizonEstimator, t: &mut Trace) {
    t.estimates.push(e.estimate().center.clone());
    if let Some(r) = e.report() {
        t.update_ns.push(r.elapsed.as_nanos() as u64);
        t.sweeps.push(r.solve.sweeps);
        t.converged.push(r.solve.status == WindowStatus::Converged);
        t.unknowns = r.unknowns;
        t.vector_unknowns = r.vector_unknowns;
    }
}

/// Per-state squared errors summed over `k = 0..=steps`, divided by the sample count (the
/// digest's `MSE_i`).
#[must_use]
pub fn mse(truth: &[DVector<f64>], est: &[DVector<f64>]) -> [f64; 4] {
    let mut out = [0.0; 4];
    for (x, e) in truth.iter().zip(est) {
        for i in 0..4 {
            out[i] += (e[i] - x[i]).powi(2);
        }
    }
    out.map(|s| s / truth.len() as f64)
}
