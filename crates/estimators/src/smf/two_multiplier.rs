//! The exact two-multiplier solver of (29).
//!
//! # Reduction (paper §3, "structure worth knowing")
//!
//! With the free first column of `Π` zero (optimal: the noise sets are symmetric) and
//! `τ₁ + τ₂ + τ₃ = 1` (the optimum uses the whole simplex: scaling `τ` up shrinks `P`),
//! the Schur complement of (28) turns (27) into
//!
//! ```text
//! P_{k+1} ⪰ Φ(L, τ) = K X₁ Kᵀ/τ₁ + K Q Kᵀ/τ₂ + L R Lᵀ/τ₃,   K = I − L C,  X₁ = A P_k Aᵀ   (27')
//!        = K M Kᵀ + L R Lᵀ/τ₃,                                M = X₁/τ₁ + Q/τ₂
//! ```
//!
//! For fixed `τ` the trace-minimising gain is Kalman-like (stationarity `K M Cᵀ = L R/τ₃`):
//!
//! ```text
//! S = τ₃ C M Cᵀ + R = G Gᵀ,   W = M Cᵀ S⁻¹,   L = τ₃ W                                   (G1)
//! P⁺(τ) = Φ(L, τ) = (M⁻¹ + τ₃ Cᵀ R⁻¹ C)⁻¹,   g(τ) = tr P⁺(τ)
//! ```
//!
//! `S` (not `C M Cᵀ + R/τ₃`) keeps everything finite as `τ₃ → 0`; `P⁺` is always evaluated in
//! the Joseph-like sum form `T₁ + T₂ + T₃` (`T₁ = K X₁ Kᵀ/τ₁`, `T₂ = K Q Kᵀ/τ₂`,
//! `T₃ = τ₃ W R Wᵀ`), never as `M − …`, which cancels catastrophically when a multiplier is
//! small and `M` is huge.
//!
//! `g` is convex (partial minimisation over `L` of `tr Φ`, jointly convex in `(L, τ)` on
//! `τ > 0`) and homogeneous of degree −1 on the positive orthant.
//!
//! # Derivatives (on the orthant, then restricted to the simplex)
//!
//! Envelope theorem (`∂tr Φ/∂L = 0` at `L(τ)`):
//!
//! ```text
//! ∂g/∂τ₁ = −tr T₁/τ₁,   ∂g/∂τ₂ = −tr T₂/τ₂,   ∂g/∂τ₃ = −tr(W R Wᵀ)                        (D1)
//! ```
//!
//! Second derivatives: `H = ∂²tr Φ/∂τ² + ∂²tr Φ/∂τ∂L · dL/dτ`. Differentiating the
//! stationarity condition gives `dL/dτⱼ = −aⱼ S̃⁻¹` with `S̃ = S/τ₃` and
//! `a₁ = K X₁ Cᵀ/τ₁²`, `a₂ = K Q Cᵀ/τ₂²`, `a₃ = −L R/τ₃²`, and
//! `∂²tr Φ/∂τᵢ∂L [dL] = 2⟨dL, aᵢ⟩`, hence with `βᵢ = ãᵢ G⁻ᵀ`, `ã₁ = K X₁ Cᵀ/τ₁`,
//! `ã₂ = K Q Cᵀ/τ₂`, `ã₃ = −W R`:
//!
//! ```text
//! H_ii = 2 tr Tᵢ/τᵢ² − 2 τ₃ ⟨βᵢ, βᵢ⟩/τᵢ²      (i = 1, 2)
//! H_12 = −2 τ₃ ⟨β₁, β₂⟩/(τ₁ τ₂),   H_i3 = −2 ⟨βᵢ, β₃⟩/τᵢ                                    (D2)
//! H_33 = 2 tr(W (C P⁺ Cᵀ) Wᵀ) = 2 ⟨W N G⁻ᵀ, W R G⁻ᵀ⟩,   N = C M Cᵀ,  C P⁺ Cᵀ = N S⁻¹ R
//! ```
//!
//! `H_33` is written without the difference `tr(WRWᵀ) − ⟨β₃,β₃⟩` of two `O(1/τ₃)` terms that
//! the generic formula would give, so it stays accurate as `τ₃ → 0`. On the simplex the free
//! coordinates are `(τ₁, τ₂)`, `τ₃ = 1 − τ₁ − τ₂`: reduced gradient `J ∇g`, Hessian `J H Jᵀ`,
//! `J = [[1, 0, −1], [0, 1, −1]]`. A unit test checks (D1), (D2) against finite differences.
//!
//! # Minimisation
//!
//! Damped Newton with an active set on the region `τ₁ ≥ f`, `τ₂ ≥ f`, `τ₃ ≥ 0` with the floor
//! [`TAU_FLOOR`] `f = 10⁻¹²`: `τ₃ = 0` is a genuine feasible edge (the measurement carries no
//! information: `L = 0`, `P⁺ = M`), while `τ₁ → 0` or `τ₂ → 0` are only limits (`M` blows up),
//! reached for example at the vertex `τ = (0, 0, 1)` when `C` is square and invertible and the
//! measurement alone is the best bound (`P⁺ → C⁻¹ R C⁻ᵀ`). Each iteration:
//!
//! 1. the constraints at their bound whose KKT multiplier (`∇g = Σ μᵢ ∇hᵢ`) is nonnegative stay
//!    fixed; at a vertex with both multipliers nonnegative the point is optimal;
//! 2. Newton's step on the remaining free directions, in the coordinates where `g` is close to
//!    quadratic: plain `τ` when the step reaches a floor (`g` is nearly linear towards a floor it
//!    wants: the step is truncated there and snapped onto it) or changes the coordinates by less
//!    than a factor 2; `ln τᵢ` when a coordinate wants to grow by a large factor (`g` behaves like
//!    `a/τᵢ` near a small `τᵢ`, where Newton in `τ` would only gain a factor 1.5 per step); the
//!    logit `ln(τ₁/τ₂)` along the edge `τ₃ = 0`. Hessians in the new coordinates follow by the
//!    chain rule and are shifted to be positive definite if needed;
//! 3. Armijo backtracking on `g` along that path.
//!
//! Stopping ([`UpdateStatus`]):
//!
//! * **Solved** when the Newton decrement `−∇gᵀd ≤ 10⁻¹³ g` (for a quadratic model the gap
//!   `g − g*` is half the decrement, so the objective is within about `10⁻¹³` relative of the
//!   optimum), or at a vertex whose KKT multipliers are both nonnegative;
//! * **AlmostSolved** when the search stalls at the rounding level of `g` with a small
//!   decrement: an accepted step that lowers `g` by at most `4ε g` while the decrement is
//!   `≤ 10⁻¹⁰ g`, or a line search that finds no decrease while it is `≤ 10⁻⁹ g` (the
//!   objective is then within about that relative distance of the optimum). This is the honest
//!   status there: `g` cannot be evaluated accurately enough to confirm `10⁻¹³`, and iterating
//!   on would only reach the iteration limit. The filter accepts it (the published set is
//!   certified from `(L, τ)` regardless, so only optimality is at stake);
//! * **NumericalTrouble** when `g` cannot be evaluated, the decrement is NaN, or the search
//!   stalls farther from the optimum; **IterationLimit** after the iteration limit.
//!
//! Warm start: the previous step's `τ`; if that sits on a
//! floor the new optimum leaves, the search restarts from `(⅓, ⅓, ⅓)` (near a vertex `g` is
//! homogeneous of degree 1 in the small multipliers, not quadratic). Typical counts: 0–1
//! iterations in steady state, 4–5 when `τ` moves far between steps.

