//! Pacejka-89 tyre (paper eqs (3)–(4)) with the coefficient laws of the MSC Adams PAC89 model
//! and truck-tyre coefficients reconstructed from a 315/80R22.5 PAC2002 example file
//! (digest §2, tags **\[R\]**).
//!
//! # Units
//!
//! The coefficient laws take the load per tyre `F_z` in **kN**, the slip angle `α` in
//! **degrees** and the slip ratio `s` in **percent**, and give forces in **N** (Adams PAC89
//! convention). The SI methods [`Pac89Tyre::lateral`] and [`Pac89Tyre::longitudinal`] take
//! `F_z` in N, `α` in rad and `s` as a unit slip, and return the slope `dF/dα` in N/rad and
//! `dF/ds` in N per unit slip (`dF/dα_deg · 180/π` and `dF/ds_% · 100`, digest §3).
//!
//! # Signs **\[R\]**
//!
//! Adams' PAC89 uses a modified SAE frame with `α` flipped. Here `α` is defined (see
//! [`crate::kinematics`]) so that the positive coefficients give `F_y > 0` for `α > 0` in the
//! y-left body frame, and `F_x > 0` for drive slip `s > 0`.
//!
//! # Guards **\[A\]** (digest §6.6)
//!
//! * The coefficients are evaluated at `max(F_z, F_z,min)` (`F_z,min = 1 kN` per tyre by
//!   default) so that `B = BCD/(C·D)` never divides by a vanishing `D`. Below `F_z,min` the
//!   force, slope and peak are multiplied by `max(F_z, 0)/F_z,min`, so the force fades
//!   continuously to zero for an unloaded (lifted) tyre instead of jumping.
//! * Camber is zero; the camber terms `a5, a8, a11` never act.
//! * The laws are used only where they give a usable curve: `D > 0`, `BCD > 0` and `E ≤ 1`,
//!   otherwise [`TruckError::TyreOutOfRange`]. With the truck coefficients this holds for
//!   loads up to about 74 kN per tyre (longitudinal `E` reaches 1 near 74 kN, `BCD` vanishes
//!   near 88 kN); the static loads are 16–33 kN per tyre.
//!
//! # Friction scale **\[A\]**
//!
//! [`Pac89Tyre::friction_scale`] `λ_μ` multiplies the peak factor `D` of both curves and keeps
//! the slip stiffness `BCD` (so `B = BCD/(C·λ_μ·D)`), as PAC2002's `λ_μ` does (its `K_y`, `K_x`
//! do not depend on `λ_μ`). The truth model's "μ × 0.8" mismatch case sets it to 0.8.

use models::validate::{finite, positive};

use crate::error::{TruckError, finite_input};

/// Number of lateral coefficients `a0..a13`.
pub const LATERAL_COEFFICIENTS: usize = 14;
/// Number of longitudinal coefficients `b0..b10`.
pub const LONGITUDINAL_COEFFICIENTS: usize = 11;

const A_NAMES: [&str; LATERAL_COEFFICIENTS] = [
    "a0 (lateral shape factor C)",
    "a1 (lateral peak, Fz^2 term)",
    "a2 (lateral peak, Fz term)",
    "a3 (lateral cornering stiffness maximum)",
    "a4 (load at maximum cornering stiffness)",
    "a5 (camber sensitivity of cornering stiffness)",
    "a6 (lateral curvature, Fz term)",
    "a7 (lateral curvature, constant)",
    "a8 (horizontal shift, camber term)",
    "a9 (horizontal shift, Fz term)",
    "a10 (horizontal shift, constant)",
    "a11 (vertical shift, camber term)",
    "a12 (vertical shift, Fz term)",
    "a13 (vertical shift, constant)",
];
const B_NAMES: [&str; LONGITUDINAL_COEFFICIENTS] = [
    "b0 (longitudinal shape factor C)",
    "b1 (longitudinal peak, Fz^2 term)",
    "b2 (longitudinal peak, Fz term)",
    "b3 (slip stiffness, Fz^2 term)",
    "b4 (slip stiffness, Fz term)",
    "b5 (slip stiffness, exponential decay)",
    "b6 (longitudinal curvature, Fz^2 term)",
    "b7 (longitudinal curvature, Fz term)",
    "b8 (longitudinal curvature, constant)",
    "b9 (longitudinal horizontal shift, Fz term)",
    "b10 (longitudinal horizontal shift, constant)",
];

