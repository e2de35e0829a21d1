//! The non-switching analytic predictive controller (NSAMPC), docs/dp-vessel.md (38)–(61),
//! reconstructed after Chen, Ballance & Gawthrop (2003) with control order 0:
//!
//! ```text
//! L_f h  = R(ψ) ν,   L_f² h = r R(ψ) S ν − R(ψ) M⁻¹ D ν,   G(x) = R(ψ) M⁻¹         (Lie derivatives)
//! e(τ') = E0 + τ' E1 + (τ'²/2)(E2 + G τ)                                            (44)–(49)
//! E0 = h − y_d,   E1 = L_f h − ẏ_d,   E2 = L_f² h − ÿ_d
//! J = ½ ∫₀^Tp (μ1 ‖e‖² + μ2 ‖e'‖²) dτ' + ½ μ3 Tp ‖τ‖²                               (39)
//! (a2 GᵀG + μ3 Tp I) τ = −Gᵀ (a0 E0 + a1 E1 + a2 E2)                                (50)–(59)
//! a0 = μ1 Tp³/6,   a1 = μ1 Tp⁴/8 + μ2 Tp²/2,   a2 = μ1 Tp⁵/20 + μ2 Tp³/3
//! μ3 = 0:  τ = −M R(ψ)ᵀ (E2 + k0 E0 + k1 E1),   k0 = a0/a2,   k1 = a1/a2              (60)–(61)
//! ```
//!
//! then clipped element-wise to the thrust limits (assumed). The law is continuous in `x` (the
//! "non-switching" property). The heading error `ψ − ψ_d` is wrapped to `(−π, π]`.

use std::f64::consts::PI;

use nalgebra::{DVector, Matrix3, Vector3};
use vessel_dynamics::{SiMatrices, ThrustLimits, VesselParams, rotation};

use crate::closed_loop::Controller;
use crate::error::{ControlError, check_finite};
use crate::reference::{ReferenceSample, SetPoint};

/// The prediction horizon and weights of (39).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NsampcParams {
    /// Prediction horizon `Tp` \[s\].
    pub tp: f64,
    /// Weight `μ1` of the output error.
    pub mu1: f64,
    /// Weight `μ2` of the output-error rate (role assumed).
    pub mu2: f64,
    /// Weight `μ3` of the control effort.
    pub mu3: f64,
}

impl NsampcParams {
    /// The paper's `Tp = 1.4 s, μ1 = 1, μ2 = 0.005, μ3 = 0` **\[P\]** (their roles assumed).
    #[must_use]
    pub fn paper() -> Self {
        Self { tp: 1.4, mu1: 1.0, mu2: 0.005, mu3: 0.0 }
    }

    /// The coefficients `a0, a1, a2` of (50)–(59) and the gains `k0 = a0/a2`, `k1 = a1/a2` of
    /// (60)–(61).
    ///
    /// # Errors
    /// [`ControlError::InvalidParameter`] unless `Tp > 0`, `μ1, μ2, μ3 ≥ 0` (finite) and
    /// `μ1 + μ2 > 0`.
    pub fn gains(&self) -> Result<Gains, ControlError> {
        let bad = |name, value, requirement| ControlError::InvalidParameter { name, value, requirement };
        if !(self.tp.is_finite() && self.tp > 0.0) {
            return Err(bad("Tp (prediction horizon)", self.tp, "positive and finite"));
        }
        for (name, v) in
            [("mu1 (error weight)", self.mu1), ("mu2 (rate weight)", self.mu2), ("mu3 (effort weight)", self.mu3)]
        {
            if !(v.is_finite() && v >= 0.0) {
                return Err(bad(name, v, "non-negative and finite"));
            }
        }
        if self.mu1 + self.mu2 <= 0.0 {
            return Err(bad("mu1 + mu2", self.mu1 + self.mu2, "positive"));
        }
        let t = self.tp;
        let a0 = self.mu1 * t.powi(3) / 6.0;
        let a1 = self.mu1 * t.powi(4) / 8.0 + self.mu2 * t * t / 2.0;
        let a2 = self.mu1 * t.powi(5) / 20.0 + self.mu2 * t.powi(3) / 3.0;
        Ok(Gains { a0, a1, a2, k0: a0 / a2, k1: a1 / a2 })
    }
}

