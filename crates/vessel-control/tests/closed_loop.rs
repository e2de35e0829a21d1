//! The closed loop on the noise-free vessel: with an exact model-based observer the NSAMPC
//! brings the vessel to (50 m, 50 m, 0°) and holds it there, the thrust never leaves its
//! limits, and bad settings are typed errors.

use estimators::{Dims, Estimate, EstimateKind, Estimator, EstimatorError, SolveOutcome, StepDetails, StepStatus};
use models::{DiscreteModel, ModelError, Noise};
use nalgebra::{DMatrix, DVector, Vector3};
use vessel_control::{
    ClosedLoopError, Controller, LoopConfig, LoopRecord, Nsampc, NsampcParams, ReferenceFilter, SetPoint,
    VesselController, run_closed_loop,
};
use vessel_dynamics::{DiscreteVessel, ThrustLimits, VesselParams};

/// Open-loop prediction with the plant's own model: exact when there is no noise. A point
/// estimate whose every step is a prediction.
struct Predictor {
    est: Predicted,
    next: DVector<f64>,
}

struct Predicted {
    x: DVector<f64>,
    weight: DMatrix<f64>,
}

impl Estimate for Predicted {
    fn kind(&self) -> EstimateKind {
        EstimateKind::Point
    }
    fn center(&self) -> &DVector<f64> {
        &self.x
    }
    fn shape(&self) -> &DMatrix<f64> {
        &self.weight
    }
    fn status(&self) -> StepStatus {
        StepStatus::unchecked(SolveOutcome::Predicted)
    }
    fn details(&self) -> StepDetails {
        StepDetails::NONE
    }
}

impl Predictor {
    fn new(n: usize) -> Self {
        Self { est: Predicted { x: DVector::zeros(n), weight: DMatrix::identity(n, n) }, next: DVector::zeros(n) }
    }
}

impl Estimator<DiscreteVessel> for Predictor {
    type Estimate = Predicted;
    fn step(
        &mut self,
        model: &DiscreteVessel,
        u: &DVector<f64>,
        _y: &DVector<f64>,
    ) -> Result<&Predicted, EstimatorError> {
        self.predict(model, u)
    }
    fn predict(&mut self, model: &DiscreteVessel, u: &DVector<f64>) -> Result<&Predicted, EstimatorError> {
        model.f(&self.est.x, u, &mut self.next)?;
        std::mem::swap(&mut self.est.x, &mut self.next);
        Ok(&self.est)
    }
    fn update(&mut self, _model: &DiscreteVessel, _y: &DVector<f64>) -> Result<&Predicted, EstimatorError> {
        Ok(&self.est)
    }
    fn estimate(&self) -> &Predicted {
        &self.est
    }
    fn dims(&self) -> Dims {
        Dims::new(self.est.x.len(), 3, 3)
    }
    fn set_data_checks(&mut self, _checks: estimators::DataChecks) -> Result<(), EstimatorError> {
        Ok(())
    }
}

fn config(steps: usize) -> LoopConfig {
    LoopConfig {
        x0: DVector::zeros(6),
        steps,
        ts: 0.1,
        input_noise: Noise::none(3),
        process_noise: Noise::none(6),
        measurement_noise: Noise::none(3),
        seed: 1,
    }
}

fn run(filtered: bool, steps: usize) -> LoopRecord {
    let plant = DiscreteVessel::paper(VesselParams::paper()).unwrap();
    let mut obs = Predictor::new(6);
    let target = Vector3::new(50.0, 50.0, 0.0);
    let set_point = if filtered {
        SetPoint::filtered(target, ReferenceFilter::new(0.07, 0.1, Vector3::zeros()).unwrap()).unwrap()
    } else {
        SetPoint::step(target).unwrap()
    };
    let mut ctrl =
        VesselController::new(Nsampc::new(&VesselParams::paper(), NsampcParams::paper()).unwrap(), set_point);
    run_closed_loop(&plant, &plant, &mut obs, &mut ctrl, &config(steps)).unwrap()
}

fn check_limits(rec: &LoopRecord) -> f64 {
    let lim = ThrustLimits::paper().max;
    let mut sat = 0usize;
    for k in 0..rec.steps {
        for i in 0..3 {
            assert!(rec.input(k)[i].abs() <= lim[i], "step {k}, input {i}: {}", rec.input(k)[i]);
        }
    }
    sat += rec.saturated.iter().filter(|s| **s).count();
    sat as f64 / rec.saturated.len() as f64
}

#[test]
fn reaches_and_holds_the_set_point_through_the_reference_filter() {
    let rec = run(true, 3000);
    check_limits(&rec);
    // The estimate is the state (noise-free, exact model).
    assert_eq!(rec.state(3000), rec.estimate(3000));
    let x = rec.state(3000);
    assert!((x[0] - 50.0).abs() < 0.05 && (x[1] - 50.0).abs() < 0.05 && x[2].abs() < 1e-4, "{x:?}");
    // The filter's reference is slow enough to follow without overshooting the target by > 1 m.
    let peak = (0..=3000).map(|k| rec.state(k)[1]).fold(f64::MIN, f64::max);
    assert!(peak < 51.0, "sway peak {peak}");
    assert_eq!(rec.reference(0).unwrap(), &[0.0, 0.0, 0.0]);
}

