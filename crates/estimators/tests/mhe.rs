//! The moving-horizon estimators (docs/robust-mhe.md) against independent references: the Kalman
//! filter (unconstrained linear MHE with the Kalman arrival cost and the filtered prior is the
//! Kalman filter), the closed form of the inner maximisation (`R_eff`), the coordinate rotation
//! against the exact saddle solver, the exact saddle against Clarabel on an uncondensed
//! epigraph formulation, and bad settings and data.

mod common;

use common::lcg::{Data, Lcg, system};
use estimators::mhe::{
    ArrivalRecursion, ArrivalStatus, BlockingPreset, InnerSolver, MheCost, MheSettings, MovingHorizonEstimator,
    PriorMean, WindowSolver, WindowStatus,
};
use estimators::{
    DataCheck, DataChecks, Estimate, Estimator, EstimatorError, InconsistencyPolicy, KalmanFilter, StepModel,
};
use nalgebra::{DMatrix, DVector};

type Case = common::Case<MheSettings>;

impl CaseExt for Case {
    fn with_preset(mut self, horizon: usize, preset: BlockingPreset) -> Result<Self, EstimatorError> {
        self.settings = self.settings.with_preset(horizon, preset)?;
        Ok(self)
    }
}

/// The blocking presets on a case.
trait CaseExt: Sized {
    fn with_preset(self, horizon: usize, preset: BlockingPreset) -> Result<Self, EstimatorError>;
}

fn new_mhe(case: Case, inputs: usize) -> Result<MovingHorizonEstimator, EstimatorError> {
    MovingHorizonEstimator::new(case.setup(inputs), case.settings)
}

/// An estimator without the data check, for the tests whose data leave `V` on purpose (so that
/// the clip of the inner maximisation binds): they compare solvers, not data.
fn unchecked(case: Case, inputs: usize) -> MovingHorizonEstimator {
    let mut e = new_mhe(case, inputs).unwrap();
    e.set_data_checks(DataChecks::OFF).unwrap();
    e
}

fn settings(n: usize, m: usize, cost: MheCost, horizon: usize, w: f64, v: f64) -> Case {
    let mut s = MheSettings::new(
        (DVector::repeat(n, -w), DVector::repeat(n, w)),
        (DVector::repeat(m, -v), DVector::repeat(m, v)),
    );
    s.cost = cost;
    s.horizon = horizon;
    s.blocks = vec![1; horizon];
    Case {
        x0: DVector::from_fn(n, |i, _| 0.1 * i as f64),
        p0: DMatrix::identity(n, n) * 0.5,
        q: DMatrix::identity(n, n) * 0.01,
        r: DMatrix::from_diagonal(&DVector::from_fn(m, |i, _| 0.1 + 0.05 * i as f64)),
        settings: s,
    }
}

/// Simulated data: inputs and measurements with noise uniform in the boxes.
fn data(a: &DMatrix<f64>, b: &DMatrix<f64>, c: &DMatrix<f64>, steps: usize, w: f64, v: f64, seed: u64) -> Data {
    common::lcg::simulate((a, b, c), steps, &mut Lcg(seed ^ 0x9e37), 0.3, (w, v), Lcg::uniform)
}