use super::gain::GainWork;
use super::kernels::StepFns;
use super::update::{UpdateProblem, UpdateSolution, UpdateSolver, UpdateStatus};
use crate::error::EstimatorError;

/// Lower bound of `τ₁` and `τ₂` (the edges `τ₁ = 0`, `τ₂ = 0` are limits where `M` blows up).
pub const TAU_FLOOR: f64 = 1e-12;

/// Relative Newton decrement below which a search that can no longer make measurable progress
/// ends as [`UpdateStatus::AlmostSolved`] (module documentation, "Minimisation").
const STALL_TOLERANCE: f64 = 1e-10;

/// The exact solver of (29) by minimisation over the two free multipliers (module docs).
#[derive(Debug, Clone)]
pub struct TwoMultiplierSolver {
    work: Option<GainWork>,
    max_iterations: u32,
    tolerance: f64,
    /// Whether the runtime-size kernels are used whatever the size (module `kernels`).
    general: bool,
}

impl Default for TwoMultiplierSolver {
    fn default() -> Self {
        Self::new()
    }
}

/// Where the iterate is: `(τ₁, τ₂)` and whether it sits on the edge `τ₃ = 0`.
#[derive(Debug, Clone, Copy)]
struct Point {
    t1: f64,
    t2: f64,
    on3: bool,
}

