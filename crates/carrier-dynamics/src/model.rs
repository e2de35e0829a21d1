//! Continuous-time model `ẋ = A x + B u` (paper eqs (4)–(7)) and its ZOH discretisation
//! (eqs (10)–(11)).

use nalgebra::{Complex, DMatrix, Matrix4, SMatrix, SVector, Schur};

use crate::error::{DynamicsError, check_finite};
use crate::params::CarrierParams;
use models::{Dims, LinearTimeVarying, ModelError, StepMatrices, zoh_discretize_fixed};

/// Number of states: `x = [β, γ, φ, φ̇]`.
pub const STATE_DIM: usize = 4;
/// Number of inputs: `u = [δl1, δl2, δl3, δl4, δr1, δr2, δr3, δr4]`.
pub const INPUT_DIM: usize = 8;
/// Number of outputs (`y = C x`, `C = I₄`).
pub const OUTPUT_DIM: usize = 4;

/// State matrix type (4 × 4).
pub type StateMatrix = SMatrix<f64, STATE_DIM, STATE_DIM>;
/// Input matrix type (4 × 8).
pub type InputMatrix = SMatrix<f64, STATE_DIM, INPUT_DIM>;
/// State vector `[β, γ, φ, φ̇]` (rad, rad/s, rad, rad/s).
pub type StateVector = SVector<f64, STATE_DIM>;
/// Input vector of the eight steering angles (rad), left wheels of rows 1..4 then right wheels.
pub type InputVector = SVector<f64, INPUT_DIM>;

/// Row (0-based, rows 1..4 → 0..3) and stiffness of input `j` (0..8): inputs 0..4 are the
/// left wheels of rows 1..4, inputs 4..8 the right wheels.
fn wheel(p: &CarrierParams, j: usize) -> (usize, f64) {
    if j < 4 { (j, p.stiffness_left[j]) } else { (j - 4, p.stiffness_right[j - 4]) }
}

/// `+1` for rows 1, 2 (ahead of the CG), `−1` for rows 3, 4 (behind).
fn row_sign(row: usize) -> f64 {
    if row < 2 { 1.0 } else { -1.0 }
}

/// The validated continuous-time straddle-carrier model `ẋ = A x + B u`, `y = C x` (eq (7)).
///
/// Derivation (paper eqs (4)–(6)). For the wheel of row `i` with stiffness `K` and steering
/// angle `δ`, the slip is `α = β + σ_i L_i γ / v − δ` (`σ_i = +1` for rows 1, 2 and `−1` for
/// rows 3, 4) and the lateral force `F = −K α`, so a positive steering angle gives a positive
/// force. With `ΣK = Σ K`, `a = Σ σ_i L_i K`, `b = Σ L_i² K` over the eight wheels:
///
/// * yaw (5), `I_z γ̇ = Σ σ_i L_i F`: rear-row forces enter **with a minus sign**, so the
///   `γ`-row entry of `B` is `σ_i L_i K / I_z` (negative for rows 3, 4). The paper prints
///   `+L_i K / I_z` for every row; this crate follows eq (5).
/// * lateral (4) and roll (6) are solved together for `β̇` and `φ̈` (a 2 × 2 system whose
///   determinant is `m v I_x`): `φ̈ = (h ΣF + m g h φ − C_φ φ̇ − K_φ φ)/I_x` and
///   `β̇ = ΣF·I_xeq/(m v I_x) + h (m g h φ − C_φ φ̇ − K_φ φ)/(I_x v) − γ`,
///   with `I_x = I_xeq − m h²`.
#[derive(Debug, Clone, PartialEq)]
pub struct CarrierModel {
    params: CarrierParams,
    a: StateMatrix,
    b: InputMatrix,
}

