//! The richer truth model that replaces TruckSim in the experiment (digest §5, everything
//! here **\[A\]** unless marked), its RK4 simulation and the slalom manoeuvre.
//!
//! Same geometry and Pac89 tyres as the estimator's model ([`crate::PlanarTruck`]), plus:
//!
//! * **lateral tyre relaxation** `dα'_j/dt = (|v_l,j|/σ_α)·(α_j − α'_j)`; the lateral force uses
//!   the lagged slip angle `α'_j` (`σ_α = 0.65 m`, `PTY1·R_0` of the tyre file **\[R\]**);
//! * **wheel-spin dynamics** `n_j·J_w·dω_j/dt = T_j − R_e·F_xj − f_r·F_zj·R_e·sat(ω_j·R_e/v_min)`,
//!   with `sat` the clamp to `[−1, 1]` (rolling resistance opposes rotation and vanishes
//!   continuously at standstill; `f_r = 0.008` is `QSY1` of the tyre file **\[R\]**);
//! * a **6×4 drive**: a PI speed controller with feed-forward of drag and rolling resistance,
//!   `T = R_e·(F_drag + f_r·m·g) + k_p·(v_ref − V_x) + k_i·∫(v_ref − V_x) dt`, split equally over
//!   the four wheel positions of axles 2–3 (no torque limit, no differential dynamics);
//! * **quasi-static load transfer** from the ground forces, `h_cg = 1.4 m`: longitudinal
//!   `ΔW = h_cg·ΣF_X/L` from axle 1 to the tandem (shared equally, `L = a + (b + c)/2`), lateral
//!   `ΔF_z,i = h_cg·ΣF_Y·(W_i/(m·g))/T_i` from the left to the right wheels of axle `i`
//!   (proportional to its static load `W_i`). The loads depend on the forces they produce; the
//!   algebraic loop is solved by [`LOAD_TRANSFER_PASSES`] fixed-point passes, started from
//!   `ΣF_X = F_drag(V_x)` and `ΣF_Y = m·V_x·γ` (the steady-state values), so straight cruising is
//!   an exact equilibrium. Drag acts at the CG height and transfers no load;
//! * **aerodynamic drag** `F_drag = ½·ρ·C_d·A·V_x·|V_x|` at the CG along x (`C_d·A = 5 m²`,
//!   `ρ = 1.2 kg/m³`);
//! * **friction-ellipse saturation**: with the pure-slip forces `F_x0`, `F_y0` and their peaks
//!   `D_x`, `D_y` (all `n·F(F_z/n)`), `r = √((F_x0/D_x)² + (F_y0/D_y)²)`; if `r > 1` both forces
//!   are divided by `r`;
//! * the ground-frame pose `X, Y, ψ` (for plots).
//!
//! State (19): `[V_x, V_y, γ, ω_L1..ω_R3, α'_L1..α'_R3, ∫(v_ref − V_x), X, Y, ψ]`; input (2):
//! `[δ, v_ref]`; output (3): `[V_x, a_y, γ]` with `a_y = ΣF_Y/m` (the same measurement as the
//! estimator's). [`simulate_truth`] integrates it with [`models::Discretized`] and
//! [`models::Integrator::Rk4`]: RK4 at `h = 0.1 ms`, input held over each 1 ms output period.

use models::error::check_dims;
use models::{ContinuousModel, Dims, DiscreteModel, Discretized, Integrator, ModelError};
use nalgebra::{DVector, Vector3};

use models::validate::{non_negative, positive};

use crate::error::{TruckError, finite_input};
use crate::kinematics::{Geometry, WHEEL_NAMES, WHEELS, WheelKinematics, wheel_kinematics};
use crate::params::TruckParams;
use crate::planar::{STATE_DIM, STATE_NAMES, TruckInput, WHEEL_SPEED_NAMES, join, sideslip};

/// Number of truth states.
pub const TRUTH_STATE_DIM: usize = 19;
/// Number of truth inputs `[δ, v_ref]`.
pub const TRUTH_INPUT_DIM: usize = 2;
/// Number of truth outputs `[V_x, a_y, γ]`.
pub const TRUTH_OUTPUT_DIM: usize = 3;
/// Index of the first wheel speed `ω_L1` in the truth state.
pub const OMEGA_INDEX: usize = 3;
/// Index of the first relaxed slip angle `α'_L1` in the truth state.
pub const ALPHA_INDEX: usize = 9;
/// Index of the speed-error integral in the truth state.
pub const INTEGRAL_INDEX: usize = 15;
/// Index of the ground position `X` in the truth state (`Y`, `ψ` follow).
pub const POSE_INDEX: usize = 16;
/// Fixed-point passes of the quasi-static load transfer.
pub const LOAD_TRANSFER_PASSES: usize = 3;

