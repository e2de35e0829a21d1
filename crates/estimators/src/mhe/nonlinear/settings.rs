//! Settings of [`NonlinearMhe`](super::NonlinearMhe), as data, and their validation.

use nalgebra::DVector;

use crate::error::EstimatorError;
use crate::ukf::UkfParams;

/// The most real-time iterations per update: beyond a few, iterate to the tolerance instead.
pub const MAX_REAL_TIME_ITERATIONS: usize = 10;

/// How the arrival-cost weight `P_s` advances when the window slides.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum NonlinearArrival {
    /// One unscented-Kalman update with `y_s` and prediction with `u_s` about `(x̂_{s|T}, P_s)`
    /// (the paper's, with its `α, β, κ`).
    Ukf(UkfParams),
    /// The same with the model's Jacobians (extended Kalman).
    Ekf,
    /// `P_s = P_0` always.
    Fixed,
}

/// Settings of [`NonlinearMhe`](super::NonlinearMhe) beyond its [`Setup`](crate::Setup) (prior
/// mean `x̄₀` and weight `P₀`, process and measurement weights `Q`, `R`), as data.
#[derive(Debug, Clone, PartialEq)]
pub struct NonlinearMheSettings {
    /// Horizon `N` (the window holds `N + 1` states; the paper's 10).
    pub horizon: usize,
    /// Arrival-cost update.
    pub arrival: NonlinearArrival,
    /// At most this many Gauss–Newton iterations per update (default 20).
    pub max_iterations: usize,
    /// Stop when `‖Δx‖∞ ≤ tolerance · max(1, ‖x‖∞)` (default `1e−10`).
    pub tolerance: f64,
    /// Stop earlier when the iteration contracts and the a-posteriori estimate of the distance
    /// to the converged window, `‖Δ_k‖ c/(1 − c)` with the observed rate
    /// `c = ‖Δ_k‖/‖Δ_{k−1}‖ < ½`, is at most this (relative, as `tolerance`): Gauss–Newton
    /// converges linearly on these windows, and the last iterations only polish digits no
    /// estimate needs (default `1e−9`, which keeps the vessel's estimates within `1e−8` of the
    /// fully iterated ones, tested; `None`: iterate to `tolerance`).
    pub estimate_tolerance: Option<f64>,
    /// Real-time iterations (as acados' RTI scheme): `Some(k)` spends at most `k` Gauss–Newton
    /// iterations per update, from the previous window shifted by one sample and the new state
    /// predicted through `f`, and publishes the iterate then reached with the status
    /// [`WindowStatus::RealTimeIteration`](crate::mhe::WindowStatus::RealTimeIteration) (not
    /// converged, by design); the covariance comes from the Gauss–Newton matrix at the last
    /// linearisation point instead of one more linearisation at the published window. `None`
    /// (default): iterate to `tolerance` (or `max_iterations`). At most
    /// `MAX_REAL_TIME_ITERATIONS` (10); docs/dp-vessel.md measures the distance to the converged
    /// windows.
    pub real_time_iterations: Option<usize>,
    /// The prior mean of a new window start (default: the paper's smoothed estimate).
    pub prior: NonlinearPrior,
    /// Optional box `[lo, hi]` on the disturbances `ω_j = x_{j+1} − f(x_j, u_j)` (length `n`;
    /// entries may be infinite). With a box (on `ω` or `ν`) each Gauss–Newton step is a QP with
    /// the linearised constraints, solved by Clarabel's pure-Rust QP path (allocates per update).
    pub w_box: Option<(DVector<f64>, DVector<f64>)>,
    /// Optional box on the measurement residuals `ν_j = y_j − h(x_j)` (length `m`).
    pub v_box: Option<(DVector<f64>, DVector<f64>)>,
}

/// Where the prior mean `x̄_{s+1}` of a new window start comes from, and about which point the
/// arrival update linearises or draws its sigma points (digest §6.8).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum NonlinearPrior {
    /// `x̄_{s+1} = x̂_{s+1|T}`, the update about `x̂_{s|T}` (the paper's, "the previous moment's
    /// estimate"). The window's measurements then enter twice (once through the smoothed prior),
    /// which makes the estimate follow the measurements more than the filters do.
    Smoothed,
    /// The arrival filter keeps its own mean: `x̄_{s+1}` is its prediction after the update with
    /// `y_s` (a UKF or EKF lagging `N` samples behind). No measurement enters twice; on a linear
    /// model with the EKF arrival the MHE is then the Kalman filter (tested).
    ArrivalFilter,
}

