//! The estimators compared in every scenario, built through the `estimators` registry.

use estimators::Setup;
use estimators::registry::{EstimatorSettings, InputBox, SetMembershipSettings, SmfSolver, names};

use super::scenarios::Scenario;
use crate::reproduce::runner::Filter;

/// The improved set-membership filter with the exact two-multiplier solver of (29).
pub const PROPOSED: &str = "improved SMF";
/// Prefix of the improved filter solved by an SDP backend (`"improved SMF via <backend>"`).
pub const PROPOSED_VIA: &str = "improved SMF via ";
/// Suffix of the same filter with every SDP solved from the backend's default start (the SDP
/// filters warm-start each solve from the previous step's solution by default).
pub const COLD_START: &str = ", cold start";
/// Reconstruction (a) of \[17\]: the input is not used.
pub const YANG_LI_NO_INPUT: &str = "[17] without input";
/// Reconstruction (b) of \[17\]: the input in the predictor (the improved filter's update).
pub const YANG_LI_WITH_INPUT: &str = "[17] with input";
/// The Kalman filter.
pub const KALMAN: &str = "Kalman filter";

/// The scenario's initial set and noise shapes (covariances for the Kalman filter).
fn setup(sc: &Scenario) -> Setup {
    Setup {
        x0: sc.x_hat0.clone(),
        p0: sc.p0.clone(),
        process_noise: sc.q.clone(),
        measurement_noise: sc.r.clone(),
        inputs: sc.steps[0].b.ncols(),
    }
}

/// The paper's filter with `solver`: the registry's interval observer off, so that the published
/// interval is the ellipsoid's projection, as in the paper.
fn paper(solver: SmfSolver) -> SetMembershipSettings {
    SetMembershipSettings { solver, interval_observer: false, ..SetMembershipSettings::default() }
}

/// The improved filter with the two-multiplier solver.
pub fn proposed(sc: &Scenario) -> Result<Filter, String> {
    Filter::new(PROPOSED, names::SMF, setup(sc), Some(EstimatorSettings::SetMembership(paper(SmfSolver::default()))))
}

/// The Kalman filter given `Q`, `R` as covariances and `P₀` as the initial covariance.
pub fn kalman(sc: &Scenario) -> Result<Filter, String> {
    Filter::new(KALMAN, names::KF, setup(sc), None)
}

/// An estimator and the number of steps it runs.
pub type ScheduledFilter = (Filter, usize);

/// Every estimator of a scenario with the number of steps it runs (SDP backends may run on a
/// prefix only, to keep the reproduction short).
pub fn for_scenario(sc: &Scenario) -> Result<Vec<ScheduledFilter>, String> {
    let n = sc.len();
    let mut out: Vec<ScheduledFilter> = vec![(proposed(sc)?, n)];
    let smf = |solver: SmfSolver| Some(EstimatorSettings::SetMembership(paper(solver)));
    for name in lmi::backend_names() {
        let solver = SmfSolver::by_name(name).map_err(|e| e.to_string())?;
        let label = format!("{PROPOSED_VIA}{name}");
        out.push((Filter::new(&label, names::SMF, setup(sc), smf(solver.clone()))?, sc.sdp_steps.min(n)));
        if name == lmi::DEFAULT_BACKEND
            && let SmfSolver::Sdp { backend, settings } = solver
        {
            // Side by side in one run: the same backend without the warm start.
            let cold = SmfSolver::Sdp { backend, settings: lmi::SolverSettings { warm_start: false, ..settings } };
            let label = format!("{PROPOSED_VIA}{name}{COLD_START}");
            out.push((Filter::new(&label, names::SMF, setup(sc), smf(cold))?, sc.sdp_steps.min(n)));
        }
    }
    let (lower, upper) = sc.input_range.clone();
    let boxed = EstimatorSettings::SetMembershipInputBox(paper(SmfSolver::default()), InputBox { lower, upper });
    out.push((Filter::new(YANG_LI_NO_INPUT, names::YANG_LI, setup(sc), Some(boxed))?, n));
    let with_input = EstimatorSettings::SetMembership(paper(SmfSolver::default()));
    out.push((Filter::new(YANG_LI_WITH_INPUT, names::YANG_LI_WITH_INPUT, setup(sc), Some(with_input))?, n));
    out.push((kalman(sc)?, n));
    Ok(out)
}