/// Names of the truth states, as they appear in error messages.
pub const TRUTH_STATE_NAMES: [&str; TRUTH_STATE_DIM] = join(
    join::<STATE_DIM, 6, 9>(STATE_NAMES, WHEEL_SPEED_NAMES),
    [
        "alpha'_L1 (relaxed slip angle)",
        "alpha'_R1 (relaxed slip angle)",
        "alpha'_L2 (relaxed slip angle)",
        "alpha'_R2 (relaxed slip angle)",
        "alpha'_L3 (relaxed slip angle)",
        "alpha'_R3 (relaxed slip angle)",
        "speed-error integral",
        "X (ground position)",
        "Y (ground position)",
        "psi (heading)",
    ],
);

/// Everything the truth model computes at one state and input.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TruthEvaluation {
    /// `ẋ` (19 entries).
    pub derivative: [f64; TRUTH_STATE_DIM],
    /// Wheel loads `F_zj` after load transfer \[N\].
    pub fz: [f64; WHEELS],
    /// Longitudinal tyre forces in wheel axes after the friction ellipse \[N\].
    pub fx: [f64; WHEELS],
    /// Lateral tyre forces in wheel axes after the friction ellipse \[N\].
    pub fy: [f64; WHEELS],
    /// Slip ratios `s_j`.
    pub slip: [f64; WHEELS],
    /// Longitudinal acceleration `(ΣF_X − F_drag)/m` \[m/s²\].
    pub ax: f64,
    /// Lateral acceleration at the CG `ΣF_Y/m` \[m/s²\].
    pub ay: f64,
    /// Total drive torque on axles 2–3 \[N m\].
    pub drive_torque: f64,
}

/// The truth model (see the module documentation). Validated parameters; a
/// [`ContinuousModel`] with state 19, input `[δ, v_ref]` and output `[V_x, a_y, γ]`.
#[derive(Debug, Clone, PartialEq)]
pub struct TruthModel {
    params: TruckParams,
    geometry: Geometry,
    axle_loads: [f64; 3],
}

struct Forces {
    fx: [f64; WHEELS],
    fy: [f64; WHEELS],
    sum_x: f64,
    sum_y: f64,
    mz: f64,
}

impl TruthModel {
    /// Validates `params`.
    ///
    /// # Errors
    /// The validation error naming the parameter ([`TruckParams::validate`]).
    pub fn new(params: TruckParams) -> Result<Self, TruckError> {
        params.validate()?;
        Ok(Self { geometry: Geometry::new(&params), axle_loads: params.static_axle_loads(), params })
    }

    /// The validated parameters.
    #[must_use]
    pub fn params(&self) -> &TruckParams {
        &self.params
    }

    /// Drag force `½·ρ·C_d·A·V_x·|V_x|` \[N\].
    #[must_use]
    pub fn drag(&self, vx: f64) -> f64 {
        0.5 * self.params.air_density * self.params.drag_area * vx * vx.abs()
    }

    /// Wheel loads for the ground-force sums `ΣF_X`, `ΣF_Y` (quasi-static transfer).
    #[must_use]
    pub fn loads(&self, sum_fx: f64, sum_fy: f64) -> [f64; WHEELS] {
        let p = &self.params;
        let weight = p.mass * p.gravity;
        let d_long = p.cg_height * sum_fx / p.tandem_wheelbase();
        let axle = [self.axle_loads[0] - d_long, self.axle_loads[1] + 0.5 * d_long, self.axle_loads[2] + 0.5 * d_long];
        let mut fz = [0.0; WHEELS];
        for i in 0..3 {
            let d_lat = p.cg_height * sum_fy * (self.axle_loads[i] / weight) / p.tracks[i];
            fz[2 * i] = 0.5 * axle[i] - d_lat;
            fz[2 * i + 1] = 0.5 * axle[i] + d_lat;
        }
        fz
    }

