//! Shared helpers for the integration tests (random systems, SPD matrices, backends).
#![allow(dead_code)]

use models::Xoshiro256StarStar;
use nalgebra::{DMatrix, DVector};

pub mod lcg;
pub mod system;
#[allow(unused_imports)]
pub use system::{LinearSystem, setup};

/// `A` of the `lmi` reference case (n = 4).
pub fn reference_a() -> DMatrix<f64> {
    DMatrix::from_row_slice(
        4,
        4,
        &[
            0.755139296689566,
            -0.019699090506075354,
            -0.04774305144944732,
            -0.0018915821287349352,
            -0.009311961979518266,
            0.9417205179851139,
            0.0002699108914448061,
            1.0206142568712238e-05,
            -0.0007011828373116359,
            -3.020454597046461e-05,
            0.9998073936269428,
            0.00999272470285723,
            -0.13392137898100265,
            -0.005464612817309362,
            -0.03728944211821784,
            0.9985252052798118,
        ],
    )
}

/// `C` of the reference case: the last three states measured.
pub fn reference_c() -> DMatrix<f64> {
    DMatrix::from_row_slice(3, 4, &[0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0])
}

/// A standard Gaussian `r × c` matrix.
pub fn gauss(rng: &mut Xoshiro256StarStar, r: usize, c: usize) -> DMatrix<f64> {
    DMatrix::from_fn(r, c, |_, _| rng.standard_normal())
}

/// A uniform `r × c` matrix on `[-1, 1]`.
pub fn uniform(rng: &mut Xoshiro256StarStar, r: usize, c: usize) -> DMatrix<f64> {
    DMatrix::from_fn(r, c, |_, _| rng.uniform(-1.0, 1.0))
}

/// A random linear system of `n` states, `m` outputs and `p` inputs to compare filters on: `A`
/// uniform times 0.7, `B`, `C` uniform, `Q = G Gᵀ + 0.1 I` (`G` uniform), `R = 0.3 I`,
/// `P₀ = 2 I`, `x₀ = (0, 0.1, 0.2, …)`.
pub fn random_linear_system(rng: &mut Xoshiro256StarStar, n: usize, m: usize, p: usize) -> LinearSystem {
    let a = uniform(rng, n, n) * 0.7;
    let b = uniform(rng, n, p);
    let c = uniform(rng, m, n);
    let g = uniform(rng, n, n);
    LinearSystem {
        a,
        b,
        c,
        q: &g * g.transpose() + DMatrix::identity(n, n) * 0.1,
        r: DMatrix::identity(m, m) * 0.3,
        p0: DMatrix::identity(n, n) * 2.0,
        x0: DVector::from_fn(n, |i, _| i as f64 * 0.1),
    }
}

/// A random orthogonal matrix (QR of a Gaussian matrix).
pub fn orthogonal(rng: &mut Xoshiro256StarStar, n: usize) -> DMatrix<f64> {
    gauss(rng, n, n).qr().q()
}

/// A random SPD matrix with condition number `cond` and largest eigenvalue `scale`.
pub fn spd(rng: &mut Xoshiro256StarStar, n: usize, scale: f64, cond: f64) -> DMatrix<f64> {
    let u = orthogonal(rng, n);
    let d = DVector::from_fn(n, |i, _| {
        let t = if n == 1 { 0.0 } else { i as f64 / (n - 1) as f64 };
        scale * cond.powf(-t)
    });
    let m = &u * DMatrix::from_diagonal(&d) * u.transpose();
    (&m + m.transpose()) * 0.5
}

/// A random `A` with spectral radius about `radius` (a rotation-like orthogonal part times a
/// random similarity with mild conditioning).
pub fn random_a(rng: &mut Xoshiro256StarStar, n: usize, radius: f64) -> DMatrix<f64> {
    let o = orthogonal(rng, n);
    let s = DMatrix::identity(n, n) + gauss(rng, n, n) * 0.2;
    let si = s.clone().try_inverse().unwrap_or_else(|| DMatrix::identity(n, n));
    let a = &s * o * si;
    let rho = a.complex_eigenvalues().iter().map(|z| z.norm()).fold(0.0, f64::max);
    a * (radius / rho.max(1e-12))
}