impl Point {
    fn tau(&self) -> [f64; 3] {
        [self.t1, self.t2, if self.on3 { 0.0 } else { (1.0 - self.t1 - self.t2).max(0.0) }]
    }
    /// Constraint values `h ≥ 0`: `τ₁ − f`, `τ₂ − f`, `τ₃`.
    fn h(&self) -> [f64; 3] {
        let t = self.tau();
        [self.t1 - TAU_FLOOR, self.t2 - TAU_FLOOR, t[2]]
    }
}

/// Inward normals of the constraints in the free coordinates `(τ₁, τ₂)`.
const NORMALS: [[f64; 2]; 3] = [[1.0, 0.0], [0.0, 1.0], [-1.0, -1.0]];
/// Directions along each edge.
const TANGENTS: [[f64; 2]; 3] = [[0.0, 1.0], [1.0, 0.0], [1.0, -1.0]];

impl TwoMultiplierSolver {
    /// Default settings: at most 100 Newton iterations, decrement tolerance `1e-13` relative.
    pub fn new() -> Self {
        Self { work: None, max_iterations: 100, tolerance: 1e-13, general: false }
    }

    /// Uses the runtime-size kernels from the next solve on (same numbers as those compiled for
    /// the size; for comparisons).
    pub(crate) fn use_general_kernels(&mut self) {
        self.general = true;
        if let Some(w) = &mut self.work {
            w.fns = StepFns::general();
        }
    }

    /// Whether the solves run the kernels compiled for the prepared size.
    pub(crate) fn runs_compiled_kernels(&self) -> bool {
        self.work.as_ref().is_some_and(|w| w.fns.fixed)
    }

    /// Sets the iteration limit (at least 1).
    pub fn with_max_iterations(mut self, n: u32) -> Self {
        self.max_iterations = n.max(1);
        self
    }

    /// The start point: the warm start clamped into the region.
    fn start(warm: [f64; 3]) -> Point {
        let ok = warm.iter().all(|v| v.is_finite() && *v >= 0.0) && warm[0] + warm[1] <= 1.0 + 1e-9;
        let w = if ok { warm } else { [1.0 / 3.0; 3] };
        let t1 = w[0].clamp(TAU_FLOOR, 1.0 - TAU_FLOOR);
        let mut t2 = w[1].max(TAU_FLOOR);
        let on3 = w[2] <= 0.0 || t1 + t2 >= 1.0;
        if on3 {
            t2 = (1.0 - t1).max(TAU_FLOOR);
        }
        Point { t1, t2, on3 }
    }