    /// Tyre forces at loads `fz` with the friction ellipse, and their body-axis sums.
    fn forces(&self, fz: &[f64; WHEELS], kin: &[WheelKinematics; WHEELS], alpha: &[f64]) -> Result<Forces, TruckError> {
        let p = &self.params;
        let g = &self.geometry;
        let mut out = Forces { fx: [0.0; WHEELS], fy: [0.0; WHEELS], sum_x: 0.0, sum_y: 0.0, mz: 0.0 };
        for j in 0..WHEELS {
            let fx0 = p.tyre.longitudinal_lumped(g.tyres[j], fz[j], kin[j].slip)?;
            let fy0 = p.tyre.lateral_lumped(g.tyres[j], fz[j], alpha[j])?;
            let (fx, fy) = if fx0.peak > 0.0 && fy0.peak > 0.0 {
                let r = (fx0.force / fx0.peak).hypot(fy0.force / fy0.peak);
                if r > 1.0 { (fx0.force / r, fy0.force / r) } else { (fx0.force, fy0.force) }
            } else {
                (0.0, 0.0)
            };
            let (c, s) = (kin[j].cos_delta, kin[j].sin_delta);
            let (big_x, big_y) = (fx * c - fy * s, fx * s + fy * c);
            out.fx[j] = fx;
            out.fy[j] = fy;
            out.sum_x += big_x;
            out.sum_y += big_y;
            out.mz += g.x[j] * big_y - g.y[j] * big_x;
        }
        Ok(out)
    }

    /// Evaluates the model at state `x` (19 entries), road-wheel angle `delta` \[rad\] and
    /// reference speed `v_ref` \[m/s\].
    ///
    /// # Errors
    /// [`TruckError::NonFiniteInput`] naming a non-finite state or input;
    /// [`TruckError::NonPositiveSpeed`] for `V_x ≤ 0` (forward-driving model, like the
    /// estimator's); [`TruckError::TyreOutOfRange`] if load transfer overloads a tyre beyond its
    /// data; a dimension error (as [`TruckError::Model`]) unless `x` has 19 entries.
    pub fn evaluate(&self, x: &[f64], delta: f64, v_ref: f64) -> Result<TruthEvaluation, TruckError> {
        if x.len() != TRUTH_STATE_DIM {
            return Err(ModelError::DimensionMismatch {
                what: "x".to_owned(),
                expected_rows: TRUTH_STATE_DIM,
                expected_cols: 1,
                rows: x.len(),
                cols: 1,
            }
            .into());
        }
        for (name, &v) in TRUTH_STATE_NAMES.iter().zip(x) {
            finite_input(name, v)?;
        }
        finite_input("delta (road-wheel angle)", delta)?;
        finite_input("v_ref (reference speed)", v_ref)?;
        let (vx, vy, gamma) = (x[0], x[1], x[2]);
        if vx <= 0.0 {
            return Err(TruckError::NonPositiveSpeed { name: TRUTH_STATE_NAMES[0], value: vx });
        }
        let p = &self.params;
        let g = &self.geometry;
        let (re, vmin) = (p.rolling_radius, p.min_speed);
        let kin: [WheelKinematics; WHEELS] =
            std::array::from_fn(|j| wheel_kinematics(g, j, [vx, vy, gamma], delta, x[OMEGA_INDEX + j], re, vmin));
        let alpha = &x[ALPHA_INDEX..ALPHA_INDEX + WHEELS];
        let drag = self.drag(vx);

        let (mut sum_x, mut sum_y) = (drag, p.mass * vx * gamma);
        let mut fz = self.loads(sum_x, sum_y);
        let mut f = self.forces(&fz, &kin, alpha)?;
        for _ in 1..LOAD_TRANSFER_PASSES {
            (sum_x, sum_y) = (f.sum_x, f.sum_y);
            fz = self.loads(sum_x, sum_y);
            f = self.forces(&fz, &kin, alpha)?;
        }

        let mut d = [0.0; TRUTH_STATE_DIM];
        d[0] = vy * gamma + (f.sum_x - drag) / p.mass;
        d[1] = -vx * gamma + f.sum_y / p.mass;
        d[2] = f.mz / p.yaw_inertia;
        let error = v_ref - vx;
        let drive_torque = re * (drag + p.rolling_resistance * p.mass * p.gravity)
            + p.speed_kp * error
            + p.speed_ki * x[INTEGRAL_INDEX];
        for j in 0..WHEELS {
            let torque = if g.axle[j] == 0 { 0.0 } else { 0.25 * drive_torque };
            let spin = (kin[j].omega_re / vmin).clamp(-1.0, 1.0);
            let resistance = p.rolling_resistance * fz[j].max(0.0) * re * spin;
            let inertia = f64::from(g.tyres[j]) * p.wheel_inertia;
            d[OMEGA_INDEX + j] = (torque - re * f.fx[j] - resistance) / inertia;
            d[ALPHA_INDEX + j] = kin[j].vl.abs() / p.relaxation_length * (kin[j].alpha - alpha[j]);
        }
        d[INTEGRAL_INDEX] = error;
        let psi = x[POSE_INDEX + 2];
        let (sin_psi, cos_psi) = psi.sin_cos();
        d[POSE_INDEX] = vx * cos_psi - vy * sin_psi;
        d[POSE_INDEX + 1] = vx * sin_psi + vy * cos_psi;
        d[POSE_INDEX + 2] = gamma;
        Ok(TruthEvaluation {
            derivative: d,
            fz,
            fx: f.fx,
            fy: f.fy,
            slip: kin.map(|k| k.slip),
            ax: (f.sum_x - drag) / p.mass,
            ay: f.sum_y / p.mass,
            drive_torque,
        })
    }