/// `(x − c)ᵀ P⁻¹ (x − c)` through a Cholesky factor.
pub fn normalized_distance(p: &DMatrix<f64>, c: &DVector<f64>, x: &DVector<f64>) -> f64 {
    let ch = p.clone().cholesky().expect("published shape is positive definite");
    let z = ch.l().solve_lower_triangular(&(x - c)).unwrap();
    z.norm_squared()
}

/// A point on the boundary of 𝓔(c, P).
pub fn boundary_point(rng: &mut Xoshiro256StarStar, c: &DVector<f64>, p: &DMatrix<f64>) -> DVector<f64> {
    let n = c.len();
    let g = DVector::from_fn(n, |_, _| rng.standard_normal());
    let dir = &g / g.norm();
    c + p.clone().cholesky().unwrap().l() * dir
}

/// The SDP backends to compare against: every backend `lmi::backend_names()` lists (the
/// pure-Rust `faer-ipm` always; Clarabel with `--features lmi/clarabel`).
pub fn backends(settings: lmi::SolverSettings) -> Vec<(String, Box<dyn lmi::SdpBackend>)> {
    let names = lmi::backend_names();
    if names.is_empty() {
        println!("no SDP backend compiled in: SDP comparisons skipped");
    }
    names.into_iter().map(|name| (name.to_string(), lmi::backend_by_name(name, settings.clone()).unwrap())).collect()
}

/// A stub solver of (29) that returns the same `(L, τ)` (every entry of `L` equal to `l`), status
/// and iteration count at every step; `closed_form` is what it claims about its gain (if true the
/// filter certifies `L` as it is, otherwise it recomputes the closed-form gain for `τ`).
pub struct FixedSolver {
    pub l: f64,
    pub tau: [f64; 3],
    pub status: estimators::smf::UpdateStatus,
    pub iterations: u32,
    pub closed_form: bool,
}

impl estimators::UpdateSolver for FixedSolver {
    fn name(&self) -> &str {
        "fixed"
    }
    fn prepare(&mut self, _: usize, _: usize) -> Result<(), estimators::EstimatorError> {
        Ok(())
    }
    fn solve(
        &mut self,
        _: &estimators::smf::UpdateProblem<'_>,
        _: [f64; 3],
        out: &mut estimators::smf::UpdateSolution,
    ) -> Result<(), estimators::EstimatorError> {
        out.l.fill(self.l);
        out.tau = self.tau;
        out.status = self.status;
        out.iterations = self.iterations;
        Ok(())
    }
    fn gain_is_closed_form(&self) -> bool {
        self.closed_form
    }
}

/// A test case of an estimator with settings beyond its setup (the moving-horizon estimators): the
/// setup's prior and weights beside the settings, which it derefs to.
#[derive(Debug, Clone)]
pub struct Case<S> {
    pub x0: DVector<f64>,
    pub p0: DMatrix<f64>,
    pub q: DMatrix<f64>,
    pub r: DMatrix<f64>,
    pub settings: S,
}

impl<S> std::ops::Deref for Case<S> {
    type Target = S;
    fn deref(&self) -> &S {
        &self.settings
    }
}

impl<S> std::ops::DerefMut for Case<S> {
    fn deref_mut(&mut self) -> &mut S {
        &mut self.settings
    }
}

impl<S> Case<S> {
    /// The estimator's setup with `inputs` inputs.
    pub fn setup(&self, inputs: usize) -> estimators::Setup {
        estimators::Setup {
            x0: self.x0.clone(),
            p0: self.p0.clone(),
            process_noise: self.q.clone(),
            measurement_noise: self.r.clone(),
            inputs,
        }
    }
}
