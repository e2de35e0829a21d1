//! The EKF and UKF steps against fixed-size floors written here, side by side in one run, with
//! the model's own evaluations timed alone (the part no filter code can remove):
//!
//! * **truck EKF** (3 states, 7 inputs, 3 measurements; Pacejka tyres, Euler at 1 ms):
//!   [`ExtendedKalmanFilter::step`] through its public dynamic-size API against a Joseph-form EKF
//!   on nalgebra `SMatrix` that calls the same model (`f` with `∂f/∂x`, `h` with `∂h/∂x`, as the
//!   filter does, through its `DVector` API into buffers made once), and these evaluations alone;
//! * **vessel UKF** (6 states, 3 inputs, 3 measurements, the paper's `α, β, κ`):
//!   [`UnscentedKalmanFilter::step`] against the same scaled-sigma-point filter on `SMatrix`
//!   (module documentation of `estimators::ukf`, without its positive-definiteness guard, which
//!   these data never trigger), and its 26 evaluations (13 of `f`, 13 of `h`) alone.
//!
//! At setup, outside the timing, each pair runs the whole cycle and must agree to 1e-9
//! (relative). `cargo bench --bench gaussian_floors`.

mod common;

use std::hint::black_box;

use common::CYCLE;
use criterion::{Criterion, criterion_group, criterion_main};
use estimators::{ExtendedKalmanFilter, GaussianEstimate, Setup, UkfParams, UnscentedKalmanFilter};
use models::{DifferentiableModel, DiscreteModel};
use nalgebra::{DMatrix, DVector, SMatrix, SVector};

/// Asserts that the floor's mean `x` and covariance `p` are the filter's estimate `e` to 1e-9
/// (relative).
fn assert_floor_agrees(what: &str, e: &GaussianEstimate, x: &[f64], p: &[f64]) {
    let (dx, dp) = (rel_diff(e.center.as_slice(), x), rel_diff(e.covariance.as_slice(), p));
    assert!(dx < 1e-9 && dp < 1e-9, "{what} floor disagrees: mean {dx:e}, covariance {dp:e}");
}

fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let scale = a.iter().fold(0.0f64, |s, v| s.max(v.abs())).max(1e-300);
    a.iter().zip(b).fold(0.0f64, |d, (x, y)| d.max((x - y).abs())) / scale
}

/// A dynamic matrix as a fixed-size one.
fn fixed<const R: usize, const C: usize>(m: &DMatrix<f64>) -> SMatrix<f64, R, C> {
    SMatrix::from_column_slice(m.as_slice())
}

/// Model evaluations through the dynamic API into buffers made once, for a fixed-size filter.
struct Evaluator<'a, M: ?Sized, const N: usize, const Y: usize> {
    model: &'a M,
    x: DVector<f64>,
    fx: DVector<f64>,
    hx: DVector<f64>,
    jf: DMatrix<f64>,
    jh: DMatrix<f64>,
}

impl<'a, M: DiscreteModel + ?Sized, const N: usize, const Y: usize> Evaluator<'a, M, N, Y> {
    fn new(model: &'a M) -> Self {
        let z = DVector::zeros;
        Self { model, x: z(N), fx: z(N), hx: z(Y), jf: DMatrix::zeros(N, N), jh: DMatrix::zeros(Y, N) }
    }
    fn f(&mut self, x: &SVector<f64, N>, u: &DVector<f64>) -> SVector<f64, N> {
        self.x.copy_from_slice(x.as_slice());
        self.model.f(&self.x, u, &mut self.fx).expect("f");
        SVector::from_column_slice(self.fx.as_slice())
    }
    fn h(&mut self, x: &SVector<f64, N>, u: &DVector<f64>) -> SVector<f64, Y> {
        self.x.copy_from_slice(x.as_slice());
        self.model.h(&self.x, u, &mut self.hx).expect("h");
        SVector::from_column_slice(self.hx.as_slice())
    }
}

impl<M: DifferentiableModel + ?Sized, const N: usize, const Y: usize> Evaluator<'_, M, N, Y> {
    /// `(f(x), ∂f/∂x(x))`.
    fn f_with_jacobian(&mut self, x: &SVector<f64, N>, u: &DVector<f64>) -> (SVector<f64, N>, SMatrix<f64, N, N>) {
        self.x.copy_from_slice(x.as_slice());
        self.model.f_with_jacobian(&self.x, u, &mut self.fx, &mut self.jf).expect("f, ∂f/∂x");
        (SVector::from_column_slice(self.fx.as_slice()), SMatrix::from_column_slice(self.jf.as_slice()))
    }
    /// `(h(x), ∂h/∂x(x))`.
    fn h_with_jacobian(&mut self, x: &SVector<f64, N>, u: &DVector<f64>) -> (SVector<f64, Y>, SMatrix<f64, Y, N>) {
        self.x.copy_from_slice(x.as_slice());
        self.model.h_with_jacobian(&self.x, u, &mut self.hx, &mut self.jh).expect("h, ∂h/∂x");
        (SVector::from_column_slice(self.hx.as_slice()), SMatrix::from_column_slice(self.jh.as_slice()))
    }
}

