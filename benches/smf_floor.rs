//! One exact set-membership filter step against a fixed-size floor, on the same data:
//! [`estimators::SetMembershipFilter`] (default solver: the exact two-multiplier method) through its
//! public dynamic-size API (its linear algebra compiled for (4, 3); `estimators-general`: the same
//! filter on the runtime-size kernels), and the same step written here on nalgebra `SMatrix` (const
//! sizes, no heap, no validation) as the floor, so that "ours / floor" can be reported.
//!
//! The floor does the same work as ours: the prediction `X₁ = A P Aᵀ`; the data-consistency check
//! (the fixed-point search of `smf/consistency.rs`); the damped Newton with active set of
//! `smf/two_multiplier.rs` (objective (27'), gain (G1), derivatives (D1)–(D2), the same paths,
//! Armijo search, stopping rule and tolerances, warm started from the previous `τ`); `clamp_tau`;
//! the certification of `smf/certify.rs` (`T₁ + T₂ + T₃`, the same rounding-error inflation), the
//! centre and the bounds. It omits input validation and the fallback paths (asserted unused), and
//! keeps the gain of the last Newton evaluation where ours recomputes it for the returned `τ`.
//!
//! Data: those of the `filter_step/smf-two-multiplier/n4m3` row of `benches/estimators.rs`, the
//! Table 1 carrier at 6 m/s, `T_s` = 1 ms: n = 4 states, p = 8 inputs, m = 3 measurements (the last
//! three states), noise on the boundary of its ellipsoids, a run of 200 000 steps cycled (each
//! filter restarts when the cycle wraps). At setup, outside the timing, both run the whole run and
//! must agree to a relative 1e-9 at every step (observed: 2.4e-13 at worst, the same Newton
//! iteration count at every step, 0.29 on average). `cargo bench --bench smf_floor`.

use std::hint::black_box;

use carrier_dynamics::{CarrierModel, CarrierParams};
use criterion::{Criterion, criterion_group, criterion_main};
use estimators::{SetMembershipFilter, Setup, StepModel};
use nalgebra::{DMatrix, DVector, SMatrix, SVector};

const N: usize = 4;
const P: usize = 8;
const M: usize = 3;
/// Steps of the simulated run the benchmark cycles through (as `benches/estimators.rs`).
const RUN: usize = 200_000;
/// Largest relative difference of centre and shape allowed at any step of the run.
const AGREEMENT: f64 = 1e-9;
// The solver's `TAU_FLOOR`, decrement and stall tolerances (`smf/two_multiplier.rs`).
const F: f64 = 1e-12;
const TOLERANCE: f64 = 1e-13;
const STALL: f64 = 1e-10;
const EPS: f64 = f64::EPSILON;
/// Inward normals of the constraints `τ₁ ≥ F`, `τ₂ ≥ F`, `τ₃ ≥ 0` in `(τ₁, τ₂)`, and the edges.
const NORMALS: [[f64; 2]; 3] = [[1.0, 0.0], [0.0, 1.0], [-1.0, -1.0]];
const TANGENTS: [[f64; 2]; 3] = [[0.0, 1.0], [1.0, 0.0], [1.0, -1.0]];

type Mn = SMatrix<f64, N, N>;
type Mnm = SMatrix<f64, N, M>;
type Mm = SMatrix<f64, M, M>;
type Vn = SVector<f64, N>;

/// `γ_k = k u / (1 − k u)`, `u = ε/2`.
fn gamma(k: usize) -> f64 {
    let ku = k as f64 * EPS / 2.0;
    ku / (1.0 - ku)
}