#[test]
fn unconstrained_mhe_with_the_kalman_arrival_cost_and_filtered_prior_is_the_kalman_filter() {
    for seed in 0..6 {
        let (n, m) = (3 + seed as usize % 2, 1 + seed as usize % 2);
        let (a, b, c) = system(n, m, seed);
        let mut s = settings(n, m, MheCost::LeastSquares, 4, f64::INFINITY, 1.0);
        s.w_box = (DVector::repeat(n, f64::NEG_INFINITY), DVector::repeat(n, f64::INFINITY));
        s.prior_mean = PriorMean::Filtered;
        let mut kf = KalmanFilter::new(s.setup(1)).unwrap();
        let mut mhe = new_mhe(s, 1).unwrap();
        let model = StepModel::new(&a, &b, &c);
        let (us, ys) = data(&a, &b, &c, 25, 0.05, 0.3, seed);
        for (k, (u, y)) in us.iter().zip(&ys).enumerate() {
            let xk = kf.step(&model, u, y).unwrap().center.clone();
            let e = mhe.step(&model, u, y).unwrap();
            let diff = (&e.center - &xk).amax();
            assert!(diff < 1e-9 * (1.0 + xk.amax()), "seed {seed} step {k}: MHE {} vs KF {}", e.center, xk);
            assert_eq!(e.report.unwrap().solve.status, WindowStatus::Converged);
        }
    }
}

#[test]
fn full_information_least_squares_is_the_kalman_filter_whatever_the_prior_mean_rule() {
    // Before the window fills (T ≤ N) the estimate is the full-information one, which equals the
    // Kalman filter for an unconstrained linear problem.
    let (a, b, c) = system(4, 2, 11);
    let mut s = settings(4, 2, MheCost::LeastSquares, 30, f64::INFINITY, 1.0);
    s.w_box = (DVector::repeat(4, f64::NEG_INFINITY), DVector::repeat(4, f64::INFINITY));
    let mut kf = KalmanFilter::new(s.setup(1)).unwrap();
    let mut mhe = new_mhe(s, 1).unwrap();
    let model = StepModel::new(&a, &b, &c);
    let (us, ys) = data(&a, &b, &c, 30, 0.05, 0.3, 3);
    for (u, y) in us.iter().zip(&ys) {
        let xk = kf.step(&model, u, y).unwrap().center.clone();
        let e = mhe.step(&model, u, y).unwrap();
        assert!((&e.center - &xk).amax() < 1e-9 * (1.0 + xk.amax()));
    }
}

#[test]
fn min_max_without_active_clip_is_least_squares_with_r_eff() {
    // With V so wide that v* = −e/(λv−1) is never clipped, the min–max cost equals the
    // least-squares cost with R_eff = R (λv − 1)/λv (docs/robust-mhe.md §2.1).
    let (a, b, c) = system(4, 1, 5);
    let lambda_v = 4.0;
    for solver in [
        WindowSolver::exact_saddle(),
        WindowSolver::CoordinateRotation { max_sweeps: 200, tolerance: 1e-13, inner: InnerSolver::ActiveSet },
    ] {
        let mut robust = settings(4, 1, MheCost::MinMax { lambda_v }, 5, 0.05, 1e6);
        robust.solver = solver;
        let mut plain = robust.clone();
        plain.cost = MheCost::LeastSquares;
        plain.r *= (lambda_v - 1.0) / lambda_v;
        plain.solver = WindowSolver::exact_saddle();
        let mut e1 = new_mhe(robust, 1).unwrap();
        let mut e2 = new_mhe(plain, 1).unwrap();
        let model = StepModel::new(&a, &b, &c);
        let (us, ys) = data(&a, &b, &c, 20, 0.05, 0.5, 7);
        for (k, (u, y)) in us.iter().zip(&ys).enumerate() {
            let x1 = e1.step(&model, u, y).unwrap().center.clone();
            let x2 = e2.step(&model, u, y).unwrap().center.clone();
            assert!((&x1 - &x2).amax() < 1e-8, "{solver:?} step {k}: {x1} vs {x2}");
        }
    }
}

