//! The continuous-time single-track car `ẋ = A x + B δ_f`, `y = C x` (eqs (1)–(5), (7)) and its
//! exact zero-order-hold discretisation (6).

use nalgebra::{Complex, DMatrix, DVector, Matrix4, RowVector4, Vector4};

use crate::error::CarError;
use crate::params::CarParams;
use models::error::check_finite;
use models::{
    ConstantModel, ContinuousModel, DifferentiableContinuousModel, Dims, LinearContinuous, ModelError, StepMatrices,
};

/// Number of states: `x = [Y, φ, β, r]`.
pub const STATE_DIM: usize = 4;
/// Number of inputs: `u = [δ_f]`.
pub const INPUT_DIM: usize = 1;
/// Number of outputs: `y = Y` (one noisy position sensor).
pub const OUTPUT_DIM: usize = 1;

/// Index of the lateral position `Y` \[m\] in the state (the paper's `x1`, see the crate docs).
pub const LATERAL_POSITION: usize = 0;
/// Index of the heading `φ` \[rad\] in the state.
pub const HEADING: usize = 1;
/// Index of the sideslip angle at the CG `β` \[rad\] in the state.
pub const SIDESLIP: usize = 2;
/// Index of the yaw rate `r` \[rad/s\] in the state.
pub const YAW_RATE: usize = 3;

/// State matrix type (4 × 4).
pub type StateMatrix = Matrix4<f64>;
/// Input matrix type (4 × 1): the column of the front steering angle.
pub type InputMatrix = Vector4<f64>;
/// Output matrix type (1 × 4).
pub type OutputMatrix = RowVector4<f64>;
/// State vector `[Y, φ, β, r]` (m, rad, rad, rad/s).
pub type StateVector = Vector4<f64>;

/// The validated continuous-time single-track car `ẋ = A x + B δ_f` (5), `y = C x` (7).
///
/// With `x = [Y, φ, β, r]` (R), the axle forces (2) in the lateral and yaw balances (1) and the
/// small-angle kinematics `Y' ≈ v_x (φ + β)` (4) give
///
/// ```text
/// A = [[0, v_x, v_x, 0],
///      [0, 0,   0,   1],
///      [0, 0,   −(C_f + C_r)/(m v_x),   (b C_r − a C_f)/(m v_x²) − 1],
///      [0, 0,   (b C_r − a C_f)/I_z,    −(a² C_f + b² C_r)/(I_z v_x)]]
/// B = [0, 0, C_f/(m v_x), a C_f/I_z]ᵀ
/// C = [1, 0, 0, 0]                                   (P, eq (7))
/// ```
///
/// `A` is block upper triangular: the integrators `Y`, `φ` (a double eigenvalue 0, one Jordan
/// block) and the yaw–sideslip ("lateral") block of `β`, `r`
/// ([`CarModel::lateral_eigenvalues`], `≈ −7.9 ± 1.1j` for the default set).
///
/// The model is also a [`models::ContinuousModel`] (with Jacobians), so
/// `models::Discretized` integrates it with Euler or RK4.
#[derive(Debug, Clone, PartialEq)]
pub struct CarModel {
    params: CarParams,
    a: StateMatrix,
    b: InputMatrix,
    linear: LinearContinuous,
}