fn dot2(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

/// `xᵀ H x` for a symmetric 2 × 2 `H`.
fn quad(h: &[[f64; 2]; 2], x: [f64; 2]) -> f64 {
    x[0] * (h[0][0] * x[0] + h[0][1] * x[1]) + x[1] * (h[1][0] * x[0] + h[1][1] * x[1])
}

/// Shifts the spectrum of a symmetric 2 × 2 matrix to make it positive definite if needed.
fn regularise(mut h: [[f64; 2]; 2]) -> [[f64; 2]; 2] {
    let (tr, det) = (h[0][0] + h[1][1], h[0][0] * h[1][1] - h[0][1] * h[1][0]);
    let disc = (0.25 * (h[0][0] - h[1][1]).powi(2) + h[0][1] * h[1][0]).max(0.0).sqrt();
    let (lmin, lmax) = (0.5 * tr - disc, 0.5 * tr + disc);
    let floor = 1e-10 * lmax.abs().max(f64::MIN_POSITIVE);
    if lmin.is_nan() || lmin <= floor || det.is_nan() || det <= 0.0 {
        let shift = floor - lmin.min(0.0) + lmax.abs() * 1e-3;
        (h[0][0], h[1][1]) = (h[0][0] + shift, h[1][1] + shift);
    }
    h
}

/// `−H⁻¹ g` for a positive definite 2 × 2 `H`.
fn solve2(h: [[f64; 2]; 2], g: [f64; 2]) -> [f64; 2] {
    let det = h[0][0] * h[1][1] - h[0][1] * h[1][0];
    [-(h[1][1] * g[0] - h[0][1] * g[1]) / det, -(h[0][0] * g[1] - h[1][0] * g[0]) / det]
}

/// The 1-D Newton step, or a unit step downhill if `h ≤ 0`.
fn newton1(g: f64, h: f64) -> f64 {
    if h > 0.0 { -g / h } else { -g.signum() }
}

fn clip(d: [f64; 2], max: f64) -> [f64; 2] {
    let m = d[0].abs().max(d[1].abs());
    if m > max { [d[0] * max / m, d[1] * max / m] } else { d }
}

/// The first two constraints of the working set.
fn active(ws: [bool; 3]) -> (Option<usize>, Option<usize>) {
    let mut it = (0..3).filter(|&i| ws[i]);
    (it.next(), it.next())
}

/// `clamp_tau` of `smf/fallback.rs` (for a finite `τ` with a positive entry).
fn clamp_tau(tau: [f64; 3]) -> [f64; 3] {
    const LIMIT: f64 = 1.0 - 2.0 * EPS;
    let top = tau.iter().fold(0.0f64, |m, v| m.max(*v));
    let t = tau.map(|v| v.max(0.0) / top);
    let t = t.map(|v| v / (t[0] + t[1] + t[2]));
    let mut t = [t[0].max(F), t[1].max(F), if t[2] < EPS * F { 0.0 } else { t[2] }];
    let big = (1..3).fold(0, |b, i| if t[i] > t[b] { i } else { b }); // the first largest entry
    for _ in 0..8 {
        let s = t[0] + t[1] + t[2];
        t[big] -= if s > LIMIT { (s - LIMIT).max(t[big] * EPS) } else { 0.0 };
    }
    t
}

/// `g(τ)`, (D1), (D2) and the gain (G1) `L = τ₃ W` at one `τ`.
#[derive(Clone, Copy)]
struct Ev {
    g: f64,
    grad: [f64; 3],
    hess: [[f64; 3]; 3],
    l: Mnm,
}

/// A point of the region: `(τ₁, τ₂)` and whether it is on the edge `τ₃ = 0`.
#[derive(Clone, Copy)]
struct Pt {
    t1: f64,
    t2: f64,
    on3: bool,
}

impl Pt {
    fn tau(self) -> [f64; 3] {
        [self.t1, self.t2, if self.on3 { 0.0 } else { (1.0 - self.t1 - self.t2).max(0.0) }]
    }
    fn edge(t1: f64) -> Pt {
        Pt { t1, t2: (1.0 - t1).max(F), on3: true }
    }
    /// The warm start clamped into the region.
    fn start(w: [f64; 3]) -> Pt {
        let ok = w.iter().all(|v| v.is_finite() && *v >= 0.0) && w[0] + w[1] <= 1.0 + 1e-9;
        let w = if ok { w } else { [1.0 / 3.0; 3] };
        let t1 = w[0].clamp(F, 1.0 - F);
        if w[2] <= 0.0 || t1 + w[1].max(F) >= 1.0 { Pt::edge(t1) } else { Pt { t1, t2: w[1].max(F), on3: false } }
    }
}

/// A step from a point as a function of its length: `τ` along `d`, `ln τᵢ` along `d` (snapped onto
/// `τ₃ = 0` if it crosses it), or the logit `ln(τ₁/τ₂)` along the edge `τ₃ = 0`.
#[derive(Clone, Copy)]
enum Path {
    Linear([f64; 2]),
    Log([f64; 2]),
    Logit(f64),
}

impl Path {
    fn point(self, pt: Pt, ws: [bool; 3], alpha: f64) -> Pt {
        match self {
            Path::Log(d) => {
                let at = |a: f64| {
                    let t1 = if ws[0] { pt.t1 } else { (pt.t1 * (a * d[0]).exp()).max(F) };
                    (t1, if ws[1] { pt.t2 } else { (pt.t2 * (a * d[1]).exp()).max(F) })
                };
                let (t1, t2) = at(alpha);
                if t1 + t2 < 1.0 {
                    return Pt { t1, t2, on3: false };
                }
                // Crossed τ₃ = 0: bisect for the crossing and snap onto the edge.
                let (mut lo, mut hi) = (0.0, alpha);
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    let (a, b) = at(mid);
                    (lo, hi) = if a + b < 1.0 { (mid, hi) } else { (lo, mid) };
                }
                Pt::edge(at(lo).0.clamp(F, 1.0 - F))
            }
            Path::Linear(d) => {
                let snap = |t: f64| if t <= F * (1.0 + 1e-9) { F } else { t };
                let t1 = if ws[0] { pt.t1 } else { snap(pt.t1 + alpha * d[0]) };
                let t2 = if ws[1] { pt.t2 } else { snap(pt.t2 + alpha * d[1]) };
                if t1 + t2 < 1.0 - 1e-15 { Pt { t1, t2, on3: false } } else { Pt::edge(t1.min(1.0 - F)) }
            }
            Path::Logit(ds) => Pt::edge((1.0 / (1.0 + (-(pt.t1 / pt.t2).ln() - alpha * ds).exp())).clamp(F, 1.0 - F)),
        }
    }
}

