//! The estimators compared in every scenario, behind the [`Filter`] trait of the runner.

use carrier_dynamics::StepMatrices;
use estimators::{
    KalmanFilter, SdpUpdateSolver, SetMembershipFilter, StepModel, TwoMultiplierSolver, UpdateSolver, yang_li,
};
use lmi::SolverSettings;
use nalgebra::DVector;

use super::runner::{Filter, Snapshot};
use super::scenarios::Scenario;

/// The improved set-membership filter with the exact two-multiplier solver of (29).
pub const PROPOSED: &str = "improved SMF";
/// Prefix of the improved filter solved by an SDP backend (`"improved SMF via <backend>"`).
pub const PROPOSED_VIA: &str = "improved SMF via ";
/// Reconstruction (a) of [17]: the input is not used.
pub const YANG_LI_NO_INPUT: &str = "[17] without input";
/// Reconstruction (b) of [17]: the input in the predictor (the improved filter's update).
pub const YANG_LI_WITH_INPUT: &str = "[17] with input";
/// The Kalman filter.
pub const KALMAN: &str = "Kalman filter";

struct SetFilter<S: UpdateSolver> {
    label: String,
    inner: SetMembershipFilter<S>,
}

impl<S: UpdateSolver> Filter for SetFilter<S> {
    fn label(&self) -> String {
        self.label.clone()
    }
    fn is_set(&self) -> bool {
        true
    }
    fn step(&mut self, m: &StepMatrices, u: &DVector<f64>, y: &DVector<f64>) -> Result<(), String> {
        self.inner.step(&StepModel::new(&m.a, &m.b, &m.c), u, y).map(|_| ()).map_err(|e| e.to_string())
    }
    fn current(&self) -> Snapshot {
        let e = self.inner.estimate();
        Snapshot {
            centre: e.center.clone(),
            shape: e.shape.clone(),
            tau: Some(e.report.tau),
            fallback: e.report.fallback_used(),
        }
    }
}

struct Kalman(KalmanFilter);

impl Filter for Kalman {
    fn label(&self) -> String {
        KALMAN.into()
    }
    fn is_set(&self) -> bool {
        false
    }
    fn step(&mut self, m: &StepMatrices, u: &DVector<f64>, y: &DVector<f64>) -> Result<(), String> {
        self.0.step(&StepModel::new(&m.a, &m.b, &m.c), u, y).map(|_| ()).map_err(|e| e.to_string())
    }
    fn current(&self) -> Snapshot {
        let e = self.0.estimate();
        Snapshot { centre: e.mean.clone(), shape: e.covariance.clone(), tau: None, fallback: false }
    }
}

fn inputs(sc: &Scenario) -> usize {
    sc.steps[0].b.ncols()
}

/// The improved filter with the two-multiplier solver.
pub fn proposed(sc: &Scenario) -> Result<Box<dyn Filter>, String> {
    let inner =
        SetMembershipFilter::two_multiplier(sc.x_hat0.clone(), sc.p0.clone(), sc.q.clone(), sc.r.clone(), inputs(sc))
            .map_err(|e| e.to_string())?;
    Ok(Box::new(SetFilter { label: PROPOSED.into(), inner }))
}

/// The Kalman filter given `Q`, `R` as covariances and `P₀` as the initial covariance.
pub fn kalman(sc: &Scenario) -> Result<Box<dyn Filter>, String> {
    let kf = KalmanFilter::new(sc.x_hat0.clone(), sc.p0.clone(), sc.q.clone(), sc.r.clone(), inputs(sc))
        .map_err(|e| e.to_string())?;
    Ok(Box::new(Kalman(kf)))
}

/// An estimator and the number of steps it runs.
pub type ScheduledFilter = (Box<dyn Filter>, usize);

/// Every estimator of a scenario with the number of steps it runs (SDP backends may run on a
/// prefix only, to keep the reproduction short).
pub fn for_scenario(sc: &Scenario) -> Result<Vec<ScheduledFilter>, String> {
    let e = |e: estimators::EstimatorError| e.to_string();
    let n = sc.len();
    let mut out: Vec<ScheduledFilter> = vec![(proposed(sc)?, n)];
    for name in lmi::backend_names() {
        let solver = SdpUpdateSolver::by_name(name, SolverSettings::default()).map_err(e)?;
        let inner =
            SetMembershipFilter::new(sc.x_hat0.clone(), sc.p0.clone(), sc.q.clone(), sc.r.clone(), inputs(sc), solver)
                .map_err(e)?;
        out.push((Box::new(SetFilter { label: format!("{PROPOSED_VIA}{name}"), inner }), sc.sdp_steps.min(n)));
    }
    let (lo, hi) = &sc.input_range;
    let yl_a = yang_li::without_input(
        sc.x_hat0.clone(),
        sc.p0.clone(),
        sc.q.clone(),
        sc.r.clone(),
        lo,
        hi,
        TwoMultiplierSolver::new(),
    )
    .map_err(e)?;
    out.push((Box::new(SetFilter { label: YANG_LI_NO_INPUT.into(), inner: yl_a }), n));
    let yl_b = yang_li::with_input(
        sc.x_hat0.clone(),
        sc.p0.clone(),
        sc.q.clone(),
        sc.r.clone(),
        inputs(sc),
        TwoMultiplierSolver::new(),
    )
    .map_err(e)?;
    out.push((Box::new(SetFilter { label: YANG_LI_WITH_INPUT.into(), inner: yl_b }), n));
    out.push((kalman(sc)?, n));
    Ok(out)
}