impl CarModel {
    /// Validates `params` ([`CarParams::validate`]) and builds `A`, `B` of eq (5) and `C` of
    /// eq (7).
    ///
    /// # Errors
    /// The validation error naming the offending parameter, or
    /// [`CarError::Model`]`(`[`ModelError::NonFiniteEntry`]`)` if finite but extreme parameters
    /// overflow `A` or `B`.
    pub fn new(params: CarParams) -> Result<Self, CarError> {
        params.validate()?;
        let p = &params;
        let (m, iz, v) = (p.mass, p.yaw_inertia, p.speed);
        let (a, b) = (p.front_axle_distance, p.rear_axle_distance);
        let (cf, cr) = (p.front_cornering_stiffness, p.rear_cornering_stiffness);
        let moment = b * cr - a * cf;

        #[rustfmt::skip]
        let a_c = StateMatrix::new(
            0.0, v,   v,                       0.0,
            0.0, 0.0, 0.0,                     1.0,
            0.0, 0.0, -(cf + cr) / (m * v),    moment / (m * v * v) - 1.0,
            0.0, 0.0, moment / iz,             -(a * a * cf + b * b * cr) / (iz * v),
        );
        let b_c = InputMatrix::new(0.0, 0.0, cf / (m * v), a * cf / iz);
        check_finite("continuous-time state matrix A", &a_c)?;
        check_finite("continuous-time input matrix B", &b_c)?;
        let linear = LinearContinuous::new(
            DMatrix::from_column_slice(STATE_DIM, STATE_DIM, a_c.as_slice()),
            DMatrix::from_column_slice(STATE_DIM, INPUT_DIM, b_c.as_slice()),
            DMatrix::from_row_slice(OUTPUT_DIM, STATE_DIM, &[1.0, 0.0, 0.0, 0.0]),
        )?;
        Ok(Self { params, a: a_c, b: b_c, linear })
    }

    /// The validated parameters.
    #[must_use]
    pub fn params(&self) -> &CarParams {
        &self.params
    }

    /// State matrix `A` of eq (5).
    #[must_use]
    pub fn a(&self) -> &StateMatrix {
        &self.a
    }

    /// Input matrix `B` of eq (5) (the column of `δ_f`).
    #[must_use]
    pub fn b(&self) -> &InputMatrix {
        &self.b
    }

    /// Output matrix `C = [1, 0, 0, 0]` of eq (7) (P): one noisy sensor of the lateral position
    /// `Y`.
    #[must_use]
    pub fn c(&self) -> OutputMatrix {
        OutputMatrix::new(1.0, 0.0, 0.0, 0.0)
    }

    /// The same model as a dynamically sized [`LinearContinuous`] (`A`, `B`, `C`), for the
    /// `models` tools (`zoh`, `euler`, Van Loan).
    #[must_use]
    pub fn continuous(&self) -> &LinearContinuous {
        &self.linear
    }

    /// `ẋ = A x + B δ_f` (5).
    #[must_use]
    pub fn derivative(&self, x: &StateVector, steering: f64) -> StateVector {
        self.a * x + self.b * steering
    }

    /// Noise-free measurement `y = C x = Y` (7).
    #[must_use]
    pub fn measure(&self, x: &StateVector) -> f64 {
        x[LATERAL_POSITION]
    }

    /// The two eigenvalues of the yaw–sideslip block `A[2..4, 2..4]` (closed form), ordered by
    /// imaginary part (real pairs: by real part). The other two eigenvalues of `A` are the
    /// integrators' `0, 0`. For the default set, `≈ −7.9 ± 1.1j` (V).
    #[must_use]
    pub fn lateral_eigenvalues(&self) -> [Complex<f64>; 2] {
        let (p, q, r, s) = (self.a[(2, 2)], self.a[(2, 3)], self.a[(3, 2)], self.a[(3, 3)]);
        let half_trace = 0.5 * (p + s);
        let disc = 0.25 * (p - s) * (p - s) + q * r;
        if disc >= 0.0 {
            let d = disc.sqrt();
            [Complex::new(half_trace - d, 0.0), Complex::new(half_trace + d, 0.0)]
        } else {
            let d = (-disc).sqrt();
            [Complex::new(half_trace, -d), Complex::new(half_trace, d)]
        }
    }

    /// All four eigenvalues of `A`: `0, 0` (integrators of `Y` and `φ`), then
    /// [`CarModel::lateral_eigenvalues`].
    #[must_use]
    pub fn eigenvalues(&self) -> [Complex<f64>; 4] {
        let [l1, l2] = self.lateral_eigenvalues();
        [Complex::new(0.0, 0.0), Complex::new(0.0, 0.0), l1, l2]
    }

    /// Whether the yaw–sideslip modes are asymptotically stable (both lateral eigenvalues in
    /// the open left half-plane). `Y` and `φ` are pure integrators and never decay.
    #[must_use]
    pub fn is_laterally_stable(&self) -> bool {
        self.lateral_eigenvalues().iter().all(|l| l.re < 0.0)
    }

