//! The vessel's data: the non-dimensional ("bis") coefficients of Fossen, Sagatun & Sørensen
//! (1996), their conversion to SI (docs/dp-vessel.md, (1)–(4) reconstructed, after MSS
//! `supply.m`), the thrust limits and the simulated force noise (§4 of the note).

use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

use models::validate::{finite, positive};

use crate::error::VesselError;

/// Non-dimensional (bis system) inertia and damping coefficients of the supply vessel.
///
/// `M = m·[[m11, 0, 0], [0, m22, L·m23], [0, L·m32, L²·m33]]` and
/// `D = m·√(g/L)·[[d11, 0, 0], [0, d22, L·d23], [0, L·d32, L²·d33]]` ([`bis_to_si`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BisCoefficients {
    /// `m11` (surge inertia including added mass).
    pub m11: f64,
    /// `m22` (sway inertia including added mass).
    pub m22: f64,
    /// `m33` (yaw inertia including added mass).
    pub m33: f64,
    /// `m23` (sway–yaw coupling; 0 in the paper **\[P\]**, −0.0744 in MSS).
    pub m23: f64,
    /// `m32` (yaw–sway coupling; 0 in the paper **\[P\]**, −0.0744 in MSS).
    pub m32: f64,
    /// `d11` (surge damping).
    pub d11: f64,
    /// `d22` (sway damping).
    pub d22: f64,
    /// `d23` (sway–yaw damping).
    pub d23: f64,
    /// `d32` (yaw–sway damping).
    pub d32: f64,
    /// `d33` (yaw damping).
    pub d33: f64,
}

impl BisCoefficients {
    /// The paper's coefficients (§4 of docs/dp-vessel.md, **\[P\]**): `m11 = 1.1274`,
    /// `m22 = 1.8902`, `m33 = 0.1278`, `m23 = m32 = 0`, `d11 = 0.0358`, `d22 = 0.1183`,
    /// `d23 = −0.0124`, `d32 = −0.0041`, `d33 = 0.0308`.
    #[must_use]
    pub fn paper() -> Self {
        Self {
            m11: 1.1274,
            m22: 1.8902,
            m33: 0.1278,
            m23: 0.0,
            m32: 0.0,
            d11: 0.0358,
            d22: 0.1183,
            d23: -0.0124,
            d32: -0.0041,
            d33: 0.0308,
        }
    }

    fn named(&self) -> [(&'static str, f64); 10] {
        [
            ("m11 (bis surge inertia)", self.m11),
            ("m22 (bis sway inertia)", self.m22),
            ("m33 (bis yaw inertia)", self.m33),
            ("m23 (bis sway-yaw inertia)", self.m23),
            ("m32 (bis yaw-sway inertia)", self.m32),
            ("d11 (bis surge damping)", self.d11),
            ("d22 (bis sway damping)", self.d22),
            ("d23 (bis sway-yaw damping)", self.d23),
            ("d32 (bis yaw-sway damping)", self.d32),
            ("d33 (bis yaw damping)", self.d33),
        ]
    }
}

/// The SI matrices of the low-speed model `M ν' + D ν = τ`, with `M⁻¹` and `M⁻¹ D` precomputed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SiMatrices {
    /// Inertia matrix `M` \[kg, kg, kg m²\] (rigid body plus added mass).
    pub m: Matrix3<f64>,
    /// Linear damping matrix `D` \[kg/s, kg m/s, kg m²/s\].
    pub d: Matrix3<f64>,
    /// `M⁻¹`.
    pub m_inv: Matrix3<f64>,
    /// `M⁻¹ D` \[1/s\].
    pub m_inv_d: Matrix3<f64>,
}

/// Converts bis coefficients to SI (docs/dp-vessel.md §1, the conversion of MSS `supply.m` with
/// `T = diag(1, 1, 1/L)`): `M = m·[[m11, 0, 0], [0, m22, L·m23], [0, L·m32, L²·m33]]`,
/// `D = m·√(g/L)·[[d11, 0, 0], [0, d22, L·d23], [0, L·d32, L²·d33]]`.
///
/// # Errors
/// [`VesselError::Parameter`] naming a coefficient, the mass, the
/// length or `g` (`m11`, `m22`, `m33`, `m`, `L`, `g` must be positive, the rest finite);
/// [`VesselError::MassNotPositiveDefinite`] when the symmetric part of `M` is not positive
/// definite.
pub fn bis_to_si(bis: &BisCoefficients, mass: f64, length: f64, gravity: f64) -> Result<SiMatrices, VesselError> {
    positive("m (mass)", mass)?;
    positive("L (length between perpendiculars)", length)?;
    positive("g (gravitational acceleration)", gravity)?;
    for (i, (name, value)) in bis.named().into_iter().enumerate() {
        if i < 3 { positive(name, value)? } else { finite(name, value)? }
    }
    let l = length;
    let m = mass * Matrix3::new(bis.m11, 0.0, 0.0, 0.0, bis.m22, l * bis.m23, 0.0, l * bis.m32, l * l * bis.m33);
    let d = mass
        * (gravity / l).sqrt()
        * Matrix3::new(bis.d11, 0.0, 0.0, 0.0, bis.d22, l * bis.d23, 0.0, l * bis.d32, l * l * bis.d33);
    // Positive definite symmetric part: leading principal minors (Sylvester), scaled.
    let sym = (m + m.transpose()) * 0.5;
    let scale = Matrix3::from_diagonal(&sym.diagonal().map(|v| 1.0 / v.sqrt()));
    let s = scale * sym * scale;
    let minors = [s[(0, 0)], s.fixed_view::<2, 2>(0, 0).determinant(), s.determinant()];
    let minor = minors.iter().copied().fold(f64::INFINITY, f64::min);
    if minor.is_nan() || minor <= 1e-12 {
        return Err(VesselError::MassNotPositiveDefinite { minor });
    }
    let Some(m_inv) = m.try_inverse() else {
        return Err(VesselError::MassNotPositiveDefinite { minor: 0.0 });
    };
    Ok(SiMatrices { m, d, m_inv, m_inv_d: m_inv * d })
}

