//! The estimators compared in every scenario, built through the `estimators` registry.

use estimators::registry::TWO_MULTIPLIER;
use estimators::{LinearSetup, NoiseSettings};

use super::scenarios::Scenario;
use crate::reproduce::runner::Filter;

/// The improved set-membership filter with the exact two-multiplier solver of (29).
pub const PROPOSED: &str = "improved SMF";
/// Prefix of the improved filter solved by an SDP backend (`"improved SMF via <backend>"`).
pub const PROPOSED_VIA: &str = "improved SMF via ";
/// Suffix of the same filter with every SDP solved from the backend's default start (the SDP
/// filters warm-start each solve from the previous step's solution by default).
pub const COLD_START: &str = ", cold start";
/// Reconstruction (a) of [17]: the input is not used.
pub const YANG_LI_NO_INPUT: &str = "[17] without input";
/// Reconstruction (b) of [17]: the input in the predictor (the improved filter's update).
pub const YANG_LI_WITH_INPUT: &str = "[17] with input";
/// The Kalman filter.
pub const KALMAN: &str = "Kalman filter";

/// The scenario's initial set, noise shapes (covariances for the Kalman filter) and input box.
fn setup(sc: &Scenario) -> LinearSetup {
    let mut s = LinearSetup::new(
        sc.x_hat0.clone(),
        sc.p0.clone(),
        NoiseSettings::new(sc.q.clone(), sc.r.clone()),
        sc.steps[0].b.ncols(),
    );
    s.input_bounds = Some(sc.input_range.clone());
    s
}

/// The improved filter with the two-multiplier solver.
pub fn proposed(sc: &Scenario) -> Result<Filter, String> {
    Filter::new(PROPOSED, "smf", &setup(sc))
}

/// The Kalman filter given `Q`, `R` as covariances and `P₀` as the initial covariance.
pub fn kalman(sc: &Scenario) -> Result<Filter, String> {
    Filter::new(KALMAN, "kf", &setup(sc))
}

/// An estimator and the number of steps it runs.
pub type ScheduledFilter = (Filter, usize);

/// Every estimator of a scenario with the number of steps it runs (SDP backends may run on a
/// prefix only, to keep the reproduction short).
pub fn for_scenario(sc: &Scenario) -> Result<Vec<ScheduledFilter>, String> {
    let n = sc.len();
    let mut out: Vec<ScheduledFilter> = vec![(proposed(sc)?, n)];
    for name in lmi::backend_names() {
        let mut s = setup(sc);
        s.solver = name.to_owned();
        out.push((Filter::new(&format!("{PROPOSED_VIA}{name}"), "smf", &s)?, sc.sdp_steps.min(n)));
        if name == lmi::DEFAULT_BACKEND {
            // Side by side in one run: the same backend without the warm start.
            let mut cold = s.clone();
            cold.sdp_settings.warm_start = false;
            out.push((Filter::new(&format!("{PROPOSED_VIA}{name}{COLD_START}"), "smf", &cold)?, sc.sdp_steps.min(n)));
        }
    }
    let two = setup(sc);
    debug_assert_eq!(two.solver, TWO_MULTIPLIER);
    out.push((Filter::new(YANG_LI_NO_INPUT, "yang-li", &two)?, n));
    out.push((Filter::new(YANG_LI_WITH_INPUT, "yang-li-with-input", &two)?, n));
    out.push((kalman(sc)?, n));
    Ok(out)
}