/// The EKF floor (module documentation of `estimators::ekf`): Joseph form, symmetrised.
struct EkfFloor<const N: usize, const Y: usize> {
    x: SVector<f64, N>,
    p: SMatrix<f64, N, N>,
    q: SMatrix<f64, N, N>,
    r: SMatrix<f64, Y, Y>,
}

impl<const N: usize, const Y: usize> EkfFloor<N, Y> {
    fn new(s: &Setup) -> Self {
        Self {
            x: SVector::from_column_slice(s.x0.as_slice()),
            p: fixed(&s.p0),
            q: fixed(&s.process_noise),
            r: fixed(&s.measurement_noise),
        }
    }
    fn step<M: DifferentiableModel + ?Sized>(
        &mut self,
        ev: &mut Evaluator<'_, M, N, Y>,
        u: &DVector<f64>,
        y: &DVector<f64>,
    ) {
        let (x, f) = ev.f_with_jacobian(&self.x, u);
        let p = f * self.p * f.transpose() + self.q;
        let (z, h) = ev.h_with_jacobian(&x, u);
        let s = h * p * h.transpose() + self.r;
        let k = p * h.transpose() * s.cholesky().expect("S is positive definite").inverse();
        self.x = x + k * (SVector::<f64, Y>::from_column_slice(y.as_slice()) - z);
        let ikh = SMatrix::<f64, N, N>::identity() - k * h;
        let p = ikh * p * ikh.transpose() + k * self.r * k.transpose();
        self.p = (p + p.transpose()) * 0.5;
    }
}

/// The UKF floor (module documentation of `estimators::ukf`), `S = 2N + 1` sigma points.
struct UkfFloor<const N: usize, const Y: usize> {
    x: SVector<f64, N>,
    p: SMatrix<f64, N, N>,
    q: SMatrix<f64, N, N>,
    r: SMatrix<f64, Y, Y>,
    gamma: f64,
    wm: (f64, f64),
    wc: (f64, f64),
}

impl<const N: usize, const Y: usize> UkfFloor<N, Y> {
    fn new(s: &Setup, k: UkfParams) -> Self {
        let n = N as f64;
        let c = k.alpha * k.alpha * (n + k.kappa);
        let lambda = c - n;
        let wi = 1.0 / (2.0 * c);
        Self {
            x: SVector::from_column_slice(s.x0.as_slice()),
            p: fixed(&s.p0),
            q: fixed(&s.process_noise),
            r: fixed(&s.measurement_noise),
            gamma: c.sqrt(),
            wm: (lambda / c, wi),
            wc: (lambda / c + 1.0 - k.alpha * k.alpha + k.beta, wi),
        }
    }
    /// `X₀ = m`, `X_i = m + γ L_i`, `X_{N+i} = m − γ L_i`.
    fn sigma(&self, m: &SVector<f64, N>, p: &SMatrix<f64, N, N>, out: &mut [SVector<f64, N>]) {
        let l = p.cholesky().expect("P is positive definite").l() * self.gamma;
        out[0] = *m;
        for i in 0..N {
            out[1 + i] = m + l.column(i);
            out[1 + N + i] = m - l.column(i);
        }
    }
    fn weights(&self, i: usize) -> (f64, f64) {
        if i == 0 { (self.wm.0, self.wc.0) } else { (self.wm.1, self.wc.1) }
    }
    fn step<M: DiscreteModel + ?Sized>(&mut self, ev: &mut Evaluator<'_, M, N, Y>, u: &DVector<f64>, y: &DVector<f64>) {
        let mut pts = [SVector::<f64, N>::zeros(); 32];
        let pts = &mut pts[..2 * N + 1];
        self.sigma(&self.x, &self.p, pts);
        for p in pts.iter_mut() {
            *p = ev.f(p, u);
        }
        let xm = pts.iter().enumerate().fold(SVector::zeros(), |a, (i, p)| a + p * self.weights(i).0);
        let mut pm = self.q;
        for (i, p) in pts.iter().enumerate() {
            let d = p - xm;
            pm += d * d.transpose() * self.weights(i).1;
        }
        let pm = (pm + pm.transpose()) * 0.5;
        self.sigma(&xm, &pm, pts);
        let mut zs = [SVector::<f64, Y>::zeros(); 32];
        for (z, p) in zs.iter_mut().zip(pts.iter()) {
            *z = ev.h(p, u);
        }
        let zs = &zs[..2 * N + 1];
        let zm = zs.iter().enumerate().fold(SVector::zeros(), |a, (i, z)| a + z * self.weights(i).0);
        let (mut pzz, mut pxz) = (self.r, SMatrix::<f64, N, Y>::zeros());
        for (i, (z, p)) in zs.iter().zip(pts.iter()).enumerate() {
            let (dz, dx, w) = (z - zm, p - xm, self.weights(i).1);
            pzz += dz * dz.transpose() * w;
            pxz += dx * dz.transpose() * w;
        }
        let pzz = (pzz + pzz.transpose()) * 0.5;
        let k = pxz * pzz.cholesky().expect("Pzz is positive definite").inverse();
        self.x = xm + k * (SVector::<f64, Y>::from_column_slice(y.as_slice()) - zm);
        let p = pm - k * pzz * k.transpose();
        self.p = (p + p.transpose()) * 0.5;
    }
}