/// Element-wise thrust limits `|τ_i| ≤ τ_max,i` (surge force, sway force, yaw moment).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThrustLimits {
    /// `[τ_max,X (N), τ_max,Y (N), τ_max,N (N m)]`.
    pub max: [f64; 3],
}

const THRUST_NAMES: [&str; 3] =
    ["surge thrust limit tau_max,X", "sway thrust limit tau_max,Y", "yaw moment limit tau_max,N"];

impl ThrustLimits {
    /// The paper's limits **\[P\]**: ±1e6 N, ±3e5 N, ±7.62e6 N m.
    #[must_use]
    pub fn paper() -> Self {
        Self { max: [1e6, 3e5, 7.62e6] }
    }

    /// Validated limits.
    ///
    /// # Errors
    /// [`VesselError::Parameter`] naming the limit.
    pub fn new(max: [f64; 3]) -> Result<Self, VesselError> {
        let limits = Self { max };
        limits.validate()?;
        Ok(limits)
    }

    /// Checks that every limit is positive and finite.
    ///
    /// # Errors
    /// As [`ThrustLimits::new`].
    pub fn validate(&self) -> Result<(), VesselError> {
        for i in 0..3 {
            positive(THRUST_NAMES[i], self.max[i])?;
        }
        Ok(())
    }

    /// Clips `tau` element-wise to the limits (docs/dp-vessel.md (60)–(61), assumed); returns
    /// which components were clipped. NaN components are left as they are and reported clipped.
    pub fn saturate(&self, tau: &mut Vector3<f64>) -> [bool; 3] {
        let mut clipped = [false; 3];
        for i in 0..3 {
            let lim = self.max[i];
            if tau[i].is_nan() {
                clipped[i] = true;
            } else if tau[i] > lim {
                tau[i] = lim;
                clipped[i] = true;
            } else if tau[i] < -lim {
                tau[i] = -lim;
                clipped[i] = true;
            }
        }
        clipped
    }

    /// The limits as a vector.
    #[must_use]
    pub fn as_vector(&self) -> Vector3<f64> {
        Vector3::from(self.max)
    }
}

/// White Gaussian force noise added to the applied thrust in simulation (the digest's
/// disturbance, §4, **\[A\]**): `w_τ ~ N(0, diag(σ²))`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ForceNoise {
    /// Standard deviations `[σ_X (N), σ_Y (N), σ_N (N m)]`.
    pub sigma: [f64; 3],
}

impl ForceNoise {
    /// The digest's force noise **\[A\]**: σ = (2e4 N, 6e3 N, 1.5e5 N m).
    #[must_use]
    pub fn digest() -> Self {
        Self { sigma: [2e4, 6e3, 1.5e5] }
    }

    /// The covariance `diag(σ²)` as a [`models::Noise`] for the simulator.
    ///
    /// # Errors
    /// [`VesselError::Parameter`] naming a standard deviation
    /// (use [`models::Noise::none`] for no noise).
    pub fn to_noise(&self) -> Result<models::Noise, VesselError> {
        for (i, name) in ["sigma_X (surge force noise)", "sigma_Y (sway force noise)", "sigma_N (yaw moment noise)"]
            .into_iter()
            .enumerate()
        {
            positive(name, self.sigma[i])?;
        }
        let cov = DMatrix::from_diagonal(&DVector::from_iterator(3, self.sigma.iter().map(|s| s * s)));
        Ok(models::Noise::gaussian(cov)?)
    }
}

/// Everything that defines the vessel: mass, length, `g`, bis coefficients and thrust limits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VesselParams {
    /// Displacement mass `m` \[kg\].
    pub mass: f64,
    /// Length between perpendiculars `L` \[m\].
    pub length: f64,
    /// Gravitational acceleration `g` \[m/s²\].
    pub gravity: f64,
    /// Non-dimensional coefficients.
    pub bis: BisCoefficients,
    /// Thrust limits.
    pub thrust: ThrustLimits,
}