/// Pac89 coefficients: lateral `a0..a13` and longitudinal `b0..b10` (Adams PAC89 laws, units
/// kN, degrees, percent → N).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pac89Coefficients {
    /// Lateral coefficients `a0..a13`.
    pub a: [f64; LATERAL_COEFFICIENTS],
    /// Longitudinal coefficients `b0..b10`.
    pub b: [f64; LONGITUDINAL_COEFFICIENTS],
}

impl Pac89Coefficients {
    /// Truck tyre 315/80R22.5 (digest §2 tables), **reconstructed \[R\]**: mapped exactly (at zero
    /// camber) from the pure-slip PAC2002 laws of the MSC example file
    /// `pac2002_315_80R22_5.tir` (`F_z0 = 35 kN`, `R_0 = 0.548 m`). The asymmetric shifts
    /// (`PHY·`, `PVY·`, `PEY3`, `PEX4`) are set to zero **\[A\]**, so straight running gives no
    /// lateral force: `a8..a13 = 0`, `b9 = b10 = 0`. These are **not** the paper's numbers (its
    /// tyre data are lost).
    #[must_use]
    pub fn truck_315_80r22_5() -> Self {
        Self {
            a: [1.5874, -2.1430, 814.57, 6285.2, 116.70, 0.0, -1.9807e-3, 0.44495, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            b: [1.7204, -6.9803, 1021.8, -2.3943, 210.56, -4.5194e-3, 6.2060e-5, 6.8843e-3, 0.14961, 0.0, 0.0],
        }
    }

    /// Checks that every coefficient is finite, the shape factors `C = a0, b0` are positive
    /// and `a4` (the load of maximum cornering stiffness) is positive. Whether the laws give a
    /// usable curve at a given load is checked at evaluation ([`TruckError::TyreOutOfRange`]).
    ///
    /// # Errors
    /// [`TruckError::Parameter`] naming the coefficient.
    pub fn validate(&self) -> Result<(), TruckError> {
        for (name, &v) in A_NAMES.iter().zip(&self.a) {
            finite(name, v)?;
        }
        for (name, &v) in B_NAMES.iter().zip(&self.b) {
            finite(name, v)?;
        }
        positive(A_NAMES[0], self.a[0])?;
        positive(A_NAMES[4], self.a[4])?;
        positive(B_NAMES[0], self.b[0])?;
        Ok(())
    }
}

/// One Magic Formula curve at a fixed load (eqs (3)–(4)):
/// `F(X) = D·sin(C·atan(B·x − E·(B·x − atan(B·x)))) + S_V`, with `x = X + S_H`.
/// `X` is in degrees (lateral) or percent (longitudinal), `F` in N.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MagicFormula {
    /// Stiffness factor `B` \[1/deg or 1/%\].
    pub b: f64,
    /// Shape factor `C`.
    pub c: f64,
    /// Peak factor `D` \[N\].
    pub d: f64,
    /// Curvature factor `E`.
    pub e: f64,
    /// Horizontal shift `S_H` \[deg or %\].
    pub sh: f64,
    /// Vertical shift `S_V` \[N\].
    pub sv: f64,
}

impl MagicFormula {
    /// The slope at the origin of the unshifted curve, `BCD` \[N/deg or N/%\].
    #[must_use]
    pub fn bcd(&self) -> f64 {
        self.b * self.c * self.d
    }

    /// `(F(X), dF/dX)`, with the slope (digest §3)
    /// `dF/dX = D·C·cos(C·atan θ)/(1 + θ²)·[B − E·(B − B/(1 + (B·x)²))]`,
    /// `θ = B·x − E·(B·x − atan(B·x))`.
    #[must_use]
    pub fn evaluate(&self, slip: f64) -> (f64, f64) {
        let x = slip + self.sh;
        let bx = self.b * x;
        let theta = bx - self.e * (bx - bx.atan());
        let phi = self.c * theta.atan();
        let force = self.d * phi.sin() + self.sv;
        let dtheta = self.b - self.e * (self.b - self.b / (1.0 + bx * bx));
        let slope = self.d * self.c * phi.cos() / (1.0 + theta * theta) * dtheta;
        (force, slope)
    }
}

