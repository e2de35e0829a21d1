//! One Kalman step against its peers, side by side on the same data: [`estimators::KalmanFilter`]
//! through its public dynamic-size API, the `adskalman` crate (nalgebra fixed sizes), and a
//! Joseph-form filter on nalgebra `SMatrix` written here as the floor.
//!
//! The Table 1 carrier at 6 m/s, `T_s` = 1 ms: n = 4 states, p = 8 inputs, m = 3 measurements,
//! a simulated run of 20 000 steps cycled (each filter restarts when the cycle wraps). At setup,
//! outside the timing, the three filters run a few hundred steps and must agree to ~1e-12.
//! `cargo bench --bench peers`.
//!
//! `adskalman` has no control input: its transition model here overrides `predict` to add the
//! (constant) `B u`; the rest of its step (Joseph-form update through `S⁻¹`) is its own.

#![allow(non_snake_case)] // adskalman's trait methods are named F, Q, H, R.

use std::hint::black_box;

use adskalman::{KalmanFilterNoControl, ObservationModel, StateAndCovariance, TransitionModelLinearNoControl};
use criterion::{Criterion, criterion_group, criterion_main};
use estimators::KalmanFilter;
use nalgebra::{DVector, SMatrix, SVector, U3, U4};

const N: usize = 4;
const P: usize = 8;
const M: usize = 3;
/// Steps of the simulated run the benchmark cycles through.
const RUN: usize = 20_000;
/// Steps run at setup before the three filters are compared.
const AGREEMENT_STEPS: usize = 300;

#[path = "../crates/estimators/tests/common/system.rs"]
mod system;

use system::LinearSystem;

/// The common data: the carrier (model, noise covariances, initial covariance), inputs and
/// measurements.
struct Case {
    sys: LinearSystem,
    u: DVector<f64>,
    ys: Vec<DVector<f64>>,
}

/// The carrier with three of the four states measured (no sideslip sensor) and a simulated run
/// with noise on the boundary of its sets.
fn case() -> Case {
    let sys = system::carrier(M);
    let u = DVector::from_element(P, 0.01);
    let ys = system::boundary_measurements(&sys, &u, RUN, 1);
    Case { sys, u, ys }
}

/// A column-major slice as a fixed-size matrix.
fn fixed<const R: usize, const C: usize>(m: &[f64]) -> SMatrix<f64, R, C> {
    SMatrix::from_column_slice(m)
}

/// The floor: a Joseph-form Kalman filter on nalgebra fixed-size matrices, symmetrised as ours.
#[derive(Clone)]
struct Floor {
    a: SMatrix<f64, N, N>,
    b: SMatrix<f64, N, P>,
    c: SMatrix<f64, M, N>,
    q: SMatrix<f64, N, N>,
    r: SMatrix<f64, M, M>,
    x: SVector<f64, N>,
    p: SMatrix<f64, N, N>,
}

impl Floor {
    fn step(&mut self, u: &SVector<f64, P>, y: &SVector<f64, M>) {
        let x = self.a * self.x + self.b * u;
        let p = self.a * self.p * self.a.transpose() + self.q;
        let s = self.c * p * self.c.transpose() + self.r;
        // S⁻¹ in closed form (nalgebra's cofactor inverse up to 4 × 4): faster than through
        // its Cholesky factor at these sizes.
        let k = p * self.c.transpose() * s.try_inverse().expect("S is invertible");
        self.x = x + k * (y - self.c * x);
        let ikc = SMatrix::<f64, N, N>::identity() - k * self.c;
        let p = ikc * p * ikc.transpose() + k * self.r * k.transpose();
        self.p = (p + p.transpose()) * 0.5;
    }
}

/// adskalman's transition model, with the constant `B u` added to its prediction.
struct Transition {
    f: SMatrix<f64, N, N>,
    ft: SMatrix<f64, N, N>,
    q: SMatrix<f64, N, N>,
    bu: SVector<f64, N>,
}

impl TransitionModelLinearNoControl<f64, U4> for Transition {
    fn F(&self) -> &SMatrix<f64, N, N> {
        &self.f
    }
    fn FT(&self) -> &SMatrix<f64, N, N> {
        &self.ft
    }
    fn Q(&self) -> &SMatrix<f64, N, N> {
        &self.q
    }
    fn predict(&self, previous: &StateAndCovariance<f64, U4>) -> StateAndCovariance<f64, U4> {
        let state = self.f * previous.state() + self.bu;
        let covariance = self.f * previous.covariance() * self.ft + self.q;
        StateAndCovariance::new(state, covariance)
    }
}

