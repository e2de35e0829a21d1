//! The INS error model against independent references: the note's scalar equations (10) written
//! out, a Taylor series of `e^{FT}` (not the Padé approximant of `models::expm`), closed forms of
//! the flat model, the Schuler period, and `Q_k` by Simpson quadrature.

use bds_ins_dynamics::{
    BiasFrame, Earth, GRAVITY, InsErrorModel, InsNoise, InsParams, MEASUREMENTS, STATES, idx, measurement_matrix,
    simulate_error_states,
};
use models::Xoshiro256StarStar;
use nalgebra::{DMatrix, DVector};

/// The right-hand side of (10) as the note writes it, entry by entry (nav-frame biases, no noise).
fn scalar_rhs(p: &InsParams, x: &DVector<f64>) -> DVector<f64> {
    let (ws, wc, tr, ir) = match p.earth {
        Earth::Rotating { latitude } => (
            p.earth_rate * latitude.sin(),
            p.earth_rate * latitude.cos(),
            latitude.tan() / p.earth_radius,
            1.0 / p.earth_radius,
        ),
        _ => (0.0, 0.0, 0.0, 0.0),
    };
    let g = p.gravity;
    let [fe, fn_] = p.specific_force;
    let [_, _, dve, dvn, dpsi, dthx, dthy, ae, an, _, ge, gn, gu] =
        <[f64; 13]>::try_from(x.as_slice()).expect("13 states");
    let mut d = DVector::zeros(13);
    d[0] = dve;
    d[1] = dvn;
    d[2] = 2.0 * ws * dvn - g * dthy + fn_ * dpsi + ae;
    d[3] = -2.0 * ws * dve + g * dthx - fe * dpsi + an;
    d[5] = -dvn * ir + ws * dthy - wc * dpsi - ge;
    d[6] = dve * ir - ws * dthx - gn;
    d[4] = tr * dve + wc * dthx - gu;
    d
}

fn test_state() -> DVector<f64> {
    DVector::from_fn(STATES, |i, _| ((i as f64 + 1.0) * 0.7).sin() * 10f64.powi(-(i as i32 % 4)))
}

/// `e^{M}` by its Taylor series with scaling and squaring (an independent reference).
fn expm_taylor(m: &DMatrix<f64>) -> DMatrix<f64> {
    let n = m.nrows();
    let s = (m.norm() / 0.1).log2().ceil().max(0.0) as i32;
    let a = m / 2f64.powi(s);
    let mut term = DMatrix::identity(n, n);
    let mut sum = DMatrix::identity(n, n);
    for k in 1..30 {
        term = &term * &a / k as f64;
        sum += &term;
    }
    for _ in 0..s {
        sum = &sum * &sum;
    }
    sum
}

#[test]
fn the_system_matrix_is_the_notes_equations() {
    let x = test_state();
    for p in [
        InsParams::digest(),
        InsParams::flat(),
        InsParams { specific_force: [0.3, -0.2], ..InsParams::digest() },
        InsParams { earth: Earth::Rotating { latitude: -0.9 }, ..InsParams::digest() },
    ] {
        let f = InsErrorModel::new(p, InsNoise::digest()).unwrap().system_matrix();
        let want = scalar_rhs(&p, &x);
        let got = &f * &x;
        assert!((&got - &want).amax() <= 1e-15 * want.amax(), "{p:?}: {got} vs {want}");
    }
}

#[test]
fn body_frame_biases_are_rotated_by_the_heading() {
    let nav = InsErrorModel::new(InsParams::digest(), InsNoise::digest()).unwrap().system_matrix();
    let at = |azimuth: f64| {
        InsErrorModel::new(
            InsParams { bias_frame: BiasFrame::Body { azimuth }, ..InsParams::digest() },
            InsNoise::digest(),
        )
        .unwrap()
        .system_matrix()
    };
    // Heading north: body right = east, forward = north: the same model.
    assert!((at(0.0) - &nav).amax() < 1e-15);
    // Heading east: a bias to the right (south) slows the north velocity; a forward bias speeds east.
    let east = at(std::f64::consts::FRAC_PI_2);
    assert!((east[(idx::DVN, idx::ACC_E)] + 1.0).abs() < 1e-15 && east[(idx::DVE, idx::ACC_E)].abs() < 1e-15);
    assert!((east[(idx::DVE, idx::ACC_N)] - 1.0).abs() < 1e-15);
    assert!((east[(idx::DTHY, idx::GYRO_E)] - 1.0).abs() < 1e-15);
    // Vertical terms do not rotate.
    assert_eq!(east[(idx::DPSI, idx::GYRO_U)], -1.0);
}