/// The coefficients of the optimality condition and the gains of the unconstrained law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gains {
    /// `a0 = μ1 Tp³/6`.
    pub a0: f64,
    /// `a1 = μ1 Tp⁴/8 + μ2 Tp²/2`.
    pub a1: f64,
    /// `a2 = μ1 Tp⁵/20 + μ2 Tp³/3`.
    pub a2: f64,
    /// `k0 = a0/a2` \[1/s²\].
    pub k0: f64,
    /// `k1 = a1/a2` \[1/s\].
    pub k1: f64,
}

/// The Lie derivatives of `h(x) = [x, y, ψ]` along `f` and `g` at a state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LieDerivatives {
    /// `h(x) = [x, y, ψ]`.
    pub h: Vector3<f64>,
    /// `L_f h = R(ψ) ν`.
    pub lf_h: Vector3<f64>,
    /// `L_f² h = r R(ψ) S ν − R(ψ) M⁻¹ D ν`.
    pub lf2_h: Vector3<f64>,
    /// `G = [L_gj L_f h_i] = R(ψ) M⁻¹` (`det G = 1/det M ≠ 0`: relative degree (2, 2, 2)).
    pub g: Matrix3<f64>,
}

/// The Lie derivatives at `x = [x, y, ψ, u, v, r]` (docs/dp-vessel.md §3), without checks.
#[must_use]
pub fn lie_derivatives(si: &SiMatrices, x: &[f64; 6]) -> LieDerivatives {
    let rot = rotation(x[2]);
    let nu = Vector3::new(x[3], x[4], x[5]);
    let s_nu = Vector3::new(-nu[1], nu[0], 0.0);
    LieDerivatives {
        h: Vector3::new(x[0], x[1], x[2]),
        lf_h: rot * nu,
        lf2_h: rot * (s_nu * x[5] - si.m_inv_d * nu),
        g: rot * si.m_inv,
    }
}

/// Which thrust components were clipped.
pub type Saturation = [bool; 3];

/// One control computation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControlOutput {
    /// The commanded thrust after saturation.
    pub tau: Vector3<f64>,
    /// The optimal thrust before saturation.
    pub unsaturated: Vector3<f64>,
    /// Which components were clipped.
    pub saturated: Saturation,
}

/// The controller: vessel matrices, gains and thrust limits.
#[derive(Debug, Clone, PartialEq)]
pub struct Nsampc {
    si: SiMatrices,
    params: NsampcParams,
    gains: Gains,
    limits: ThrustLimits,
}

fn wrap_angle(a: f64) -> f64 {
    let w = (a + PI).rem_euclid(2.0 * PI) - PI;
    if w == -PI { PI } else { w }
}

impl Nsampc {
    /// The controller for `vessel` (its matrices and thrust limits) with `params`.
    ///
    /// # Errors
    /// The vessel's validation errors; [`NsampcParams::gains`].
    pub fn new(vessel: &VesselParams, params: NsampcParams) -> Result<Self, ControlError> {
        let si = vessel.validate()?;
        Ok(Self { si, params, gains: params.gains()?, limits: vessel.thrust })
    }

    /// The gains in use.
    #[must_use]
    pub fn gains(&self) -> Gains {
        self.gains
    }

    /// The parameters.
    #[must_use]
    pub fn params(&self) -> NsampcParams {
        self.params
    }

    /// The thrust limits.
    #[must_use]
    pub fn limits(&self) -> ThrustLimits {
        self.limits
    }