    /// Exact zero-order-hold discretisation (6) with period `ts` \[s\] (A; the paper does not
    /// say how it discretises): `A_c = e^{A T_s}`, `B_c = ∫₀^{T_s} e^{Aτ} dτ B`, `C` unchanged,
    /// from `expm([[A, B], [0, 0]] T_s) = [[A_c, B_c], [0, 1]]`
    /// ([`models::LinearContinuous::zoh`]). The paper's period is
    /// [`crate::DIGEST_SAMPLING_PERIOD`] `= 0.5 s`.
    ///
    /// Forward Euler (`models::LinearContinuous::euler`) is **not** offered here: at 0.5 s it
    /// maps the yaw–sideslip modes to moduli ≈ 3 (unstable; see the crate's tests).
    ///
    /// # Errors
    /// [`CarError::Model`]`(`[`ModelError::InvalidSamplingPeriod`]`)` unless `ts` is positive
    /// and finite, or an exponential failure (see [`models::expm`]).
    pub fn discretize(&self, ts: f64) -> Result<ConstantModel, CarError> {
        let StepMatrices { a, b, c } = self.linear.zoh(ts)?;
        Ok(ConstantModel::new(a, b, c)?)
    }
}

impl ContinuousModel for CarModel {
    fn dims(&self) -> Dims {
        Dims::new(STATE_DIM, INPUT_DIM, OUTPUT_DIM)
    }
    fn derivative(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        self.linear.derivative(x, u, out)
    }
    fn output(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        self.linear.output(x, u, out)
    }
}