    /// The equilibrium of straight running at `speed` \[m/s\] with `δ = 0`, `v_ref = speed`:
    /// `V_y = γ = 0`, `α' = 0`, zero speed-error integral, pose 0, and wheel speeds whose slips
    /// give the forces that balance rolling resistance (front) and the feed-forward drive torque
    /// (rear), which sum to the drag. `ẋ = 0` there except for `X`.
    ///
    /// # Errors
    /// [`TruckError::NonPositiveSpeed`] naming the speed; [`TruckError::SlipNotFound`] if a
    /// wheel's required force is beyond the tyre's grip.
    pub fn straight_running_state(&self, speed: f64) -> Result<DVector<f64>, TruckError> {
        finite_input("initial speed", speed)?;
        if speed <= 0.0 {
            return Err(TruckError::NonPositiveSpeed { name: "initial speed", value: speed });
        }
        let p = &self.params;
        let g = &self.geometry;
        let (re, vmin) = (p.rolling_radius, p.min_speed);
        let drag = self.drag(speed);
        let fz = self.loads(drag, 0.0);
        let per_driven = 0.25 * (drag + p.rolling_resistance * p.mass * p.gravity);
        let spin = (speed / vmin).min(1.0);
        let mut x = DVector::zeros(TRUTH_STATE_DIM);
        x[0] = speed;
        for j in 0..WHEELS {
            let resistance = p.rolling_resistance * fz[j] * spin;
            let target = if g.axle[j] == 0 { -resistance } else { per_driven - resistance };
            let slip = self.slip_for_force(j, fz[j], target)?;
            // Invert s = (ωR_e − v_l)/max(|ωR_e|, |v_l|, v_min) for ωR_e (v_l = speed > 0).
            let omega_re = if slip >= 0.0 && speed / (1.0 - slip) >= vmin {
                speed / (1.0 - slip)
            } else if slip < 0.0 && speed >= vmin {
                speed * (1.0 + slip)
            } else {
                speed + slip * vmin
            };
            x[OMEGA_INDEX + j] = omega_re / re;
        }
        Ok(x)
    }

    /// Slip of wheel `j` at load `fz` giving the longitudinal force `target`, by bisection on the
    /// monotone part `|s| ≤ 0.08`.
    fn slip_for_force(&self, j: usize, fz: f64, target: f64) -> Result<f64, TruckError> {
        const MAX_SLIP: f64 = 0.08;
        let p = &self.params;
        let n = self.geometry.tyres[j];
        let force = |s: f64| p.tyre.longitudinal_lumped(n, fz, s).map(|f| f.force);
        let (mut lo, mut hi) = (-MAX_SLIP, MAX_SLIP);
        if !(force(lo)? <= target && target <= force(hi)?) {
            return Err(TruckError::SlipNotFound { wheel: WHEEL_NAMES[j], force: target, max_slip: MAX_SLIP });
        }
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if force(mid)? < target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Ok(0.5 * (lo + hi))
    }
}

fn read_input(u: &DVector<f64>) -> Result<(f64, f64), ModelError> {
    check_dims("u", u, TRUTH_INPUT_DIM, 1)?;
    Ok((u[0], u[1]))
}

impl ContinuousModel for TruthModel {
    fn dims(&self) -> Dims {
        Dims::new(TRUTH_STATE_DIM, TRUTH_INPUT_DIM, TRUTH_OUTPUT_DIM)
    }
    fn derivative(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        let (delta, v_ref) = read_input(u)?;
        check_dims("x", x, TRUTH_STATE_DIM, 1)?;
        check_dims("dx/dt", out, TRUTH_STATE_DIM, 1)?;
        let e = self.evaluate(x.as_slice(), delta, v_ref)?;
        out.copy_from_slice(&e.derivative);
        Ok(())
    }
    fn output(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        let (delta, v_ref) = read_input(u)?;
        check_dims("x", x, TRUTH_STATE_DIM, 1)?;
        check_dims("y", out, TRUTH_OUTPUT_DIM, 1)?;
        let e = self.evaluate(x.as_slice(), delta, v_ref)?;
        out.copy_from_slice(&[x[0], e.ay, x[2]]);
        Ok(())
    }
}