#[test]
fn coordinate_rotation_agrees_with_the_exact_saddle_where_it_converges() {
    // Small V so that the clip binds often; λv = 10 makes the rotation contract (rate ≈ 1/9).
    let mut checked = 0;
    let mut clipped = 0;
    for seed in 0..8 {
        let (a, b, c) = system(4, 1 + seed as usize % 2, 100 + seed);
        let m = c.nrows();
        for preset in [BlockingPreset::Rmhe, BlockingPreset::RmheOp, BlockingPreset::RmheOf] {
            let base =
                settings(4, m, MheCost::MinMax { lambda_v: 10.0 }, 6, 0.03, 0.02).with_preset(6, preset).unwrap();
            let mut cr = base.clone();
            cr.solver =
                WindowSolver::CoordinateRotation { max_sweeps: 100, tolerance: 1e-12, inner: InnerSolver::ActiveSet };
            let mut ex = base;
            ex.solver = WindowSolver::exact_saddle();
            let mut e1 = unchecked(cr, 1);
            let mut e2 = unchecked(ex, 1);
            let model = StepModel::new(&a, &b, &c);
            let (us, ys) = data(&a, &b, &c, 14, 0.03, 0.5, seed);
            for (u, y) in us.iter().zip(&ys) {
                let r1 = *e1.step(&model, u, y).unwrap().report.as_ref().unwrap();
                let x1 = e1.estimate().center.clone();
                let r2 = *e2.step(&model, u, y).unwrap().report.as_ref().unwrap();
                let x2 = e2.estimate().center.clone();
                assert_eq!(r2.solve.status, WindowStatus::Converged);
                assert!(
                    (r1.objective - r2.objective) >= -1e-9 * r2.objective.abs().max(1.0),
                    "the saddle solver's value is not the minimum"
                );
                if r1.solve.status == WindowStatus::Converged {
                    checked += 1;
                    assert!((&x1 - &x2).amax() < 1e-6, "seed {seed} {preset:?}: {x1} vs {x2}");
                }
                // Residuals beyond (λv − 1)·v̄ = 0.18 mean the clip is active somewhere.
                clipped += usize::from(r2.objective > 0.0 && r2.solve.sweeps > 1);
            }
        }
    }
    assert!(checked > 200, "only {checked} converged windows compared");
    assert!(clipped > 0, "the clip never bound: the test does not exercise the pieces");
}