impl CarrierModel {
    /// Validates `params` ([`CarrierParams::validate`]) and builds `A` and `B` (eq (7)).
    ///
    /// # Errors
    /// The validation error naming the offending parameter, or
    /// [`DynamicsError::Model`] with [`models::ModelError::NonFiniteEntry`] if finite but extreme
    /// parameters overflow `A` or `B`.
    pub fn new(params: CarrierParams) -> Result<Self, DynamicsError> {
        params.validate()?;
        let p = &params;
        let (m, h, v, g) = (p.mass, p.cg_height, p.speed, p.gravity);
        let i_x = p.roll_inertia_cg();
        let i_xeq = p.roll_inertia_eq();
        let (k_phi, c_phi, i_z) = (p.roll_stiffness, p.roll_damping, p.yaw_inertia);

        let (mut sum_k, mut a_k, mut b_k) = (0.0, 0.0, 0.0);
        for j in 0..INPUT_DIM {
            let (row, k) = wheel(p, j);
            let l = p.row_distances[row];
            sum_k += k;
            a_k += row_sign(row) * l * k;
            b_k += l * l * k;
        }
        let roll_spring = m * g * h - k_phi; // coefficient of φ in m g h φ − K_φ φ

        #[rustfmt::skip]
        let a = StateMatrix::new(
            -sum_k * i_xeq / (m * v * i_x), -a_k * i_xeq / (m * v * v * i_x) - 1.0, h * roll_spring / (i_x * v), -h * c_phi / (i_x * v),
            -a_k / i_z,                     -b_k / (i_z * v),                        0.0,                          0.0,
            0.0,                            0.0,                                     0.0,                          1.0,
            -sum_k * h / i_x,               -a_k * h / (i_x * v),                    roll_spring / i_x,            -c_phi / i_x,
        );
        let mut b = InputMatrix::zeros();
        for j in 0..INPUT_DIM {
            let (row, k) = wheel(p, j);
            let l = p.row_distances[row];
            b[(0, j)] = k * i_xeq / (m * v * i_x);
            b[(1, j)] = row_sign(row) * l * k / i_z;
            b[(3, j)] = h * k / i_x;
        }
        check_finite("continuous-time state matrix A", &a)?;
        check_finite("continuous-time input matrix B", &b)?;
        Ok(Self { params, a, b })
    }

    /// The validated parameters.
    #[must_use]
    pub fn params(&self) -> &CarrierParams {
        &self.params
    }

    /// State matrix `A` of eq (7).
    #[must_use]
    pub fn a(&self) -> &StateMatrix {
        &self.a
    }

    /// Input matrix `B` of eq (7); column `j` belongs to input `u_j`.
    #[must_use]
    pub fn b(&self) -> &InputMatrix {
        &self.b
    }

    /// Output matrix `C = I₄` (all four states measured, paper §1).
    #[must_use]
    pub fn c(&self) -> Matrix4<f64> {
        Matrix4::identity()
    }

    /// `ẋ = A x + B u`.
    #[must_use]
    pub fn derivative(&self, x: &StateVector, u: &InputVector) -> StateVector {
        self.a * x + self.b * u
    }

    /// Eigenvalues of `A` (real Schur form), or `None` if the QR iteration does not converge
    /// (not observed for finite matrices of this size).
    #[must_use]
    pub fn eigenvalues(&self) -> Option<SVector<Complex<f64>, STATE_DIM>> {
        Schur::try_new(self.a, f64::EPSILON, 10_000).map(|s| s.complex_eigenvalues())
    }

    /// Whether every eigenvalue of `A` has a negative real part (`false` if the eigenvalue
    /// computation fails).
    #[must_use]
    pub fn is_stable(&self) -> bool {
        self.eigenvalues().is_some_and(|e| e.iter().all(|l| l.re < 0.0))
    }

    /// Exact zero-order-hold discretisation with period `ts` \[s\] (eqs (10)–(11)):
    /// `A_p = e^{A T_s}`, `B_p = ∫₀^{T_s} e^{Aτ} dτ B`, `C_p = C`.
    ///
    /// # Errors
    /// [`DynamicsError::Model`] with [`models::ModelError::InvalidSamplingPeriod`] unless `ts` is
    /// positive and finite, or an
    /// exponential failure (see [`models::expm`]).
    pub fn discretize(&self, ts: f64) -> Result<DiscreteCarrier, DynamicsError> {
        let (a_p, b_p) = zoh_discretize_fixed(&self.a, &self.b, ts)?;
        Ok(DiscreteCarrier { a_p, b_p, c_p: self.c(), ts })
    }
}