/// A tyre force with its slope and peak.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TyreForce {
    /// Force \[N\].
    pub force: f64,
    /// `dF/dα` \[N/rad\] (lateral) or `dF/ds` \[N per unit slip\] (longitudinal).
    pub slope: f64,
    /// Peak force `λ_μ·D` \[N\] (semi-axis of the friction ellipse).
    pub peak: f64,
}

impl TyreForce {
    fn scaled(self, k: f64) -> Self {
        Self { force: k * self.force, slope: k * self.slope, peak: k * self.peak }
    }
}

/// The Pac89 tyre: coefficients, load clamp and friction scale (plain data; [`validate`]
/// checks it, and [`crate::TruckParams::validate`] calls it).
///
/// [`validate`]: Pac89Tyre::validate
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pac89Tyre {
    /// The coefficient set.
    pub coefficients: Pac89Coefficients,
    /// Load clamp `F_z,min` per tyre \[N\] (digest §6.6: 1 kN) **\[A\]**.
    pub fz_min: f64,
    /// Friction scale `λ_μ` on the peak factors (1 nominal) **\[A\]**.
    pub friction_scale: f64,
}

impl Pac89Tyre {
    /// The truck tyre of the digest: [`Pac89Coefficients::truck_315_80r22_5`] **\[R\]**,
    /// `F_z,min = 1 kN`, `λ_μ = 1` **\[A\]**.
    #[must_use]
    pub fn truck() -> Self {
        Self { coefficients: Pac89Coefficients::truck_315_80r22_5(), fz_min: 1000.0, friction_scale: 1.0 }
    }

    /// Checks the coefficients, `F_z,min > 0` and `λ_μ > 0`.
    ///
    /// # Errors
    /// The first violation, naming the parameter.
    pub fn validate(&self) -> Result<(), TruckError> {
        self.coefficients.validate()?;
        positive("F_z,min (tyre load clamp)", self.fz_min)?;
        positive("lambda_mu (tyre friction scale)", self.friction_scale)?;
        Ok(())
    }

    /// The lateral curve at load `fz_kn` \[kN per tyre\], camber 0:
    /// `C = a0`, `D = λ_μ·(a1·F_z² + a2·F_z)`, `BCD = a3·sin(2·atan(F_z/a4))`, `B = BCD/(C·D)`,
    /// `E = a6·F_z + a7`, `S_H = a9·F_z + a10`, `S_V = a12·F_z + a13`.
    ///
    /// # Errors
    /// [`TruckError::TyreOutOfRange`] if `D ≤ 0`, `BCD ≤ 0`, `E > 1` or a factor is not finite.
    pub fn lateral_curve(&self, fz_kn: f64) -> Result<MagicFormula, TruckError> {
        let a = &self.coefficients.a;
        let c = a[0];
        let d = self.friction_scale * (a[1] * fz_kn * fz_kn + a[2] * fz_kn);
        let bcd = a[3] * (2.0 * (fz_kn / a[4]).atan()).sin();
        let e = a[6] * fz_kn + a[7];
        let curve = MagicFormula { b: bcd / (c * d), c, d, e, sh: a[9] * fz_kn + a[10], sv: a[12] * fz_kn + a[13] };
        check_curve("lateral", fz_kn, &curve, bcd)?;
        Ok(curve)
    }

    /// The longitudinal curve at load `fz_kn` \[kN per tyre\]:
    /// `C = b0`, `D = λ_μ·(b1·F_z² + b2·F_z)`, `BCD = (b3·F_z² + b4·F_z)·e^(−b5·F_z)`,
    /// `B = BCD/(C·D)`, `E = b6·F_z² + b7·F_z + b8`, `S_H = b9·F_z + b10`, `S_V = 0`.
    ///
    /// # Errors
    /// As [`Pac89Tyre::lateral_curve`].
    pub fn longitudinal_curve(&self, fz_kn: f64) -> Result<MagicFormula, TruckError> {
        let b = &self.coefficients.b;
        let c = b[0];
        let d = self.friction_scale * (b[1] * fz_kn * fz_kn + b[2] * fz_kn);
        let bcd = (b[3] * fz_kn * fz_kn + b[4] * fz_kn) * (-b[5] * fz_kn).exp();
        let e = b[6] * fz_kn * fz_kn + b[7] * fz_kn + b[8];
        let curve = MagicFormula { b: bcd / (c * d), c, d, e, sh: b[9] * fz_kn + b[10], sv: 0.0 };
        check_curve("longitudinal", fz_kn, &curve, bcd)?;
        Ok(curve)
    }