/// Independent reference for a full-information window (T ≤ N, prior (x̄0, P0), no blocking):
/// Clarabel on the uncondensed problem over (x_0..x_T, w_0..w_{T−1}, a, t) with the dynamics as
/// equalities and the maximised stage cost as `e²/R + (a²/μ + 2t)/R`, `|e − a| ≤ t`
/// (`g(e) = (e² + Huber_μ(e))/R` for V = [−1, 1]).
fn clarabel_full_information(
    s: &Case,
    output_constraint: bool,
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    c: &DMatrix<f64>,
    us: &[DVector<f64>],
    ys: &[DVector<f64>],
) -> DVector<f64> {
    use clarabel_qp::algebra::CscMatrix;
    use clarabel_qp::solver::{DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, ZeroConeT};
    let (n, m) = (a.nrows(), c.nrows());
    let t_len = us.len();
    let mu = match s.cost {
        MheCost::MinMax { lambda_v } => lambda_v - 1.0,
        _ => unreachable!(),
    };
    // Variable layout.
    let nx = n * (t_len + 1);
    let nw = n * t_len;
    let ne = m * t_len; // measurements y_1..y_T
    let (ox, ow, oa, ot) = (0, nx, nx + nw, nx + nw + ne);
    let nv = ot + ne;
    let mut pm = DMatrix::<f64>::zeros(nv, nv);
    let mut q = DVector::<f64>::zeros(nv);
    let p0i = s.p0.clone().try_inverse().unwrap();
    let qi = s.q.clone().try_inverse().unwrap();
    // ½ vᵀ P v + qᵀ v = cost/2·... use P = 2·Hess, q = linear; cost = (x0−x̄)ᵀP0⁻¹(x0−x̄) + …
    for i in 0..n {
        for j in 0..n {
            pm[(ox + i, ox + j)] += 2.0 * p0i[(i, j)];
        }
    }
    let lin = -2.0 * &p0i * &s.x0;
    for i in 0..n {
        q[ox + i] += lin[i];
    }
    for k in 0..t_len {
        for i in 0..n {
            for j in 0..n {
                pm[(ow + k * n + i, ow + k * n + j)] += 2.0 * qi[(i, j)];
            }
        }
    }
    // e_k = y_k − C x_k (k = 1..T): e² /R term and a²/(μR) + 2t/R.
    for k in 0..t_len {
        for i in 0..m {
            let rinv = 1.0 / s.r[(i, i)];
            let xk = ox + (k + 1) * n;
            for p in 0..n {
                for r in 0..n {
                    pm[(xk + p, xk + r)] += 2.0 * rinv * c[(i, p)] * c[(i, r)];
                }
                q[xk + p] += -2.0 * rinv * ys[k][i] * c[(i, p)];
            }
            pm[(oa + k * m + i, oa + k * m + i)] += 2.0 * rinv / mu;
            q[ot + k * m + i] += 2.0 * rinv;
        }
    }
    // Constraints: dynamics (zero cone), then |e − a| ≤ t and the W box (nonnegative cone).
    let mut rows: Vec<(Vec<(usize, f64)>, f64)> = Vec::new();
    for k in 0..t_len {
        let bu = b * &us[k];
        for i in 0..n {
            // x_{k+1} − A x_k − w_k = B u_k
            let mut row = vec![(ox + (k + 1) * n + i, 1.0), (ow + k * n + i, -1.0)];
            for j in 0..n {
                row.push((ox + k * n + j, -a[(i, j)]));
            }
            rows.push((row, bu[i]));
        }
    }
    let n_eq = rows.len();
    for k in 0..t_len {
        for i in 0..m {
            let xk = ox + (k + 1) * n;
            // e − a ≤ t  ⇔  −C x − a − t ≤ −y ;   −(e − a) ≤ t  ⇔  C x + a − t ≤ y
            let mut r1: Vec<(usize, f64)> = (0..n).map(|p| (xk + p, -c[(i, p)])).collect();
            r1.push((oa + k * m + i, -1.0));
            r1.push((ot + k * m + i, -1.0));
            rows.push((r1, -ys[k][i]));
            let mut r2: Vec<(usize, f64)> = (0..n).map(|p| (xk + p, c[(i, p)])).collect();
            r2.push((oa + k * m + i, 1.0));
            r2.push((ot + k * m + i, -1.0));
            rows.push((r2, ys[k][i]));
        }
    }
    for k in 0..t_len {
        for i in 0..n {
            rows.push((vec![(ow + k * n + i, 1.0)], s.w_box.1[i]));
            rows.push((vec![(ow + k * n + i, -1.0)], -s.w_box.0[i]));
        }
    }
    if output_constraint {
        // v_lo ≤ y_k − C x_k ≤ v_hi:  −C x ≤ v_hi − y,  C x ≤ y − v_lo.
        for k in 0..t_len {
            let xk = ox + (k + 1) * n;
            for i in 0..m {
                rows.push(((0..n).map(|p| (xk + p, -c[(i, p)])).collect(), s.v_box.1[i] - ys[k][i]));
                rows.push(((0..n).map(|p| (xk + p, c[(i, p)])).collect(), ys[k][i] - s.v_box.0[i]));
            }
        }
    }
    let a_dense =
        DMatrix::from_fn(rows.len(), nv, |r, col| rows[r].0.iter().filter(|(j, _)| *j == col).map(|(_, v)| v).sum());
    let bvec: Vec<f64> = rows.iter().map(|r| r.1).collect();
    let to_csc = |mat: &DMatrix<f64>, upper: bool| {
        let mut colptr = vec![0];
        let mut rowval = Vec::new();
        let mut nzval = Vec::new();
        for j in 0..mat.ncols() {
            for i in 0..mat.nrows() {
                if (!upper || i <= j) && mat[(i, j)] != 0.0 {
                    rowval.push(i);
                    nzval.push(mat[(i, j)]);
                }
            }
            colptr.push(rowval.len());
        }
        CscMatrix::new(mat.nrows(), mat.ncols(), colptr, rowval, nzval)
    };
    let cones = [ZeroConeT(n_eq), NonnegativeConeT(rows.len() - n_eq)];
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .tol_gap_abs(1e-11)
        .tol_gap_rel(1e-11)
        .tol_feas(1e-11)
        .build()
        .unwrap();
    let mut solver =
        DefaultSolver::new(&to_csc(&pm, true), q.as_slice(), &to_csc(&a_dense, false), &bvec, &cones, settings)
            .unwrap();
    solver.solve();
    DVector::from_fn(n, |i, _| solver.solution.x[ox + t_len * n + i])
}