fn truck_ekf(crit: &mut Criterion) {
    let (model, common::Cycle { setup, inputs, ys }) = common::truck();
    let mut ev = Evaluator::<_, 3, 3>::new(&model);
    {
        let (mut ours, mut floor) = (ExtendedKalmanFilter::new(setup.clone()).unwrap(), EkfFloor::<3, 3>::new(&setup));
        for (u, y) in inputs.iter().zip(&ys) {
            ours.step(&model, u, y).unwrap();
            floor.step(&mut ev, u, y);
        }
        assert_floor_agrees("truck EKF", ours.estimate(), floor.x.as_slice(), floor.p.as_slice());
    }
    let mut group = crit.benchmark_group("truck_ekf_floor");
    let mut ours = ExtendedKalmanFilter::new(setup.clone()).unwrap();
    let mut k = 0;
    group.bench_function("estimators", |b| {
        b.iter(|| {
            k = (k + 1) % CYCLE;
            if k == 0 {
                ours = ExtendedKalmanFilter::new(setup.clone()).unwrap();
            }
            black_box(ours.step(&model, &inputs[k], &ys[k]).unwrap().center[0])
        })
    });
    let mut floor = EkfFloor::<3, 3>::new(&setup);
    group.bench_function("smatrix-floor", |b| {
        b.iter(|| {
            k = (k + 1) % CYCLE;
            if k == 0 {
                floor = EkfFloor::new(&setup);
            }
            floor.step(&mut ev, &inputs[k], &ys[k]);
            black_box(floor.x[0])
        })
    });
    let x0 = SVector::<f64, 3>::from_column_slice(setup.x0.as_slice());
    group.bench_function("model-f-with-jacobian-h-with-jacobian", |b| {
        b.iter(|| {
            k = (k + 1) % CYCLE;
            let (x, f) = ev.f_with_jacobian(&x0, &inputs[k]);
            let (z, h) = ev.h_with_jacobian(&x, &inputs[k]);
            black_box(f[0] + h[0] + z[0])
        })
    });
    group.finish();
}

fn vessel_ukf(crit: &mut Criterion) {
    let (model, common::Cycle { setup, inputs, ys }) = common::vessel();
    let params = UkfParams::paper();
    let mut ev = Evaluator::<_, 6, 3>::new(&model);
    {
        let mut ours = UnscentedKalmanFilter::new(setup.clone(), params).unwrap();
        let mut floor = UkfFloor::<6, 3>::new(&setup, params);
        for (u, y) in inputs.iter().zip(&ys) {
            ours.step(&model, u, y).unwrap();
            floor.step(&mut ev, u, y);
        }
        assert_floor_agrees("vessel UKF", ours.estimate(), floor.x.as_slice(), floor.p.as_slice());
    }
    let mut group = crit.benchmark_group("vessel_ukf_floor");
    let fresh = || UnscentedKalmanFilter::new(setup.clone(), params).unwrap();
    let mut ours = fresh();
    let mut k = 0;
    group.bench_function("estimators", |b| {
        b.iter(|| {
            k = (k + 1) % CYCLE;
            if k == 0 {
                ours = fresh();
            }
            black_box(ours.step(&model, &inputs[k], &ys[k]).unwrap().center[0])
        })
    });
    let mut floor = UkfFloor::<6, 3>::new(&setup, params);
    group.bench_function("smatrix-floor", |b| {
        b.iter(|| {
            k = (k + 1) % CYCLE;
            if k == 0 {
                floor = UkfFloor::new(&setup, params);
            }
            floor.step(&mut ev, &inputs[k], &ys[k]);
            black_box(floor.x[0])
        })
    });
    let x0 = SVector::<f64, 6>::from_element(0.1);
    group.bench_function("model-13-f-13-h", |b| {
        b.iter(|| {
            k = (k + 1) % CYCLE;
            let mut acc = 0.0;
            for _ in 0..13 {
                acc += ev.f(&x0, &inputs[k])[0] + ev.h(&x0, &inputs[k])[0];
            }
            black_box(acc)
        })
    });
    group.finish();
}

criterion_group!(benches, truck_ekf, vessel_ukf);
criterion_main!(benches);
