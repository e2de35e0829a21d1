//! The set-membership step compiled per size gives the same bits as the runtime-size step: two
//! filters on the same data, one on each path, compared after every call (centre, shape, bounds,
//! every number of the report, the status, every error) on every compiled size and one that is
//! not; with noise on the boundary of its sets, outliers under each inconsistency policy,
//! ill-conditioned noise, signed zeros, inputs as bounded disturbances, predictions alone,
//! predict-then-update, partial steps and angle outputs.

mod common;

use estimators::{Estimate, EstimatorError, InconsistencyPolicy, SetEstimate, SetMembershipFilter, Setup};
use models::{Angles, ConstantModel, Noise, Xoshiro256StarStar};
use nalgebra::DVector;

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// Every published number bit for bit (the solver's wall-clock time aside).
fn same(a: &SetEstimate, b: &SetEstimate, at: &str) {
    assert_eq!(bits(a.center.as_slice()), bits(b.center.as_slice()), "{at}: centre");
    assert_eq!(bits(a.shape.as_slice()), bits(b.shape.as_slice()), "{at}: shape");
    assert_eq!(bits(a.lower.as_slice()), bits(b.lower.as_slice()), "{at}: lower");
    assert_eq!(bits(a.upper.as_slice()), bits(b.upper.as_slice()), "{at}: upper");
    let (r, s) = (&a.report, &b.report);
    assert_eq!(bits(&r.tau), bits(&s.tau), "{at}: τ");
    assert_eq!(
        (r.outcome, r.status, r.iterations, r.fallback),
        (s.outcome, s.status, s.iterations, s.fallback),
        "{at}"
    );
    assert_eq!(
        bits(&[r.inflation.relative, r.inflation.absolute]),
        bits(&[s.inflation.relative, s.inflation.absolute])
    );
    // Debug prints the shortest round-trip form, the sign of a zero included.
    assert_eq!(format!("{:?}", r.consistency), format!("{:?}", s.consistency), "{at}: data check");
    assert_eq!((r.guaranteed, a.diverging, a.status()), (s.guaranteed, b.diverging, b.status()), "{at}");
}

fn agree(a: Result<&SetEstimate, EstimatorError>, b: Result<&SetEstimate, EstimatorError>, at: &str) -> bool {
    match (a, b) {
        (Ok(a), Ok(b)) => {
            same(a, b, at);
            true
        }
        (Err(e), Err(f)) => {
            assert_eq!(format!("{e:?}"), format!("{f:?}"), "{at}");
            false
        }
        (a, b) => panic!("{at}: {:?} against {:?}", a.map(|e| e.report), b.map(|e| e.report)),
    }
}

/// How a case is driven.
#[derive(Clone, Copy, Debug)]
struct Drive {
    policy: InconsistencyPolicy,
    /// Every this many steps an outlier (0: none).
    outliers: usize,
    /// Condition number of `R` (and `Q`).
    cond: f64,
    bounded_input: bool,
    angle: bool,
}