    fn minimise(&mut self, pr: &UpdateProblem<'_>, warm: [f64; 3]) -> (Point, UpdateStatus, u32) {
        // tidy: invariant — `solve` prepares the work buffers before calling `minimise`.
        let work = self.work.as_mut().expect("prepared");
        let eval = |w: &mut GainWork, p: &Point| w.eval(p.tau(), pr);
        let mut pt = Self::start(warm);
        let mut ev = match eval(work, &pt) {
            Some(e) => e,
            None => {
                pt = Self::start([1.0 / 3.0; 3]);
                match eval(work, &pt) {
                    Some(e) => e,
                    None => return (pt, UpdateStatus::NumericalTrouble, 0),
                }
            }
        };
        let mut iters = 0u32;
        let mut restarted = false;
        loop {
            let hs = &ev.hess;
            let gr = [ev.grad[0] - ev.grad[2], ev.grad[1] - ev.grad[2]];
            let hr = [
                [hs[0][0] - 2.0 * hs[0][2] + hs[2][2], hs[0][1] - hs[0][2] - hs[1][2] + hs[2][2]],
                [0.0, hs[1][1] - 2.0 * hs[1][2] + hs[2][2]],
            ];
            let hr = [hr[0], [hr[0][1], hr[1][1]]];
            // Working set: active constraints with nonnegative multipliers (∇g = Σ μᵢ nᵢ).
            let h = pt.h();
            let mut ws = [h[0] <= 0.0, h[1] <= 0.0, pt.on3];
            loop {
                let act: Vec2Idx = active_pair(&ws);
                match act {
                    Vec2Idx::Two(a, b) => {
                        let (na, nb) = (NORMALS[a], NORMALS[b]);
                        let det = na[0] * nb[1] - nb[0] * na[1];
                        let mu_a = (gr[0] * nb[1] - nb[0] * gr[1]) / det;
                        let mu_b = (na[0] * gr[1] - gr[0] * na[1]) / det;
                        if mu_a >= 0.0 && mu_b >= 0.0 {
                            return (pt, UpdateStatus::Solved, iters);
                        }
                        if mu_a < mu_b {
                            ws[a] = false;
                        } else {
                            ws[b] = false;
                        }
                    }
                    Vec2Idx::One(a) => {
                        let na = NORMALS[a];
                        if gr[0] * na[0] + gr[1] * na[1] < 0.0 {
                            ws[a] = false;
                        } else {
                            break;
                        }
                    }
                    Vec2Idx::None => break,
                }
            }
            if iters == 0 && ((h[0] <= 0.0 && !ws[0]) || (h[1] <= 0.0 && !ws[1])) && !restarted {
                // The warm start sits on a floor the optimum leaves: g is far from quadratic
                // there (homogeneous of degree 1 near a vertex), so restart from the centre.
                restarted = true;
                let centre = Self::start([1.0 / 3.0; 3]);
                if let Some(e) = eval(work, &centre) {
                    if e.g < ev.g {
                        pt = centre;
                        ev = e;
                        continue;
                    }
                }
            }
            // Newton direction on the free subspace, in coordinates where the barrier-like
            // behaviour of g near τ₁ → 0, τ₂ → 0 is mild: log τᵢ for floored coordinates and
            // in the interior, the logit log(τ₁/τ₂) along the edge τ₃ = 0.
            let (t1, t2) = (pt.t1, pt.t2);
            let path = match active_pair(&ws) {
                Vec2Idx::None => {
                    let mut hrr = hr;
                    regularise(&mut hrr);
                    let dt = solve2(&hrr, gr);
                    let crosses = t1 + dt[0] <= TAU_FLOOR || t2 + dt[1] <= TAU_FLOOR;
                    let grows = dt[0] > t1 || dt[1] > t2;
                    if pt.on3 && dt[0] + dt[1] >= 0.0 {
                        // Leaving the edge τ₃ = 0: Newton along the inward normal plus the edge.
                        let n = NORMALS[2];
                        let e = TANGENTS[2];
                        let qn = quad(&hr, n);
                        let qe = quad(&hr, e);
                        let sn = -(gr[0] * n[0] + gr[1] * n[1]) / qn.max(f64::MIN_POSITIVE);
                        let se = if qe > 0.0 { -(gr[0] * e[0] + gr[1] * e[1]) / qe } else { 0.0 };
                        Path::Linear([sn * n[0] + se * e[0], sn * n[1] + se * e[1]])
                    } else if crosses || !grows {
                        // Plain Newton in τ, truncated at a floor it would cross (g is nearly
                        // linear towards a floor it wants to reach).
                        Path::Linear(dt)
                    } else {
                        // A coordinate wants to grow by a large factor (g is barrier-like near
                        // a small τᵢ): Newton in s = (ln τ₁, ln τ₂), where
                        // g_s = D gr, H_s = D Hr D + diag(D gr), D = diag(τ₁, τ₂).
                        let gs = [t1 * gr[0], t2 * gr[1]];
                        let mut hs = [
                            [t1 * t1 * hr[0][0] + gs[0], t1 * t2 * hr[0][1]],
                            [t1 * t2 * hr[0][1], t2 * t2 * hr[1][1] + gs[1]],
                        ];
                        regularise(&mut hs);
                        let mut d = solve2(&hs, gs);
                        // A coordinate leaving its floor must move up.
                        if (h[0] <= 0.0 && d[0] < 0.0) || (h[1] <= 0.0 && d[1] < 0.0) {
                            d = [-gs[0] / hs[0][0], -gs[1] / hs[1][1]];
                        }
                        Path::Log(clip(d, 20.0))
                    }
                }
                Vec2Idx::One(a) => {
                    // Along one edge. Plain 1-D Newton in τ if it reaches a floor or changes
                    // the coordinates by less than a factor 2; otherwise in log / logit scale.
                    let e = TANGENTS[a];
                    let dt = newton1(gr[0] * e[0] + gr[1] * e[1], quad(&hr, e));
                    let d = [dt * e[0], dt * e[1]];
                    let crosses = t1 + d[0] <= TAU_FLOOR || t2 + d[1] <= TAU_FLOOR;
                    let grows = d[0] > t1 || d[1] > t2;
                    if crosses || !grows {
                        Path::Linear(d)
                    } else if a == 2 {
                        // σ = ln(τ₁/τ₂) on τ₁ + τ₂ = 1: dτ₁/dσ = τ₁τ₂, d²τ₁/dσ² = τ₁τ₂(τ₂ − τ₁).
                        let p = t1 * t2;
                        let ge = gr[0] - gr[1];
                        let he = quad(&hr, TANGENTS[2]);
                        let g1 = ge * p;
                        let h1 = he * p * p + ge * p * (t2 - t1);
                        Path::Logit(clip1(newton1(g1, h1), 20.0))
                    } else {
                        // One floor active: the other coordinate in log scale.
                        let i = 1 - a;
                        let ti = if i == 0 { t1 } else { t2 };
                        let g1 = ti * gr[i];
                        let h1 = ti * ti * hr[i][i] + g1;
                        let mut d = [0.0; 2];
                        d[i] = clip1(newton1(g1, h1), 20.0);
                        Path::Log(d)
                    }
                }
                Vec2Idx::Two(..) => Path::Log([0.0; 2]),
            };
            let dec = match path {
                Path::Log(d) => -(t1 * gr[0] * d[0] + t2 * gr[1] * d[1]),
                Path::Linear(d) => -(gr[0] * d[0] + gr[1] * d[1]),
                Path::Logit(ds) => -(gr[0] - gr[1]) * t1 * t2 * ds,
            };
            if dec.is_nan() {
                // The model at this point is broken (a NaN gradient or Hessian entry that
                // escaped the finiteness check through the step computation): not a solution.
                return (pt, UpdateStatus::NumericalTrouble, iters);
            }
            if dec <= self.tolerance * ev.g.abs() {
                return (pt, UpdateStatus::Solved, iters);
            }
            if iters >= self.max_iterations {
                return (pt, UpdateStatus::IterationLimit, iters);
            }
            let mut alpha: f64 = 1.0;
            if let Path::Linear(d) = path {
                // Stop exactly at the first floor or at τ₃ = 0 if the full step crosses it.
                for i in 0..3 {
                    let rate = NORMALS[i][0] * d[0] + NORMALS[i][1] * d[1];
                    if !ws[i] && rate < 0.0 && h[i] > 0.0 {
                        alpha = alpha.min(h[i] / -rate);
                    }
                }
            }
            let mut accepted = None;
            for _ in 0..60 {
                let trial = path.point(&pt, &ws, alpha);
                if let Some(e) = eval(work, &trial) {
                    if e.g <= ev.g - 1e-4 * alpha * dec + 4.0 * f64::EPSILON * ev.g.abs() {
                        accepted = Some((trial, e));
                        break;
                    }
                }
                alpha *= 0.5;
            }
            iters += 1;
            match accepted {
                Some((p, e)) => {
                    let gain = ev.g - e.g;
                    pt = p;
                    ev = e;
                    if gain <= 4.0 * f64::EPSILON * ev.g.abs() && dec <= STALL_TOLERANCE * ev.g.abs() {
                        // No measurable progress: g is at its rounding floor, further steps
                        // cannot certify the 1e-13 test; the decrement still bounds the gap.
                        return (pt, UpdateStatus::AlmostSolved, iters);
                    }
                }
                None => {
                    let status = if dec <= 1e-9 * ev.g.abs() {
                        UpdateStatus::AlmostSolved
                    } else {
                        UpdateStatus::NumericalTrouble
                    };
                    return (pt, status, iters);
                }
            }
        }
    }
}