    /// Load at which the coefficients are evaluated \[kN\] and the fade factor below the clamp.
    fn clamp(&self, fz: f64) -> Result<(f64, f64), TruckError> {
        finite_input("F_z (tyre load)", fz)?;
        Ok(if fz >= self.fz_min { (fz / 1000.0, 1.0) } else { (self.fz_min / 1000.0, fz.max(0.0) / self.fz_min) })
    }

    /// Lateral force of one tyre at load `fz` \[N\] and slip angle `alpha` \[rad\]; the slope
    /// is `dF_y/dα` \[N/rad\].
    ///
    /// # Errors
    /// [`TruckError::NonFiniteInput`] naming `F_z` or `α`; [`TruckError::TyreOutOfRange`].
    pub fn lateral(&self, fz: f64, alpha: f64) -> Result<TyreForce, TruckError> {
        finite_input("alpha (tyre slip angle)", alpha)?;
        let (fz_kn, k) = self.clamp(fz)?;
        Ok(lateral_force(&self.lateral_curve(fz_kn)?, alpha, k))
    }

    /// Longitudinal force of one tyre at load `fz` \[N\] and slip ratio `slip` (unit slip,
    /// `s > 0` drive); the slope is `dF_x/ds` \[N per unit slip\].
    ///
    /// # Errors
    /// [`TruckError::NonFiniteInput`] naming `F_z` or `s`; [`TruckError::TyreOutOfRange`].
    pub fn longitudinal(&self, fz: f64, slip: f64) -> Result<TyreForce, TruckError> {
        finite_input("s (tyre slip ratio)", slip)?;
        let (fz_kn, k) = self.clamp(fz)?;
        Ok(longitudinal_force(&self.longitudinal_curve(fz_kn)?, slip, k))
    }

    /// `n` identical tyres sharing the load `fz` \[N\] of one wheel position (dual tyres,
    /// digest decision 3): `n·F_y(F_z/n, α)`, slope and peak likewise times `n` **\[A\]**.
    ///
    /// # Errors
    /// As [`Pac89Tyre::lateral`], and [`TruckError::Parameter`] for `n = 0`.
    pub fn lateral_lumped(&self, tyres: u32, fz: f64, alpha: f64) -> Result<TyreForce, TruckError> {
        let n = tyre_count(tyres)?;
        Ok(self.lateral(fz / n, alpha)?.scaled(n))
    }

    /// `n·F_x(F_z/n, s)` for `n` tyres at one wheel position (see [`Pac89Tyre::lateral_lumped`]).
    ///
    /// # Errors
    /// As [`Pac89Tyre::longitudinal`], and [`TruckError::Parameter`] for `n = 0`.
    pub fn longitudinal_lumped(&self, tyres: u32, fz: f64, slip: f64) -> Result<TyreForce, TruckError> {
        let n = tyre_count(tyres)?;
        Ok(self.longitudinal(fz / n, slip)?.scaled(n))
    }
}

/// `F_y` at slip angle `alpha` \[rad\] on `curve` (in degrees), times the fade `k`.
fn lateral_force(curve: &MagicFormula, alpha: f64, k: f64) -> TyreForce {
    let (f, df) = curve.evaluate(alpha.to_degrees());
    TyreForce { force: f, slope: df.to_degrees(), peak: curve.d }.scaled(k)
}

/// `F_x` at slip ratio `slip` on `curve` (in percent), times the fade `k`.
fn longitudinal_force(curve: &MagicFormula, slip: f64, k: f64) -> TyreForce {
    let (f, df) = curve.evaluate(100.0 * slip);
    TyreForce { force: f, slope: 100.0 * df, peak: curve.d }.scaled(k)
}