/// The floor: the exact set-membership filter on nalgebra fixed-size matrices.
#[derive(Clone)]
struct Floor {
    a: Mn,
    b: SMatrix<f64, N, P>,
    c: SMatrix<f64, M, N>,
    q: Mn,
    r: Mm,
    x: Vn,
    p: Mn,
    bounds: (Vn, Vn),
    tau: [f64; 3],
    iterations: u32,
}

/// One step's problem (29): `X₁` and the `τ`-independent products `X₁Cᵀ`, `QCᵀ`, `CX₁Cᵀ`, `CQCᵀ`.
struct Problem<'a> {
    f: &'a Floor,
    x1: Mn,
    x1c: Mnm,
    qc: Mnm,
    cx1c: Mm,
    cqc: Mm,
}

impl Problem<'_> {
    /// `g`, (D1), (D2) and `L` at `τ` (`None` if `S` is not positive definite or a value is not finite).
    fn eval(&self, [t1, t2, t3]: [f64; 3]) -> Option<Ev> {
        let f = self.f;
        let mc = self.x1c * (1.0 / t1) + self.qc * (1.0 / t2);
        let nmat = self.cx1c * (1.0 / t1) + self.cqc * (1.0 / t2);
        // S = τ₃ N + R = G Gᵀ, W = M Cᵀ S⁻¹, L = τ₃ W, K = I − L C; βᵢᵀ = G⁻¹ ãᵢᵀ.
        let ch = (nmat * t3 + f.r).cholesky()?;
        let w = ch.solve(&mc.transpose()).transpose();
        let (l, wr) = (w * t3, w * f.r);
        let k = Mn::identity() - l * f.c;
        let beta = |a: Mnm| {
            let mut t = a.transpose();
            ch.l_dirty().solve_lower_triangular_unchecked_mut(&mut t);
            t
        };
        let (tr1, tr2, wrw) = ((k * self.x1).dot(&k) / t1, (k * f.q).dot(&k) / t2, wr.dot(&w));
        let (g, grad) = (tr1 + tr2 + t3 * wrw, [-tr1 / t1, -tr2 / t2, -wrw]);
        let (b1, b2) = (beta(k * self.x1c * (1.0 / t1)), beta(k * self.qc * (1.0 / t2)));
        let (b3, wn) = (beta(wr), beta(w * nmat));
        let h11 = 2.0 * (tr1 - t3 * b1.dot(&b1)) / (t1 * t1);
        let h22 = 2.0 * (tr2 - t3 * b2.dot(&b2)) / (t2 * t2);
        let h12 = -2.0 * t3 * b1.dot(&b2) / (t1 * t2);
        let (h13, h23, h33) = (2.0 * b1.dot(&b3) / t1, 2.0 * b2.dot(&b3) / t2, 2.0 * wn.dot(&b3));
        let hess = [[h11, h12, h13], [h12, h22, h23], [h13, h23, h33]];
        let finite = g.is_finite() && grad.iter().chain(hess.iter().flatten()).all(|v| v.is_finite());
        (finite && w.iter().all(|v| v.is_finite())).then_some(Ev { g, grad, hess, l })
    }

    /// The damped Newton of `smf/two_multiplier.rs`: the point, its evaluation, whether it is
    /// (almost) optimal, and the iterations.
    fn minimise(&self, warm: [f64; 3]) -> (Pt, Ev, bool, u32) {
        let centre = Pt::start([1.0 / 3.0; 3]);
        let (mut pt, mut iters, mut restarted) = (Pt::start(warm), 0u32, false);
        let mut ev = self.eval(pt.tau()).unwrap_or_else(|| {
            pt = centre;
            self.eval(pt.tau()).expect("g at the centre of the simplex")
        });
        loop {
            let (hs, gr) = (ev.hess, [ev.grad[0] - ev.grad[2], ev.grad[1] - ev.grad[2]]);
            let h01 = hs[0][1] - hs[0][2] - hs[1][2] + hs[2][2];
            let hr = [[hs[0][0] - 2.0 * hs[0][2] + hs[2][2], h01], [h01, hs[1][1] - 2.0 * hs[1][2] + hs[2][2]]];
            let h = [pt.t1 - F, pt.t2 - F, pt.tau()[2]]; // constraint values, h ≥ 0
            // Working set: the active constraints with nonnegative KKT multipliers.
            let mut ws = [h[0] <= 0.0, h[1] <= 0.0, pt.on3];
            loop {
                match active(ws) {
                    (Some(a), Some(b)) => {
                        let (na, nb) = (NORMALS[a], NORMALS[b]);
                        let det = na[0] * nb[1] - nb[0] * na[1];
                        match [(gr[0] * nb[1] - nb[0] * gr[1]) / det, (na[0] * gr[1] - gr[0] * na[1]) / det] {
                            mu if mu[0] >= 0.0 && mu[1] >= 0.0 => return (pt, ev, true, iters),
                            mu => ws[if mu[0] < mu[1] { a } else { b }] = false,
                        }
                    }
                    (Some(a), None) if dot2(gr, NORMALS[a]) < 0.0 => ws[a] = false,
                    _ => break,
                }
            }
            if iters == 0 && !restarted && ((h[0] <= 0.0 && !ws[0]) || (h[1] <= 0.0 && !ws[1])) {
                // The warm start sits on a floor the optimum leaves: restart from the centre.
                restarted = true;
                if let Some(e) = self.eval(centre.tau()).filter(|e| e.g < ev.g) {
                    (pt, ev) = (centre, e);
                    continue;
                }
            }
            // Plain Newton in τ if it reaches a floor or changes τ by less than a factor 2, else in
            // log scale (logit along τ₃ = 0).
            let (t1, t2) = (pt.t1, pt.t2);
            let plain = |d: [f64; 2]| t1 + d[0] <= F || t2 + d[1] <= F || !(d[0] > t1 || d[1] > t2);
            let dt = solve2(regularise(hr), gr);
            let path = match active(ws) {
                (None, _) if pt.on3 && dt[0] + dt[1] >= 0.0 => {
                    // Leaving the edge τ₃ = 0: Newton along its inward normal plus along the edge.
                    let (n, e) = (NORMALS[2], TANGENTS[2]);
                    let sn = -dot2(gr, n) / quad(&hr, n).max(f64::MIN_POSITIVE);
                    let se = if quad(&hr, e) > 0.0 { -dot2(gr, e) / quad(&hr, e) } else { 0.0 };
                    Path::Linear([sn * n[0] + se * e[0], sn * n[1] + se * e[1]])
                }
                (None, _) if plain(dt) => Path::Linear(dt),
                (None, _) => {
                    // Newton in (ln τ₁, ln τ₂): g_s = D gr, H_s = D Hr D + diag(g_s), D = diag(τ).
                    let (gs, off) = ([t1 * gr[0], t2 * gr[1]], t1 * t2 * hr[0][1]);
                    let hs = regularise([[t1 * t1 * hr[0][0] + gs[0], off], [off, t2 * t2 * hr[1][1] + gs[1]]]);
                    let d = solve2(hs, gs);
                    let leaves_down = (h[0] <= 0.0 && d[0] < 0.0) || (h[1] <= 0.0 && d[1] < 0.0);
                    Path::Log(clip(if leaves_down { [-gs[0] / hs[0][0], -gs[1] / hs[1][1]] } else { d }, 20.0))
                }
                (Some(a), None) => {
                    let e = TANGENTS[a];
                    let s = newton1(dot2(gr, e), quad(&hr, e));
                    let (p, ge, i) = (t1 * t2, gr[0] - gr[1], 1 - a.min(1));
                    let ti = [t1, t2][i];
                    match [s * e[0], s * e[1]] {
                        d if plain(d) => Path::Linear(d),
                        _ if a == 2 => {
                            Path::Logit(newton1(ge * p, quad(&hr, e) * p * p + ge * p * (t2 - t1)).clamp(-20.0, 20.0))
                        }
                        _ => {
                            let mut d = [0.0; 2];
                            d[i] = newton1(ti * gr[i], ti * ti * hr[i][i] + ti * gr[i]).clamp(-20.0, 20.0);
                            Path::Log(d)
                        }
                    }
                }
                _ => Path::Log([0.0; 2]),
            };
            let dec = match path {
                Path::Log(d) => -(t1 * gr[0] * d[0] + t2 * gr[1] * d[1]),
                Path::Linear(d) => -dot2(gr, d),
                Path::Logit(ds) => -(gr[0] - gr[1]) * t1 * t2 * ds,
            };
            if dec.is_nan() || iters >= 100 || dec <= TOLERANCE * ev.g.abs() {
                return (pt, ev, dec <= TOLERANCE * ev.g.abs(), iters);
            }
            // A plain step stops at the first floor (or τ₃ = 0) it would cross; Armijo backtracking.
            let alpha = match path {
                Path::Linear(d) => (0..3)
                    .filter(|&i| !ws[i] && dot2(NORMALS[i], d) < 0.0 && h[i] > 0.0)
                    .fold(1.0f64, |a, i| a.min(h[i] / -dot2(NORMALS[i], d))),
                _ => 1.0,
            };
            let accepted = std::iter::successors(Some(alpha), |a| Some(a * 0.5)).take(60).find_map(|a| {
                let trial = path.point(pt, ws, a);
                let bound = ev.g - 1e-4 * a * dec + 4.0 * EPS * ev.g.abs();
                self.eval(trial.tau()).filter(|e| e.g <= bound).map(|e| (trial, e))
            });
            iters += 1;
            let Some((p, e)) = accepted else { return (pt, ev, dec <= 1e-9 * ev.g.abs(), iters) };
            let stalled = ev.g - e.g <= 4.0 * EPS * e.g.abs() && dec <= STALL * e.g.abs();
            (pt, ev) = (p, e);
            if stalled {
                return (pt, ev, true, iters);
            }
        }
    }
}

