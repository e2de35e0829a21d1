//! Wheel kinematics of the planar three-axle body (digest §2, **\[R\]**: the standard
//! multi-wheel planar model) and its derivatives with respect to the body state
//! `x = [V_x, V_y, γ]` (digest §3).
//!
//! Body axes at the CG, x forward, y left, `γ` counter-clockwise. Wheel `j` of
//! `L1, R1, L2, R2, L3, R3` sits at `(x_j, y_j)` with `x_j = (a, a, −b, −b, −c, −c)` and
//! `y_j = ±T_i/2`; the road-wheel angle is `δ` on axle 1 (no Ackermann) and 0 elsewhere.
//!
//! ```text
//! u_j = V_x − y_j·γ          v_j = V_y + x_j·γ
//! α_j = δ_j − atan2(v_j, u_j)                       (α > 0 gives F_y > 0)
//! v_l,j = u_j·cos δ_j + v_j·sin δ_j                 (speed along the wheel plane)
//! s_j = (ω_j·R_e − v_l,j) / max(|ω_j·R_e|, |v_l,j|, v_min)   (s > 0 drive, s < 0 brake)
//! ```

use crate::params::TruckParams;

/// Number of wheel positions.
pub const WHEELS: usize = 6;

/// Names of the wheel positions, in the order used everywhere in this crate.
pub const WHEEL_NAMES: [&str; WHEELS] = ["L1", "R1", "L2", "R2", "L3", "R3"];

/// Positions, tyre counts and steering of the six wheel positions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Geometry {
    /// `x_j` \[m\] (forward of the CG positive).
    pub x: [f64; WHEELS],
    /// `y_j` \[m\] (left positive).
    pub y: [f64; WHEELS],
    /// Tyres at each position.
    pub tyres: [u32; WHEELS],
    /// Whether the position is steered (axle 1).
    pub steered: [bool; WHEELS],
    /// Axle (0, 1, 2) of each position.
    pub axle: [usize; WHEELS],
}

impl Geometry {
    /// The geometry of `params` (not validated here).
    #[must_use]
    pub fn new(params: &TruckParams) -> Self {
        let [a, b, c] = params.axle_distances;
        let [t1, t2, t3] = params.tracks;
        let [n1, n2, n3] = params.tyres_per_position;
        Self {
            x: [a, a, -b, -b, -c, -c],
            y: [0.5 * t1, -0.5 * t1, 0.5 * t2, -0.5 * t2, 0.5 * t3, -0.5 * t3],
            tyres: [n1, n1, n2, n2, n3, n3],
            steered: [true, true, false, false, false, false],
            axle: [0, 0, 1, 1, 2, 2],
        }
    }
}

/// Kinematic quantities of one wheel at a body state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WheelKinematics {
    /// Longitudinal velocity of the wheel centre in body axes, `u_j` \[m/s\].
    pub u: f64,
    /// Lateral velocity of the wheel centre in body axes, `v_j` \[m/s\].
    pub v: f64,
    /// Road-wheel angle of this wheel, `δ_j` \[rad\].
    pub delta: f64,
    /// `cos δ_j`.
    pub cos_delta: f64,
    /// `sin δ_j`.
    pub sin_delta: f64,
    /// Slip angle `α_j` \[rad\].
    pub alpha: f64,
    /// Speed along the wheel plane `v_l,j` \[m/s\].
    pub vl: f64,
    /// Circumferential speed `ω_j·R_e` \[m/s\].
    pub omega_re: f64,
    /// Slip ratio `s_j` (unit slip).
    pub slip: f64,
}

/// The kinematics of wheel `j` at body state `(vx, vy, gamma)`, road-wheel angle `delta` (used
/// if the wheel is steered) and wheel speed `omega` \[rad/s\]; `v_min` is the low-speed guard.
#[must_use]
pub fn wheel_kinematics(
    geometry: &Geometry,
    j: usize,
    state: [f64; 3],
    delta: f64,
    omega: f64,
    rolling_radius: f64,
    v_min: f64,
) -> WheelKinematics {
    let [vx, vy, gamma] = state;
    let u = vx - geometry.y[j] * gamma;
    let v = vy + geometry.x[j] * gamma;
    let delta = if geometry.steered[j] { delta } else { 0.0 };
    let (sin_delta, cos_delta) = delta.sin_cos();
    let alpha = delta - v.atan2(u);
    let vl = u * cos_delta + v * sin_delta;
    let omega_re = omega * rolling_radius;
    let slip = (omega_re - vl) / omega_re.abs().max(vl.abs()).max(v_min);
    WheelKinematics { u, v, delta, cos_delta, sin_delta, alpha, vl, omega_re, slip }
}

