//! Certified containment: random systems, noise on the boundary of its sets, `x₀` on the
//! boundary of the initial set; the true state must satisfy
//! `(x − x̂)ᵀ P⁻¹ (x − x̂) ≤ 1 + 1e-9` at every step. Two-multiplier path (≥ 10 000 steps),
//! the SDP-backend path, the Yang–Li reconstruction (a), and the fallback path (a stub solver
//! that always hits its iteration limit, and a zero time budget).

mod common;

use std::time::Duration;

use carrier_dynamics::{BoundedNoise, Xoshiro256StarStar};
use estimators::{
    FallbackReason, SdpUpdateSolver, SetMembershipFilter, StepModel, TwoMultiplierSolver, UpdateProblem,
    UpdateSolution, UpdateSolver, yang_li,
};
use nalgebra::{DMatrix, DVector};

const TOL: f64 = 1e-9;

struct Sys {
    a: Vec<DMatrix<f64>>,
    b: DMatrix<f64>,
    c: DMatrix<f64>,
    q: DMatrix<f64>,
    r: DMatrix<f64>,
    p0: DMatrix<f64>,
    x_hat0: DVector<f64>,
}

fn random_system(rng: &mut Xoshiro256StarStar, i: usize) -> Sys {
    let n = 1 + i % 4;
    let m = 1 + (i / 4) % n;
    let radius = [0.7, 0.95, 1.0, 1.02][i % 4];
    let a0 = common::random_a(rng, n, radius);
    // Time-varying: a few matrices cycled through (the LDTV framing).
    let a = (0..3).map(|_| &a0 + common::gauss(rng, n, n) * 0.01).collect();
    let (qc, rc) = if i % 3 == 0 { (1e3, 1e2) } else { (2.0, 2.0) };
    // Boundary regimes: square C with a precise sensor (optimum at or near the vertex
    // τ = (0, 0, 1)), and a useless sensor (optimum on the edge τ₃ = 0).
    let (c, r_scale) = match i % 5 {
        3 => (DMatrix::identity(n, n), 1e-4),
        4 => (common::gauss(rng, m, n), 1e6),
        _ => (common::gauss(rng, m, n), 0.2),
    };
    let m = c.nrows();
    Sys {
        a,
        b: common::gauss(rng, n, 2),
        c,
        q: common::spd(rng, n, 0.1, qc),
        r: common::spd(rng, m, r_scale, rc),
        p0: common::spd(rng, n, 1.0, 5.0),
        x_hat0: common::gauss(rng, n, 1).column(0).into(),
    }
}

/// Runs `steps` steps with worst-case (boundary) noise; returns the largest normalised
/// distance seen and how many steps fell back.
fn run<S: UpdateSolver>(
    sys: &Sys,
    filter: &mut SetMembershipFilter<S>,
    rng: &mut Xoshiro256StarStar,
    steps: usize,
    u_of: impl Fn(&mut Xoshiro256StarStar) -> DVector<f64>,
) -> (f64, usize) {
    let wn = BoundedNoise::ellipsoid_boundary(sys.q.clone()).unwrap();
    let vn = BoundedNoise::ellipsoid_boundary(sys.r.clone()).unwrap();
    let mut x = common::boundary_point(rng, &sys.x_hat0, &sys.p0);
    let mut worst: f64 = 0.0;
    let mut fallbacks = 0;
    for k in 0..steps {
        let a = &sys.a[k % sys.a.len()];
        let u = u_of(rng);
        x = a * &x + &sys.b * &u + wn.sample(rng);
        let y = &sys.c * &x + vn.sample(rng);
        let e = filter.step(&StepModel::new(a, &sys.b, &sys.c), &u, &y).unwrap();
        let d = common::normalized_distance(&e.shape, &e.center, &x);
        assert!(d <= 1.0 + TOL, "step {k}: distance {d}, report {:?}", e.report);
        worst = worst.max(d);
        fallbacks += usize::from(e.report.fallback.is_some());
    }
    (worst, fallbacks)
}

fn gauss_u(rng: &mut Xoshiro256StarStar) -> DVector<f64> {
    DVector::from_fn(2, |_, _| rng.standard_normal())
}

#[test]
fn two_multiplier_path_contains_the_true_state() {
    let mut rng = Xoshiro256StarStar::seed_from_u64(7);
    let (mut total, mut worst, mut fb) = (0, 0.0f64, 0);
    for i in 0..40 {
        let sys = random_system(&mut rng, i);
        let mut f =
            SetMembershipFilter::two_multiplier(sys.x_hat0.clone(), sys.p0.clone(), sys.q.clone(), sys.r.clone(), 2)
                .unwrap();
        let (w, f_) = run(&sys, &mut f, &mut rng, 300, gauss_u);
        total += 300;
        worst = worst.max(w);
        fb += f_;
    }
    println!("two-multiplier: {total} steps, worst normalised distance 1 {:+.2e}, fallbacks {fb}", worst - 1.0);
    assert!(total >= 10_000);
    assert_eq!(fb, 0);
}