/// The slalom of digest §5 **\[A\]**: `δ = 0` before `start`, then `A·sin(2π·f·(t − start))`
/// with `A = first_amplitude` for the first half-period (zero-mean heading) and `amplitude`
/// afterwards.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slalom {
    /// Start time \[s\].
    pub start: f64,
    /// Frequency `f` \[Hz\].
    pub frequency: f64,
    /// Amplitude of the first half-period \[rad\].
    pub first_amplitude: f64,
    /// Amplitude afterwards \[rad\].
    pub amplitude: f64,
}

impl Slalom {
    /// Digest §5: start 1 s, 0.2 Hz, 0.75° then 1.5° (pylon spacing 48.6 m at 70 km/h).
    #[must_use]
    pub fn digest() -> Self {
        Self { start: 1.0, frequency: 0.2, first_amplitude: 0.75f64.to_radians(), amplitude: 1.5f64.to_radians() }
    }

    /// Road-wheel angle `δ(t)` \[rad\].
    #[must_use]
    pub fn angle(&self, t: f64) -> f64 {
        let tau = t - self.start;
        if tau < 0.0 {
            return 0.0;
        }
        let a = if tau < 0.5 / self.frequency { self.first_amplitude } else { self.amplitude };
        a * (2.0 * std::f64::consts::PI * self.frequency * tau).sin()
    }
}

/// How the truth is simulated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TruthConfig {
    /// Duration \[s\] (digest: 12 s **\[P\]**).
    pub duration: f64,
    /// Output period \[s\] (1 ms: 1 kHz); the steering angle is held over each period.
    pub output_period: f64,
    /// RK4 sub-steps per output period (10: `h = 0.1 ms`).
    pub substeps: usize,
    /// Initial speed \[m/s\] (straight-running equilibrium, [`TruthModel::straight_running_state`]).
    pub initial_speed: f64,
    /// Reference speed of the speed controller \[m/s\] (70 km/h **\[P\]**).
    pub target_speed: f64,
}

impl TruthConfig {
    /// Digest §5: 12 s at 70 km/h, output at 1 kHz, RK4 at 0.1 ms.
    #[must_use]
    pub fn digest() -> Self {
        let v = 70.0 / 3.6;
        Self { duration: 12.0, output_period: 1e-3, substeps: 10, initial_speed: v, target_speed: v }
    }

    /// Checks `duration ≥ 0`, `output_period > 0`, `substeps ≥ 1`, speeds `> 0`.
    ///
    /// # Errors
    /// The first violation, naming the setting.
    pub fn validate(&self) -> Result<(), TruckError> {
        non_negative("duration", self.duration)?;
        positive("output period", self.output_period)?;
        positive("RK4 sub-steps per output period", self.substeps as f64)?;
        positive("initial speed", self.initial_speed)?;
        positive("target speed", self.target_speed)?;
        Ok(())
    }
}

/// One truth sample at `t_k = k·T`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TruthSample {
    /// Time \[s\].
    pub t: f64,
    /// Road-wheel angle held over `[t_k, t_k + T)` \[rad\].
    pub delta: f64,
    /// `V_x` \[m/s\].
    pub vx: f64,
    /// `V_y` \[m/s\].
    pub vy: f64,
    /// Yaw rate `γ` \[rad/s\].
    pub gamma: f64,
    /// Sideslip `β = atan(V_y/V_x)` \[rad\] (2).
    pub beta: f64,
    /// Longitudinal acceleration `(ΣF_X − F_drag)/m` \[m/s²\].
    pub ax: f64,
    /// Lateral acceleration `ΣF_Y/m` \[m/s²\], evaluated with `δ_k`.
    pub ay: f64,
    /// Wheel speeds `ω_j` \[rad/s\] (what the estimator consumes).
    pub omega: [f64; WHEELS],
    /// Wheel loads \[N\].
    pub fz: [f64; WHEELS],
    /// Ground position `X` \[m\].
    pub x: f64,
    /// Ground position `Y` \[m\] (left positive).
    pub y: f64,
    /// Heading `ψ` \[rad\].
    pub psi: f64,
    /// Total drive torque \[N m\].
    pub drive_torque: f64,
}