/// How a step moves from the current point, as a function of the step length `α`.
#[derive(Debug, Clone, Copy)]
enum Path {
    /// `τᵢ ← τᵢ e^{α dᵢ}` (i = 1, 2), clamped at the floor, snapped onto `τ₃ = 0` if crossed.
    Log([f64; 2]),
    /// `τ ← τ + α d` (leaving the edge `τ₃ = 0`), clamped at the floors.
    Linear([f64; 2]),
    /// Along `τ₃ = 0`: `ln(τ₁/τ₂) += α dσ`.
    Logit(f64),
}

impl Path {
    fn point(&self, pt: &Point, ws: &[bool; 3], alpha: f64) -> Point {
        let f = TAU_FLOOR;
        match *self {
            Path::Log(d) => {
                let at = |a: f64| {
                    let t1 = if ws[0] { pt.t1 } else { (pt.t1 * (a * d[0]).exp()).max(f) };
                    let t2 = if ws[1] { pt.t2 } else { (pt.t2 * (a * d[1]).exp()).max(f) };
                    (t1, t2)
                };
                let (t1, t2) = at(alpha);
                if t1 + t2 < 1.0 {
                    return Point { t1, t2, on3: false };
                }
                // Crossed τ₃ = 0: bisect for the crossing and snap onto the edge.
                let (mut lo, mut hi) = (0.0, alpha);
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    let (a, b) = at(mid);
                    if a + b < 1.0 { lo = mid } else { hi = mid }
                }
                let (t1, _) = at(lo);
                let t1 = t1.clamp(f, 1.0 - f);
                Point { t1, t2: (1.0 - t1).max(f), on3: true }
            }
            Path::Linear(d) => {
                // Within a relative 1e-9 of a floor counts as on it (the truncated step lands
                // there up to rounding).
                let snap = |t: f64| if t <= f * (1.0 + 1e-9) { f } else { t };
                let t1 = if ws[0] { pt.t1 } else { snap(pt.t1 + alpha * d[0]) };
                let t2 = if ws[1] { pt.t2 } else { snap(pt.t2 + alpha * d[1]) };
                if t1 + t2 < 1.0 - 1e-15 {
                    Point { t1, t2, on3: false }
                } else {
                    let t1 = t1.min(1.0 - f);
                    Point { t1, t2: (1.0 - t1).max(f), on3: true }
                }
            }
            Path::Logit(ds) => {
                let sigma = (pt.t1 / pt.t2).ln() + alpha * ds;
                let t1 = (1.0 / (1.0 + (-sigma).exp())).clamp(f, 1.0 - f);
                Point { t1, t2: (1.0 - t1).max(f), on3: true }
            }
        }
    }
}