impl Floor {
    /// The consistency check of `smf/consistency.rs` for the prediction `z = A x̂ + B u`.
    fn consistent(&self, x1: &Mn, z: &Vn, y: &SVector<f64, M>) -> bool {
        let e = y - self.c * z;
        let sym = |m: Mm| (m + m.transpose()) * 0.5;
        let (m1, m2) = (sym(self.c * x1 * self.c.transpose()), sym(self.c * self.q * self.c.transpose()));
        let t = self.tau.map(|v| v.max(1e-6));
        let (mut t, mut previous) = (t.map(|v| v / (t[0] + t[1] + t[2])), f64::NAN);
        for _ in 0..30 {
            let Some(ch) = (m1 * (1.0 / t[0]) + m2 * (1.0 / t[1]) + self.r * (1.0 / t[2])).cholesky() else {
                return true;
            };
            let d = ch.solve(&e);
            let delta = e.dot(&d);
            let h = [m1, m2, self.r].map(|m| d.dot(&(m * d)).max(0.0).sqrt());
            let support = h[0] + h[1] + h[2];
            let g = delta - support;
            if !(g.is_finite() && support.is_finite()) {
                return true;
            } else if g > 1e-7 * (delta.abs() + support) {
                return false;
            } else if (0..3).all(|i| h[i] <= t[i]) || (delta - previous).abs() <= 1e-12 * delta.abs() || support <= 0.0
            {
                return true;
            }
            previous = delta;
            let s = h.map(|v| (v / support).max(1e-9));
            t = s.map(|v| v / (s[0] + s[1] + s[2]));
        }
        true
    }

