use nalgebra::{DMatrix, DVector};

use super::ClosureModel;
use crate::{Angles, Capability, DifferentiableModel, DiscreteModel, Integrator, ModelError, numeric_jacobians};

/// A damped pendulum on a cart with a range sensor: every kind of operation, plain numbers on
/// both sides, an input-only row.
macro_rules! pendulum {
    ($new:expr) => {
        $new(
            |x: &[crate::Dual<3>; 3], u: &[f64]| {
                let s = x[1].sin();
                [x[0] * 0.5 + 0.1 * x[2], 1.0 - s * x[2] / (2.0 + x[0].cos()), u[0].into()]
            },
            |x: &[crate::Dual<3>; 3], u: &[f64]| {
                [x[0].hypot(x[1]) + u[1], x[1].atan2(x[0]), (x[2] * x[2] + 1.0).sqrt().ln() - (-x[0]).exp() / 3.0]
            },
        )
    };
}

fn points() -> [(DVector<f64>, DVector<f64>); 4] {
    let v = |s: &[f64]| DVector::from_column_slice(s);
    [
        (v(&[0.3, -0.2, 1.5]), v(&[0.5, 0.0])),
        (v(&[-1.2, 0.9, -0.4]), v(&[-2.0, 1.0])),
        (v(&[2.5, 3.0, 0.0]), v(&[0.0, -0.3])),
        (v(&[0.01, -2.0, 7.0]), v(&[1.0, 2.0])),
    ]
}

/// The Jacobians against central differences (step 1e-6, relative error 1e-7) and `f`, `h`
/// against the `_with_jacobian` forms, at every point.
fn check_against_differences<Mo: DifferentiableModel>(model: &Mo) {
    let d = model.dims();
    for (x, u) in points() {
        let (fd, hd) = numeric_jacobians(model, &x, &u, 1e-6).unwrap();
        let (mut fa, mut ha) = (DMatrix::zeros(d.states, d.states), DMatrix::zeros(d.outputs, d.states));
        model.f_jacobian(&x, &u, &mut fa).unwrap();
        model.h_jacobian(&x, &u, &mut ha).unwrap();
        assert!((&fa - &fd).amax() < 1e-7 * fd.amax().max(1.0), "F at {x}: {fa} vs {fd}");
        assert!((&ha - &hd).amax() < 1e-7 * hd.amax().max(1.0), "H at {x}: {ha} vs {hd}");
        let (mut f, mut f2, mut fj) = (DVector::zeros(d.states), DVector::zeros(d.states), DMatrix::zeros(3, 3));
        model.f(&x, &u, &mut f).unwrap();
        model.f_with_jacobian(&x, &u, &mut f2, &mut fj).unwrap();
        assert_eq!((&f, &fa), (&f2, &fj));
        let (mut h, mut h2, mut hj) = (DVector::zeros(d.outputs), DVector::zeros(d.outputs), DMatrix::zeros(3, 3));
        model.h(&x, &u, &mut h).unwrap();
        model.h_with_jacobian(&x, &u, &mut h2, &mut hj).unwrap();
        assert_eq!((&h, &ha), (&h2, &hj));
    }
}

#[test]
fn jacobians_match_central_differences_discrete_and_integrated() {
    let discrete = pendulum!(|f, h| ClosureModel::discrete(2, f, h)).unwrap();
    check_against_differences(&discrete);
    let euler = pendulum!(|f, h| ClosureModel::continuous(2, 0.1, Integrator::Euler, f, h)).unwrap();
    check_against_differences(&euler);
    let rk4 = pendulum!(|f, h| ClosureModel::continuous(2, 0.1, Integrator::Rk4 { substeps: 3 }, f, h)).unwrap();
    check_against_differences(&rk4);
    // The values are the closures' (discrete) and their integration (Euler by hand).
    let (x, u) = &points()[0];
    let (mut a, mut b) = (DVector::zeros(3), DVector::zeros(3));
    discrete.f(x, u, &mut a).unwrap();
    euler.f(x, u, &mut b).unwrap();
    assert_eq!(a[2], 0.5);
    assert!((&b - (x + &a * 0.1)).amax() < 1e-15, "{b} vs {a}");
}