/// A truth run sampled at the output period.
#[derive(Debug, Clone, PartialEq)]
pub struct TruthTrajectory {
    /// Output period `T` \[s\].
    pub output_period: f64,
    /// Samples at `t_k = k·T`, `k = 0..=N`.
    pub samples: Vec<TruthSample>,
}

impl TruthTrajectory {
    /// Number of samples.
    #[must_use]
    pub fn len(&self) -> usize {
        self.samples.len()
    }

    /// Whether there is no sample.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.samples.is_empty()
    }

    /// The estimator's input at sample `k`: `δ_k` and the truth wheel speeds `ω_j(t_k)`.
    #[must_use]
    pub fn estimator_input(&self, k: usize) -> Option<TruckInput> {
        self.samples.get(k).map(|s| TruckInput { delta: s.delta, omega: s.omega })
    }

    /// The noise-free measurement `[V_x, a_y, γ]` at sample `k` (14).
    #[must_use]
    pub fn measurement(&self, k: usize) -> Option<Vector3<f64>> {
        self.samples.get(k).map(|s| Vector3::new(s.vx, s.ay, s.gamma))
    }

    /// The estimator's state `[V_x, V_y, γ]` at sample `k`.
    #[must_use]
    pub fn body_state(&self, k: usize) -> Option<Vector3<f64>> {
        self.samples.get(k).map(|s| Vector3::new(s.vx, s.vy, s.gamma))
    }
}