#[test]
fn exact_saddle_matches_clarabel_on_an_uncondensed_formulation() {
    for seed in 0..5 {
        let (a, b, c) = system(3, 1 + seed as usize % 2, 300 + seed);
        let m = c.nrows();
        // V = [−1, 1]; small R so that residuals beyond (λv − 1) occur.
        let mut s = settings(3, m, MheCost::MinMax { lambda_v: 1.5 }, 10, 0.05, 1.0);
        s.solver = WindowSolver::exact_saddle();
        s.r = DMatrix::identity(m, m) * 0.2;
        let mut mhe = unchecked(s.clone(), 1);
        let model = StepModel::new(&a, &b, &c);
        let (us, ys) = data(&a, &b, &c, 8, 0.05, 1.5, seed);
        for t in 0..us.len() {
            let x = mhe.step(&model, &us[t], &ys[t]).unwrap().center.clone();
            let reference = clarabel_full_information(&s, false, &a, &b, &c, &us[..=t], &ys[..=t]);
            assert!((&x - &reference).amax() < 1e-6, "seed {seed} T = {}: {x} vs Clarabel {reference}", t + 1);
        }
    }
}

#[test]
fn clarabel_as_inner_solver_gives_the_active_set_result() {
    let (a, b, c) = system(4, 1, 9);
    let base = settings(4, 1, MheCost::MinMax { lambda_v: 10.0 }, 6, 0.03, 0.05)
        .with_preset(6, BlockingPreset::RmheOp)
        .unwrap();
    let mut s1 = base.clone();
    s1.solver = WindowSolver::CoordinateRotation { max_sweeps: 10, tolerance: 1e-8, inner: InnerSolver::ActiveSet };
    let mut s2 = base;
    s2.solver = WindowSolver::CoordinateRotation { max_sweeps: 10, tolerance: 1e-8, inner: InnerSolver::Clarabel };
    let mut e1 = unchecked(s1, 1);
    let mut e2 = unchecked(s2, 1);
    let model = StepModel::new(&a, &b, &c);
    let (us, ys) = data(&a, &b, &c, 12, 0.03, 0.3, 1);
    for (u, y) in us.iter().zip(&ys) {
        let x1 = e1.step(&model, u, y).unwrap().center.clone();
        let x2 = e2.step(&model, u, y).unwrap().center.clone();
        assert!((&x1 - &x2).amax() < 1e-6, "{x1} vs {x2}");
    }
}

#[test]
fn unknown_counts_are_the_papers() {
    let base = settings(4, 1, MheCost::MinMax { lambda_v: 10.0 }, 6, 0.1, 1.0);
    let (a, b, c) = system(4, 1, 2);
    let model = StepModel::new(&a, &b, &c);
    for (preset, vectors) in [(BlockingPreset::Rmhe, 7), (BlockingPreset::RmheOp, 4), (BlockingPreset::RmheOf, 3)] {
        let s = base.clone().with_preset(6, preset).unwrap();
        assert_eq!(s.vector_unknowns(), vectors);
        let mut e = new_mhe(s, 1).unwrap();
        let (us, ys) = data(&a, &b, &c, 9, 0.1, 1.0, 4);
        for (u, y) in us.iter().zip(&ys) {
            e.step(&model, u, y).unwrap();
        }
        let r = e.report().unwrap();
        assert_eq!((r.window, r.vector_unknowns, r.unknowns), (7, vectors, 4 * vectors));
    }
    assert_eq!(BlockingPreset::RmheOp.lengths(6).unwrap(), vec![3, 2, 1]);
    assert_eq!(BlockingPreset::RmheOf.lengths(6).unwrap(), vec![5, 1]);
}