/// Gradients of a wheel's slip angle and slip ratio with respect to `x = [V_x, V_y, γ]`
/// (digest §3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WheelGradients {
    /// `∂α_j/∂x = [v_j, −u_j, −(x_j·u_j + y_j·v_j)] / max(u_j² + v_j², v_min²)`.
    pub alpha: [f64; 3],
    /// `∂s_j/∂x = (∂s/∂v_l)·∂v_l/∂x` with `∂v_l/∂x = [cos δ, sin δ, x_j·sin δ − y_j·cos δ]` and
    /// `∂s/∂v_l = −1/|ωR_e|` where `|ωR_e|` is the denominator (drive), `−sign(v_l)·ωR_e/v_l²`
    /// where `|v_l|` is (brake), `−1/v_min` where the guard is.
    pub slip: [f64; 3],
}

/// The gradients of wheel `j` (the kinematics `k` must come from [`wheel_kinematics`] with the
/// same `v_min`). Exact except where the floor `v_min²` on `u² + v²` acts (wheel ground speed
/// below `v_min`) and on the switching surfaces `|ωR_e| = |v_l|` of the slip denominator, where
/// `s` is not differentiable.
#[must_use]
pub fn wheel_gradients(geometry: &Geometry, j: usize, k: &WheelKinematics, v_min: f64) -> WheelGradients {
    let (xj, yj) = (geometry.x[j], geometry.y[j]);
    let q = (k.u * k.u + k.v * k.v).max(v_min * v_min);
    let alpha = [k.v / q, -k.u / q, -(xj * k.u + yj * k.v) / q];
    let dvl = [k.cos_delta, k.sin_delta, xj * k.sin_delta - yj * k.cos_delta];
    let (wr, vl) = (k.omega_re.abs(), k.vl.abs());
    let ds_dvl = if wr >= vl && wr >= v_min {
        -1.0 / wr
    } else if vl >= v_min {
        -k.vl.signum() * k.omega_re / (k.vl * k.vl)
    } else {
        -1.0 / v_min
    };
    WheelGradients { alpha, slip: dvl.map(|d| ds_dvl * d) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinematics_signs_and_gradients() {
        let p = TruckParams::digest_preset();
        let g = Geometry::new(&p);
        let (re, vmin) = (p.rolling_radius, p.min_speed);
        // Left turn at zero sideslip: both axles see α > 0 (centripetal forces); sideslip to the
        // left gives the rear wheels α < 0.
        let x = [15.0, 0.0, 0.1];
        let front = wheel_kinematics(&g, 0, x, 0.05, 15.0 / re, re, vmin);
        let rear = wheel_kinematics(&g, 4, x, 0.05, 15.0 / re, re, vmin);
        assert!(front.alpha > 0.0 && rear.alpha > 0.0 && rear.delta == 0.0);
        assert!(wheel_kinematics(&g, 4, [15.0, 0.5, 0.0], 0.0, 0.0, re, vmin).alpha < 0.0);
        // Drive slip and brake slip.
        assert!(wheel_kinematics(&g, 2, [10.0, 0.0, 0.0], 0.0, 10.5 / re, re, vmin).slip > 0.0);
        let locked = wheel_kinematics(&g, 2, [10.0, 0.0, 0.0], 0.0, 0.0, re, vmin);
        assert_eq!(locked.slip, -1.0);
        // Gradients against central differences, in all three slip regimes.
        for (j, omega, delta) in [(0, 16.0 / re, 0.04), (1, 14.0 / re, -0.03), (3, 0.02, 0.0), (5, 15.5 / re, 0.0)] {
            let x = [15.0, 0.4, 0.12];
            let k = wheel_kinematics(&g, j, x, delta, omega, re, vmin);
            let grad = wheel_gradients(&g, j, &k, vmin);
            for i in 0..3 {
                let h = 1e-6;
                let (mut xp, mut xm) = (x, x);
                xp[i] += h;
                xm[i] -= h;
                let kp = wheel_kinematics(&g, j, xp, delta, omega, re, vmin);
                let km = wheel_kinematics(&g, j, xm, delta, omega, re, vmin);
                let da = (kp.alpha - km.alpha) / (2.0 * h);
                let ds = (kp.slip - km.slip) / (2.0 * h);
                assert!((da - grad.alpha[i]).abs() < 1e-8, "wheel {j}, ∂α/∂x{i}: {da} vs {}", grad.alpha[i]);
                assert!((ds - grad.slip[i]).abs() < 1e-8, "wheel {j}, ∂s/∂x{i}: {ds} vs {}", grad.slip[i]);
            }
        }
    }
}