/// Simulates the truth model from straight running at `config.initial_speed`, with the
/// road-wheel angle `steering(t)` \[rad\] sampled at `t_k` and held over each output period:
/// classical RK4 ([`models::Integrator::Rk4`]) with `config.substeps` sub-steps per period.
///
/// # Errors
/// Invalid parameters or settings (named); [`TruckError::NonFiniteInput`] naming `δ` if
/// `steering` returns NaN or ±∞, or naming the state that diverged; the other errors of
/// [`TruthModel::evaluate`].
pub fn simulate_truth<F: Fn(f64) -> f64>(
    params: &TruckParams,
    config: &TruthConfig,
    steering: F,
) -> Result<TruthTrajectory, TruckError> {
    config.validate()?;
    let model = TruthModel::new(*params)?;
    let dt = config.output_period;
    let steps = (config.duration / dt).round() as usize;
    let mut x = model.straight_running_state(config.initial_speed)?;
    let disc = Discretized::new(model.clone(), dt, Integrator::Rk4 { substeps: config.substeps })?;
    let mut next = DVector::zeros(TRUTH_STATE_DIM);
    let mut u = DVector::zeros(TRUTH_INPUT_DIM);
    u[1] = config.target_speed;
    let mut samples = Vec::with_capacity(steps + 1);
    for k in 0..=steps {
        let t = k as f64 * dt;
        let delta = steering(t);
        finite_input("delta (road-wheel angle)", delta)?;
        u[0] = delta;
        let e = model.evaluate(x.as_slice(), delta, config.target_speed)?;
        samples.push(TruthSample {
            t,
            delta,
            vx: x[0],
            vy: x[1],
            gamma: x[2],
            beta: sideslip(x[0], x[1])?,
            ax: e.ax,
            ay: e.ay,
            omega: std::array::from_fn(|j| x[OMEGA_INDEX + j]),
            fz: e.fz,
            x: x[POSE_INDEX],
            y: x[POSE_INDEX + 1],
            psi: x[POSE_INDEX + 2],
            drive_torque: e.drive_torque,
        });
        if k < steps {
            disc.f(&x, &u, &mut next).map_err(TruckError::from)?;
            std::mem::swap(&mut x, &mut next);
        }
    }
    Ok(TruthTrajectory { output_period: dt, samples })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::planar::PlanarTruck;

    fn v70() -> f64 {
        70.0 / 3.6
    }

    #[test]
    fn straight_running_is_an_equilibrium() {
        let model = TruthModel::new(TruckParams::digest_preset()).unwrap();
        let x = model.straight_running_state(v70()).unwrap();
        let e = model.evaluate(x.as_slice(), 0.0, v70()).unwrap();
        for (i, d) in e.derivative.iter().enumerate() {
            let want = if i == POSE_INDEX { v70() } else { 0.0 };
            assert!((d - want).abs() < 1e-9, "{}: {d}", TRUTH_STATE_NAMES[i]);
        }
        // Front wheels brake slightly (rolling resistance), driven wheels slip forward.
        assert!(e.slip[0] < 0.0 && e.slip[2] > 0.0, "{:?}", e.slip);
        assert!((e.fx.iter().sum::<f64>() - model.drag(v70())).abs() < 1e-6);
        let mut y = DVector::zeros(3);
        model.output(&x, &DVector::from_vec(vec![0.0, v70()]), &mut y).unwrap();
        assert_eq!(y.as_slice(), &[v70(), 0.0, 0.0]);
    }

    #[test]
    fn load_transfer_conserves_weight_and_the_friction_ellipse_holds() {
        let p = TruckParams::digest_preset();
        let model = TruthModel::new(p).unwrap();
        let mut x = model.straight_running_state(15.0).unwrap();
        // Left cornering while axle 3 brakes near its peak slip: combined slip beyond the ellipse.
        x[1] = -0.3;
        x[2] = 0.1;
        for (j, a) in [0.02, 0.02, 0.06, 0.06, 0.06, 0.06].into_iter().enumerate() {
            x[ALPHA_INDEX + j] = a;
        }
        x[OMEGA_INDEX + 4] = 0.85 * 15.0 / p.rolling_radius;
        x[OMEGA_INDEX + 5] = 0.85 * 15.0 / p.rolling_radius;
        let e = model.evaluate(x.as_slice(), 0.05, 15.0).unwrap();
        assert!((e.fz.iter().sum::<f64>() - p.mass * p.gravity).abs() < 1e-6);
        assert!(e.ay > 0.0 && e.fz[1] > e.fz[0] && e.fz[3] > e.fz[2], "{:?}", e.fz);
        let g = Geometry::new(&p);
        let mut saturated = Vec::new();
        for j in 0..WHEELS {
            let dx = p.tyre.longitudinal_lumped(g.tyres[j], e.fz[j], 0.0).unwrap().peak;
            let dy = p.tyre.lateral_lumped(g.tyres[j], e.fz[j], 0.0).unwrap().peak;
            let r = (e.fx[j] / dx).hypot(e.fy[j] / dy);
            assert!(r <= 1.0 + 1e-12, "wheel {j}: r = {r}");
            if r > 1.0 - 1e-9 {
                saturated.push(j);
            }
        }
        assert_eq!(saturated, [4, 5], "the braked wheels, and only they, sit on the ellipse");
        // Braking decelerates.
        assert!(e.ax < -1.0, "{}", e.ax);
    }

    /// The digest's slalom (§5) up to 9 s: its \[V\] peaks (from the digest's prototype, not the
    /// paper), the speed controller, and agreement of the estimator's simpler model with the
    /// truth along the run.
    #[test]
    fn slalom_reproduces_the_digest_peaks_and_matches_the_estimator_model() {
        let p = TruckParams::digest_preset();
        let slalom = Slalom::digest();
        let config = TruthConfig { duration: 9.0, ..TruthConfig::digest() };
        let run = simulate_truth(&p, &config, |t| slalom.angle(t)).unwrap();
        assert_eq!(run.len(), 9001);
        let peak = |f: &dyn Fn(&TruthSample) -> f64| run.samples.iter().map(f).fold(0.0_f64, |m, v| m.max(v.abs()));
        let (ay, gamma, beta) = (peak(&|s| s.ay), peak(&|s| s.gamma).to_degrees(), peak(&|s| s.beta).to_degrees());
        assert!((ay - 1.47).abs() < 0.05 * 1.47, "max |a_y| = {ay}");
        assert!((gamma - 4.85).abs() < 0.05 * 4.85, "max |γ| = {gamma} deg/s");
        assert!((beta - 1.23).abs() < 0.05 * 1.23, "max |β| = {beta} deg");
        assert!(peak(&|s| s.vx - v70()) < 0.05, "speed controller");
        // Before the slalom starts nothing moves sideways.
        assert_eq!(run.samples[999].vy, 0.0);

        // The estimator's model (static loads, no relaxation) driven by the truth's inputs.
        let planar = PlanarTruck::new(p).unwrap();
        let (mut sq, mut n) = (0.0, 0.0);
        for k in (0..run.len()).step_by(10) {
            let ay_model =
                planar.lateral_acceleration(&run.body_state(k).unwrap(), &run.estimator_input(k).unwrap()).unwrap();
            sq += (ay_model - run.measurement(k).unwrap()[1]).powi(2);
            n += 1.0;
        }
        let rms = (sq / n).sqrt();
        assert!(rms < 0.05 * ay, "a_y of the estimator's model vs truth: RMS {rms}");
    }

    #[test]
    fn mirrored_steering_mirrors_the_truth() {
        let p = TruckParams::digest_preset();
        let config = TruthConfig { duration: 1.2, ..TruthConfig::digest() };
        let steer = |t: f64| if t < 0.1 { 0.0 } else { 0.03 * (3.0 * (t - 0.1)).sin() };
        let left = simulate_truth(&p, &config, steer).unwrap();
        let right = simulate_truth(&p, &config, |t| -steer(t)).unwrap();
        for (a, b) in left.samples.iter().zip(&right.samples) {
            assert!((a.vx - b.vx).abs() < 1e-9, "t = {}", a.t);
            assert!((a.vy + b.vy).abs() < 1e-9 && (a.gamma + b.gamma).abs() < 1e-9, "t = {}", a.t);
            assert!((a.ay + b.ay).abs() < 1e-8 && (a.y + b.y).abs() < 1e-9);
            for (i, j) in [(0, 1), (2, 3), (4, 5)] {
                assert!((a.omega[i] - b.omega[j]).abs() < 1e-9 && (a.fz[i] - b.fz[j]).abs() < 1e-6);
            }
        }
        assert!(left.samples.last().unwrap().gamma > 0.01);
    }

    #[test]
    fn bad_truth_input_is_named() {
        let p = TruckParams::digest_preset();
        let short = TruthConfig { duration: 0.01, ..TruthConfig::digest() };
        let e = simulate_truth(&p, &short, |t| if t > 0.004 { f64::NAN } else { 0.0 }).unwrap_err();
        assert!(e.to_string().contains("delta (road-wheel angle) must be finite"), "{e}");
        let e = simulate_truth(&TruckParams { wheel_inertia: 0.0, ..p }, &short, |_| 0.0).unwrap_err();
        assert!(e.to_string().contains("J_w (wheel spin inertia per tyre) must be positive"), "{e}");
        let e = simulate_truth(&TruckParams { mass: -1.0, ..p }, &short, |_| 0.0).unwrap_err();
        assert!(e.to_string().contains("m (mass) must be positive"), "{e}");
        for (config, what) in [
            (TruthConfig { output_period: 0.0, ..short }, "output period must be positive"),
            (TruthConfig { substeps: 0, ..short }, "RK4 sub-steps per output period must be positive"),
            (TruthConfig { duration: f64::NAN, ..short }, "duration must be finite"),
            (TruthConfig { initial_speed: -2.0, ..short }, "initial speed must be positive"),
        ] {
            let e = simulate_truth(&p, &config, |_| 0.0).unwrap_err();
            assert!(e.to_string().contains(what), "{e} lacks {what}");
        }
        let model = TruthModel::new(p).unwrap();
        let x = model.straight_running_state(10.0).unwrap();
        let mut bad = x.clone();
        bad[OMEGA_INDEX + 2] = f64::NAN;
        let e = model.evaluate(bad.as_slice(), 0.0, 10.0).unwrap_err();
        assert_eq!(e.to_string(), "omega_L2 (wheel speed) must be finite, got NaN");
        let mut bad = x.clone();
        bad[0] = 0.0;
        assert!(matches!(model.evaluate(bad.as_slice(), 0.0, 10.0), Err(TruckError::NonPositiveSpeed { .. })));
        assert!(model.evaluate(&x.as_slice()[..18], 0.0, 10.0).is_err());
        let mut out = DVector::zeros(TRUTH_STATE_DIM);
        let e = model.derivative(&x, &DVector::from_vec(vec![f64::INFINITY, 10.0]), &mut out).unwrap_err();
        assert!(matches!(&e, ModelError::Evaluation(m) if m.contains("delta (road-wheel angle)")), "{e:?}");
        let e = model.derivative(&x, &DVector::zeros(3), &mut out).unwrap_err();
        assert_eq!(e.to_string(), "u: expected 2x1, got 3x1");
        assert!(model.straight_running_state(0.0).is_err());
        // A drag no tyre can balance.
        let windy = TruthModel::new(TruckParams { drag_area: 2000.0, ..p }).unwrap();
        assert!(matches!(windy.straight_running_state(v70()), Err(TruckError::SlipNotFound { .. })));
    }

    #[test]
    fn slalom_angles() {
        let s = Slalom::digest();
        assert_eq!(s.angle(0.5), 0.0);
        assert!((s.angle(2.25) - 0.75f64.to_radians()).abs() < 1e-12);
        assert!((s.angle(4.75) + 1.5f64.to_radians()).abs() < 1e-12);
    }
}