/// The carrier discretised with a zero-order hold: `x_{k+1} = A_p x_k + B_p u_k`,
/// `y_k = C_p x_k` (eqs (10)–(11), noise-free part).
#[derive(Debug, Clone, PartialEq)]
pub struct DiscreteCarrier {
    /// `A_p = e^{A T_s}`.
    pub a_p: StateMatrix,
    /// `B_p = ∫₀^{T_s} e^{Aτ} dτ B`.
    pub b_p: InputMatrix,
    /// `C_p = C = I₄`.
    pub c_p: Matrix4<f64>,
    /// Sampling period `T_s` \[s\].
    pub ts: f64,
}

impl DiscreteCarrier {
    /// The three matrices as dynamically sized copies `(A_p, B_p, C_p)`.
    #[must_use]
    pub fn to_dynamic(&self) -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
        (
            DMatrix::from_column_slice(STATE_DIM, STATE_DIM, self.a_p.as_slice()),
            DMatrix::from_column_slice(STATE_DIM, INPUT_DIM, self.b_p.as_slice()),
            DMatrix::from_column_slice(OUTPUT_DIM, STATE_DIM, self.c_p.as_slice()),
        )
    }
}

impl LinearTimeVarying for DiscreteCarrier {
    fn dims(&self) -> Dims {
        Dims::new(STATE_DIM, INPUT_DIM, OUTPUT_DIM)
    }
    fn matrices(&self, _k: usize) -> Result<StepMatrices, ModelError> {
        let (a, b, c) = self.to_dynamic();
        Ok(StepMatrices { a, b, c })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use models::Xoshiro256StarStar;

    /// `[β̇, γ̇, φ̇, φ̈]` straight from eqs (4)–(6): wheel slips and forces, the yaw moment, and
    /// a 2 × 2 solve of (4) and (6) for `β̇` and `φ̈` by Cramer's rule.
    fn from_equations(p: &CarrierParams, x: &StateVector, u: &InputVector) -> StateVector {
        let (beta, gamma, phi, phi_dot) = (x[0], x[1], x[2], x[3]);
        let (m, h, v, g) = (p.mass, p.cg_height, p.speed, p.gravity);
        let i_xeq = p.roll_inertia_eq();
        let (mut sum_f, mut moment) = (0.0, 0.0);
        for j in 0..8 {
            let (row, k) = if j < 4 { (j, p.stiffness_left[j]) } else { (j - 4, p.stiffness_right[j - 4]) };
            let l = p.row_distances[row];
            let front = row < 2;
            let alpha = if front { beta + l * gamma / v - u[j] } else { beta - l * gamma / v - u[j] };
            let f = -k * alpha;
            sum_f += f;
            moment += if front { l * f } else { -l * f };
        }
        // (4): m v β̇ − m h φ̈ = ΣF − m v γ
        // (6): −m h v β̇ + I_xeq φ̈ = m h v γ + m g h φ − C_φ φ̇ − K_φ φ
        let r1 = sum_f - m * v * gamma;
        let r2 = m * h * v * gamma + m * g * h * phi - p.roll_damping * phi_dot - p.roll_stiffness * phi;
        let (a11, a12, a21, a22) = (m * v, -m * h, -m * h * v, i_xeq);
        let det = a11 * a22 - a12 * a21;
        let beta_dot = (r1 * a22 - a12 * r2) / det;
        let phi_ddot = (a11 * r2 - a21 * r1) / det;
        StateVector::new(beta_dot, moment / p.yaw_inertia, phi_dot, phi_ddot)
    }

    #[test]
    fn matrices_match_equations_4_to_6() {
        let mut rng = Xoshiro256StarStar::seed_from_u64(7);
        for n in 0..=2 {
            // Also unequal stiffnesses and distances, to exercise every index.
            let mut p = CarrierParams::for_load(n).unwrap().with_speed(2.0 + 3.0 * n as f64);
            if n == 2 {
                p.stiffness_left = [5.0e5, 5.5e5, 4.0e5, 4.5e5];
                p.stiffness_right = [5.2e5, 5.7e5, 4.2e5, 4.7e5];
                p.row_distances = [4.0, 2.0, 1.5, 3.5];
            }
            let model = CarrierModel::new(p).unwrap();
            for _ in 0..200 {
                let x = StateVector::from_fn(|_, _| rng.next_f64() * 2.0 - 1.0);
                let u = InputVector::from_fn(|_, _| rng.next_f64() - 0.5);
                let want = from_equations(&p, &x, &u);
                let got = model.derivative(&x, &u);
                // Relative to the size of the terms of each row (the sums may cancel).
                for i in 0..4 {
                    let row_scale = (model.a().row(i).abs() * x.abs()).sum() + (model.b().row(i).abs() * u.abs()).sum();
                    assert!(
                        (got[i] - want[i]).abs() <= 1e-12 * row_scale,
                        "n = {n}, state {i}: {} vs {}",
                        got[i],
                        want[i]
                    );
                }
            }
        }
    }

    #[test]
    fn rear_steering_enters_yaw_with_minus_sign() {
        let model = CarrierModel::new(CarrierParams::paper_preset()).unwrap();
        let b = model.b();
        for j in 0..8 {
            let row = j % 4;
            assert_eq!(b[(1, j)] > 0.0, row < 2, "input {j}");
            assert!(b[(0, j)] > 0.0 && b[(3, j)] > 0.0 && b[(2, j)] == 0.0);
        }
        assert!((b[(1, 2)] + 1.95 * 460_000.0 / 1_052_500.0).abs() < 1e-12);
    }

    #[test]
    fn preset_eigenvalues_at_6_m_per_s_match_the_digest() {
        let model = CarrierModel::new(CarrierParams::paper_preset()).unwrap();
        let mut e: Vec<Complex<f64>> = model.eigenvalues().unwrap().iter().copied().collect();
        e.sort_by(|a, b| a.re.total_cmp(&b.re).then(a.im.total_cmp(&b.im)));
        // Digest: ≈ −28.2, −5.9, −0.075 ± 1.05j; measured −28.229, −5.895, −0.0750 ± 1.0461j.
        assert!((e[0].re + 28.229).abs() < 1e-3 && e[0].im == 0.0, "{e:?}");
        assert!((e[1].re + 5.895).abs() < 1e-3 && e[1].im == 0.0, "{e:?}");
        for l in &e[2..] {
            assert!((l.re + 0.0750).abs() < 1e-4, "{e:?}");
            assert!((l.im.abs() - 1.0461).abs() < 1e-4, "{e:?}");
        }
        assert!(e[2].im < 0.0 && e[3].im > 0.0);
        assert!(model.is_stable());
    }

    #[test]
    fn preset_is_open_loop_stable_from_2_to_10_m_per_s() {
        for tenth in (20..=100).step_by(5) {
            let v = f64::from(tenth) / 10.0;
            let model = CarrierModel::new(CarrierParams::paper_preset().with_speed(v)).unwrap();
            assert!(model.is_stable(), "v = {v}: {:?}", model.eigenvalues());
        }
        // A top-heavy carrier (K_φ < m g h) is a valid model, and reported unstable.
        let top_heavy = CarrierParams { roll_stiffness: 5.0e6, ..CarrierParams::paper_preset() };
        assert!(!CarrierModel::new(top_heavy).unwrap().is_stable());
    }

    #[test]
    fn overflowing_parameters_are_reported() {
        let p = CarrierParams { mass: 1e-305, ..CarrierParams::paper_preset() };
        let e = CarrierModel::new(p).unwrap_err();
        assert_eq!(e.to_string(), "continuous-time state matrix A has a non-finite entry at (0, 0)");
        let e = CarrierModel::new(CarrierParams::paper_preset().with_speed(-1.0)).unwrap_err();
        assert_eq!(e.to_string(), "parameter v (forward speed) must be positive, got -1");
    }

    #[test]
    fn discretisation_at_1_ms_is_close_to_euler() {
        let model = CarrierModel::new(CarrierParams::paper_preset()).unwrap();
        let d = model.discretize(1e-3).unwrap();
        assert_eq!(d.ts, 1e-3);
        assert_eq!(d.c_p, Matrix4::identity());
        let euler_a = Matrix4::identity() + model.a() * 1e-3;
        let euler_b = model.b() * 1e-3;
        assert!((d.a_p - euler_a).amax() < 1e-3);
        assert!((d.b_p - euler_b).amax() < 1e-4);
        let (a, b, c) = d.to_dynamic();
        assert_eq!(a[(2, 3)], d.a_p[(2, 3)]);
        assert_eq!(b[(3, 7)], d.b_p[(3, 7)]);
        assert_eq!(c, DMatrix::identity(4, 4));
        let e = model.discretize(0.0).unwrap_err();
        assert_eq!(e.to_string(), "sampling period T_s must be positive and finite, got 0");
    }
}