#[test]
fn yang_li_without_input_contains_the_true_state() {
    let mut rng = Xoshiro256StarStar::seed_from_u64(8);
    let (lo, hi) = (DVector::from_vec(vec![-1.0, 0.5]), DVector::from_vec(vec![2.0, 0.5]));
    let (mut total, mut worst) = (0, 0.0f64);
    for i in 0..8 {
        let sys = random_system(&mut rng, i);
        let mut f = yang_li::without_input(
            sys.x_hat0.clone(),
            sys.p0.clone(),
            sys.q.clone(),
            sys.r.clone(),
            &lo,
            &hi,
            TwoMultiplierSolver::new(),
        )
        .unwrap();
        // Inputs on the corners of the box: the worst case for the ellipsoidal cover.
        let (w, _) = run(&sys, &mut f, &mut rng, 200, |r| {
            DVector::from_vec(vec![if r.next_f64() < 0.5 { -1.0 } else { 2.0 }, 0.5])
        });
        total += 200;
        worst = worst.max(w);
    }
    println!("yang-li (a): {total} steps, worst normalised distance 1 {:+.2e}", worst - 1.0);
}

#[test]
fn sdp_path_contains_the_true_state() {
    let mut rng = Xoshiro256StarStar::seed_from_u64(9);
    for (name, _) in common::backends(lmi::SolverSettings::default()) {
        let (mut total, mut worst, mut fb) = (0, 0.0f64, 0);
        for i in [1usize, 3, 4, 6] {
            let sys = random_system(&mut rng, i);
            let backend =
                common::backends(lmi::SolverSettings::default()).into_iter().find(|(n, _)| *n == name).unwrap().1;
            let mut f = SetMembershipFilter::new(
                sys.x_hat0.clone(),
                sys.p0.clone(),
                sys.q.clone(),
                sys.r.clone(),
                2,
                SdpUpdateSolver::new(backend),
            )
            .unwrap();
            let (w, f_) = run(&sys, &mut f, &mut rng, 75, gauss_u);
            if f_ > 0 {
                println!(
                    "SDP ({name}), system {i}: {f_} of 75 steps fell back, last: {:?}",
                    f.estimate().report.fallback
                );
            }
            total += 75;
            worst = worst.max(w);
            fb += f_;
        }
        println!("SDP ({name}): {total} steps, worst normalised distance 1 {:+.2e}, fallbacks {fb}", worst - 1.0);
    }
}

/// A solver that never converges.
struct Stub;

impl UpdateSolver for Stub {
    fn name(&self) -> &str {
        "stub"
    }
    fn prepare(&mut self, _: usize, _: usize) -> Result<(), estimators::EstimatorError> {
        Ok(())
    }
    fn solve(
        &mut self,
        _: &UpdateProblem<'_>,
        _: [f64; 3],
        out: &mut UpdateSolution,
    ) -> Result<(), estimators::EstimatorError> {
        out.l.fill(f64::NAN);
        out.tau = [0.9, 0.9, 0.9];
        out.status = lmi::SolveStatus::IterationLimit;
        out.iterations = 100;
        Ok(())
    }
}

#[test]
fn fallback_path_contains_the_true_state() {
    let mut rng = Xoshiro256StarStar::seed_from_u64(10);
    let (mut total, mut worst) = (0, 0.0f64);
    for i in 0..10 {
        let sys = random_system(&mut rng, i);
        let mut f = SetMembershipFilter::new(sys.x_hat0.clone(), sys.p0.clone(), sys.q.clone(), sys.r.clone(), 2, Stub)
            .unwrap();
        let (w, fb) = run(&sys, &mut f, &mut rng, 100, gauss_u);
        assert_eq!(fb, 100);
        assert_eq!(f.estimate().report.fallback, Some(FallbackReason::Status(lmi::SolveStatus::IterationLimit)));
        total += 100;
        worst = worst.max(w);
        // Zero time budget with the exact solver: every step falls back too.
        let mut g =
            SetMembershipFilter::two_multiplier(sys.x_hat0.clone(), sys.p0.clone(), sys.q.clone(), sys.r.clone(), 2)
                .unwrap();
        g.set_time_budget(Some(Duration::ZERO));
        let (w, fb) = run(&sys, &mut g, &mut rng, 100, gauss_u);
        assert_eq!(fb, 100);
        assert_eq!(g.estimate().report.fallback, Some(FallbackReason::TimeBudget));
        total += 100;
        worst = worst.max(w);
    }
    println!("fallback: {total} steps, worst normalised distance 1 {:+.2e}", worst - 1.0);
}