fn run(n: usize, m: usize, seed: u64, d: Drive) {
    let mut rng = Xoshiro256StarStar::seed_from_u64(seed);
    let a = common::random_a(&mut rng, n, 0.97);
    let b = common::gauss(&mut rng, n, 2) * 0.1;
    let mut c = common::gauss(&mut rng, m, n);
    // Structural zeros (as a selection of states), which the kernels skip.
    for i in 0..m {
        c[(i, (i + 1) % n)] = 0.0;
    }
    let (q, r) = (common::spd(&mut rng, n, 1e-3, d.cond), common::spd(&mut rng, m, 1e-2, d.cond));
    let p0 = common::spd(&mut rng, n, 1.0, 10.0);
    let mut model = ConstantModel::new(a.clone(), b.clone(), c.clone()).unwrap();
    if d.angle {
        model = model.with_angles(Angles { states: &[], outputs: &[0] }).unwrap();
    }
    let setup = Setup {
        x0: DVector::zeros(n),
        p0: p0.clone(),
        process_noise: q.clone(),
        measurement_noise: r.clone(),
        inputs: 2,
    };
    let mut fixed = SetMembershipFilter::new(setup.clone()).unwrap();
    let mut general = SetMembershipFilter::new(setup).unwrap();
    if d.bounded_input {
        let (lo, hi) = (DVector::from_element(2, -1.0), DVector::from_element(2, 1.0));
        fixed = fixed.with_input_bounds(&lo, &hi).unwrap();
        general = general.with_input_bounds(&lo, &hi).unwrap();
    }
    general.use_general_kernels();
    let compiled = [3, 4, 6, 13].contains(&n) && (1..=5).contains(&m);
    assert_eq!(fixed.runs_compiled_step(), compiled, "({n}, {m})");
    assert!(!general.runs_compiled_step());
    for f in [&mut fixed, &mut general] {
        f.set_inconsistency_policy(d.policy);
    }
    let (w, v) = (Noise::ellipsoid_boundary(q).unwrap(), Noise::ellipsoid_boundary(r.clone()).unwrap());
    let mut x = common::boundary_point(&mut rng, &DVector::zeros(n), &p0);
    let mut ok = 0;
    for k in 0..240 {
        let at = format!("({n}, {m}) seed {seed} {d:?} step {k}");
        let u = DVector::from_fn(2, |i, _| ((k * (i + 3)) as f64 * 0.37).sin());
        let before = x.clone();
        x = &a * &x + &b * &u + w.sample(&mut rng);
        let mut y = &c * &x + v.sample(&mut rng);
        if d.outliers > 0 && k % d.outliers == d.outliers - 1 {
            y[0] += 50.0 * r[(0, 0)].sqrt() * (1.0 + k as f64);
        }
        if k % 11 == 5 && d.policy != InconsistencyPolicy::Error {
            y[m - 1] = -0.0;
        }
        if d.angle {
            y[0] = models::wrap_angle(y[0]);
        }
        let done = match k % 9 {
            // A prediction alone, then its update with the same measurement.
            3 => {
                let p = agree(fixed.predict(&model, &u), general.predict(&model, &u), &at) as usize;
                p + agree(fixed.update(&model, &y), general.update(&model, &y), &at) as usize
            }
            // A prediction with no measurement arriving.
            6 => agree(fixed.predict(&model, &u), general.predict(&model, &u), &at) as usize,
            // A partial step (the filter of the measured count is compiled for its size too).
            7 if m > 1 => {
                let mask: Vec<bool> = (0..m).map(|i| (i + k / 9) % 3 != 0).collect();
                let mut y = y.clone();
                for (i, _) in mask.iter().enumerate().filter(|(_, s)| !**s) {
                    y[i] = f64::NAN;
                }
                agree(fixed.step_partial(&model, &u, &y, &mask), general.step_partial(&model, &u, &y, &mask), &at)
                    as usize
            }
            _ => agree(fixed.step(&model, &u, &y), general.step(&model, &u, &y), &at) as usize,
        };
        if done == 0 {
            // Refused: the set stays where it was, so the truth does too.
            x = before;
        }
        ok += done;
    }
    // A 13-state set soon spans a full turn of its angle output, which ends the guarantee.
    let enough = if d.angle { 50 } else { 100 };
    assert!(ok > enough, "({n}, {m}) {d:?}: only {ok} calls succeeded");
}

const PLAIN: Drive =
    Drive { policy: InconsistencyPolicy::Error, outliers: 0, cond: 10.0, bounded_input: false, angle: false };

#[test]
fn every_compiled_size_gives_the_general_bits() {
    for (n, m) in [(3, 1), (3, 2), (3, 3), (4, 1), (4, 2), (4, 3), (4, 4), (4, 5), (6, 3), (6, 5), (13, 3), (5, 2)] {
        run(n, m, 7 + (10 * n + m) as u64, PLAIN);
    }
}

#[test]
fn outliers_under_every_policy_give_the_general_bits() {
    for policy in [
        InconsistencyPolicy::Error,
        InconsistencyPolicy::FlagAndContinue,
        InconsistencyPolicy::Restart,
        InconsistencyPolicy::Off,
    ] {
        for (n, m) in [(4, 3), (6, 3), (3, 2)] {
            run(n, m, 100 + n as u64, Drive { policy, outliers: 13, ..PLAIN });
        }
    }
}

#[test]
fn ill_conditioned_noise_bounded_inputs_and_angles_give_the_general_bits() {
    for (n, m) in [(4, 3), (4, 4), (13, 3)] {
        run(n, m, 200 + n as u64, Drive { cond: 1e10, ..PLAIN });
        run(n, m, 300 + n as u64, Drive { bounded_input: true, ..PLAIN });
        run(n, m, 400 + n as u64, Drive { angle: true, policy: InconsistencyPolicy::FlagAndContinue, ..PLAIN });
    }
}
