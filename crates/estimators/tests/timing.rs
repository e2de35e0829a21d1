//! Release-mode timing loop (not a benchmark suite, no assertions): run with
//! `cargo test --release -p estimators --test timing -- --ignored --nocapture`.

mod common;

use std::time::Instant;

use estimators::{KalmanFilter, SdpUpdateSolver, SetMembershipFilter, StepModel, UpdateSolver};
use nalgebra::{DMatrix, DVector};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    v[v.len() / 2]
}

/// The Table 1 carrier at 6 m/s, `T_s = 1 ms`, last `m` states measured, small noise: the
/// filter has work to do (as in the workspace's criterion bench).
fn time_carrier(m: usize) {
    let d = carrier_dynamics::CarrierModel::new(carrier_dynamics::CarrierParams::paper_preset())
        .unwrap()
        .discretize(1e-3)
        .unwrap();
    let (a, b, _) = d.to_dynamic();
    let c = DMatrix::from_fn(m, 4, |i, j| if j == 4 - m + i { 1.0 } else { 0.0 });
    let q = DMatrix::from_diagonal(&DVector::from_vec(vec![1.6e-7, 1e-6, 4e-10, 1e-6]));
    let r = DMatrix::identity(m, m) * 2e-5;
    let model = StepModel::new(&a, &b, &c);
    let u = DVector::from_element(8, 0.01);
    let mut f =
        SetMembershipFilter::two_multiplier(DVector::zeros(4), DMatrix::identity(4, 4) * 1e-2, q, r, 8).unwrap();
    let mut samples = Vec::new();
    let mut iters = 0u64;
    for k in 0..20000 {
        let y = DVector::from_fn(m, |i, _| 1e-3 * ((k * 7 + i * 3) % 11) as f64 - 5e-3);
        let t = Instant::now();
        let e = f.step(&model, &u, &y).unwrap();
        samples.push(t.elapsed().as_secs_f64() * 1e6);
        iters += u64::from(e.report.iterations);
    }
    println!(
        "{:>28} carrier (n, m) = (4, {m}): median {:8.3} µs, mean iterations {:.2}, tau {:?}",
        "two-multiplier SMF",
        median(samples),
        iters as f64 / 20000.0,
        f.estimate().report.tau
    );
}

fn system(m: usize) -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
    let a = common::reference_a();
    let b = DMatrix::from_fn(4, 2, |i, j| 0.01 * (i as f64 + 1.0) * if j == 0 { 1.0 } else { -0.5 });
    let c = if m == 3 { common::reference_c() } else { DMatrix::identity(4, 4) };
    (a, b, c)
}

/// `varying`: the model alternates between `A` and a perturbed `A`, and `R` between two
/// scales, so that `τ` moves every step (no free warm start).
fn time_smf<S: UpdateSolver>(label: &str, m: usize, solver: S, steps: usize, varying: bool) {
    let (a, b, c) = system(m);
    let a2 = &a * 0.97 + DMatrix::from_fn(4, 4, |i, j| 0.02 * ((i * 4 + j) as f64).sin());
    let (r1, r2) = (DMatrix::identity(m, m) * 0.05, DMatrix::identity(m, m) * 0.5);
    let mut f = SetMembershipFilter::new(
        DVector::zeros(4),
        DMatrix::identity(4, 4) * 0.5,
        DMatrix::identity(4, 4) * 0.01,
        DMatrix::identity(m, m) * 0.05,
        2,
        solver,
    )
    .unwrap();
    let u = DVector::from_vec(vec![0.1, -0.2]);
    let mut samples = Vec::with_capacity(steps);
    let mut iters = 0u64;
    for k in 0..steps {
        let y = DVector::from_fn(m, |i, _| 0.1 * ((k + i) as f64 * 0.37).sin());
        if varying {
            f.set_measurement_noise(if k % 2 == 0 { &r1 } else { &r2 }).unwrap();
        }
        let model = StepModel::new(if varying && k % 2 == 1 { &a2 } else { &a }, &b, &c);
        let t = Instant::now();
        let e = f.step(&model, &u, &y).unwrap();
        samples.push(t.elapsed().as_secs_f64() * 1e6);
        iters += u64::from(e.report.iterations);
    }
    let e = f.estimate();
    println!(
        "{label:>28}{} (n, m) = (4, {m}): median {:8.3} µs over {steps} steps, mean iterations {:.2}, trace {:.6}, fallback {:?}",
        if varying { " varying" } else { " constant" },
        median(samples),
        iters as f64 / steps as f64,
        e.trace(),
        e.report.fallback
    );
}

#[test]
#[ignore = "timing; run in release with --ignored --nocapture"]
fn step_times() {
    for m in [3, 4] {
        let (a, b, c) = system(m);
        let model = StepModel::new(&a, &b, &c);
        let mut kf = KalmanFilter::new(
            DVector::zeros(4),
            DMatrix::identity(4, 4),
            DMatrix::identity(4, 4) * 0.01,
            DMatrix::identity(m, m) * 0.05,
            2,
        )
        .unwrap();
        let u = DVector::from_vec(vec![0.1, -0.2]);
        let mut samples = Vec::new();
        for k in 0..20000 {
            let y = DVector::from_fn(m, |i, _| 0.1 * ((k + i) as f64 * 0.37).sin());
            let t = Instant::now();
            kf.step(&model, &u, &y).unwrap();
            samples.push(t.elapsed().as_secs_f64() * 1e6);
        }
        println!("{:>28} (n, m) = (4, {m}): median {:8.3} µs", "Kalman", median(samples));
        time_carrier(m);
        for varying in [false, true] {
            time_smf("two-multiplier SMF", m, estimators::TwoMultiplierSolver::new(), 20000, varying);
            for (name, backend) in common::backends(lmi::SolverSettings::default()) {
                time_smf(&format!("SDP SMF ({name})"), m, SdpUpdateSolver::new(backend), 300, varying);
            }
        }
    }
}