/// `xᵀ H x` for a symmetric 2 × 2 `H`.
fn quad(h: &[[f64; 2]; 2], x: [f64; 2]) -> f64 {
    x[0] * (h[0][0] * x[0] + h[0][1] * x[1]) + x[1] * (h[1][0] * x[0] + h[1][1] * x[1])
}

/// Makes a symmetric 2 × 2 matrix positive definite by shifting its spectrum if needed.
fn regularise(h: &mut [[f64; 2]; 2]) {
    let tr = h[0][0] + h[1][1];
    let det = h[0][0] * h[1][1] - h[0][1] * h[1][0];
    let disc = (0.25 * (h[0][0] - h[1][1]).powi(2) + h[0][1] * h[1][0]).max(0.0).sqrt();
    let lmin = 0.5 * tr - disc;
    let lmax = 0.5 * tr + disc;
    let floor = 1e-10 * lmax.abs().max(f64::MIN_POSITIVE);
    if lmin.is_nan() || lmin <= floor || det.is_nan() || det <= 0.0 {
        let shift = floor - lmin.min(0.0) + lmax.abs() * 1e-3;
        h[0][0] += shift;
        h[1][1] += shift;
    }
}

/// `−H⁻¹ g` for a positive definite 2 × 2 `H`.
fn solve2(h: &[[f64; 2]; 2], g: [f64; 2]) -> [f64; 2] {
    let det = h[0][0] * h[1][1] - h[0][1] * h[1][0];
    [-(h[1][1] * g[0] - h[0][1] * g[1]) / det, -(h[0][0] * g[1] - h[1][0] * g[0]) / det]
}