#[test]
fn the_transition_matrix_matches_a_taylor_series() {
    let m = InsErrorModel::new(InsParams::digest(), InsNoise::digest()).unwrap();
    for ts in [0.01, 1.0, 60.0] {
        let d = m.discretize(ts).unwrap();
        let want = expm_taylor(&(m.system_matrix() * ts));
        let err = (&d.phi - &want).amax();
        assert!(err < 1e-12 * want.amax(), "T = {ts}: {err}");
    }
}

#[test]
fn flat_model_closed_forms() {
    let m = InsErrorModel::new(InsParams::flat(), InsNoise::digest()).unwrap();
    let t = 3.0;
    let phi = m.discretize(t).unwrap().phi;
    let g = GRAVITY;
    // Chain δx ← δvE ← (−g δθy + ∇E) ← −εN: powers of T.
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1.0);
    assert!(close(phi[(idx::DX, idx::DVE)], t));
    assert!(close(phi[(idx::DX, idx::DTHY)], -g * t * t / 2.0));
    assert!(close(phi[(idx::DX, idx::ACC_E)], t * t / 2.0));
    assert!(close(phi[(idx::DX, idx::GYRO_N)], g * t.powi(3) / 6.0));
    assert!(close(phi[(idx::DY, idx::GYRO_E)], -g * t.powi(3) / 6.0));
    assert!(close(phi[(idx::DY, idx::DTHX)], g * t * t / 2.0));
    assert!(close(phi[(idx::DPSI, idx::GYRO_U)], -t));
    // ∇U drives nothing.
    for i in 0..STATES {
        assert_eq!(phi[(i, idx::ACC_U)], if i == idx::ACC_U { 1.0 } else { 0.0 });
    }
}

#[test]
fn the_schuler_loop_closes_after_one_schuler_period() {
    // Without Earth rate at the equator, (δvE, δθy) and (δvN, δθx) oscillate at √(g/R).
    let p = InsParams { earth: Earth::Rotating { latitude: 0.0 }, earth_rate: 0.0, ..InsParams::digest() };
    let m = InsErrorModel::new(p, InsNoise::digest()).unwrap();
    let period = 2.0 * std::f64::consts::PI * (p.earth_radius / p.gravity).sqrt();
    assert!((period / 60.0 - 84.57).abs() < 0.01, "Schuler period {} min", period / 60.0);
    let phi = m.discretize(period).unwrap().phi;
    // Entry scales: velocity per tilt √(gR), tilt per velocity 1/√(gR).
    let amp = (p.gravity * p.earth_radius).sqrt();
    for &(i, j) in &[(idx::DVE, idx::DTHY), (idx::DVN, idx::DTHX)] {
        for &(a, b, scale) in &[(i, i, 1.0), (i, j, amp), (j, i, 1.0 / amp), (j, j, 1.0)] {
            let want = if a == b { 1.0 } else { 0.0 };
            assert!((phi[(a, b)] - want).abs() < 1e-8 * scale, "Φ[{a}][{b}] = {}", phi[(a, b)]);
        }
    }
    // A quarter period turns a tilt into the velocity amplitude −√(gR)·δθy.
    let phi = m.discretize(period / 4.0).unwrap().phi;
    let amp = -(p.gravity * p.earth_radius).sqrt();
    assert!((phi[(idx::DVE, idx::DTHY)] / amp - 1.0).abs() < 1e-9);
}