impl VesselParams {
    /// The paper's vessel (docs/dp-vessel.md §4): `m = 4.2e6 kg` **\[P\]** (MSS uses 6000 t),
    /// `L = 76.2 m` **\[P\]**, `g = 9.81 m/s²` **\[A\]** (MSS uses 9.8),
    /// [`BisCoefficients::paper`], [`ThrustLimits::paper`].
    #[must_use]
    pub fn paper() -> Self {
        Self { mass: 4.2e6, length: 76.2, gravity: 9.81, bis: BisCoefficients::paper(), thrust: ThrustLimits::paper() }
    }

    /// Checks every parameter and returns the SI matrices.
    ///
    /// # Errors
    /// As [`bis_to_si`] and [`ThrustLimits::validate`].
    pub fn validate(&self) -> Result<SiMatrices, VesselError> {
        self.thrust.validate()?;
        bis_to_si(&self.bis, self.mass, self.length, self.gravity)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use models::validate::ParamError;

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    /// The digest's SI matrices (§2, values printed to 6 significant digits).
    #[test]
    fn paper_matrices_match_the_digest() {
        let si = VesselParams::paper().validate().unwrap();
        let want_m = [4.73508e6, 7.93884e6, 3.11666e9];
        for i in 0..3 {
            assert!(rel(si.m[(i, i)], want_m[i]) < 5e-6, "M{i}{i} = {}", si.m[(i, i)]);
        }
        assert_eq!(si.m[(1, 2)], 0.0);
        assert_eq!(si.m[(2, 1)], 0.0);
        let want_d = [(0, 0, 5.39497e4), (1, 1, 1.78275e5), (1, 2, -1.42391e6), (2, 1, -4.70809e5), (2, 2, 2.69505e8)];
        for (i, j, v) in want_d {
            assert!(rel(si.d[(i, j)], v) < 5e-6, "D{i}{j} = {}", si.d[(i, j)]);
        }
        assert!((si.m * si.m_inv - Matrix3::identity()).amax() < 1e-14);
        // Digest §2: maximum accelerations at the thrust limits, open-loop time constants.
        let lim = ThrustLimits::paper().max;
        for (i, a) in [0.211, 0.0378, 2.44e-3].into_iter().enumerate() {
            assert!(rel(lim[i] / si.m[(i, i)], a) < 5e-3, "axis {i}");
        }
        // Printed to one decimal: within half a unit of the last digit.
        for (i, t) in [87.8, 44.5, 11.6].into_iter().enumerate() {
            assert!((si.m[(i, i)] / si.d[(i, i)] - t).abs() <= 0.05, "axis {i}");
        }
    }

    /// The conversion against the hand-written formula on made-up coefficients with coupling.
    #[test]
    fn bis_to_si_follows_the_scaling_law() {
        let bis = BisCoefficients { m23: -0.0744, m32: -0.0744, ..BisCoefficients::paper() };
        let (m, l, g) = (6e6, 76.2, 9.8);
        let si = bis_to_si(&bis, m, l, g).unwrap();
        assert!(rel(si.m[(1, 2)], m * l * -0.0744) < 1e-15);
        assert!(rel(si.m[(2, 2)], m * l * l * 0.1278) < 1e-15);
        assert!(rel(si.d[(2, 1)], m * (g / l).sqrt() * l * -0.0041) < 1e-15);
        assert!(rel(si.d[(0, 0)], m * (g / l).sqrt() * 0.0358) < 1e-15);
        assert!((si.m_inv_d - si.m.try_inverse().unwrap() * si.d).amax() < 1e-12);
    }

    #[test]
    fn bad_parameters_are_typed_errors() {
        let p = VesselParams { mass: -1.0, ..VesselParams::paper() };
        assert!(matches!(p.validate(), Err(VesselError::Parameter(ParamError::NotPositive { name: "m (mass)", .. }))));
        let p = VesselParams { length: f64::NAN, ..VesselParams::paper() };
        assert!(matches!(p.validate(), Err(VesselError::Parameter(ParamError::NonFinite { .. }))));
        let bis = BisCoefficients { d23: f64::INFINITY, ..BisCoefficients::paper() };
        let e = bis_to_si(&bis, 1.0, 1.0, 1.0).unwrap_err();
        assert_eq!(e.to_string(), "parameter d23 (bis sway-yaw damping) must be finite, got inf");
        // A huge coupling makes M indefinite.
        let bis = BisCoefficients { m23: 1.0, m32: 1.0, ..BisCoefficients::paper() };
        assert!(matches!(bis_to_si(&bis, 4.2e6, 76.2, 9.81), Err(VesselError::MassNotPositiveDefinite { .. })));
        assert!(ThrustLimits::new([1.0, 0.0, 1.0]).is_err());
        assert!(ForceNoise { sigma: [1.0, -1.0, 1.0] }.to_noise().is_err());
        assert_eq!(ForceNoise::digest().to_noise().unwrap().dim(), 3);
    }

    #[test]
    fn saturation_clips_element_wise() {
        let lim = ThrustLimits::paper();
        let mut tau = Vector3::new(2e6, -1e5, -1e7);
        assert_eq!(lim.saturate(&mut tau), [true, false, true]);
        assert_eq!(tau, Vector3::new(1e6, -1e5, -7.62e6));
    }
}