#[test]
fn integrated_like_the_discretized_continuous_model() {
    // The same RK4 as `Discretized`'s, on a linear system whose exact Jacobian is known:
    // ẋ = A x, RK4 with one step: I + hA + (hA)²/2 + (hA)³/6 + (hA)⁴/24.
    let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -4.0, -0.4]);
    let m = ClosureModel::continuous(
        0,
        0.05,
        Integrator::Rk4 { substeps: 1 },
        |x, _| [x[1], -4.0 * x[0] - 0.4 * x[1]],
        |x, _| [x[0]],
    )
    .unwrap();
    let ah = &a * 0.05;
    let ah2 = &ah * &ah;
    let expect = DMatrix::identity(2, 2) + &ah + &ah2 / 2.0 + &ah2 * &ah / 6.0 + &ah2 * &ah2 / 24.0;
    let mut j = DMatrix::zeros(2, 2);
    m.f_jacobian(&DVector::from_vec(vec![0.7, -1.0]), &DVector::zeros(0), &mut j).unwrap();
    assert!((&j - &expect).amax() < 1e-15, "{j} vs {expect}");
}

#[test]
fn wrong_sizes_and_non_finite_values_are_errors_naming_the_place() {
    let m = pendulum!(|f, h| ClosureModel::discrete(2, f, h)).unwrap();
    let (x, u) = points()[0].clone();
    let err = |r: Result<(), ModelError>| r.unwrap_err().to_string();
    let mut f = DVector::zeros(3);
    assert_eq!(err(m.f(&DVector::zeros(2), &u, &mut f)), "x: expected 3x1, got 2x1");
    assert_eq!(err(m.f(&x, &DVector::zeros(3), &mut f)), "u: expected 2x1, got 3x1");
    assert_eq!(err(m.f(&x, &u, &mut DVector::zeros(4))), "f(x, u): expected 3x1, got 4x1");
    assert_eq!(err(m.h(&x, &u, &mut DVector::zeros(2))), "h(x, u): expected 3x1, got 2x1");
    assert_eq!(err(m.f_jacobian(&x, &u, &mut DMatrix::zeros(3, 2))), "F = df/dx: expected 3x3, got 3x2");
    assert_eq!(err(m.h_jacobian(&x, &u, &mut DMatrix::zeros(2, 3))), "H = dh/dx: expected 3x3, got 2x3");
    let nan_u = DVector::from_vec(vec![0.0, f64::NAN]);
    assert_eq!(err(m.h(&x, &nan_u, &mut f)), "u has a non-finite entry at (1, 0)");
    // 2 + cos(x0) never vanishes; h's row 2 is ln(0) = -inf where x2 = ±i: use a model that
    // divides by a state instead.
    let m =
        ClosureModel::discrete(0, |x: &[crate::Dual<2>; 2], _| [x[0], 1.0 / x[1]], |x, _| [x[0], x[1].sqrt()]).unwrap();
    let zero = DVector::from_vec(vec![1.0, 0.0]);
    let none = DVector::zeros(0);
    assert_eq!(err(m.f(&zero, &none, &mut DVector::zeros(2))), "f(x, u) has a non-finite entry at (1, 0)");
    // sqrt at 0: a finite value, an infinite derivative in row 1, column 1.
    let mut y = DVector::zeros(2);
    m.h(&zero, &none, &mut y).unwrap();
    assert_eq!(y, zero);
    assert_eq!(
        err(m.h_jacobian(&zero, &none, &mut DMatrix::zeros(2, 2))),
        "H = dh/dx has a non-finite entry at (1, 1)"
    );
    // Construction: the sampling period, the sub-steps, the angles.
    let bad = |ts, integrator| {
        ClosureModel::continuous(0, ts, integrator, |x: &[crate::Dual<1>; 1], _| [x[0]], |x, _| [x[0]]).unwrap_err()
    };
    assert_eq!(bad(0.0, Integrator::Euler), ModelError::InvalidSamplingPeriod(0.0));
    assert!(matches!(bad(f64::NAN, Integrator::Euler), ModelError::InvalidSamplingPeriod(_)));
    assert!(matches!(bad(0.1, Integrator::Rk4 { substeps: 0 }), ModelError::InvalidSubsteps { .. }));
    let m = pendulum!(|f, h| ClosureModel::discrete(2, f, h)).unwrap();
    assert!(matches!(m.with_angles(Angles::new(&[3], &[])), Err(ModelError::InvalidAngles { index: 3, .. })));
}

#[test]
fn capabilities_and_angles() {
    let m = pendulum!(|f, h| ClosureModel::discrete(2, f, h)).unwrap().with_angles(Angles::new(&[1], &[1])).unwrap();
    assert_eq!(Capability::of(&m), Capability::Differentiable);
    assert_eq!(DiscreteModel::angles(&m), Angles::new(&[1], &[1]));
    assert_eq!(m.dims(), crate::Dims::new(3, 2, 3));
    assert_eq!(m.sampling(), None);
    assert!(format!("{m:?}").starts_with("ClosureModel { dims: Dims { states: 3, inputs: 2, outputs: 3 }"));
}