#[test]
fn blocked_disturbances_stay_in_their_box_on_boundary_noise() {
    // Noise on the boundary of W: the estimated blocked disturbances respect W exactly.
    let (a, b, c) = system(4, 1, 21);
    let s = settings(4, 1, MheCost::MinMax { lambda_v: 10.0 }, 6, 0.02, 1.0)
        .with_preset(6, BlockingPreset::RmheOf)
        .unwrap();
    let mut e = new_mhe(s, 1).unwrap();
    let model = StepModel::new(&a, &b, &c);
    let mut x = DVector::<f64>::zeros(4);
    for k in 0..40 {
        let u = DVector::from_element(1, 0.0);
        let w = DVector::from_fn(4, |i, _| if (k + i) % 2 == 0 { 0.02 } else { -0.02 });
        x = &a * &x + &w;
        let y = &c * &x + DVector::from_element(1, if k % 3 == 0 { 1.0 } else { -1.0 });
        let est = e.step(&model, &u, &y).unwrap();
        assert!(est.center.iter().all(|v| v.is_finite()));
        assert_ne!(est.report.unwrap().solve.status, WindowStatus::InnerFailure);
    }
}

#[test]
fn the_h_infinity_recursion_reports_a_failed_existence_condition_and_continues() {
    let (a, b, c) = system(3, 1, 8);
    let model = StepModel::new(&a, &b, &c);
    let mut ok = settings(3, 1, MheCost::MinMax { lambda_v: 10.0 }, 4, 0.1, 1.0);
    ok.arrival = ArrivalRecursion::HInfinity { theta: 0.05 };
    let mut bad = ok.clone();
    bad.arrival = ArrivalRecursion::HInfinity { theta: 1e3 };
    let mut e_ok = new_mhe(ok, 1).unwrap();
    let mut e_bad = new_mhe(bad, 1).unwrap();
    let (us, ys) = data(&a, &b, &c, 8, 0.1, 1.0, 5);
    for (u, y) in us.iter().zip(&ys) {
        assert_eq!(e_ok.step(&model, u, y).unwrap().report.unwrap().arrival, ArrivalStatus::HInfinity);
        let r = e_bad.step(&model, u, y).unwrap().report.unwrap();
        assert_eq!(r.arrival, ArrivalStatus::HInfinityConditionFailed);
        assert!(e_bad.estimate().center.iter().all(|v| v.is_finite()));
    }
}