    /// The optimal thrust for the state estimate `x` and reference `r` (50)–(61), then clipped.
    /// Allocation-free.
    ///
    /// # Errors
    /// [`ControlError::NonFinite`] for a non-finite state or reference, or a non-finite result.
    pub fn control(&self, x: &[f64; 6], r: &ReferenceSample) -> Result<ControlOutput, ControlError> {
        check_finite("state estimate", x)?;
        check_finite("reference y_d", r.y.as_slice())?;
        check_finite("reference y_d'", r.y_dot.as_slice())?;
        check_finite("reference y_d''", r.y_ddot.as_slice())?;
        let lie = lie_derivatives(&self.si, x);
        let mut e0 = lie.h - r.y;
        e0[2] = wrap_angle(e0[2]);
        let e1 = lie.lf_h - r.y_dot;
        let e2 = lie.lf2_h - r.y_ddot;
        let Gains { a0, a1, a2, k0, k1 } = self.gains;
        let unsaturated = if self.params.mu3 == 0.0 {
            // (60)–(61): G⁻¹ = M R(ψ)ᵀ.
            -(self.si.m * rotation(x[2]).transpose() * (e2 + e0 * k0 + e1 * k1))
        } else {
            // (50)–(59), solved in thrust units scaled by M (well conditioned: G M = R(ψ)).
            // With τ = M σ: (a2 Mᵀ GᵀG M + μ3 Tp MᵀM) σ = −Mᵀ Gᵀ p, and G M = R orthogonal.
            let p = e0 * a0 + e1 * a1 + e2 * a2;
            let mt_m = self.si.m.transpose() * self.si.m;
            let lhs = Matrix3::identity() * a2 + mt_m * (self.params.mu3 * self.params.tp);
            let rhs = -(rotation(x[2]).transpose() * p);
            let Some(chol) = lhs.cholesky() else {
                return Err(ControlError::NonFinite { what: "normal equations (50)-(59)", index: 0 });
            };
            self.si.m * chol.solve(&rhs)
        };
        check_finite("thrust", unsaturated.as_slice())?;
        let mut tau = unsaturated;
        let saturated = self.limits.saturate(&mut tau);
        Ok(ControlOutput { tau, unsaturated, saturated })
    }
}

/// The controller with its set point, as the closed loop's [`Controller`]: at step `k` it takes
/// the reference sample of `t_k`, computes the clipped NSAMPC thrust from `x̂_k` and then advances
/// the reference.
#[derive(Debug, Clone)]
pub struct VesselController {
    nsampc: Nsampc,
    set_point: SetPoint,
    last_reference: [f64; 3],
    last: Option<ControlOutput>,
}

impl VesselController {
    /// The controller and the set point generator.
    #[must_use]
    pub fn new(nsampc: Nsampc, set_point: SetPoint) -> Self {
        Self { nsampc, set_point, last_reference: [f64::NAN; 3], last: None }
    }

    /// The last control computation.
    #[must_use]
    pub fn last(&self) -> Option<&ControlOutput> {
        self.last.as_ref()
    }

    /// The controller.
    #[must_use]
    pub fn nsampc(&self) -> &Nsampc {
        &self.nsampc
    }
}

impl Controller for VesselController {
    type Error = ControlError;

    fn input_dim(&self) -> usize {
        3
    }

    fn control(&mut self, _k: usize, x_hat: &DVector<f64>, tau: &mut DVector<f64>) -> Result<(), ControlError> {
        if x_hat.len() != 6 {
            return Err(ControlError::DimensionMismatch { what: "state estimate", expected: 6, found: x_hat.len() });
        }
        if tau.len() != 3 {
            return Err(ControlError::DimensionMismatch { what: "thrust", expected: 3, found: tau.len() });
        }
        let x: [f64; 6] = std::array::from_fn(|i| x_hat[i]);
        let r = self.set_point.current();
        let out = self.nsampc.control(&x, &r)?;
        self.set_point.advance();
        for i in 0..3 {
            tau[i] = out.tau[i];
        }
        self.last_reference = [r.y[0], r.y[1], r.y[2]];
        self.last = Some(out);
        Ok(())
    }

    fn reference(&self) -> Option<&[f64]> {
        self.last.is_some().then_some(&self.last_reference[..])
    }