/// The curves of one wheel position at a fixed load, computed once: `n` tyres sharing the load,
/// each on the curves at its share with the fade `k` below the clamp. Evaluations give what
/// [`Pac89Tyre::lateral_lumped`] and [`Pac89Tyre::longitudinal_lumped`] give at that load, bit
/// for bit, without deriving the coefficients again.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct LumpedCurves {
    /// The lateral curve of one tyre.
    pub(crate) lateral: MagicFormula,
    /// The longitudinal curve of one tyre.
    pub(crate) longitudinal: MagicFormula,
    /// The fade below the load clamp.
    pub(crate) k: f64,
    /// Tyres at the position.
    pub(crate) n: f64,
}

impl LumpedCurves {
    /// As [`Pac89Tyre::lateral_lumped`] at the curves' load.
    pub(crate) fn lateral(&self, alpha: f64) -> Result<TyreForce, TruckError> {
        finite_input("alpha (tyre slip angle)", alpha)?;
        Ok(lateral_force(&self.lateral, alpha, self.k).scaled(self.n))
    }

    /// As [`Pac89Tyre::longitudinal_lumped`] at the curves' load.
    pub(crate) fn longitudinal(&self, slip: f64) -> Result<TyreForce, TruckError> {
        finite_input("s (tyre slip ratio)", slip)?;
        Ok(longitudinal_force(&self.longitudinal, slip, self.k).scaled(self.n))
    }
}

impl Pac89Tyre {
    /// The curves of `tyres` tyres sharing the load `fz` \[N\] of one wheel position.
    pub(crate) fn lumped_curves(&self, tyres: u32, fz: f64) -> Result<LumpedCurves, TruckError> {
        let n = tyre_count(tyres)?;
        let (fz_kn, k) = self.clamp(fz / n)?;
        Ok(LumpedCurves { lateral: self.lateral_curve(fz_kn)?, longitudinal: self.longitudinal_curve(fz_kn)?, k, n })
    }
}

fn tyre_count(tyres: u32) -> Result<f64, TruckError> {
    let n = f64::from(tyres);
    positive("n (tyres per wheel position)", n)?;
    Ok(n)
}