#[test]
fn bad_settings_are_named() {
    let s = settings(4, 1, MheCost::MinMax { lambda_v: 10.0 }, 6, 0.1, 1.0);
    let message = |s: Case| match new_mhe(s, 1) {
        Err(EstimatorError::InvalidConfiguration { message, .. }) => message,
        other => panic!("expected an invalid configuration, got {other:?}"),
    };
    let mut t = s.clone();
    t.blocks = vec![3, 2];
    assert!(message(t).contains("sum to 5"));
    let mut t = s.clone();
    t.cost = MheCost::MinMax { lambda_v: 1.0 };
    assert!(message(t).contains("lambda_v"));
    let mut t = s.clone();
    t.v_box.0[0] = 2.0;
    assert!(message(t).contains("box V"));
    let mut t = s.clone();
    t.w_box = (DVector::repeat(4, 0.1), DVector::repeat(4, 0.1));
    assert!(message(t).contains("box W"));
    let mut t = s.clone();
    t.r = DMatrix::from_element(1, 1, -1.0);
    assert!(message(t).contains("R["));
    let mut t = s.clone();
    t.p0[(0, 0)] = f64::NAN;
    assert!(message(t).contains("P0"));
    let mut t = s.clone();
    t.q[(0, 1)] = 1.0;
    assert!(message(t).contains("Q"));
    let mut t = s.clone();
    t.blocks = vec![6, 0];
    assert!(message(t).contains("positive"));
    assert!(BlockingPreset::RmheOp.lengths(2).is_err());
    assert!(estimators::mhe::AlphaMap::OneOverAlpha.lambda_v(1.0).is_err());
    assert!((estimators::mhe::AlphaMap::OneOverOneMinusAlpha.lambda_v(0.9).unwrap() - 10.0).abs() < 1e-12);
}

#[test]
fn bad_data_is_refused_and_leaves_the_estimator_unchanged() {
    let (a, b, c) = system(4, 1, 3);
    let model = StepModel::new(&a, &b, &c);
    let mut e = new_mhe(settings(4, 1, MheCost::MinMax { lambda_v: 10.0 }, 6, 0.1, 1.0), 1).unwrap();
    let (us, ys) = data(&a, &b, &c, 10, 0.1, 1.0, 6);
    for (u, y) in us.iter().zip(&ys).take(8) {
        e.step(&model, u, y).unwrap();
    }
    let before = e.clone();
    let nan_y = DVector::from_element(1, f64::NAN);
    assert!(matches!(e.step(&model, &us[8], &nan_y), Err(EstimatorError::NonFinite { .. })));
    assert!(matches!(e.step(&model, &DVector::zeros(2), &ys[8]), Err(EstimatorError::DimensionMismatch { .. })));
    let wrong_c = DMatrix::zeros(2, 4);
    assert!(e.step(&StepModel::new(&a, &b, &wrong_c), &us[8], &ys[8]).is_err());
    let mut bad_a = a.clone();
    bad_a[(0, 0)] = f64::INFINITY;
    assert!(e.step(&StepModel::new(&bad_a, &b, &c), &us[8], &ys[8]).is_err());
    assert_eq!(e.time(), before.time());
    // The next steps give exactly what the untouched copy gives.
    let mut twin = before;
    for k in 8..10 {
        let x1 = e.step(&model, &us[k], &ys[k]).unwrap().center.clone();
        let x2 = twin.step(&model, &us[k], &ys[k]).unwrap().center.clone();
        assert_eq!(x1, x2);
    }
}

#[test]
fn an_overflowing_model_is_an_error_not_a_nan_estimate() {
    let a = DMatrix::identity(2, 2) * 1e200;
    let b = DMatrix::zeros(2, 1);
    let c = DMatrix::from_row_slice(1, 2, &[1.0, 0.0]);
    let model = StepModel::new(&a, &b, &c);
    let mut e = new_mhe(settings(2, 1, MheCost::LeastSquares, 3, 0.1, 1.0), 1).unwrap();
    let u = DVector::zeros(1);
    let y = DVector::from_element(1, 1.0);
    let mut failed = false;
    for _ in 0..6 {
        match e.step(&model, &u, &y) {
            Ok(est) => assert!(est.center.iter().all(|v| v.is_finite())),
            Err(err) => {
                assert!(matches!(err, EstimatorError::NumericalFailure(_)), "{err}");
                failed = true;
            }
        }
    }
    assert!(failed);
    assert!(e.estimate().center().iter().all(|v| v.is_finite()));
}