    fn step(&mut self, u: &SVector<f64, P>, y: &SVector<f64, M>) {
        let x1 = self.a * self.p * self.a.transpose();
        let z = self.a * self.x + self.b * u;
        assert!(self.consistent(&x1, &z, y), "the floor's data are inconsistent");
        let (x1c, qc) = (x1 * self.c.transpose(), self.q * self.c.transpose());
        let pr = Problem { f: self, x1, x1c, qc, cx1c: self.c * x1c, cqc: self.c * qc };
        let (pt, ev, optimal, iters) = pr.minimise(self.tau);
        assert!(optimal, "the floor's Newton did not converge");
        let tau = clamp_tau(pt.tau());
        let l = if tau[2] == 0.0 { Mnm::zeros() } else { ev.l };
        // Certification (`smf/certify.rs`): P = (1 + s) sym(T₁ + T₂ + T₃) + ε I, centre K z + L y.
        let k = Mn::identity() - l * self.c;
        let (na, nb, nc, nl, nk) = (self.a.norm(), self.b.norm(), self.c.norm(), l.norm(), k.norm());
        let (nx1, nq, nr, np, n) = (x1.norm(), self.q.norm(), self.r.norm(), self.p.norm(), N as f64);
        let e_x = gamma(2 * N) * na * na * np;
        let e_k = gamma(M + 1) * (n.sqrt() + nl * nc);
        let (kappa, lin) = (nk + e_k, 2.0 * nk * e_k + e_k * e_k);
        let t1 = k * x1 * k.transpose() * (1.0 / tau[0]);
        let t2 = k * self.q * k.transpose() * (1.0 / tau[1]);
        let mut err = (gamma(2 * N + 2) * nk * nk * nx1 + lin * nx1 + kappa * kappa * e_x) / tau[0];
        err += (gamma(2 * N + 2) * nk * nk * nq + lin * nq) / tau[1];
        let (mut phi, mut nt3) = (t1 + t2, 0.0);
        if tau[2] > 0.0 {
            let t3 = l * self.r * l.transpose() * (1.0 / tau[2]);
            (phi, nt3) = (phi + t3, t3.norm());
            err += gamma(2 * M + 2) * nl * nl * nr / tau[2];
        }
        err += gamma(4) * (t1.norm() + t2.norm() + nt3);
        let phi = (phi + phi.transpose()) * 0.5;
        let nphi = phi.norm();
        let eps2 = 2.0 * err + 2.0 * EPS * nphi;
        let (nz, e_z) = (z.norm(), gamma(N + P) * (na * self.x.norm() + nb * u.norm()));
        let rho = 2.0 * (gamma(N + M + 1) * (nk * nz + nl * y.norm()) + e_k * nz + kappa * e_z);
        let trc = phi.trace() + n * eps2;
        let s = if rho > 0.0 && trc > 0.0 { rho * (n / trc).sqrt() } else { 0.0 };
        let extra = if s > 0.0 { (1.0 + 1.0 / s) * rho * rho } else { 0.0 };
        let absolute = (1.0 + s) * eps2 + extra + 2.0 * EPS * (1.0 + s) * (nphi + n.sqrt() * eps2);
        (self.x, self.p) = (k * z + l * y, phi * (1.0 + s) + Mn::identity() * absolute);
        let radius = self.p.diagonal().map(|v| v.max(0.0).sqrt());
        (self.bounds, self.tau, self.iterations) = ((self.x - radius, self.x + radius), tau, iters);
    }
}