#[test]
fn literal_step_saturates_but_converges() {
    let rec = run(false, 5000);
    let fraction = check_limits(&rec);
    assert!(fraction > 0.01, "the raw step must saturate the thrusters ({fraction})");
    let x = rec.state(5000);
    assert!((x[0] - 50.0).abs() < 0.1 && (x[1] - 50.0).abs() < 0.1 && x[2].abs() < 1e-3, "{x:?}");
}

struct Lazy;
impl Controller for Lazy {
    type Error = ModelError;
    fn input_dim(&self) -> usize {
        3
    }
    fn control(&mut self, _k: usize, _x: &DVector<f64>, u: &mut DVector<f64>) -> Result<(), ModelError> {
        u.fill(2e6);
        Ok(())
    }
    fn input_limits(&self) -> Option<&[f64]> {
        const LIMITS: [f64; 3] = [1e6, 3e5, 7.62e6];
        Some(&LIMITS)
    }
}

#[test]
fn bad_settings_are_typed_errors() {
    let plant = DiscreteVessel::paper(VesselParams::paper()).unwrap();
    let mut obs = Predictor::new(6);
    let mut ctrl = VesselController::new(
        Nsampc::new(&VesselParams::paper(), NsampcParams::paper()).unwrap(),
        SetPoint::step(Vector3::new(50.0, 50.0, 0.0)).unwrap(),
    );
    let mut c = config(10);
    c.x0 = DVector::zeros(5);
    assert!(matches!(
        run_closed_loop(&plant, &plant, &mut obs, &mut ctrl, &c),
        Err(ClosedLoopError::DimensionMismatch { what: "x0", expected: 6, found: 5 })
    ));
    let mut c = config(10);
    c.measurement_noise = Noise::none(2);
    assert!(matches!(
        run_closed_loop(&plant, &plant, &mut obs, &mut ctrl, &c),
        Err(ClosedLoopError::DimensionMismatch { .. })
    ));
    assert!(matches!(
        run_closed_loop(&plant, &plant, &mut obs, &mut ctrl, &config(0)),
        Err(ClosedLoopError::InvalidSetting { .. })
    ));
    let mut c = config(10);
    c.x0[2] = f64::NAN;
    assert!(matches!(
        run_closed_loop(&plant, &plant, &mut obs, &mut ctrl, &c),
        Err(ClosedLoopError::InvalidSetting { .. })
    ));
    // A controller that ignores its own limits is caught.
    let e = run_closed_loop(&plant, &plant, &mut obs, &mut Lazy, &config(10)).unwrap_err();
    assert!(matches!(e, ClosedLoopError::LimitViolated { step: 0, index: 0, .. }), "{e}");
    // An observer of the wrong size.
    let mut small = Predictor::new(4);
    assert!(run_closed_loop(&plant, &plant, &mut small, &mut ctrl, &config(10)).is_err());
}

/// A seed reproduces a noisy run; another seed gives another one; the record keeps the
/// commanded thrust (the plant saw it plus the force noise).
#[test]
fn seeds_reproduce_noisy_runs() {
    let plant = DiscreteVessel::paper(VesselParams::paper()).unwrap();
    let noisy = |seed| {
        let mut obs = Predictor::new(6);
        let mut ctrl = VesselController::new(
            Nsampc::new(&VesselParams::paper(), NsampcParams::paper()).unwrap(),
            SetPoint::filtered(
                Vector3::new(50.0, 50.0, 0.0),
                ReferenceFilter::new(0.07, 0.1, Vector3::zeros()).unwrap(),
            )
            .unwrap(),
        );
        let mut c = config(300);
        c.input_noise = vessel_dynamics::ForceNoise::digest().to_noise().unwrap();
        c.measurement_noise =
            Noise::gaussian(nalgebra::DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 1.0, 0.1]))).unwrap();
        c.seed = seed;
        run_closed_loop(&plant, &plant, &mut obs, &mut ctrl, &c).unwrap()
    };
    let (a, b, c) = (noisy(5), noisy(5), noisy(6));
    assert_eq!(a.states, b.states);
    assert_eq!(a.measurements, b.measurements);
    assert_ne!(a.states, c.states);
    // The open-loop predictor does not see the force noise: its estimate drifts from the truth.
    assert!((a.estimate(300)[3] - a.state(300)[3]).abs() > 0.0);
    // The measurement noise is there: z − h(x) has roughly the variance of R.
    let var_x: f64 = (1..=300).map(|k| (a.measurement(k)[0] - a.state(k)[0]).powi(2)).sum::<f64>() / 300.0;
    assert!(var_x > 0.7 && var_x < 1.3, "{var_x}");
}