#[test]
fn predictions_bridge_missing_measurements_and_the_initial_measurement_is_used() {
    let (a, b, c) = system(3, 1, 4);
    let model = StepModel::new(&a, &b, &c);
    let s = settings(3, 1, MheCost::MinMax { lambda_v: 10.0 }, 4, 0.1, 1.0);
    let mut e = new_mhe(s, 1).unwrap();
    let x0 = e.measure_initial(&model, &DVector::from_element(1, 0.7)).unwrap().center.clone();
    assert_ne!(x0, DVector::from_fn(3, |i, _| 0.1 * i as f64));
    assert!(e.measure_initial(&model, &DVector::from_element(1, 0.7)).is_err());
    let (us, ys) = data(&a, &b, &c, 12, 0.1, 1.0, 9);
    for (k, (u, y)) in us.iter().zip(&ys).enumerate() {
        let est = if k % 3 == 1 { e.predict(&model, u) } else { e.step(&model, u, y) }.unwrap();
        assert!(est.center.iter().all(|v| v.is_finite()));
    }
    assert_eq!(e.time(), 12);
}

#[test]
fn output_constraints_match_clarabel_and_infeasibility_is_an_outcome() {
    for seed in 0..3 {
        let (a, b, c) = system(3, 1, 400 + seed);
        let mut s = settings(3, 1, MheCost::MinMax { lambda_v: 1.5 }, 10, 0.05, 1.0);
        s.r = DMatrix::identity(1, 1) * 0.2;
        s.output_constraint = true;
        let model = StepModel::new(&a, &b, &c);
        let (us, ys) = data(&a, &b, &c, 8, 0.05, 1.0, seed);
        for solver in [
            WindowSolver::exact_saddle(),
            WindowSolver::CoordinateRotation { max_sweeps: 200, tolerance: 1e-12, inner: InnerSolver::ActiveSet },
        ] {
            let mut s = s.clone();
            s.solver = solver;
            let mut mhe = new_mhe(s.clone(), 1).unwrap();
            for t in 0..us.len() {
                let e = mhe.step(&model, &us[t], &ys[t]).unwrap();
                let x = e.center.clone();
                let status = e.report.unwrap().solve.status;
                assert!(((&c * &x)[0] - ys[t][0]).abs() <= 1.0 + 1e-6, "the output constraint at T");
                if matches!(solver, WindowSolver::ExactSaddle { .. }) {
                    assert_eq!(status, WindowStatus::Converged);
                    let reference = clarabel_full_information(&s, true, &a, &b, &c, &us[..=t], &ys[..=t]);
                    assert!((&x - &reference).amax() < 1e-6, "seed {seed} T = {}: {x} vs Clarabel {reference}", t + 1);
                }
            }
        }
    }
    // An outlier no admissible trajectory explains: solved without the constraints, reported.
    let (a, b, c) = system(3, 1, 9);
    let model = StepModel::new(&a, &b, &c);
    let mut s = settings(3, 1, MheCost::MinMax { lambda_v: 10.0 }, 4, 1e-3, 0.5);
    s.output_constraint = true;
    s.solver = WindowSolver::exact_saddle();
    let mut mhe = new_mhe(s, 1).unwrap();
    // The data check would refuse the outlier's step (the default): publish it, marked.
    mhe.set_data_checks(DataChecks::with_policy(InconsistencyPolicy::FlagAndContinue)).unwrap();
    let u = DVector::zeros(1);
    let mut statuses = Vec::new();
    for k in 0..6 {
        let y = DVector::from_element(1, if k == 3 { 50.0 } else { 0.0 });
        let e = mhe.step(&model, &u, &y).unwrap();
        assert!(e.center.iter().all(|v| v.is_finite()));
        let expected = if k >= 3 { DataCheck::Inconsistent } else { DataCheck::Consistent };
        assert_eq!(e.status().data, expected, "step {}", k + 1);
        statuses.push(e.report.unwrap().solve.status);
    }
    assert!(statuses.contains(&WindowStatus::Infeasible), "{statuses:?}");
    assert_eq!(statuses[0], WindowStatus::Converged);
}