/// The largest entry-wise difference between two (flattened) estimates, relative to their size.
fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let scale = a.iter().fold(0.0f64, |s, v| s.max(v.abs())).max(1e-300);
    a.iter().zip(b).fold(0.0f64, |d, (x, y)| d.max((x - y).abs())) / scale
}

/// The next index of the cycle; `true` when it wrapped (the caller restarts its filter).
fn advance(k: &mut usize, len: usize) -> bool {
    *k = (*k + 1) % len;
    *k == 0
}

/// A column-major slice as a fixed-size matrix.
fn fixed<const R: usize, const C: usize>(m: &[f64]) -> SMatrix<f64, R, C> {
    SMatrix::from_column_slice(m)
}

fn smf_floor(crit: &mut Criterion) {
    // The data of the `n4m3` rows of `benches/estimators.rs`.
    let (a, b, _) = CarrierModel::new(CarrierParams::paper_preset()).unwrap().discretize(1e-3).unwrap().to_dynamic();
    let c = DMatrix::from_fn(M, N, |i, j| if j == N - M + i { 1.0 } else { 0.0 });
    let q = DMatrix::from_diagonal(&DVector::from_vec(vec![1.6e-7, 1e-6, 4e-10, 1e-6]));
    let (r, p0, u) = (DMatrix::identity(M, M) * 2e-5, DMatrix::identity(N, N) * 1e-2, DVector::from_element(P, 0.01));
    let config = models::SimulationConfig {
        x0: DVector::zeros(N),
        inputs: vec![u.clone(); RUN],
        process_noise: models::Noise::ellipsoid_boundary(q.clone()).unwrap(),
        measurement_noise: models::Noise::ellipsoid_boundary(r.clone()).unwrap(),
        seed: 1,
    };
    let run = models::simulate_ltv(&models::ConstantModel::new(a.clone(), b.clone(), c.clone()).unwrap(), &config);
    let dys = run.unwrap().measurements[1..].to_vec();
    let model = StepModel::new(&a, &b, &c);
    let (x0, process_noise, measurement_noise) = (DVector::zeros(N), q.clone(), r.clone());
    let smf0 = SetMembershipFilter::new(Setup { x0, p0: p0.clone(), process_noise, measurement_noise, inputs: P });
    let smf0 = smf0.unwrap();
    let (a_f, b_f, c_f, q_f, r_f) =
        (fixed(a.as_slice()), fixed(b.as_slice()), fixed(c.as_slice()), fixed(q.as_slice()), fixed(r.as_slice()));
    let (x, p, bounds) = (Vn::zeros(), fixed(p0.as_slice()), Default::default());
    let floor0 = Floor { a: a_f, b: b_f, c: c_f, q: q_f, r: r_f, x, p, bounds, tau: [1.0 / 3.0; 3], iterations: 0 };
    let (us, ys): (_, Vec<_>) = (fixed(u.as_slice()), dys.iter().map(|y| fixed(y.as_slice())).collect());

    // Both run the whole run (outside the timing) and agree at every step.
    let (mut smf, mut floor) = (smf0.clone(), floor0.clone());
    let (mut worst, mut ours_iters, mut floor_iters, mut same) = (0.0f64, 0u64, 0u64, 0usize);
    for k in 0..ys.len() {
        let est = smf.step(&model, &u, &dys[k]).unwrap();
        floor.step(&us, &ys[k]);
        let dx = rel_diff(est.center.as_slice(), floor.x.as_slice());
        let dp = rel_diff(est.shape.as_slice(), floor.p.as_slice());
        assert!(dx <= AGREEMENT && dp <= AGREEMENT, "step {k}: centre {dx:e}, shape {dp:e}");
        worst = worst.max(dx).max(dp);
        (ours_iters, floor_iters) =
            (ours_iters + u64::from(est.report.iterations), floor_iters + u64::from(floor.iterations));
        same += usize::from(est.report.iterations == floor.iterations);
    }
    let (steps, mean) = (ys.len(), |i: u64| i as f64 / ys.len() as f64);
    eprintln!(
        "smf_floor: {steps} steps, max relative difference {worst:.2e}; Newton iterations per step: ours {:.4}, floor {:.4} \
         (equal at {same} steps)",
        mean(ours_iters),
        mean(floor_iters),
    );

    let mut group = crit.benchmark_group("smf_floor");
    let mut k = 0;
    smf = smf0.clone();
    group.bench_function("estimators", |b| {
        b.iter(|| {
            if advance(&mut k, dys.len()) {
                smf = smf0.clone();
            }
            black_box(smf.step(&model, &u, &dys[k]).unwrap().center[0])
        })
    });
    // The same filter on the runtime-size kernels (the step before it was compiled per size;
    // the same bits, tested in `crates/estimators/tests/smf_compiled.rs`).
    let mut general0 = smf0.clone();
    general0.use_general_kernels();
    let mut general = general0.clone();
    k = 0;
    group.bench_function("estimators-general", |b| {
        b.iter(|| {
            if advance(&mut k, dys.len()) {
                general = general0.clone();
            }
            black_box(general.step(&model, &u, &dys[k]).unwrap().center[0])
        })
    });
    (k, floor) = (0, floor0.clone());
    group.bench_function("smatrix-floor", |b| {
        b.iter(|| {
            if advance(&mut k, ys.len()) {
                floor = floor0.clone();
            }
            floor.step(&us, &ys[k]);
            black_box(floor.x[0] + floor.bounds.0[0])
        })
    });
    group.finish();
}

criterion_group!(benches, smf_floor);
criterion_main!(benches);