/// The 1-D Newton step `−g/h`, or a unit step downhill if `h ≤ 0`.
fn newton1(g: f64, h: f64) -> f64 {
    if h > 0.0 { -g / h } else { -g.signum() }
}

fn clip1(d: f64, max: f64) -> f64 {
    d.clamp(-max, max)
}

fn clip(d: [f64; 2], max: f64) -> [f64; 2] {
    let m = d[0].abs().max(d[1].abs());
    if m > max { [d[0] * max / m, d[1] * max / m] } else { d }
}

enum Vec2Idx {
    None,
    One(usize),
    Two(usize, usize),
}

fn active_pair(ws: &[bool; 3]) -> Vec2Idx {
    let mut first = None;
    for i in 0..3 {
        if ws[i] {
            match first {
                None => first = Some(i),
                Some(a) => return Vec2Idx::Two(a, i),
            }
        }
    }
    match first {
        Some(a) => Vec2Idx::One(a),
        None => Vec2Idx::None,
    }
}

impl UpdateSolver for TwoMultiplierSolver {
    fn name(&self) -> &str {
        "two-multiplier"
    }

    fn prepare(&mut self, n: usize, m: usize) -> Result<(), EstimatorError> {
        let mut work = GainWork::new(n, m);
        if self.general {
            work.fns = StepFns::general();
        }
        self.work = Some(work);
        Ok(())
    }

    /// `L` is computed by (G1) for the returned `τ`.
    fn gain_is_closed_form(&self) -> bool {
        true
    }

    /// The same settings, without the workspace (prepared for its own size).
    fn for_fewer_outputs(&self) -> Option<Self> {
        Some(Self { work: None, max_iterations: self.max_iterations, tolerance: self.tolerance, general: self.general })
    }