    fn input_limits(&self) -> Option<&[f64]> {
        Some(&self.nsampc.limits.max[..])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use models::ContinuousModel;
    use vessel_dynamics::Vessel;

    #[test]
    fn digest_gains() {
        let g = NsampcParams::paper().gains().unwrap();
        assert!((g.k0 - 1.6722).abs() < 5e-5, "k0 = {}", g.k0);
        assert!((g.k1 - 1.7738).abs() < 5e-5, "k1 = {}", g.k1);
        // ωn = 1.29 rad/s, ζ = 0.69 (digest §3.3).
        let wn = g.k0.sqrt();
        assert!((wn - 1.29).abs() < 5e-3 && (g.k1 / (2.0 * wn) - 0.69).abs() < 5e-3);
        // μ2 = 0 gives Chen's 10/(3 Tp²) and 5/(2 Tp).
        for tp in [0.5, 1.4, 3.0] {
            let g = NsampcParams { tp, mu2: 0.0, ..NsampcParams::paper() }.gains().unwrap();
            assert!((g.k0 - 10.0 / (3.0 * tp * tp)).abs() < 1e-12 && (g.k1 - 5.0 / (2.0 * tp)).abs() < 1e-12);
        }
        // The weights cancel with μ3 = 0: scaling μ1, μ2 together leaves the gains.
        let a = NsampcParams { mu1: 7.0, mu2: 0.035, ..NsampcParams::paper() }.gains().unwrap();
        assert!((a.k0 - 1.6722).abs() < 5e-5);
    }

    #[test]
    fn bad_parameters_are_typed_errors() {
        for p in [
            NsampcParams { tp: 0.0, ..NsampcParams::paper() },
            NsampcParams { mu1: -1.0, ..NsampcParams::paper() },
            NsampcParams { mu3: f64::NAN, ..NsampcParams::paper() },
            NsampcParams { mu1: 0.0, mu2: 0.0, ..NsampcParams::paper() },
        ] {
            assert!(matches!(p.gains(), Err(ControlError::InvalidParameter { .. })), "{p:?}");
        }
        let c = Nsampc::new(&VesselParams::paper(), NsampcParams::paper()).unwrap();
        let r = ReferenceSample::hold(Vector3::new(50.0, 50.0, 0.0));
        assert!(matches!(c.control(&[f64::NAN, 0.0, 0.0, 0.0, 0.0, 0.0], &r), Err(ControlError::NonFinite { .. })));
        let bad = ReferenceSample { y_dot: Vector3::new(0.0, f64::INFINITY, 0.0), ..r };
        assert!(c.control(&[0.0; 6], &bad).is_err());
    }

    fn state() -> [f64; 6] {
        [3.0, -4.0, 0.8, 0.6, -0.2, 0.03]
    }

    /// `L_f h` and `L_f² h + G τ` against finite differences of `h` along the flow `ẋ = f + g τ`.
    #[test]
    fn lie_derivatives_match_the_flow() {
        let vessel = Vessel::new(VesselParams::paper()).unwrap();
        let si = *vessel.matrices();
        let x = state();
        let tau = Vector3::new(2e5, -5e4, 1e6);
        let xdot = |x: &[f64; 6]| {
            let mut out = DVector::zeros(6);
            vessel.derivative(&DVector::from_row_slice(x), &DVector::from_row_slice(tau.as_slice()), &mut out).unwrap();
            out
        };
        let l = lie_derivatives(&si, &x);
        let d = xdot(&x);
        assert!((l.lf_h - Vector3::new(d[0], d[1], d[2])).amax() < 1e-14);
        // d/dt (L_f h) along the flow = L_f² h + G τ (second derivative of the output).
        let eps = 1e-4;
        let xp: [f64; 6] = std::array::from_fn(|i| x[i] + eps * d[i]);
        let xm: [f64; 6] = std::array::from_fn(|i| x[i] - eps * d[i]);
        let fd = (lie_derivatives(&si, &xp).lf_h - lie_derivatives(&si, &xm).lf_h) / (2.0 * eps);
        let want = l.lf2_h + l.g * tau;
        assert!((fd - want).amax() < 1e-9 * want.amax().max(1e-6), "{fd} vs {want}");
        assert!((l.g.determinant() - 1.0 / si.m.determinant()).abs() < 1e-12 / si.m.determinant());
    }

    /// Unsaturated, the law makes the output error obey `e'' + k1 e' + k0 e = 0`.
    #[test]
    fn law_imposes_the_error_dynamics() {
        let vessel = VesselParams::paper();
        let si = vessel.validate().unwrap();
        let c = Nsampc::new(&vessel, NsampcParams::paper()).unwrap();
        // Close to the reference, so that no thruster saturates.
        let x = [3.0, -4.0, 0.8, 0.01, -0.005, 1e-4];
        let r = ReferenceSample {
            y: Vector3::new(3.005, -4.004, 0.8005),
            y_dot: Vector3::new(0.012, 0.0, 0.0),
            y_ddot: Vector3::new(1e-4, 0.0, -1e-6),
        };
        let out = c.control(&x, &r).unwrap();
        assert_eq!(out.saturated, [false; 3]);
        let l = lie_derivatives(&si, &x);
        let e0 = l.h - r.y;
        let e1 = l.lf_h - r.y_dot;
        let e2 = l.lf2_h + l.g * out.tau - r.y_ddot;
        let g = c.gains();
        let res = e2 + e1 * g.k1 + e0 * g.k0;
        assert!(res.amax() < 1e-12, "{res}");
        // μ3 > 0 solves the normal equations (50)–(59) and tends to the μ3 = 0 law.
        let mut prev = out.tau.norm();
        for mu3 in [1e-16, 1e-14, 1e-12] {
            let cm = Nsampc::new(&vessel, NsampcParams { mu3, ..NsampcParams::paper() }).unwrap();
            let o = cm.control(&x, &r).unwrap();
            let p = e0 * g.a0 + e1 * g.a1 + (l.lf2_h - r.y_ddot) * g.a2;
            let lhs = l.g.transpose() * l.g * g.a2 + Matrix3::identity() * (mu3 * 1.4);
            let resid = lhs * o.unsaturated + l.g.transpose() * p;
            assert!(resid.amax() < 1e-9 * (l.g.transpose() * p).amax(), "mu3 {mu3}: {resid}");
            assert!(o.tau.norm() < prev, "effort must shrink as mu3 grows");
            prev = o.tau.norm();
        }
        let tiny = Nsampc::new(&vessel, NsampcParams { mu3: 1e-30, ..NsampcParams::paper() }).unwrap();
        assert!((tiny.control(&x, &r).unwrap().tau - out.tau).amax() < 1e-6 * out.tau.amax());
    }

    #[test]
    fn large_errors_saturate_element_wise_and_heading_error_wraps() {
        let c = Nsampc::new(&VesselParams::paper(), NsampcParams::paper()).unwrap();
        let out = c.control(&[0.0; 6], &ReferenceSample::hold(Vector3::new(50.0, 50.0, 0.0))).unwrap();
        assert_eq!(out.saturated, [true, true, false]);
        assert_eq!(out.tau[0], 1e6);
        assert_eq!(out.tau[1], 3e5);
        assert!(out.unsaturated[1] > 3e5);
        // ψ = 350°, ψ_d = 0: the error is −10°, not 350°.
        let x = [0.0, 0.0, 350f64.to_radians(), 0.0, 0.0, 0.0];
        let a = c.control(&x, &ReferenceSample::hold(Vector3::zeros())).unwrap();
        let b = c
            .control(&[0.0, 0.0, (-10f64).to_radians(), 0.0, 0.0, 0.0], &ReferenceSample::hold(Vector3::zeros()))
            .unwrap();
        assert!((a.unsaturated[2] - b.unsaturated[2]).abs() < 1e-6 * b.unsaturated[2].abs());
        assert!(b.unsaturated[2] > 0.0);
    }
}