impl NonlinearMheSettings {
    /// The paper's shape: `N = 10`, UKF arrival cost with `α, β, κ = 0.5, 2, −2`, 20 iterations,
    /// tolerance `1e−10`.
    #[must_use]
    pub fn paper() -> Self {
        Self {
            horizon: 10,
            arrival: NonlinearArrival::Ukf(UkfParams::paper()),
            max_iterations: 20,
            tolerance: 1e-10,
            estimate_tolerance: Some(1e-9),
            real_time_iterations: None,
            prior: NonlinearPrior::Smoothed,
            w_box: None,
            v_box: None,
        }
    }

    /// The bytes the estimator takes for a model of `n` states, `m` outputs and `p` inputs, an
    /// estimate from above for a caller to check before building it (the horizon sizes every
    /// buffer): `N + 2` slots of the window's vectors and `n×n` matrices, the trajectory and the
    /// rings, each block counted with room for its header, the fixed `n`- and `m`-sized buffers
    /// of the arrival cost, and, with a box, the QP of a Gauss–Newton step. `None` when the count
    /// overflows `u128`.
    #[must_use]
    pub fn memory_estimate(&self, n: usize, m: usize, p: usize) -> Option<u128> {
        let [n, m, p, horizon] = [n, m, p, self.horizon].map(|v| v as u128);
        let slots = horizon.checked_add(2)?;
        // Per slot: x, x_trial, f(x), gradient, step, trajectory (6n), h(x) and y (2m), two
        // inputs (2p), A, D, W (3n²), C (mn), a partial measurement's weight (m²) and mask; 17
        // heap blocks of up to 64 bytes of header and rounding each.
        let f64s = n.checked_mul(n)?.checked_mul(3)?.checked_add(m.checked_mul(n)?)?;
        let f64s = f64s.checked_add(m.checked_mul(m)?)?.checked_add(m)?;
        let f64s =
            f64s.checked_add(n.checked_mul(6)?)?.checked_add(m.checked_mul(2)?)?.checked_add(p.checked_mul(2)?)?;
        let mut slot = f64s.checked_mul(8)?.checked_add(17 * 64)?;
        if self.w_box.is_some() || self.v_box.is_some() {
            // The sparse QP of a Gauss–Newton step and Clarabel's factorisation of it: per slot
            // (n + m + 1)² entries, counted as 1 KiB each (the sum of every request of an update,
            // measured, is below this; its peak far below).
            slot = slot.checked_add((n + m + 1).checked_mul(n + m + 1)?.checked_mul(1024)?)?;
        }
        // Fixed: the weights, their inverses and the arrival filter's sigma points and work.
        let fixed = n.checked_mul(n)?.checked_mul(64)?.checked_add(m.checked_mul(m)?.checked_mul(64)?)?;
        let fixed = fixed.checked_add(n.checked_mul(m)?.checked_mul(64)?)?.checked_add(n.checked_mul(256)?)?;
        slots.checked_mul(slot)?.checked_add(fixed)?.checked_add(1 << 17)
    }