fn check_curve(curve: &'static str, fz_kn: f64, mf: &MagicFormula, bcd: f64) -> Result<(), TruckError> {
    let fail =
        |quantity, value, requirement| Err(TruckError::TyreOutOfRange { curve, fz_kn, quantity, value, requirement });
    if !(mf.d.is_finite() && mf.d > 0.0) {
        return fail("D (peak factor)", mf.d, "must be positive");
    }
    if !(bcd.is_finite() && bcd > 0.0) {
        return fail("BCD (slip stiffness)", bcd, "must be positive");
    }
    if !(mf.e.is_finite() && mf.e <= 1.0) {
        return fail("E (curvature factor)", mf.e, "must not exceed 1");
    }
    if !(mf.b.is_finite() && mf.sh.is_finite() && mf.sv.is_finite()) {
        return fail("B (stiffness factor)", mf.b, "must be finite");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(got: f64, want: f64, rel: f64) -> bool {
        (got - want).abs() <= rel * want.abs()
    }

    #[test]
    fn digest_values_at_22_5_kn() {
        let t = Pac89Tyre::truck();
        let lat = t.lateral_curve(22.5).unwrap();
        // Digest §2 [V]: B = 0.0854 /deg, D = 17 243 N, E = 0.4004, BCD = 2337 N/deg, Fy(2°) = 4557 N.
        assert!(close(lat.b, 0.0854, 5e-4), "B = {}", lat.b);
        assert!(close(lat.d, 17_243.0, 1e-4), "D = {}", lat.d);
        assert!(close(lat.e, 0.4004, 1e-4), "E = {}", lat.e);
        assert!(close(lat.bcd(), 2337.0, 2e-4), "BCD = {}", lat.bcd());
        assert!(close(lat.evaluate(2.0).0, 4557.0, 1e-4));
        // The SI entry point: 22.5 kN as 22 500 N and 2° in rad.
        let f = t.lateral(22_500.0, 2f64.to_radians()).unwrap();
        assert!(close(f.force, 4557.0, 1e-4), "Fy = {}", f.force);
        assert_eq!(f.peak, lat.d);
    }

    #[test]
    fn digest_values_at_32_8_and_35_kn() {
        let t = Pac89Tyre::truck();
        let lat = t.lateral_curve(32.8).unwrap();
        assert!(close(lat.bcd(), 3274.0, 2e-4), "{}", lat.bcd());
        assert!(close(lat.evaluate(2.0).0, 6390.0, 1e-4));
        let lon = t.longitudinal_curve(32.8).unwrap();
        assert!(close(lon.bcd(), 5022.0, 1e-4), "{}", lon.bcd());
        assert!(close(lon.evaluate(1.0).0, 4962.0, 1e-4));
        let f = t.longitudinal(32_800.0, 0.01).unwrap();
        assert!(close(f.force, 4962.0, 1e-4));
        // μ at F_z0 = 35 kN reproduces PDY1 = 0.740 and PDX1 = 0.778.
        assert!(close(t.lateral_curve(35.0).unwrap().d / 35_000.0, 0.740, 1e-3));
        assert!(close(t.longitudinal_curve(35.0).unwrap().d / 35_000.0, 0.778, 1e-3));
    }

    #[test]
    fn curves_are_odd_without_shifts_and_signs_follow_the_convention() {
        let t = Pac89Tyre::truck();
        for x in [0.001, 0.03, 0.2, 1.0] {
            let p = t.lateral(20_000.0, x).unwrap();
            let m = t.lateral(20_000.0, -x).unwrap();
            assert!(p.force > 0.0 && (p.force + m.force).abs() < 1e-9 * p.force);
            assert!((p.slope - m.slope).abs() < 1e-9 * p.slope.abs());
            let p = t.longitudinal(20_000.0, x).unwrap();
            let m = t.longitudinal(20_000.0, -x).unwrap();
            assert!(p.force > 0.0 && (p.force + m.force).abs() < 1e-9 * p.force);
        }
        assert_eq!(t.lateral(20_000.0, 0.0).unwrap().force, 0.0);
    }

    /// Central difference of `g` at `x` with step `h`.
    fn central(g: impl Fn(f64) -> f64, x: f64, h: f64) -> f64 {
        (g(x + h) - g(x - h)) / (2.0 * h)
    }

    #[test]
    fn slopes_match_central_differences() {
        let t = Pac89Tyre::truck();
        // Magic Formula itself, with shifts, in its own units.
        let mf = MagicFormula { b: 0.1, c: 1.6, d: 17_000.0, e: -0.5, sh: 0.3, sv: 120.0 };
        for x in [-15.0, -2.0, 0.0, 0.7, 4.0, 30.0] {
            let fd = central(|s| mf.evaluate(s).0, x, 1e-5);
            let slope = mf.evaluate(x).1;
            assert!((slope - fd).abs() <= 1e-8 * mf.bcd(), "x = {x}: {slope} vs {fd}");
        }
        for fz in [500.0, 16_000.0, 22_470.0, 32_740.0, 44_940.0] {
            for alpha in [-0.3, -0.02, 0.0, 0.004, 0.05, 0.4] {
                let fd = central(|a| t.lateral(fz, a).unwrap().force, alpha, 1e-7);
                let s = t.lateral(fz, alpha).unwrap().slope;
                assert!((s - fd).abs() <= 1e-7 * s.abs().max(1e3), "Fz {fz}, α {alpha}: {s} vs {fd}");
                let fd = central(|a| t.lateral_lumped(2, fz, a).unwrap().force, alpha, 1e-7);
                let s = t.lateral_lumped(2, fz, alpha).unwrap().slope;
                assert!((s - fd).abs() <= 1e-7 * s.abs().max(1e3), "lumped Fz {fz}, α {alpha}: {s} vs {fd}");
            }
            for slip in [-0.5, -0.03, 0.0, 0.002, 0.08, 0.9] {
                let fd = central(|s| t.longitudinal(fz, s).unwrap().force, slip, 1e-7);
                let s = t.longitudinal(fz, slip).unwrap().slope;
                assert!((s - fd).abs() <= 1e-7 * s.abs().max(1e3), "Fz {fz}, s {slip}: {s} vs {fd}");
                let fd = central(|s| t.longitudinal_lumped(2, fz, s).unwrap().force, slip, 1e-7);
                let s = t.longitudinal_lumped(2, fz, slip).unwrap().slope;
                assert!((s - fd).abs() <= 1e-7 * s.abs().max(1e3), "lumped Fz {fz}, s {slip}: {s} vs {fd}");
            }
        }
    }

    #[test]
    fn duals_are_lumped_as_n_times_half_load() {
        let t = Pac89Tyre::truck();
        let dual = t.lateral_lumped(2, 44_940.0, 0.02).unwrap();
        let one = t.lateral(22_470.0, 0.02).unwrap();
        assert_eq!(dual.force, 2.0 * one.force);
        assert_eq!(dual.slope, 2.0 * one.slope);
        // Load sensitivity: two tyres carry more than one tyre at twice the load.
        assert!(dual.force > t.lateral(44_940.0, 0.02).unwrap().force);
        // Axle cornering stiffness of the digest §4: front ≈ 375 kN/rad, each rear axle ≈ 535 kN/rad.
        let front = 2.0 * t.lateral(32_740.0, 0.0).unwrap().slope;
        let rear = 2.0 * t.lateral_lumped(2, 44_940.0, 0.0).unwrap().slope;
        assert!(close(front, 375e3, 2e-3), "front {front}");
        assert!(close(rear, 535e3, 2e-3), "rear {rear}");
        assert!(t.lateral_lumped(0, 1e4, 0.1).is_err());
    }

    #[test]
    fn load_clamp_fades_to_zero() {
        let t = Pac89Tyre::truck();
        let at_min = t.lateral(1000.0, 0.05).unwrap();
        let half = t.lateral(500.0, 0.05).unwrap();
        assert!((half.force - 0.5 * at_min.force).abs() < 1e-9 * at_min.force);
        assert!((half.peak - 0.5 * at_min.peak).abs() < 1e-9 * at_min.peak);
        for fz in [0.0, -3000.0] {
            let f = t.longitudinal(fz, 0.1).unwrap();
            assert_eq!((f.force, f.slope, f.peak), (0.0, 0.0, 0.0));
        }
    }

    #[test]
    fn friction_scale_lowers_the_peak_and_keeps_the_stiffness() {
        let t = Pac89Tyre { friction_scale: 0.8, ..Pac89Tyre::truck() };
        let nominal = Pac89Tyre::truck();
        let (a, b) = (t.lateral_curve(22.5).unwrap(), nominal.lateral_curve(22.5).unwrap());
        assert!(close(a.d, 0.8 * b.d, 1e-12) && close(a.bcd(), b.bcd(), 1e-12));
        let (a, b) = (t.longitudinal(22_500.0, 0.0).unwrap(), nominal.longitudinal(22_500.0, 0.0).unwrap());
        assert!(close(a.slope, b.slope, 1e-12));
    }

    #[test]
    fn bad_tyre_input_is_named() {
        let t = Pac89Tyre::truck();
        let e = t.lateral(f64::NAN, 0.1).unwrap_err().to_string();
        assert!(e.contains("F_z (tyre load)"), "{e}");
        let e = t.lateral(1e4, f64::INFINITY).unwrap_err().to_string();
        assert!(e.contains("alpha (tyre slip angle)"), "{e}");
        let e = t.longitudinal(1e4, f64::NAN).unwrap_err().to_string();
        assert!(e.contains("s (tyre slip ratio)"), "{e}");
        // Beyond the data's range: longitudinal E exceeds 1 above 74 kN, lateral D vanishes at 380 kN.
        let e = t.longitudinal(80_000.0, 0.01).unwrap_err().to_string();
        assert!(e.contains("E (curvature factor)") && e.contains("longitudinal"), "{e}");
        let e = t.lateral(400_000.0, 0.01).unwrap_err().to_string();
        assert!(e.contains("D (peak factor)"), "{e}");
        let mut bad = Pac89Tyre::truck();
        bad.coefficients.a[3] = f64::NAN;
        assert!(bad.validate().unwrap_err().to_string().contains("a3 (lateral cornering stiffness maximum)"));
        bad = Pac89Tyre { friction_scale: 0.0, ..Pac89Tyre::truck() };
        assert!(bad.validate().unwrap_err().to_string().contains("lambda_mu (tyre friction scale) must be positive"));
        bad = Pac89Tyre { fz_min: -1.0, ..Pac89Tyre::truck() };
        assert!(bad.validate().unwrap_err().to_string().contains("F_z,min"));
        bad = Pac89Tyre::truck();
        bad.coefficients.b[0] = 0.0;
        assert!(bad.validate().unwrap_err().to_string().contains("b0 (longitudinal shape factor C) must be positive"));
    }
}