impl DifferentiableContinuousModel for CarModel {
    fn derivative_jacobian(
        &self,
        x: &DVector<f64>,
        u: &DVector<f64>,
        out: &mut DMatrix<f64>,
    ) -> Result<(), ModelError> {
        self.linear.derivative_jacobian(x, u, out)
    }
    fn output_jacobian(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        self.linear.output_jacobian(x, u, out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use models::Xoshiro256StarStar;

    /// `[Y', φ', β', r']` straight from eqs (1)–(4): axle forces (2), lateral and yaw balances
    /// (1), small-angle kinematics (4).
    fn from_equations(p: &CarParams, x: &StateVector, delta: f64) -> StateVector {
        let (y_dot_phi, beta, r) = (x[HEADING], x[SIDESLIP], x[YAW_RATE]);
        let (m, iz, v) = (p.mass, p.yaw_inertia, p.speed);
        let (a, b) = (p.front_axle_distance, p.rear_axle_distance);
        let fyf = p.front_cornering_stiffness * (delta - beta - a * r / v);
        let fyr = p.rear_cornering_stiffness * (-beta + b * r / v);
        let beta_dot = (fyf + fyr) / (m * v) - r;
        let r_dot = (a * fyf - b * fyr) / iz;
        StateVector::new(v * (y_dot_phi + beta), r, beta_dot, r_dot)
    }

    #[test]
    fn matrices_match_equations_1_to_4() {
        let mut rng = Xoshiro256StarStar::seed_from_u64(12);
        for (i, p) in
            [CarParams::digest_default(), CarParams::digest_alternative(), CarParams::digest_default().with_speed(3.0)]
                .into_iter()
                .enumerate()
        {
            let model = CarModel::new(p).unwrap();
            for _ in 0..200 {
                let x = StateVector::from_fn(|_, _| rng.next_f64() * 2.0 - 1.0);
                let delta = (rng.next_f64() - 0.5) * 0.1;
                let want = from_equations(&p, &x, delta);
                let got = model.derivative(&x, delta);
                for k in 0..4 {
                    let scale = (model.a().row(k).abs() * x.abs())[0] + model.b()[k].abs() * delta.abs();
                    assert!((got[k] - want[k]).abs() <= 1e-12 * scale.max(1e-300), "set {i}, row {k}");
                }
            }
        }
    }

    #[test]
    fn default_lateral_modes_match_the_digest() {
        let model = CarModel::new(CarParams::digest_default()).unwrap();
        let [lo, hi] = model.lateral_eigenvalues();
        // Digest (V): λ ≈ −7.9 ± 1.1j.
        // Measured: −7.8839 ± 1.0926j.
        assert!((lo.re + 7.9).abs() < 0.05 && (hi.re + 7.9).abs() < 0.05, "{lo} {hi}");
        assert!((lo.im + 1.1).abs() < 0.05 && (hi.im - 1.1).abs() < 0.05, "{lo} {hi}");
        assert!(model.is_laterally_stable());
        // The closed form agrees with nalgebra's eigenvalues of A.
        let mut e: Vec<Complex<f64>> = model.a().complex_eigenvalues().iter().copied().collect();
        e.sort_by(|x, y| x.re.total_cmp(&y.re).then(x.im.total_cmp(&y.im)));
        assert!((e[0] - lo).norm() < 1e-9 && (e[1] - hi).norm() < 1e-9, "{e:?}");
        assert!(e[2].norm() < 1e-6 && e[3].norm() < 1e-6, "{e:?}");
        let all = model.eigenvalues();
        assert_eq!(all[0], Complex::new(0.0, 0.0));
        assert_eq!(all[3], hi);
    }

    #[test]
    fn both_sets_are_laterally_stable_from_1_to_60_m_per_s() {
        for p in [CarParams::digest_default(), CarParams::digest_alternative()] {
            for v in 1..=60 {
                let model = CarModel::new(p.with_speed(f64::from(v))).unwrap();
                assert!(model.is_laterally_stable(), "v = {v}: {:?}", model.lateral_eigenvalues());
            }
        }
        // An oversteering car above its critical speed is a valid, laterally unstable model.
        let oversteer = CarParams { rear_cornering_stiffness: 30_000.0, ..CarParams::digest_default() };
        assert!(oversteer.understeer_moment() < 0.0);
        let model = CarModel::new(oversteer.with_speed(60.0)).unwrap();
        assert!(!model.is_laterally_stable(), "{:?}", model.lateral_eigenvalues());
    }

    #[test]
    fn output_and_matrices_have_the_digest_structure() {
        let model = CarModel::new(CarParams::digest_default()).unwrap();
        assert_eq!(model.c(), OutputMatrix::new(1.0, 0.0, 0.0, 0.0));
        assert_eq!(model.continuous().c, DMatrix::from_row_slice(1, 4, &[1.0, 0.0, 0.0, 0.0]));
        assert_eq!(model.continuous().a.as_slice(), model.a().as_slice());
        assert_eq!(model.continuous().b.as_slice(), model.b().as_slice());
        assert_eq!(model.a()[(0, 1)], 25.0);
        assert_eq!(model.a()[(0, 2)], 25.0);
        assert_eq!(model.a()[(1, 3)], 1.0);
        assert_eq!(model.b()[0], 0.0);
        assert_eq!(model.b()[1], 0.0);
        assert_eq!(model.measure(&StateVector::new(-2.0, 0.1, 0.2, 0.3)), -2.0);
        assert_eq!(ContinuousModel::dims(&model), Dims::new(4, 1, 1));
    }

    #[test]
    fn overflowing_parameters_and_bad_periods_are_reported() {
        let p = CarParams { mass: 1e-310, ..CarParams::digest_default() };
        let e = CarModel::new(p).unwrap_err();
        assert_eq!(e.to_string(), "continuous-time state matrix A has a non-finite entry at (2, 2)");
        let e = CarModel::new(CarParams::digest_default().with_speed(0.0)).unwrap_err();
        assert_eq!(e.to_string(), "parameter v_x (longitudinal speed) must be positive, got 0");
        let model = CarModel::new(CarParams::digest_default()).unwrap();
        for ts in [0.0, -0.5, f64::NAN, f64::INFINITY] {
            let e = model.discretize(ts).unwrap_err();
            assert!(matches!(e, CarError::Model(ModelError::InvalidSamplingPeriod(_))), "{e:?}");
        }
    }
}