    /// Checks the settings for a model of `n` states and `m` outputs: a horizon of at least 1,
    /// at least one iteration, a positive tolerance, boxes of the right lengths with `lo < hi`.
    pub(super) fn validate(&self, n: usize, m: usize) -> Result<(), EstimatorError> {
        let bad = |message: String| EstimatorError::InvalidConfiguration { estimator: "nonlinear-mhe", message };
        if self.horizon == 0 {
            return Err(bad("the horizon N must be at least 1".into()));
        }
        if let Some(t) = self.estimate_tolerance
            && !(t > 0.0 && t.is_finite())
        {
            return Err(EstimatorError::InvalidConfiguration {
                estimator: "mhe-ukf",
                message: format!("estimate_tolerance must be positive and finite, got {t}"),
            });
        }
        if let Some(k) = self.real_time_iterations
            && !(1..=MAX_REAL_TIME_ITERATIONS).contains(&k)
        {
            return Err(bad(format!(
                "real_time_iterations must be between 1 and {MAX_REAL_TIME_ITERATIONS}, got {k} (none: iterate to the \
                 tolerance)"
            )));
        }
        if self.max_iterations == 0 || self.tolerance.is_nan() || self.tolerance <= 0.0 {
            return Err(bad(format!(
                "max_iterations must be ≥ 1 and tolerance > 0, got {} and {}",
                self.max_iterations, self.tolerance
            )));
        }
        for (what, b, len) in [("w_box", &self.w_box, n), ("v_box", &self.v_box, m)] {
            if let Some((lo, hi)) = b {
                if lo.len() != len || hi.len() != len {
                    return Err(bad(format!("{what} must have {len} components, got {} and {}", lo.len(), hi.len())));
                }
                if let Some(i) = (0..len).find(|&i| lo[i].is_nan() || hi[i].is_nan() || lo[i] >= hi[i]) {
                    return Err(bad(format!("{what} is empty or NaN at component {i}: [{}, {}]", lo[i], hi[i])));
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn message(s: &NonlinearMheSettings) -> String {
        match s.validate(2, 1) {
            Err(EstimatorError::InvalidConfiguration { estimator: "nonlinear-mhe", message }) => message,
            other => panic!("expected an invalid configuration, got {other:?}"),
        }
    }

    #[test]
    fn the_paper_settings_are_valid() {
        let s = NonlinearMheSettings::paper();
        assert_eq!((s.horizon, s.max_iterations, s.tolerance), (10, 20, 1e-10));
        assert_eq!(s.arrival, NonlinearArrival::Ukf(UkfParams::paper()));
        assert_eq!(s.prior, NonlinearPrior::Smoothed);
        assert!(s.validate(6, 3).is_ok());
        // Infinite box entries leave a side open.
        let open = NonlinearMheSettings {
            w_box: Some((
                DVector::from_vec(vec![f64::NEG_INFINITY, -1.0]),
                DVector::from_vec(vec![1.0, f64::INFINITY]),
            )),
            v_box: Some((DVector::from_element(1, -0.5), DVector::from_element(1, 0.5))),
            ..NonlinearMheSettings::paper()
        };
        assert!(open.validate(2, 1).is_ok());
    }

    #[test]
    fn invalid_settings_are_named() {
        let paper = NonlinearMheSettings::paper;
        assert_eq!(message(&NonlinearMheSettings { horizon: 0, ..paper() }), "the horizon N must be at least 1");
        assert!(message(&NonlinearMheSettings { max_iterations: 0, ..paper() }).contains("max_iterations must be ≥ 1"));
        for k in [0, MAX_REAL_TIME_ITERATIONS + 1] {
            let rti = NonlinearMheSettings { real_time_iterations: Some(k), ..paper() };
            assert!(message(&rti).starts_with("real_time_iterations must be between 1 and 10"), "{k}");
        }
        for tolerance in [0.0, -1.0, f64::NAN] {
            assert!(message(&NonlinearMheSettings { tolerance, ..paper() }).contains("tolerance > 0"), "{tolerance}");
        }
        let v = |x: &[f64]| DVector::from_column_slice(x);
        let short = NonlinearMheSettings { w_box: Some((v(&[-1.0]), v(&[1.0]))), ..paper() };
        assert_eq!(message(&short), "w_box must have 2 components, got 1 and 1");
        let long = NonlinearMheSettings { v_box: Some((v(&[-1.0, -1.0]), v(&[1.0, 1.0]))), ..paper() };
        assert_eq!(message(&long), "v_box must have 1 components, got 2 and 2");
        let empty = NonlinearMheSettings { w_box: Some((v(&[-1.0, 1.0]), v(&[1.0, 1.0]))), ..paper() };
        assert_eq!(message(&empty), "w_box is empty or NaN at component 1: [1, 1]");
        let nan = NonlinearMheSettings { v_box: Some((v(&[f64::NAN]), v(&[1.0]))), ..paper() };
        assert!(message(&nan).starts_with("v_box is empty or NaN at component 0"));
    }
}