    fn solve(
        &mut self,
        pr: &UpdateProblem<'_>,
        warm: [f64; 3],
        out: &mut UpdateSolution,
    ) -> Result<(), EstimatorError> {
        let (n, m) = (pr.a.nrows(), pr.c.nrows());
        if self.work.as_ref().is_none_or(|w| w.l.shape() != (n, m)) {
            self.prepare(n, m)?;
        }
        // tidy: invariant — prepared just above.
        self.work.as_mut().expect("prepared").load(pr.x1, pr.q, pr.c);
        let (pt, status, iters) = self.minimise(pr, warm);
        let tau = pt.tau();
        // tidy: invariant — prepared just above.
        let work = self.work.as_mut().expect("prepared");
        out.iterations = iters;
        out.tau = tau;
        // The last evaluation of the minimisation is usually at the returned τ: its gain stands.
        if work.has_gain_for(tau) || work.gain(tau, pr.c, pr.r) {
            out.l.copy_from(&work.l);
            out.status = status;
        } else {
            out.status = UpdateStatus::NumericalTrouble;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    fn case() -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
        let a = DMatrix::from_row_slice(3, 3, &[0.9, 0.2, -0.1, 0.0, 1.1, 0.3, 0.2, -0.4, 0.7]);
        let p = DMatrix::from_row_slice(3, 3, &[2.0, 0.3, 0.1, 0.3, 1.0, -0.2, 0.1, -0.2, 0.5]);
        let x1 = &a * &p * a.transpose();
        let q = DMatrix::from_row_slice(3, 3, &[0.3, 0.05, 0.0, 0.05, 0.2, 0.01, 0.0, 0.01, 0.1]);
        let c = DMatrix::from_row_slice(2, 3, &[1.0, 0.0, 0.5, 0.0, 1.0, -0.3]);
        let r = DMatrix::from_row_slice(2, 2, &[0.2, 0.03, 0.03, 0.1]);
        let _ = &q;
        (x1, q, c, r)
    }

    /// `g` on the orthant by the information form, independently of the code under test.
    fn g_ref(tau: [f64; 3], x1: &DMatrix<f64>, q: &DMatrix<f64>, c: &DMatrix<f64>, r: &DMatrix<f64>) -> f64 {
        let m = x1 / tau[0] + q / tau[1];
        let info = m.try_inverse().unwrap() + c.transpose() * r.clone().try_inverse().unwrap() * c * tau[2];
        info.try_inverse().unwrap().trace()
    }

    #[test]
    fn gradient_and_hessian_match_finite_differences() {
        let (x1, q, c, r) = case();
        let (identity, zero) = (DMatrix::identity(3, 3), nalgebra::DVector::zeros(3));
        let pr = UpdateProblem { a: &identity, c: &c, q: &q, r: &r, p: &identity, x_hat: &zero, x1: &x1 };
        let mut w = GainWork::new(3, 2);
        w.load(&x1, &q, &c);
        for tau in [[0.3, 0.5, 0.2], [0.2, 0.1, 0.7], [0.6, 0.35, 0.05], [0.4, 0.3, 1e-7]] {
            let e = w.eval(tau, &pr).unwrap();
            assert!((e.g - g_ref(tau, &x1, &q, &c, &r)).abs() < 1e-10 * e.g);
            for i in 0..3 {
                let hstep = 1e-6 * tau[i].max(1e-4);
                let mut tp = tau;
                tp[i] += hstep;
                let mut tm = tau;
                tm[i] -= hstep;
                let fd = (g_ref(tp, &x1, &q, &c, &r) - g_ref(tm, &x1, &q, &c, &r)) / (2.0 * hstep);
                assert!((fd - e.grad[i]).abs() < 1e-6 * (1.0 + fd.abs()), "grad {i} {tau:?}: {fd} vs {}", e.grad[i]);
                let ep = w.eval(tp, &pr).unwrap();
                let em = w.eval(tm, &pr).unwrap();
                for j in 0..3 {
                    let fd = (ep.grad[j] - em.grad[j]) / (2.0 * hstep);
                    let an = e.hess[i][j];
                    assert!((fd - an).abs() < 1e-5 * (1.0 + fd.abs()), "hess {i}{j} {tau:?}: {fd} vs {an}");
                }
            }
        }
    }

    #[test]
    fn optimum_satisfies_the_stationarity_check() {
        let (x1, q, c, r) = case();
        let a = DMatrix::identity(3, 3);
        let p = DMatrix::identity(3, 3);
        let xh = nalgebra::DVector::zeros(3);
        let pr = UpdateProblem { a: &a, c: &c, q: &q, r: &r, p: &p, x_hat: &xh, x1: &x1 };
        let mut s = TwoMultiplierSolver::new();
        s.prepare(3, 2).unwrap();
        let mut out = UpdateSolution::new(3, 2);
        s.solve(&pr, [1.0 / 3.0; 3], &mut out).unwrap();
        assert_eq!(out.status, UpdateStatus::Solved);
        let tau = out.tau;
        let w = s.work.as_mut().unwrap();
        let e = w.eval(tau, &pr).unwrap();
        // tr(Tᵢ)/τᵢ = tr P for every active multiplier: ∂g/∂τᵢ = −g.
        for i in 0..3 {
            assert!((e.grad[i] + e.g).abs() < 1e-8 * e.g, "{i}: {:?} {}", e.grad, e.g);
        }
        // A coarse grid never does better.
        for i in 1..40 {
            for j in 1..(40 - i) {
                let t = [i as f64 / 40.0, j as f64 / 40.0, 1.0 - (i + j) as f64 / 40.0];
                assert!(g_ref(t, &x1, &q, &c, &r) >= e.g * (1.0 - 1e-12));
            }
        }
    }
}