#[test]
fn process_noise_matches_quadrature() {
    let noise = InsNoise::digest().with_bias_walk(1e-6, 1e-8);
    let m = InsErrorModel::new(InsParams::digest(), noise).unwrap();
    let ts = 1.0;
    let d = m.discretize(ts).unwrap();
    let f = m.system_matrix();
    let gqg = m.noise_input() * m.noise_intensity() * m.noise_input().transpose();
    // Composite Simpson on 200 intervals; Φ(τ) from the Taylor series.
    let n = 200;
    let h = ts / n as f64;
    let mut q = DMatrix::zeros(STATES, STATES);
    for k in 0..=n {
        let e = expm_taylor(&(&f * (k as f64 * h)));
        let w = if k == 0 || k == n {
            1.0
        } else if k % 2 == 1 {
            4.0
        } else {
            2.0
        };
        q += &e * &gqg * e.transpose() * (w * h / 3.0);
    }
    for i in 0..STATES {
        for j in 0..STATES {
            let scale = (q[(i, i)] * q[(j, j)]).sqrt();
            assert!(
                (d.q[(i, j)] - q[(i, j)]).abs() <= 1e-9 * scale + 1e-300,
                "Q[{i}][{j}]: {} vs {}",
                d.q[(i, j)],
                q[(i, j)]
            );
        }
    }
    // Constant biases: no noise on them, nor on ∇U at all.
    let q0 = InsErrorModel::new(InsParams::digest(), InsNoise::digest()).unwrap().discretize(ts).unwrap().q;
    for j in 0..STATES {
        assert_eq!(q0[(idx::ACC_U, j)], 0.0);
        assert_eq!(q0[(idx::GYRO_E, j)], 0.0);
    }
    // Flat model: δx is driven by w_aE twice integrated and by w_gN four times,
    // Q[0][0] = σa² T³/3 + g² σg² T⁵/20.
    let n = InsNoise::digest();
    let qf = InsErrorModel::new(InsParams::flat(), n).unwrap().discretize(2.0).unwrap().q;
    let want = n.accel_white.powi(2) * 8.0 / 3.0 + (GRAVITY * n.gyro_white).powi(2) * 32.0 / 20.0;
    assert!((qf[(0, 0)] / want - 1.0).abs() < 1e-12, "{} vs {want}", qf[(0, 0)]);
}

#[test]
fn measurement_matrix_selects_position_and_heading() {
    let h = measurement_matrix();
    assert_eq!(h.shape(), (MEASUREMENTS, STATES));
    let x = test_state();
    let z = &h * &x;
    assert_eq!(z.as_slice(), &[x[idx::DX], x[idx::DY], x[idx::DPSI]]);
    assert_eq!(h.iter().filter(|v| **v != 0.0).count(), 3);
}

#[test]
fn invalid_parameters_and_periods_are_errors() {
    let m = InsErrorModel::new(InsParams::digest(), InsNoise::digest()).unwrap();
    assert!(m.discretize(0.0).is_err());
    assert!(m.discretize(f64::NAN).is_err());
    assert!(InsErrorModel::new(InsParams { gravity: f64::NAN, ..InsParams::digest() }, InsNoise::digest()).is_err());
}

#[test]
fn the_truth_without_noise_is_the_transition_applied_k_times() {
    let zero = InsNoise { accel_white: 0.0, gyro_white: 0.0, accel_bias_walk: 0.0, gyro_bias_walk: 0.0 };
    let d = InsErrorModel::new(InsParams::digest(), zero).unwrap().discretize(1.0).unwrap();
    let x0 = bds_ins_dynamics::scenario::initial_error();
    let xs = simulate_error_states(&d, &x0, 50, &mut Xoshiro256StarStar::seed_from_u64(1)).unwrap();
    assert_eq!(xs.len(), 51);
    let mut x = x0.clone();
    for _ in 0..50 {
        x = &d.phi * x;
    }
    assert!((&xs[50] - &x).amax() < 1e-12 * x.amax());
    // Same seed, same run; the noise is there with the digest's intensities.
    let d = InsErrorModel::new(InsParams::digest(), InsNoise::digest()).unwrap().discretize(1.0).unwrap();
    let a = simulate_error_states(&d, &x0, 20, &mut Xoshiro256StarStar::seed_from_u64(9)).unwrap();
    let b = simulate_error_states(&d, &x0, 20, &mut Xoshiro256StarStar::seed_from_u64(9)).unwrap();
    assert_eq!(a, b);
    assert!(a[20][idx::DVE] != x0[idx::DVE]);
    // Biases stay exactly constant.
    assert_eq!(a[20][idx::GYRO_N], x0[idx::GYRO_N]);
    assert!(simulate_error_states(&d, &DVector::zeros(12), 1, &mut Xoshiro256StarStar::seed_from_u64(1)).is_err());
}