/// adskalman's linear observation model.
struct Observation {
    h: SMatrix<f64, M, N>,
    ht: SMatrix<f64, N, M>,
    r: SMatrix<f64, M, M>,
}

impl ObservationModel<f64, U4, U3> for Observation {
    fn H(&self) -> &SMatrix<f64, M, N> {
        &self.h
    }
    fn HT(&self) -> &SMatrix<f64, N, M> {
        &self.ht
    }
    fn R(&self) -> &SMatrix<f64, M, M> {
        &self.r
    }
}

/// The largest entry-wise difference between two (flattened) estimates, relative to their size.
fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let scale = a.iter().fold(0.0f64, |s, v| s.max(v.abs())).max(1e-300);
    a.iter().zip(b).fold(0.0f64, |d, (x, y)| d.max((x - y).abs())) / scale
}

fn peers(crit: &mut Criterion) {
    let cs = case();
    let model = cs.sys.model();
    let setup = || cs.sys.setup();
    let kf0 = KalmanFilter::new(setup()).unwrap();

    let floor0 = Floor {
        a: fixed(cs.sys.a.as_slice()),
        b: fixed(cs.sys.b.as_slice()),
        c: fixed(cs.sys.c.as_slice()),
        q: fixed(cs.sys.q.as_slice()),
        r: fixed(cs.sys.r.as_slice()),
        x: SVector::zeros(),
        p: fixed(cs.sys.p0.as_slice()),
    };
    let us: SVector<f64, P> = fixed(cs.u.as_slice());
    let ys: Vec<SVector<f64, M>> = cs.ys.iter().map(|y| fixed(y.as_slice())).collect();

    let transition = Transition { f: floor0.a, ft: floor0.a.transpose(), q: floor0.q, bu: floor0.b * us };
    let observation = Observation { h: floor0.c, ht: floor0.c.transpose(), r: floor0.r };
    let ads = KalmanFilterNoControl::new(&transition, &observation);
    let ads0 = StateAndCovariance::new(SVector::<f64, N>::zeros(), floor0.p);

    // The three agree on the same data (outside the timing).
    {
        let (mut kf, mut floor, mut est) = (kf0.clone(), floor0.clone(), ads0.clone());
        for k in 0..AGREEMENT_STEPS {
            kf.step(&model, &cs.u, &cs.ys[k]).unwrap();
            floor.step(&us, &ys[k]);
            est = ads.step(&est, &ys[k]).unwrap();
        }
        let ours = kf.estimate();
        for (name, x, p) in [("floor", floor.x, floor.p), ("adskalman", *est.state(), *est.covariance())] {
            let (dx, dp) =
                (rel_diff(ours.center.as_slice(), x.as_slice()), rel_diff(ours.covariance.as_slice(), p.as_slice()));
            assert!(
                dx < 1e-12 && dp < 1e-12,
                "{name} disagrees after {AGREEMENT_STEPS} steps: mean {dx:e}, covariance {dp:e}"
            );
        }
    }

    let mut group = crit.benchmark_group("kalman_peers");
    let mut kf = kf0.clone();
    let mut k = 0;
    group.bench_function("estimators", |b| {
        b.iter(|| {
            k = (k + 1) % RUN;
            if k == 0 {
                kf = kf0.clone();
            }
            black_box(kf.step(&model, &cs.u, &cs.ys[k]).unwrap().center[0])
        })
    });
    let mut est = ads0.clone();
    k = 0;
    group.bench_function("adskalman", |b| {
        b.iter(|| {
            k = (k + 1) % RUN;
            if k == 0 {
                est = ads0.clone();
            }
            est = ads.step(&est, &ys[k]).unwrap();
            black_box(est.state()[0])
        })
    });
    let mut floor = floor0.clone();
    k = 0;
    group.bench_function("smatrix-floor", |b| {
        b.iter(|| {
            k = (k + 1) % RUN;
            if k == 0 {
                floor = floor0.clone();
            }
            floor.step(&us, &ys[k]);
            black_box(floor.x[0])
        })
    });
    group.finish();
}

criterion_group!(benches, peers);
criterion_main!(benches);
