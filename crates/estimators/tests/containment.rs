//! Certified containment: random systems, noise on the boundary of its sets, `x₀` on the
//! boundary of the initial set; the true state must satisfy
//! `(x − x̂)ᵀ P⁻¹ (x − x̂) ≤ 1 + 1e-9` at every step. Two-multiplier path (≥ 10 000 steps),
//! the SDP-backend path, the Yang–Li reconstruction (a), and the fallback path (a stub solver
//! that always hits its iteration limit, a zero time budget, and stub solvers that report
//! "solved" with finite but unusable results).
//!
//! The random systems rarely make the bound tight, so they cannot tell a certified shape from
//! an uncertified one. The adversarial tests can: a useless sensor puts the optimum on the edge
//! `τ₃ = 0` (pure prediction), where the trace-optimal outer bound of the Minkowski sum is exact
//! along the error direction when `P` stays proportional to `Q`; with the error on the boundary
//! and the noise on the boundary pushing outward, the true state stays on the boundary of the
//! estimate, so `1 − 1e-6 ≤ (x − x̂)ᵀ P⁻¹ (x − x̂) ≤ 1 + 1e-12` at every step.

mod common;

use common::FixedSolver;

use std::time::Duration;

use estimators::smf::FallbackReason;
use estimators::{SdpUpdateSolver, SetMembershipFilter, StepModel, TwoMultiplierSolver, UpdateSolver, yang_li};
use models::{Noise, Xoshiro256StarStar};
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
    let wn = Noise::ellipsoid_boundary(sys.q.clone()).unwrap();
    let vn = Noise::ellipsoid_boundary(sys.r.clone()).unwrap();
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
        let mut f = SetMembershipFilter::new(common::setup(&sys.x_hat0, &sys.p0, &sys.q, &sys.r, 2)).unwrap();
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
            common::setup(&sys.x_hat0, &sys.p0, &sys.q, &sys.r, lo.len()),
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
    // Warm-started solves, as the filters built through `LinearSetup` use them.
    let settings = || lmi::SolverSettings { warm_start: true, ..lmi::SolverSettings::default() };
    for (name, _) in common::backends(settings()) {
        let (mut total, mut worst, mut fb) = (0, 0.0f64, 0);
        for i in [1usize, 3, 4, 6] {
            let sys = random_system(&mut rng, i);
            let backend = common::backends(settings()).into_iter().find(|(n, _)| *n == name).unwrap().1;
            let mut f = SetMembershipFilter::with_solver(
                common::setup(&sys.x_hat0, &sys.p0, &sys.q, &sys.r, 2),
                SdpUpdateSolver::new(backend),
            )
            .unwrap();
            let (w, f_) = run(&sys, &mut f, &mut rng, 75, gauss_u);
            // The test is about the SDP path: every step must use the backend's τ.
            assert_eq!(f_, 0, "SDP ({name}), system {i}: {f_} of 75 steps fell back");
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
fn never_converges() -> FixedSolver {
    FixedSolver {
        l: f64::NAN,
        tau: [0.9, 0.9, 0.9],
        status: estimators::smf::UpdateStatus::IterationLimit,
        iterations: 100,
        closed_form: false,
    }
}

#[test]
fn fallback_path_contains_the_true_state() {
    let mut rng = Xoshiro256StarStar::seed_from_u64(10);
    let (mut total, mut worst) = (0, 0.0f64);
    for i in 0..10 {
        let sys = random_system(&mut rng, i);
        let mut f =
            SetMembershipFilter::with_solver(common::setup(&sys.x_hat0, &sys.p0, &sys.q, &sys.r, 2), never_converges())
                .unwrap();
        let (w, fb) = run(&sys, &mut f, &mut rng, 100, gauss_u);
        assert_eq!(fb, 100);
        assert_eq!(
            f.estimate().report.fallback,
            Some(FallbackReason::Status(estimators::smf::UpdateStatus::IterationLimit))
        );
        total += 100;
        worst = worst.max(w);
        // Zero time budget with the exact solver: every step falls back too.
        let mut g = SetMembershipFilter::new(common::setup(&sys.x_hat0, &sys.p0, &sys.q, &sys.r, 2)).unwrap();
        g.set_time_budget(Some(Duration::ZERO));
        let (w, fb) = run(&sys, &mut g, &mut rng, 100, gauss_u);
        assert_eq!(fb, 100);
        assert_eq!(g.estimate().report.fallback, Some(FallbackReason::TimeBudget));
        total += 100;
        worst = worst.max(w);
    }
    println!("fallback: {total} steps, worst normalised distance 1 {:+.2e}", worst - 1.0);
}

#[test]
fn finite_but_unusable_solver_results_fall_back_and_stay_contained() {
    // Each of these used to make every step fail with "the set estimate is not finite" (a
    // deterministic solver then leaves the filter stuck): τ₁ = 0 after normalising an
    // overflowing sum; 1/τ₃ with τ₃ subnormal and L ≠ 0; τ₁ below the floor after dividing by
    // Στ; L R Lᵀ overflowing.
    let cases = [
        ("τ = 1e308 (Στ overflows)", [1e308; 3], 0.5),
        ("τ₃ = 1e-320 with L ≠ 0", [0.5, 0.5, 1e-320], 1.0),
        ("τ = (0, 0, 1e300)", [0.0, 0.0, 1e300], 0.5),
        ("L = 1e200", [1.0 / 3.0; 3], 1e200),
    ];
    let mut rng = Xoshiro256StarStar::seed_from_u64(11);
    for (what, tau, l) in cases {
        let mut worst = 0.0f64;
        for i in 0..10 {
            let sys = random_system(&mut rng, i);
            // `Solved` with a finite but unusable (L, τ), claiming L is the closed-form gain (so the
            // filter certifies it as it is).
            let solver =
                FixedSolver { l, tau, status: estimators::smf::UpdateStatus::Solved, iterations: 1, closed_form: true };
            let mut f =
                SetMembershipFilter::with_solver(common::setup(&sys.x_hat0, &sys.p0, &sys.q, &sys.r, 2), solver)
                    .unwrap();
            // `run` unwraps every step and asserts containment.
            let (w, fb) = run(&sys, &mut f, &mut rng, 60, gauss_u);
            assert_eq!(fb, 60, "{what}, system {i}");
            let report = &f.estimate().report;
            assert_eq!(report.fallback, Some(FallbackReason::InvalidSolution), "{what}, system {i}");
            let t = report.tau;
            assert!(t[0] >= estimators::smf::TAU_FLOOR && t[1] >= estimators::smf::TAU_FLOOR && t[2] >= 0.0, "{t:?}");
            assert!(t[0] + t[1] + t[2] <= 1.0, "{t:?}");
            worst = worst.max(w);
        }
        println!("{what}: 600 steps, all fell back, worst normalised distance 1 {:+.2e}", worst - 1.0);
    }
}

/// Runs a filter on `x_{k+1} = a x_k + B u_k + g` (noise `g = G z` fixed on the boundary of
/// `𝓔(0, G Gᵀ)`), `y = C x + v` with `v` on the boundary of `𝓔(0, R)`, from
/// `x₀ = x̂₀ + e₀`; returns the normalised distances and checks that every step is on the
/// edge `τ₃ = 0` without fallback.
fn adversarial_run(
    filter: &mut SetMembershipFilter,
    a: f64,
    b: &DMatrix<f64>,
    c: &DMatrix<f64>,
    v: &DVector<f64>,
    x0: DVector<f64>,
    g: &DVector<f64>,
    steps: usize,
) -> Vec<f64> {
    let n = x0.len();
    let am = DMatrix::identity(n, n) * a;
    let mut x = x0;
    let mut out = Vec::with_capacity(steps);
    for k in 0..steps {
        let u = DVector::from_fn(b.ncols(), |i, _| (0.1 * (k + 3 * i) as f64).sin());
        x = &am * &x + b * &u + g;
        let y = c * &x + v;
        let e = filter.step(&StepModel::new(&am, b, c), &u, &y).unwrap();
        assert!(e.report.fallback.is_none(), "step {k}: {:?}", e.report);
        assert_eq!(e.report.tau[2], 0.0, "step {k}: not on the edge τ₃ = 0: {:?}", e.report);
        out.push(common::normalized_distance(&e.shape, &e.center, &x));
    }
    out
}

fn check_tight(what: &str, d: &[f64]) {
    let (lo, hi) = d.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    println!("{what}: {} steps, normalised distance in [1 {:+.2e}, 1 {:+.2e}]", d.len(), lo - 1.0, hi - 1.0);
    for (k, &v) in d.iter().enumerate() {
        assert!(v <= 1.0 + 1e-12, "{what}, step {k}: distance {v} (the certification must cover rounding)");
        assert!(v >= 1.0 - 1e-6, "{what}, step {k}: distance {v} (the bound should be tight here)");
    }
}

#[test]
fn adversarial_scalar_case_is_tight_and_contained() {
    // x⁺ = 0.95 x + 0.3 u + w, |w| ≤ √Q = 0.2, useless sensor (R = 1e12 ≫ P ≈ 16): the optimum
    // is τ₃ = 0, L = 0, and P⁺ = min over τ₁ of a²P/τ₁ + Q/(1 − τ₁) = (a√P + √Q)², the exact
    // interval sum. With e₀ = +√P₀ and w = +√Q every step, e_k = √P_k exactly.
    let (a, q, r, p0) = (0.95, 0.04, 1e12, 2.25);
    let b = DMatrix::from_element(1, 1, 0.3);
    let c = DMatrix::from_element(1, 1, 1.0);
    let x_hat0 = DVector::from_element(1, 0.5);
    let mut f = SetMembershipFilter::new(common::setup(
        &x_hat0,
        &DMatrix::from_element(1, 1, p0),
        &DMatrix::from_element(1, 1, q),
        &DMatrix::from_element(1, 1, r),
        1,
    ))
    .unwrap();
    let x0 = &x_hat0 + DVector::from_element(1, p0.sqrt());
    let d = adversarial_run(
        &mut f,
        a,
        &b,
        &c,
        &DVector::from_element(1, r.sqrt()),
        x0,
        &DVector::from_element(1, q.sqrt()),
        1000,
    );
    check_tight("adversarial scalar", &d);
}

#[test]
fn adversarial_multidimensional_case_is_tight_and_contained() {
    // A = 0.9 I, Q = D, P₀ = 4 D (D random SPD), a useless sensor: P_k = c_k D with
    // √c_{k+1} = 0.9 √c_k + 1, and the trace-optimal τ₁ is the exact one along every direction.
    // With e₀ = 2 G z and w = G z (G Gᵀ = D, ‖z‖ = 1: the error and the noise at the same
    // boundary point, the vertex of an axis of the ellipsoid for z = eᵢ), e_k = √c_k G z is on
    // the boundary of 𝓔(0, P_k) at every step.
    let mut rng = Xoshiro256StarStar::seed_from_u64(12);
    let n = 3;
    let d = common::spd(&mut rng, n, 1.0, 10.0);
    let g = d.clone().cholesky().unwrap().l();
    let b = common::gauss(&mut rng, n, 2);
    let c = common::gauss(&mut rng, 2, n);
    let r = DMatrix::identity(2, 2) * 1e12;
    let x_hat0 = common::gauss(&mut rng, n, 1).column(0).into_owned();
    let mut zs: Vec<DVector<f64>> = (0..n).map(|i| DVector::from_fn(n, |j, _| f64::from(u8::from(i == j)))).collect();
    let z = common::gauss(&mut rng, n, 1).column(0).into_owned();
    zs.push(&z / z.norm());
    for (i, z) in zs.iter().enumerate() {
        let mut f = SetMembershipFilter::new(common::setup(&x_hat0, &(&d * 4.0), &d, &r, 2)).unwrap();
        let w = &g * z;
        let x0 = &x_hat0 + &w * 2.0;
        let v = DVector::from_vec(vec![1e6, 0.0]);
        let dist = adversarial_run(&mut f, 0.9, &b, &c, &v, x0, &w, 1000);
        check_tight(&format!("adversarial n = 3, direction {i}"), &dist);
    }
}
