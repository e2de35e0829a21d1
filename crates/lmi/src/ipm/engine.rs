//! The interior-point iteration (homogeneous self-dual embedding, NT direction, Mehrotra
//! predictor–corrector). See the module documentation of [`crate::ipm`] for the equations.

use std::time::Instant;

use faer::dyn_stack::MemStack;

use crate::solver::{SdpSolution, SolveStart, SolveStatus, SolverSettings};

use super::dense::{self, view};
use super::eig::{max_step, max_step_coarse, max_step_pencil, sym_eig};
use super::workspace::{BlockWs, Ent, SchurKind, Workspace};

/// `out ← Σᵢ coefᵢ Fᵢ` in one block (dense symmetric, or the diagonal of a nonnegative block),
/// over the nonzero entries.
#[inline(always)]
fn combine(nz: (&[usize], &[usize], &[f64], &[usize]), coef: &[f64], out: &mut [f64]) {
    let (p1s, p2s, vs, start) = nz;
    out.fill(0.0);
    for (i, &ci) in coef.iter().enumerate() {
        if ci == 0.0 {
            continue;
        }
        let r = start[i]..start[i + 1];
        for ((&p1, &p2), &v) in p1s[r.clone()].iter().zip(&p2s[r.clone()]).zip(&vs[r]) {
            let cv = ci * v;
            out[p1] += cv;
            if p2 != p1 {
                out[p2] += cv;
            }
        }
    }
}

/// `tr[i] += tr(Fᵢ G)` for `i = 0..=m` in one block (`G` dense symmetric, or a diagonal).
#[inline(always)]
fn traces(blk: &BlockWs, g: &[f64], tr: &mut [f64]) {
    for (i, t) in tr.iter_mut().enumerate() {
        let r = blk.nz_start[i]..blk.nz_start[i + 1];
        let mut s = 0.0;
        for ((&p1, &p2), &v) in blk.nz_p1[r.clone()].iter().zip(&blk.nz_p2[r.clone()]).zip(&blk.nz_v[r]) {
            s += v * if p1 == p2 { g[p1] } else { g[p1] + g[p2] };
        }
        *t += s;
    }
}

/// Schur contributions of one dense block from all pairs of groups at once: every `Fᵢ` is a sum
/// over its groups `e_c wᵀ + w e_cᵀ`, and with `y_h = D w_h`, `Z = Wᵀ D W`,
/// `tr(Fᵢ D Fⱼ D) = 2 Σ_{g ∈ i} Σ_{h ∈ j} (y_g[c_h] y_h[c_g] + Z_gh D_{c_g c_h})`. Only the groups
/// with a nonzero entry take part (`ag_*`).
#[inline(always)]
fn assemble_grouped(blk: &mut BlockWs, mhat: &mut [f64], mp: usize) {
    let n = blk.n;
    let na = blk.ag_row.len();
    let d = &blk.d;
    // y_a = D w_a (columns of gy), then Yᵀ (rows of yt, length na).
    for a in 0..na {
        let y = &mut blk.gy[a * n..a * n + n];
        y.fill(0.0);
        for e in blk.ag_ent[a]..blk.ag_ent[a + 1] {
            let (o, v) = (blk.ag_idx[e], blk.ag_val[e]);
            for (yy, dd) in y.iter_mut().zip(&d[o * n..o * n + n]) {
                *yy += v * dd;
            }
        }
        for o in 0..n {
            blk.yt[o * na + a] = y[o];
        }
    }
    // Row a of Z: Σ_{e ∈ a} v_e Yᵀ[o_e, :] (only the groups of matrices up to a's are used).
    for a in 0..na {
        let hend = blk.ag_start[blk.ag_mat[a] + 1];
        let z = &mut blk.zg[a * na..a * na + hend];
        z.fill(0.0);
        for e in blk.ag_ent[a]..blk.ag_ent[a + 1] {
            let (o, v) = (blk.ag_idx[e], blk.ag_val[e]);
            for (zz, yy) in z.iter_mut().zip(&blk.yt[o * na..o * na + hend]) {
                *zz += v * yy;
            }
        }
    }
    for a in 0..na {
        let i = blk.ag_mat[a];
        let c = blk.ag_row[a];
        let ya = &blk.gy[a * n..a * n + n];
        let dc = &d[c * n..c * n + n];
        let ytc = &blk.yt[c * na..c * na + na];
        let z = &blk.zg[a * na..a * na + na];
        let mut h0 = 0;
        while h0 < blk.ag_start[i + 1] {
            let j = blk.ag_mat[h0];
            let h1 = blk.ag_start[j + 1];
            let mut s = 0.0;
            for ((&ch, &y), &zz) in blk.ag_row[h0..h1].iter().zip(&ytc[h0..h1]).zip(&z[h0..h1]) {
                s += ya[ch] * y + zz * dc[ch];
            }
            mhat[i + j * mp] += 2.0 * s;
            h0 = h1;
        }
    }
}

/// Schur contributions `Σ_r Fᵢ[r] d_r² Fⱼ[r]` of a nonnegative block (NT and HKM alike).
#[inline(always)]
fn assemble_diag(blk: &BlockWs, mhat: &mut [f64], fbuf: &mut [f64], mp: usize) {
    let w = &mut fbuf[..blk.n];
    w.fill(0.0); // the dense path of another block may have left values here
    for j in 0..mp {
        let rj = blk.range(j);
        if rj.is_empty() {
            continue;
        }
        for k in rj.clone() {
            let r = blk.ents[k].row;
            w[r] = blk.val[k] * blk.d[r] * blk.d[r];
        }
        for i in j..mp {
            let mut s = 0.0;
            for k in blk.range(i) {
                s += blk.val[k] * w[blk.ents[k].row];
            }
            mhat[i + j * mp] += s;
        }
        for k in rj {
            w[blk.ents[k].row] = 0.0;
        }
    }
}

/// Diagonal (NT = HKM) scaling of a nonnegative block; `false` if an iterate is not positive.
#[inline(always)]
fn scale_diag(blk: &mut BlockWs) -> bool {
    for i in 0..blk.n {
        let (x, y) = (blk.x[i], blk.y[i]);
        if !(x > 0.0 && y > 0.0) {
            return false;
        }
        blk.lam[i] = (x * y).sqrt();
        blk.d[i] = (y / x).sqrt();
        blk.t[i] = blk.d[i].sqrt();
        blk.drd[i] = blk.d[i] * blk.d[i] * blk.rz[i];
    }
    true
}

/// HKM version of [`assemble_grouped`]: with `ξ_a = X⁻¹ w_a`, `η_a = Y w_a`,
/// `Zˣ = Wᵀ X⁻¹ W`, `Zʸ = Wᵀ Y W`, a pair of active groups `a ∈ i`, `h ∈ j` adds
/// `ξ_h[c_a] η_a[c_h] + ξ_a[c_h] η_h[c_a] + Zˣ_ah Y[c_a, c_h] + Zʸ_ah X⁻¹[c_a, c_h]` to `M̂ᵢⱼ`.
#[inline(always)]
fn assemble_grouped_hkm(blk: &mut BlockWs, mhat: &mut [f64], mp: usize) {
    let n = blk.n;
    let na = blk.ag_row.len();
    let (yy, xi) = (&blk.y, &blk.xinv);
    for a in 0..na {
        let xa = &mut blk.gy[a * n..a * n + n];
        let ya = &mut blk.gy2[a * n..a * n + n];
        xa.fill(0.0);
        ya.fill(0.0);
        for e in blk.ag_ent[a]..blk.ag_ent[a + 1] {
            let (o, v) = (blk.ag_idx[e], blk.ag_val[e]);
            for ((p, q), (s, t)) in
                xa.iter_mut().zip(ya.iter_mut()).zip(xi[o * n..o * n + n].iter().zip(&yy[o * n..o * n + n]))
            {
                *p += v * s;
                *q += v * t;
            }
        }
        for o in 0..n {
            blk.yt[o * na + a] = xa[o];
            blk.yt2[o * na + a] = ya[o];
        }
    }
    for a in 0..na {
        let hend = blk.ag_start[blk.ag_mat[a] + 1];
        let zx = &mut blk.zg[a * na..a * na + hend];
        let zy = &mut blk.zg2[a * na..a * na + hend];
        zx.fill(0.0);
        zy.fill(0.0);
        for e in blk.ag_ent[a]..blk.ag_ent[a + 1] {
            let (o, v) = (blk.ag_idx[e], blk.ag_val[e]);
            for ((p, q), (s, t)) in zx
                .iter_mut()
                .zip(zy.iter_mut())
                .zip(blk.yt[o * na..o * na + hend].iter().zip(&blk.yt2[o * na..o * na + hend]))
            {
                *p += v * s;
                *q += v * t;
            }
        }
    }
    for a in 0..na {
        let i = blk.ag_mat[a];
        let c = blk.ag_row[a];
        let (xa, ya) = (&blk.gy[a * n..a * n + n], &blk.gy2[a * n..a * n + n]);
        let (yc, xic) = (&yy[c * n..c * n + n], &xi[c * n..c * n + n]);
        let (xtc, ytc) = (&blk.yt[c * na..c * na + na], &blk.yt2[c * na..c * na + na]);
        let (zx, zy) = (&blk.zg[a * na..a * na + na], &blk.zg2[a * na..a * na + na]);
        let mut h0 = 0;
        while h0 < blk.ag_start[i + 1] {
            let j = blk.ag_mat[h0];
            let h1 = blk.ag_start[j + 1];
            let mut s = 0.0;
            for h in h0..h1 {
                let ch = blk.ag_row[h];
                s += xtc[h] * ya[ch] + xa[ch] * ytc[h] + zx[h] * yc[ch] + zy[h] * xic[ch];
            }
            mhat[i + j * mp] += s;
            h0 = h1;
        }
    }
}

/// Frobenius norm of `Fᵢ` (all blocks).
fn matrix_norm(ws: &Workspace, i: usize) -> f64 {
    let mut s = 0.0;
    for blk in &ws.blocks {
        for k in blk.range(i) {
            let e = blk.ents[k];
            let f = if e.row == e.col { 1.0 } else { 2.0 };
            s += f * blk.val[k] * blk.val[k];
        }
    }
    s.sqrt()
}

/// `λ` of the warm start: the weight of the previous solution against a multiple of the identity
/// (the carrier's filter steps took 4.0 iterations on average with 0.97 and 0.99, 5.0 with 0.9,
/// against 11–13 from the default start; `docs/sdp.md` §3.7).
pub(crate) const WARM_WEIGHT: f64 = 0.99;

/// Which scaled complementarity right-hand side `w_s` a Newton solve uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Ws {
    /// `w_s = −λ` (affine scaling), with the shortcut `T w_s Tᵀ = −Y`.
    Affine,
    /// `w_s` as stored in each block's `ws`.
    Given,
    /// `w_s = 0` (refinement steps).
    Zero,
}

/// Why the iteration stopped early.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Stop {
    Trouble,
    IterLimit,
    TimeLimit,
}

/// Scalar state of the embedding and the quantities of the last residual evaluation.
#[derive(Debug, Default, Clone, Copy)]
struct State {
    tau: f64,
    kappa: f64,
    mu: f64,
    rtau: f64,
    // Per-iteration scalars of the Newton system.
    /// `β − (b + c)ᵀ M⁻¹ (b − c)`, the Schur complement of the `τ` row without `κ/τ`.
    den0: f64,
    dtau: f64,
    dkappa: f64,
    dtau_a: f64,
    dkappa_a: f64,
    // Reporting.
    pobj: f64,
    dobj: f64,
    pres: f64,
    dres: f64,
    gap_abs: f64,
    gap_rel: f64,
    /// `‖A*(Y)‖ / tr(F₀Y)` if `tr(F₀Y) > 0`, else `∞`.
    pinf: f64,
    /// `‖A(x) − X‖ / (−cᵀx)` if `cᵀx < 0`, else `∞`.
    dinf: f64,
    norm_f0: f64,
    norm_c: f64,
}

impl Workspace {
    /// Runs the method on the loaded values and writes the outcome into `sol`.
    #[inline(always)]
    pub(crate) fn run(
        &mut self,
        settings: &SolverSettings,
        start: Instant,
        sol: &mut SdpSolution,
        stack: &mut MemStack,
    ) {
        let warm = self.warm_wanted && self.has_warm;
        self.has_warm = false;
        let mut used = 0u32;
        if warm {
            let (status, st, iterations) = self.attempt(settings, start, stack, true, settings.max_iterations);
            used = iterations;
            // A certificate or a solution passes the same tests as from a cold start; anything
            // else (a relaxed outcome, a stall) is repeated cold with what is left of the
            // iteration budget and the time limit. With nothing left, the warm outcome stands.
            let definite =
                matches!(status, SolveStatus::Solved | SolveStatus::PrimalInfeasible | SolveStatus::DualInfeasible);
            let out_of_time = settings.time_limit.is_some_and(|limit| limit <= start.elapsed());
            if definite || out_of_time || used >= settings.max_iterations {
                self.finish(status, &st, used, SolveStart::Warm, sol);
                sol.solve_time = start.elapsed();
                return;
            }
        }
        let (status, st, iterations) = self.attempt(settings, start, stack, false, settings.max_iterations - used);
        let how = if warm { SolveStart::ColdAfterWarm } else { SolveStart::Cold };
        self.finish(status, &st, used + iterations, how, sol);
        sol.solve_time = start.elapsed();
    }

    /// One run of the method from the default start, or from the warm point
    /// ([`Workspace::warm_point`]), with at most `max_iterations` iterations; returns the
    /// outcome, the final state and the iterations.
    #[inline(always)]
    fn attempt(
        &mut self,
        settings: &SolverSettings,
        start: Instant,
        stack: &mut MemStack,
        warm: bool,
        max_iterations: u32,
    ) -> (SolveStatus, State, u32) {
        let mut st = State { tau: 1.0, kappa: 1.0, ..State::default() };
        st.norm_f0 = self.norm_f0();
        st.norm_c = dense::norm2(&self.c).sqrt();
        let mut iterations = 0u32;
        self.precise = false;
        self.hkm_on = self.hkm;
        let status = if self.initialize(stack) {
            if warm {
                st.kappa = self.warm_point();
            }
            self.iterate(settings, start, max_iterations, &mut st, &mut iterations, stack)
        } else {
            SolveStatus::NumericalTrouble
        };
        (status, st, iterations)
    }

    /// Writes the outcome and keeps a solved iterate, divided by `τ`, for the next warm start.
    fn finish(&mut self, status: SolveStatus, st: &State, iterations: u32, how: SolveStart, sol: &mut SdpSolution) {
        if matches!(status, SolveStatus::Solved | SolveStatus::AlmostSolved) && st.tau > 0.0 {
            let inv = 1.0 / st.tau;
            for (w, x) in self.warm_xv.iter_mut().zip(&self.x) {
                *w = x * inv;
            }
            for blk in &mut self.blocks {
                for (w, x) in blk.warm_x.iter_mut().zip(&blk.x) {
                    *w = x * inv;
                }
                for (w, y) in blk.warm_y.iter_mut().zip(&blk.y) {
                    *w = y * inv;
                }
            }
            self.has_warm = true;
        }
        self.write_solution(status, st, iterations, sol);
        sol.start = how;
    }

    #[inline(always)]
    fn iterate(
        &mut self,
        settings: &SolverSettings,
        start: Instant,
        max_iterations: u32,
        st: &mut State,
        iterations: &mut u32,
        stack: &mut MemStack,
    ) -> SolveStatus {
        let strict = Tols::new(settings, 1.0);
        let relaxed = Tols::new(settings, settings.reduced_tol_factor);
        let mut best_merit = f64::INFINITY;
        let mut best_iter = 0u32;
        let stop = loop {
            self.residuals(st);
            if settings.verbose {
                eprintln!(
                    "faer-ipm {:3}  pobj {:+.9e}  dobj {:+.9e}  pres {:.2e}  dres {:.2e}  gap {:.2e}  tau {:.2e}  kappa {:.2e}  mu {:.2e}",
                    iterations, st.pobj, st.dobj, st.pres, st.dres, st.gap_rel, st.tau, st.kappa, st.mu
                );
            }
            if let Some(s) = classify(st, &strict, false) {
                return s;
            }
            let merit = merit(st, &strict);
            if merit < best_merit {
                best_merit = merit;
                best_iter = *iterations;
                self.save_best(st);
            } else if (*iterations >= best_iter + STALL_ITERATIONS && best_merit <= settings.reduced_tol_factor)
                || *iterations >= best_iter + 4 * STALL_ITERATIONS
            {
                // No progress for a while after reaching the relaxed tolerances: stalled.
                if settings.verbose {
                    eprintln!("faer-ipm: no progress since iteration {best_iter}");
                }
                break Stop::Trouble;
            }
            if *iterations >= max_iterations {
                break Stop::IterLimit;
            }
            if settings.time_limit.is_some_and(|limit| limit < start.elapsed()) {
                break Stop::TimeLimit;
            }
            let mut result = None;
            if self.hkm_on {
                // HKM: Cholesky factors only. Any breakdown falls back to NT for the rest of the
                // solve (below, from the same iterate).
                if self.scaling_hkm(stack) {
                    self.assemble_schur_hkm();
                    if self.factor_schur(stack) {
                        result = self.step(st);
                    }
                }
                if result.is_none() || result == Some(NEED_PRECISION) {
                    if !(st.tau > 0.0 && st.kappa > 0.0) {
                        // The failed step was already taken (τ or κ left the cone): as in NT.
                        if settings.verbose {
                            eprintln!("faer-ipm: no valid search direction");
                        }
                        break Stop::Trouble;
                    }
                    if settings.verbose {
                        eprintln!("faer-ipm: HKM direction failed, NT from here");
                    }
                    self.hkm_on = false;
                    result = None;
                }
            }
            if !self.hkm_on {
                if !self.scaling(stack) {
                    if settings.verbose {
                        eprintln!("faer-ipm: an iterate is not numerically positive definite");
                    }
                    break Stop::Trouble;
                }
                self.assemble_schur();
                let factored = if self.precise { self.factor_qr(stack) } else { self.factor_schur(stack) };
                if !factored {
                    if settings.verbose {
                        eprintln!("faer-ipm: the Schur matrix could not be factorised");
                    }
                    break Stop::Trouble;
                }
                result = self.step(st);
            }
            if result == Some(NEED_PRECISION) {
                // The normal equations lost too much accuracy: switch to the QR-based factor for
                // the rest of this solve and redo the step.
                if settings.verbose {
                    eprintln!("faer-ipm: switching to the QR-based Schur factor");
                }
                self.precise = true;
                result = if self.factor_qr(stack) { self.step(st) } else { None };
            }
            let Some(alpha) = result else {
                if settings.verbose {
                    eprintln!("faer-ipm: no valid search direction");
                }
                break Stop::Trouble;
            };
            *iterations += 1;
            if alpha < 1e-10 {
                if settings.verbose {
                    eprintln!("faer-ipm: step {alpha:e} too short");
                }
                self.residuals(st);
                break Stop::Trouble;
            }
        };
        // Fall back to the best iterate seen, then test it with the relaxed tolerances.
        if best_merit.is_finite() && best_merit < merit(st, &strict) {
            self.restore_best(st);
            self.residuals(st);
        }
        if let Some(s) = classify(st, &relaxed, true) {
            return s;
        }
        match stop {
            Stop::Trouble => SolveStatus::NumericalTrouble,
            Stop::IterLimit => SolveStatus::IterationLimit,
            Stop::TimeLimit => SolveStatus::TimeLimit,
        }
    }

    fn save_best(&mut self, st: &State) {
        self.best_x.copy_from_slice(&self.x);
        self.best_tk = (st.tau, st.kappa);
        for blk in &mut self.blocks {
            blk.best_x.copy_from_slice(&blk.x);
            blk.best_y.copy_from_slice(&blk.y);
        }
    }

    fn restore_best(&mut self, st: &mut State) {
        self.x.copy_from_slice(&self.best_x);
        (st.tau, st.kappa) = self.best_tk;
        for blk in &mut self.blocks {
            blk.x.copy_from_slice(&blk.best_x);
            blk.y.copy_from_slice(&blk.best_y);
        }
    }

    fn norm_f0(&self) -> f64 {
        let mut s = 0.0;
        for blk in &self.blocks {
            for k in blk.range(0) {
                let e = blk.ents[k];
                let f = if e.row == e.col { 1.0 } else { 2.0 };
                s += f * blk.val[k] * blk.val[k];
            }
        }
        s.sqrt()
    }

    /// Starting point (as in SDPT3): `x = 0`, `X = ξI`, `Y = ηI` with
    /// `ξ = max(10, √ν, ‖F₀‖, maxᵢ ‖Fᵢ‖)` and `η = max(10, √ν, ν maxᵢ (1 + |cᵢ|)/(1 + ‖Fᵢ‖))`;
    /// `τ = κ = 1`.
    fn initialize(&mut self, _stack: &mut MemStack) -> bool {
        let m = self.m;
        let mut fnorm = matrix_norm(self, 0);
        let mut ratio: f64 = 0.0;
        for i in 1..=m {
            let nf = matrix_norm(self, i);
            fnorm = fnorm.max(nf);
            ratio = ratio.max((1.0 + self.c[i - 1].abs()) / (1.0 + nf));
        }
        let root = self.nu.sqrt();
        let xi = 10f64.max(root).max(fnorm);
        let eta = 10f64.max(root).max(self.nu * ratio);
        self.x.fill(0.0);
        for blk in &mut self.blocks {
            blk.x.fill(0.0);
            blk.y.fill(0.0);
            for i in 0..blk.n {
                let k = blk.diag(i);
                blk.x[k] = xi;
                blk.y[k] = eta;
            }
        }
        true
    }

    /// The warm starting point (Skajaa, Andersen and Ye, for the homogeneous embedding), from the
    /// stored solution `(x_w, X_w, Y_w)` of the previous solve: `x = λ x_w`,
    /// `X = λ X_w + (1 − λ) ξ_w I`, `Y = λ Y_w + (1 − λ) η_w I`, `τ = 1`, with `λ` =
    /// [`WARM_WEIGHT`] and `ξ_w`, `η_w` the mean eigenvalues of `X_w`, `Y_w` (`tr/ν`: the default
    /// start's `ξ`, `η` can be orders of magnitude larger than the solution, which would undo the
    /// warm start). Returns `κ = ⟨X, Y⟩/ν`, so that `τκ` is the start's `μ`.
    fn warm_point(&mut self) -> f64 {
        let lam = WARM_WEIGHT;
        let (mut tx, mut ty) = (0.0, 0.0);
        for blk in &self.blocks {
            tx += blk.trace(&blk.warm_x);
            ty += blk.trace(&blk.warm_y);
        }
        // A stored solution has positive traces; keep the default start's shift otherwise.
        let shift = |t: f64, cold: f64| if t > 0.0 && t.is_finite() { t } else { cold };
        for (x, w) in self.x.iter_mut().zip(&self.warm_xv) {
            *x = lam * w;
        }
        let mut xy = 0.0;
        for blk in &mut self.blocks {
            // The default start is a multiple of the identity: read its scale before overwriting.
            let (xi, eta) = (blk.x[blk.diag(0)], blk.y[blk.diag(0)]);
            let (xs, ys) = ((1.0 - lam) * shift(tx / self.nu, xi), (1.0 - lam) * shift(ty / self.nu, eta));
            for (x, w) in blk.x.iter_mut().zip(&blk.warm_x) {
                *x = lam * w;
            }
            for (y, w) in blk.y.iter_mut().zip(&blk.warm_y) {
                *y = lam * w;
            }
            for i in 0..blk.n {
                let k = blk.diag(i);
                blk.x[k] += xs;
                blk.y[k] += ys;
            }
            xy += dense::dot(&blk.x, &blk.y);
        }
        xy / self.nu
    }

    /// Residuals, objectives and termination measures of the current iterate.
    #[inline(always)]
    fn residuals(&mut self, st: &mut State) {
        let m = self.m;
        // r_z = A(x) − X − F₀τ ; A*(Y).
        self.coef[0] = -st.tau;
        self.coef[1..].copy_from_slice(&self.x);
        self.tr.fill(0.0);
        let mut rz2 = 0.0;
        let mut xy = 0.0;
        let (mut xx, mut yy) = (0.0, 0.0);
        for blk in &mut self.blocks {
            combine((&blk.nz_p1, &blk.nz_p2, &blk.nz_v, &blk.nz_start), &self.coef, &mut blk.rz);
            for (r, x) in blk.rz.iter_mut().zip(&blk.x) {
                *r -= x;
            }
            rz2 += dense::norm2(&blk.rz);
            xy += dense::dot(&blk.x, &blk.y);
            xx += dense::norm2(&blk.x);
            yy += dense::norm2(&blk.y);
        }
        for blk in &mut self.blocks {
            traces(blk, &blk.y, &mut self.tr);
        }
        let mut rx2 = 0.0;
        let mut aty2 = 0.0;
        let mut cx = 0.0;
        for i in 0..m {
            self.rx[i] = -self.tr[i + 1] + self.c[i] * st.tau;
            rx2 += self.rx[i] * self.rx[i];
            aty2 += self.tr[i + 1] * self.tr[i + 1];
            cx += self.c[i] * self.x[i];
        }
        st.rtau = -cx + self.tr[0] - st.kappa;
        st.mu = (xy + st.tau * st.kappa) / (self.nu + 1.0);
        st.pobj = cx / st.tau;
        st.dobj = self.tr[0] / st.tau;
        // Relative residuals as in Clarabel: scaled by the norms of the data and of the point.
        let nx = dense::norm2(&self.x).sqrt() / st.tau;
        st.pres = rz2.sqrt() / st.tau / (st.norm_f0 + nx + xx.sqrt() / st.tau).max(1.0);
        st.dres = rx2.sqrt() / st.tau / (st.norm_c + nx + yy.sqrt() / st.tau).max(1.0);
        st.gap_abs = (st.pobj - st.dobj).abs();
        // The crate's relative gap (`SdpSolution::relative_gap`).
        st.gap_rel = st.gap_abs / (1.0 + st.pobj.abs() + st.dobj.abs());
        st.pinf = if self.tr[0] > 0.0 { aty2.sqrt() / self.tr[0] } else { f64::INFINITY };
        st.dinf = if cx < 0.0 {
            // ‖A(x) − X‖ (only needed for a candidate improving ray).
            self.coef[0] = 0.0;
            let mut dinf_num = 0.0;
            for blk in &mut self.blocks {
                combine((&blk.nz_p1, &blk.nz_p2, &blk.nz_v, &blk.nz_start), &self.coef, &mut blk.tmp);
                for (t, x) in blk.tmp.iter_mut().zip(&blk.x) {
                    *t -= x;
                }
                dinf_num += dense::norm2(&blk.tmp);
            }
            dinf_num.sqrt() / (-cx)
        } else {
            f64::INFINITY
        };
    }

    /// NT scaling of every block; `false` if an iterate is not numerically positive definite.
    #[inline(always)]
    fn scaling(&mut self, stack: &mut MemStack) -> bool {
        for blk in &mut self.blocks {
            let n = blk.n;
            if !blk.psd {
                if !scale_diag(blk) {
                    return false;
                }
                continue;
            }
            blk.l1.copy_from_slice(&blk.x);
            if !dense::cholesky(&mut blk.l1, n, stack) {
                return false;
            }
            blk.l2.copy_from_slice(&blk.y);
            if !dense::cholesky(&mut blk.l2, n, stack) {
                return false;
            }
            // K = L₂ᵀ L₁, K Kᵀ = L₂ᵀ X L₂ = U Λ² Uᵀ.
            dense::mul(&mut blk.k, n, view(&blk.l2, n).transpose(), view(&blk.l1, n));
            dense::mul(&mut blk.tmp, n, view(&blk.k, n), view(&blk.k, n).transpose());
            if !sym_eig(&mut blk.tmp, n, &mut blk.ev, &mut blk.ee, true) {
                return false;
            }
            for i in 0..n {
                if blk.ev[i].is_nan() || blk.ev[i] <= 0.0 {
                    return false;
                }
                blk.lam[i] = blk.ev[i].sqrt();
                blk.lis[i] = 1.0 / blk.lam[i].sqrt();
            }
            // T = L₂ U Λ^{-1/2}, D = T Tᵀ.
            dense::mul(&mut blk.t, n, view(&blk.l2, n), view(&blk.tmp, n));
            for j in 0..n {
                let s = 1.0 / blk.lam[j].sqrt();
                blk.t[j * n..j * n + n].iter_mut().for_each(|v| *v *= s);
            }
            dense::mul(&mut blk.d, n, view(&blk.t, n), view(&blk.t, n).transpose());
            dense::symmetrize(&mut blk.d, n);
            dense::mul(&mut blk.tmp, n, view(&blk.rz, n), view(&blk.d, n));
            dense::mul(&mut blk.drd, n, view(&blk.d, n), view(&blk.tmp, n));
            dense::symmetrize(&mut blk.drd, n);
        }
        true
    }

    /// HKM scaling of every block (`docs/sdp.md` §3.6): Cholesky factors `X = L₁L₁ᵀ`,
    /// `Y = L₂L₂ᵀ`, their inverses (`l1`, `l2`), `X⁻¹` and `sym(Y r_z X⁻¹)` (`drd`); `false` if
    /// an iterate is not numerically positive definite.
    #[inline(always)]
    fn scaling_hkm(&mut self, stack: &mut MemStack) -> bool {
        for blk in &mut self.blocks {
            let n = blk.n;
            if !blk.psd {
                if !scale_diag(blk) {
                    return false;
                }
                continue;
            }
            blk.k.copy_from_slice(&blk.x);
            if !dense::cholesky(&mut blk.k, n, stack) {
                return false;
            }
            dense::invert_lower(&blk.k, &mut blk.l1, n);
            blk.k.copy_from_slice(&blk.y);
            if !dense::cholesky(&mut blk.k, n, stack) {
                return false;
            }
            dense::invert_lower(&blk.k, &mut blk.l2, n);
            dense::mul(&mut blk.xinv, n, view(&blk.l1, n).transpose(), view(&blk.l1, n));
            dense::symmetrize(&mut blk.xinv, n);
            dense::mul(&mut blk.k, n, view(&blk.rz, n), view(&blk.xinv, n));
            dense::mul(&mut blk.drd, n, view(&blk.y, n), view(&blk.k, n));
            dense::symmetrize(&mut blk.drd, n);
            if !blk.xinv.iter().chain(&blk.l2).all(|v| v.is_finite()) {
                return false;
            }
        }
        true
    }

    /// HKM Schur matrix `M̂ᵢⱼ = tr(Fᵢ Y Fⱼ X⁻¹)` for `0 ≤ j ≤ i ≤ m` (symmetric in `i, j`), from
    /// the groups of the entries: every `Fᵢ` is a sum over its groups `e_c wᵀ + w e_cᵀ`, and with
    /// `ξ_g = X⁻¹ w_g`, `η_g = Y w_g`, a pair of groups `h ∈ i`, `g ∈ j` adds
    /// `ξ_g[c_h] η_h[c_g] + ξ_h[c_g] η_g[c_h] + (w_hᵀξ_g) Y[c_h, c_g] + (w_hᵀη_g) X⁻¹[c_h, c_g]`.
    #[inline(always)]
    fn assemble_schur_hkm(&mut self) {
        let mp = self.m + 1;
        self.mhat.fill(0.0);
        for blk in &mut self.blocks {
            let n = blk.n;
            if !blk.psd {
                assemble_diag(blk, &mut self.mhat, &mut self.fbuf, mp);
                continue;
            }
            if blk.grouped {
                assemble_grouped_hkm(blk, &mut self.mhat, mp);
                continue;
            }
            let (y, xi) = (&blk.y, &blk.xinv);
            for g in 0..blk.grp_row.len() {
                let xg = &mut blk.gy[g * n..g * n + n];
                let yg = &mut blk.gy2[g * n..g * n + n];
                xg.fill(0.0);
                yg.fill(0.0);
                for e in blk.grp_ent_start[g]..blk.grp_ent_start[g + 1] {
                    let (o, v) = (blk.gw_idx[e], blk.gw_val[e]);
                    for ((a, b), (xx, yy)) in
                        xg.iter_mut().zip(yg.iter_mut()).zip(xi[o * n..o * n + n].iter().zip(&y[o * n..o * n + n]))
                    {
                        *a += v * xx;
                        *b += v * yy;
                    }
                }
            }
            let (gx, gy) = (&blk.gy, &blk.gy2);
            for j in 0..mp {
                if matches!(blk.kind[j], SchurKind::Dense | SchurKind::RankUpdate) {
                    // Many groups (a dense Fⱼ): Y Fⱼ X⁻¹ by two products, then the traces.
                    let f = &mut self.fbuf[..n * n];
                    f.fill(0.0);
                    for k in blk.range(j) {
                        let Ent { row, col } = blk.ents[k];
                        f[row + col * n] = blk.val[k];
                        f[col + row * n] = blk.val[k];
                    }
                    dense::mul(&mut blk.tmp, n, view(f, n), view(xi, n));
                    dense::mul(&mut blk.tmp2, n, view(y, n), view(&blk.tmp, n));
                    let g = &blk.tmp2;
                    for i in j..mp {
                        let mut s = 0.0;
                        for k in blk.range(i) {
                            let Ent { row, col } = blk.ents[k];
                            s += blk.val[k]
                                * if row == col { g[row + row * n] } else { g[row + col * n] + g[col + row * n] };
                        }
                        self.mhat[i + j * mp] += s;
                    }
                    continue;
                }
                for g in blk.grp_start[j]..blk.grp_start[j + 1] {
                    let cg = blk.grp_row[g];
                    let (xg, yg) = (&gx[g * n..g * n + n], &gy[g * n..g * n + n]);
                    let (ycg, xcg) = (&y[cg * n..cg * n + n], &xi[cg * n..cg * n + n]);
                    for i in j..mp {
                        let mut s = 0.0;
                        for h in blk.grp_start[i]..blk.grp_start[i + 1] {
                            let ch = blk.grp_row[h];
                            let mut t = 0.0;
                            let mut u = 0.0;
                            for e in blk.grp_ent_start[h]..blk.grp_ent_start[h + 1] {
                                let (o, v) = (blk.gw_idx[e], blk.gw_val[e]);
                                t += v * xg[o];
                                u += v * yg[o];
                            }
                            s += xg[ch] * gy[h * n + cg] + gx[h * n + cg] * yg[ch] + t * ycg[ch] + u * xcg[ch];
                        }
                        self.mhat[i + j * mp] += s;
                    }
                }
            }
        }
    }

    /// `M̂ᵢⱼ = tr(Fᵢ D Fⱼ D)` for `0 ≤ j ≤ i ≤ m` (lower triangle, column-major `(m+1)²`).
    #[inline(always)]
    fn assemble_schur(&mut self) {
        let mp = self.m + 1;
        self.mhat.fill(0.0);
        for blk in &mut self.blocks {
            let n = blk.n;
            if !blk.psd {
                assemble_diag(blk, &mut self.mhat, &mut self.fbuf, mp);
                continue;
            }
            let d = &blk.d;
            if blk.grouped {
                assemble_grouped(blk, &mut self.mhat, mp);
                continue;
            }
            if blk.lr_first < mp {
                // y_g = D w_g for every group of the matrices the low-rank columns meet.
                for g in blk.grp_start[blk.lr_first]..blk.grp_start[mp] {
                    let y = &mut blk.gy[g * n..g * n + n];
                    y.fill(0.0);
                    for e in blk.grp_ent_start[g]..blk.grp_ent_start[g + 1] {
                        let (o, v) = (blk.gw_idx[e], blk.gw_val[e]);
                        for (yy, dd) in y.iter_mut().zip(&d[o * n..o * n + n]) {
                            *yy += v * dd;
                        }
                    }
                }
            }
            for j in 0..mp {
                match blk.kind[j] {
                    SchurKind::Empty => {}
                    SchurKind::LowRank => {
                        let gj = blk.grp_start[j]..blk.grp_start[j + 1];
                        for i in j..mp {
                            let mut s = 0.0;
                            for g in blk.grp_start[i]..blk.grp_start[i + 1] {
                                let c = blk.grp_row[g];
                                let yg = &blk.gy[g * n..g * n + n];
                                let wi = &blk.gw_idx[blk.grp_ent_start[g]..blk.grp_ent_start[g + 1]];
                                let wv = &blk.gw_val[blk.grp_ent_start[g]..blk.grp_ent_start[g + 1]];
                                let dc = &d[c * n..c * n + n];
                                for h in gj.clone() {
                                    let dh = blk.grp_row[h];
                                    let yh = &blk.gy[h * n..h * n + n];
                                    let mut dot = 0.0;
                                    for (&o, &v) in wi.iter().zip(wv) {
                                        dot += v * yh[o];
                                    }
                                    s += yg[dh] * yh[c] + dot * dc[dh];
                                }
                            }
                            self.mhat[i + j * mp] += 2.0 * s;
                        }
                    }
                    SchurKind::Pairwise => {
                        let rj = blk.range(j);
                        for i in j..mp {
                            let mut s = 0.0;
                            for k in blk.range(i) {
                                let Ent { row: a, col: b } = blk.ents[k];
                                let da = &d[a * n..a * n + n];
                                let db = &d[b * n..b * n + n];
                                let mut t = 0.0;
                                for l in rj.clone() {
                                    let Ent { row: c, col: dd } = blk.ents[l];
                                    t += blk.sval[l] * (db[c] * da[dd] + db[dd] * da[c]);
                                }
                                s += blk.sval[k] * t;
                            }
                            self.mhat[i + j * mp] += s;
                        }
                    }
                    SchurKind::Dense | SchurKind::RankUpdate => {
                        if blk.kind[j] == SchurKind::Dense {
                            let f = &mut self.fbuf[..n * n];
                            f.fill(0.0);
                            for k in blk.range(j) {
                                let Ent { row, col } = blk.ents[k];
                                f[row + col * n] = blk.val[k];
                                f[col + row * n] = blk.val[k];
                            }
                            dense::mul(&mut blk.tmp, n, view(f, n), view(d, n));
                            dense::mul(&mut blk.tmp2, n, view(d, n), view(&blk.tmp, n));
                        } else {
                            // Σ over groups of d_c wᵀ + w d_cᵀ, upper triangle only (entries are
                            // stored with row ≤ col), then mirrored.
                            let g = &mut blk.tmp2[..n * n];
                            g.fill(0.0);
                            for grp in blk.grp_start[j]..blk.grp_start[j + 1] {
                                let c = blk.grp_row[grp];
                                let w = &mut blk.wv[..n];
                                w.fill(0.0);
                                for &k in &blk.grp_ents[blk.grp_ent_start[grp]..blk.grp_ent_start[grp + 1]] {
                                    let Ent { row: a, col: b } = blk.ents[k];
                                    let (other, v) = if a == b {
                                        (a, 0.5 * blk.val[k])
                                    } else {
                                        (if a == c { b } else { a }, blk.val[k])
                                    };
                                    for (x, y) in w.iter_mut().zip(&d[other * n..other * n + n]) {
                                        *x += v * y;
                                    }
                                }
                                let dc = &d[c * n..c * n + n];
                                for (q, gq) in g.chunks_exact_mut(n).enumerate() {
                                    let (u, z) = (w[q], dc[q]);
                                    for ((x, y), ww) in gq[..=q].iter_mut().zip(dc).zip(w.iter()) {
                                        *x += y * u + ww * z;
                                    }
                                }
                            }
                            for q in 0..n {
                                for r in q + 1..n {
                                    g[r + q * n] = g[q + r * n];
                                }
                            }
                        }
                        let g = &blk.tmp2;
                        for i in j..mp {
                            let mut s = 0.0;
                            for k in blk.range(i) {
                                let Ent { row, col } = blk.ents[k];
                                s += blk.val[k]
                                    * if row == col { g[row + row * n] } else { g[row + col * n] + g[col + row * n] };
                            }
                            self.mhat[i + j * mp] += s;
                        }
                    }
                }
            }
        }
    }

    /// Cholesky of the `m × m` Schur matrix, with a tiny diagonal shift on failure.
    #[inline(always)]
    fn factor_schur(&mut self, stack: &mut MemStack) -> bool {
        let m = self.m;
        let mp = m + 1;
        if m == 0 {
            return true;
        }
        let mut maxdiag: f64 = 0.0;
        for i in 0..m {
            maxdiag = maxdiag.max(self.mhat[(i + 1) * (mp + 1)]);
        }
        for reg in [0.0, 1e-13, 1e-10] {
            for j in 0..m {
                for i in j..m {
                    self.lfac[i + j * m] = self.mhat[(i + 1) + (j + 1) * mp];
                }
                self.lfac[j + j * m] += reg * maxdiag.max(1e-300);
            }
            if dense::cholesky(&mut self.lfac, m, stack) {
                return true;
            }
        }
        false
    }

    /// Factor `Rᵀ` of `M = RᵀR` from a Householder QR of the scaled constraint matrix
    /// `[svec(TᵀFᵢT)]ᵢ` (condition number `√cond(M)`), stored like the Cholesky factor.
    fn factor_qr(&mut self, stack: &mut MemStack) -> bool {
        let m = self.m;
        let rows = self.ls_rows;
        if m == 0 {
            return true;
        }
        self.ls.fill(0.0);
        let mut off = 0;
        for blk in &mut self.blocks {
            let n = blk.n;
            if !blk.psd {
                for i in 1..=m {
                    let col = &mut self.ls[(i - 1) * rows + off..(i - 1) * rows + off + n];
                    for k in blk.range(i) {
                        let r = blk.ents[k].row;
                        col[r] += blk.val[k] * blk.d[r];
                    }
                }
                off += n;
                continue;
            }
            // Rows of T, contiguous.
            for a in 0..n {
                for p in 0..n {
                    blk.tmp2[a * n + p] = blk.t[a + p * n];
                }
            }
            let len = n * (n + 1) / 2;
            for i in 1..=m {
                let col = &mut self.ls[(i - 1) * rows + off..(i - 1) * rows + off + len];
                for k in blk.range(i) {
                    let Ent { row: a, col: b } = blk.ents[k];
                    let v = blk.val[k];
                    let ta = &blk.tmp2[a * n..a * n + n];
                    let tb = &blk.tmp2[b * n..b * n + n];
                    let mut idx = 0;
                    for q in 0..n {
                        for p in q..n {
                            let x = if a == b { ta[p] * ta[q] } else { ta[p] * tb[q] + tb[p] * ta[q] };
                            col[idx] += v * x * if p == q { 1.0 } else { std::f64::consts::SQRT_2 };
                            idx += 1;
                        }
                    }
                }
            }
            off += len;
        }
        dense::qr(&mut self.ls, rows, m, &mut self.qcoef, self.qr_bs, stack);
        let mut rmax: f64 = 0.0;
        for j in 0..m {
            rmax = rmax.max(self.ls[j + j * rows].abs());
        }
        for j in 0..m {
            let d = self.ls[j + j * rows];
            if !d.is_finite() || d.abs() <= 1e-15 * rmax {
                return false;
            }
            for i in j..m {
                self.lfac[i + j * m] = self.ls[j + i * rows];
            }
        }
        true
    }

    /// One predictor–corrector step; returns the step length taken, or `None` on breakdown.
    #[inline(always)]
    fn step(&mut self, st: &mut State) -> Option<f64> {
        let m = self.m;
        for i in 0..m {
            let b = self.mhat[i + 1];
            self.cb[i] = self.c[i] + b;
            self.q[i] = b - self.c[i];
        }
        dense::cholesky_solve(&self.lfac, m, &mut self.q);
        // β − (b + c)ᵀq = ‖Tᵀ(F₀ − A(q))T‖², computed in that form (no cancellation).
        self.coef[0] = 1.0;
        for i in 0..m {
            self.coef[i + 1] = -self.q[i];
        }
        st.den0 = 0.0;
        for blk in &mut self.blocks {
            let n = blk.n;
            combine((&blk.nz_p1, &blk.nz_p2, &blk.nz_v, &blk.nz_start), &self.coef, &mut blk.tmp2);
            if blk.psd && self.hkm_on {
                // HKM: ⟨H, sym(Y H X⁻¹)⟩ = ‖L₁⁻¹ H L₂‖² (`l1 = L₁⁻¹`, `Y = L₂L₂ᵀ`) = ⟨H Y, X⁻¹ H⟩.
                dense::mul(&mut blk.tmp, n, view(&blk.tmp2, n), view(&blk.y, n));
                dense::mul(&mut blk.g, n, view(&blk.xinv, n), view(&blk.tmp2, n));
                st.den0 += dense::dot(&blk.tmp, &blk.g);
            } else if blk.psd {
                dense::congruence(&mut blk.g, &mut blk.tmp, &blk.t, &blk.tmp2, n, true);
                st.den0 += dense::norm2(&blk.g);
            } else {
                for i in 0..n {
                    let v = blk.d[i] * blk.tmp2[i];
                    st.den0 += v * v;
                }
            }
        }
        // Predictor (affine scaling): w_s = −Λ.
        for blk in &mut self.blocks {
            let n = blk.n;
            if blk.psd && self.hkm_on {
                // HKM keeps `w_s` unscaled: the affine right-hand side is `−Y`.
                for (w, y) in blk.ws.iter_mut().zip(&blk.y) {
                    *w = -y;
                }
            } else if blk.psd {
                blk.ws.fill(0.0);
                for i in 0..n {
                    blk.ws[i + i * n] = -blk.lam[i];
                }
            } else {
                for i in 0..n {
                    blk.ws[i] = -blk.lam[i];
                }
            }
        }
        let dk = -st.tau * st.kappa;
        self.direction(st, 1.0, dk, Ws::Affine, false)?;
        st.dtau_a = st.dtau;
        st.dkappa_a = st.dkappa;
        for blk in &mut self.blocks {
            blk.dxs_a.copy_from_slice(&blk.dxs);
            blk.dys_a.copy_from_slice(&blk.dys);
        }
        let alpha_a = self.max_step(st, 1.0, true)?;
        let sigma = (1.0 - alpha_a).powi(3).clamp(0.0, 1.0);
        let smu = sigma * st.mu;
        // Corrector: λ ∘ (Δx̃ + Δỹ) = −λ∘λ + σμI − Δx̃ₐ∘Δỹₐ.
        for blk in &mut self.blocks {
            let n = blk.n;
            if blk.psd && self.hkm_on {
                // HKM: (Y + ΔY)(X + ΔX) = σμI linearised with the predictor's second-order
                // term, times X⁻¹: ΔY = σμX⁻¹ − Y − sym(ΔYₐ ΔXₐ X⁻¹) − sym(Y ΔX X⁻¹).
                dense::mul(&mut blk.k, n, view(&blk.dxs_a, n), view(&blk.xinv, n));
                dense::mul(&mut blk.tmp, n, view(&blk.dys_a, n), view(&blk.k, n));
                dense::symmetrize(&mut blk.tmp, n);
                for ((w, t), (xi, y)) in blk.ws.iter_mut().zip(&blk.tmp).zip(blk.xinv.iter().zip(&blk.y)) {
                    *w = smu * xi - y - t;
                }
            } else if blk.psd {
                dense::mul(&mut blk.tmp, n, view(&blk.dxs_a, n), view(&blk.dys_a, n));
                for j in 0..n {
                    for i in 0..n {
                        let mut r = -0.5 * (blk.tmp[i + j * n] + blk.tmp[j + i * n]);
                        if i == j {
                            r += smu - blk.lam[i] * blk.lam[i];
                        }
                        blk.ws[i + j * n] = 2.0 * r / (blk.lam[i] + blk.lam[j]);
                    }
                }
            } else {
                for i in 0..n {
                    let r = -blk.lam[i] * blk.lam[i] + smu - blk.dxs_a[i] * blk.dys_a[i];
                    blk.ws[i] = r / blk.lam[i];
                }
            }
        }
        let dk = -st.tau * st.kappa + smu - st.dtau_a * st.dkappa_a;
        self.direction(st, 1.0 - sigma, dk, Ws::Given, true)?;
        if !self.precise && self.loss > PRECISION_LOSS {
            return Some(NEED_PRECISION);
        }
        let alpha = (STEP_FRACTION * self.max_step(st, 1.0 / STEP_FRACTION, false)?).min(1.0);
        // Update: X += α ΔX (ΔX = E), Y += α T Δỹ Tᵀ.
        for i in 0..m {
            self.x[i] += alpha * self.dx[i];
        }
        for blk in &mut self.blocks {
            for (x, e) in blk.x.iter_mut().zip(&blk.e) {
                *x += alpha * e;
            }
            for (y, dy) in blk.y.iter_mut().zip(&blk.dy) {
                *y += alpha * dy;
            }
        }
        st.tau += alpha * st.dtau;
        st.kappa += alpha * st.dkappa;
        if !(st.tau > 0.0 && st.kappa > 0.0) {
            return None;
        }
        Some(alpha)
    }

    /// Computes a search direction for `d_x = −η r_x`, `d_z = −η r_z`, `d_τ = −η r_τ`, the
    /// scaled complementarity `w_s` (`ws`) and `d_κ`. The final (corrector) direction also gets
    /// `ΔY` and, when the equations `(1)` and `(3)` it should satisfy are off by more than a
    /// small fraction of their right-hand side (ill-conditioned Schur matrix near the end), one
    /// step of iterative refinement on the full Newton system.
    #[inline(always)]
    fn direction(&mut self, st: &mut State, eta: f64, dkappa: f64, ws: Ws, last: bool) -> Option<()> {
        let m = self.m;
        for i in 0..m {
            self.rhs[i] = -eta * self.rx[i];
        }
        let dtau_rhs = -eta * st.rtau;
        let (mut dt, mut dk) = self.kkt_solve(st, eta, dtau_rhs, dkappa, ws, last)?;
        if last {
            // Residuals of (1) −A*(ΔY) + cΔτ = d_x and (3) −cᵀΔx + tr(F₀ΔY) − Δκ = d_τ.
            self.tr.fill(0.0);
            for blk in &self.blocks {
                traces(blk, &blk.dy, &mut self.tr);
            }
            let mut e1 = 0.0;
            let mut r1 = 0.0;
            let mut cdx = 0.0;
            for i in 0..m {
                let r = self.rhs[i] + self.tr[i + 1] - self.c[i] * dt;
                r1 += self.rhs[i] * self.rhs[i];
                self.rhs[i] = r;
                e1 += r * r;
                cdx += self.c[i] * self.dx[i];
            }
            let e3 = dtau_rhs + cdx - self.tr[0] + dk;
            self.loss = if r1 > 0.0 { e1 / r1 } else { 0.0 };
            if e1 > 1e-14 * r1 || e3.abs() > 1e-7 * dtau_rhs.abs() {
                self.dx2.copy_from_slice(&self.dx);
                for blk in &mut self.blocks {
                    blk.e2.copy_from_slice(&blk.e);
                    blk.dxs2.copy_from_slice(&blk.dxs);
                    blk.dys2.copy_from_slice(&blk.dys);
                    blk.dy2.copy_from_slice(&blk.dy);
                }
                let (dt2, dk2) = self.kkt_solve(st, 0.0, e3, 0.0, Ws::Zero, true)?;
                dt += dt2;
                dk += dk2;
                for (a, b) in self.dx.iter_mut().zip(&self.dx2) {
                    *a += b;
                }
                for blk in &mut self.blocks {
                    for (a, b) in blk.e.iter_mut().zip(&blk.e2) {
                        *a += b;
                    }
                    for (a, b) in blk.dxs.iter_mut().zip(&blk.dxs2) {
                        *a += b;
                    }
                    for (a, b) in blk.dys.iter_mut().zip(&blk.dys2) {
                        *a += b;
                    }
                    for (a, b) in blk.dy.iter_mut().zip(&blk.dy2) {
                        *a += b;
                    }
                }
            }
        }
        st.dtau = dt;
        st.dkappa = dk;
        Some(())
    }

    /// One solve of the Newton system with `d_x` in `rhs`, `d_z = −η r_z`, `d_τ`, `w_s` as
    /// selected by `ws`, and `d_κ`. Writes `Δx` (`dx`), `ΔX` (`e`), `Δx̃`, `Δỹ` and, if `with_dy`,
    /// `ΔY`; returns `(Δτ, Δκ)`.
    #[inline(always)]
    fn kkt_solve(
        &mut self,
        st: &State,
        eta: f64,
        dtau_rhs: f64,
        dkappa: f64,
        ws: Ws,
        with_dy: bool,
    ) -> Option<(f64, f64)> {
        let m = self.m;
        self.tr.fill(0.0);
        for blk in &mut self.blocks {
            let n = blk.n;
            // G = T w_s Tᵀ + D d_z D.
            match ws {
                Ws::Zero => blk.g.fill(0.0),
                Ws::Given if blk.psd && self.hkm_on => {
                    for (g, (w, r)) in blk.g.iter_mut().zip(blk.ws.iter().zip(&blk.drd)) {
                        *g = w - eta * r;
                    }
                }
                Ws::Affine if blk.psd => {
                    for (g, (y, r)) in blk.g.iter_mut().zip(blk.y.iter().zip(&blk.drd)) {
                        *g = -y - eta * r;
                    }
                }
                _ if !blk.psd => {
                    for i in 0..n {
                        blk.g[i] = blk.d[i] * blk.ws[i] - eta * blk.drd[i];
                    }
                }
                _ => {
                    dense::congruence(&mut blk.g, &mut blk.tmp, &blk.t, &blk.ws, n, false);
                    for (g, r) in blk.g.iter_mut().zip(&blk.drd) {
                        *g -= eta * r;
                    }
                }
            }
            traces(blk, &blk.g, &mut self.tr);
        }
        for i in 0..m {
            self.p[i] = self.rhs[i] + self.tr[i + 1];
        }
        let g0 = self.tr[0];
        dense::cholesky_solve(&self.lfac, m, &mut self.p);
        let cbp = dense::dot(&self.cb, &self.p);
        let num = dtau_rhs + cbp - g0 + dkappa / st.tau;
        let den = st.den0 + st.kappa / st.tau;
        if den.is_nan() || den <= 0.0 || !num.is_finite() {
            return None;
        }
        let dtau = num / den;
        let dkap = (dkappa - st.kappa * dtau) / st.tau;
        for i in 0..m {
            self.dx[i] = self.p[i] + self.q[i] * dtau;
        }
        self.coef[0] = -dtau;
        self.coef[1..].copy_from_slice(&self.dx);
        for blk in &mut self.blocks {
            let n = blk.n;
            combine((&blk.nz_p1, &blk.nz_p2, &blk.nz_v, &blk.nz_start), &self.coef, &mut blk.e);
            if eta != 0.0 {
                for (e, r) in blk.e.iter_mut().zip(&blk.rz) {
                    *e += eta * r;
                }
            }
            if blk.psd && self.hkm_on {
                // HKM, unscaled: Δx̃ = ΔX, Δỹ = ΔY = w_s − sym(Y ΔX X⁻¹).
                blk.dxs.copy_from_slice(&blk.e);
                dense::mul(&mut blk.k, n, view(&blk.e, n), view(&blk.xinv, n));
                dense::mul(&mut blk.tmp, n, view(&blk.y, n), view(&blk.k, n));
                dense::symmetrize(&mut blk.tmp, n);
                if ws == Ws::Zero {
                    for (dy, t) in blk.dys.iter_mut().zip(&blk.tmp) {
                        *dy = -t;
                    }
                } else {
                    for (dy, (w, t)) in blk.dys.iter_mut().zip(blk.ws.iter().zip(&blk.tmp)) {
                        *dy = w - t;
                    }
                }
                if with_dy {
                    blk.dy.copy_from_slice(&blk.dys);
                }
                continue;
            }
            if blk.psd {
                dense::congruence(&mut blk.dxs, &mut blk.tmp, &blk.t, &blk.e, n, true);
            } else {
                for i in 0..n {
                    blk.dxs[i] = blk.d[i] * blk.e[i];
                }
            }
            if ws == Ws::Zero {
                for (dy, dx) in blk.dys.iter_mut().zip(&blk.dxs) {
                    *dy = -dx;
                }
            } else {
                for (dy, (w, dx)) in blk.dys.iter_mut().zip(blk.ws.iter().zip(&blk.dxs)) {
                    *dy = w - dx;
                }
            }
            if with_dy {
                if blk.psd {
                    dense::congruence(&mut blk.dy, &mut blk.tmp, &blk.t, &blk.dys, n, false);
                } else {
                    for i in 0..n {
                        blk.dy[i] = blk.d[i] * blk.dys[i];
                    }
                }
            }
        }
        Some((dtau, dkap))
    }

    /// Largest `α` keeping `Λ + αΔx̃`, `Λ + αΔỹ`, `τ + αΔτ`, `κ + αΔκ` nonnegative.
    /// With `coarse`, dense blocks use a few Cholesky tests instead of an eigenvalue bracket.
    #[inline(always)]
    fn max_step(&mut self, st: &State, cap: f64, coarse: bool) -> Option<f64> {
        let mut alpha = cap;
        if st.dtau < 0.0 {
            alpha = alpha.min(-st.tau / st.dtau);
        }
        if st.dkappa < 0.0 {
            alpha = alpha.min(-st.kappa / st.dkappa);
        }
        for blk in &mut self.blocks {
            let n = blk.n;
            for primal in [true, false] {
                let dir = if primal { &blk.dxs } else { &blk.dys };
                if blk.psd && self.hkm_on {
                    // Cholesky tests of X + αΔX (Y + αΔY) directly; the corrector's step to
                    // within HKM_STEP_RTOL.
                    let base = if primal { &blk.x } else { &blk.y };
                    alpha = if coarse {
                        max_step_pencil(base, dir, &mut blk.tmp2, n, alpha, PREDICTOR_HALVINGS, f64::INFINITY)
                    } else {
                        max_step_pencil(base, dir, &mut blk.tmp2, n, alpha, 0, HKM_STEP_RTOL)
                    };
                } else if blk.psd {
                    for j in 0..n {
                        let sj = blk.lis[j];
                        for i in j..n {
                            blk.tmp[i + j * n] = dir[i + j * n] * sj * blk.lis[i];
                        }
                    }
                    alpha = if coarse {
                        max_step_coarse(&blk.tmp, &mut blk.tmp2, n, alpha, PREDICTOR_HALVINGS)
                    } else {
                        max_step(&mut blk.tmp, &mut blk.tmp2, n, alpha, &mut blk.ev, &mut blk.ee)?
                    };
                } else {
                    for i in 0..n {
                        if dir[i] < 0.0 {
                            alpha = alpha.min(-blk.lam[i] / dir[i]);
                        }
                    }
                }
            }
        }
        if alpha.is_nan() { None } else { Some(alpha) }
    }

    fn write_solution(&self, status: SolveStatus, st: &State, iterations: u32, sol: &mut SdpSolution) {
        sol.status = status;
        sol.iterations = iterations;
        let (xscale, yscale) = match status {
            SolveStatus::PrimalInfeasible | SolveStatus::AlmostPrimalInfeasible => (0.0, 1.0 / self.tr[0]),
            SolveStatus::DualInfeasible | SolveStatus::AlmostDualInfeasible => {
                let cx = dense::dot(&self.c, &self.x);
                (-1.0 / cx, 0.0)
            }
            _ => (1.0 / st.tau, 1.0 / st.tau),
        };
        // A zero scale marks the part that is not the certificate: exactly zero.
        let scaled = |v: f64, scale: f64| if scale == 0.0 { 0.0 } else { v * scale };
        for (s, x) in sol.x.iter_mut().zip(&self.x) {
            *s = scaled(*x, xscale);
        }
        for (dst, blk) in sol.dual.iter_mut().zip(&self.blocks) {
            let out = dst.as_mut_slice();
            if blk.psd {
                for (o, y) in out.iter_mut().zip(&blk.y) {
                    *o = scaled(*y, yscale);
                }
            } else {
                out.fill(0.0);
                for i in 0..blk.n {
                    out[i + i * blk.n] = scaled(blk.y[i], yscale);
                }
            }
        }
        match status {
            SolveStatus::PrimalInfeasible | SolveStatus::AlmostPrimalInfeasible => {
                sol.primal_objective = f64::INFINITY;
                sol.dual_objective = f64::INFINITY;
                sol.primal_residual = f64::NAN;
                sol.dual_residual = st.pinf;
            }
            SolveStatus::DualInfeasible | SolveStatus::AlmostDualInfeasible => {
                sol.primal_objective = f64::NEG_INFINITY;
                sol.dual_objective = f64::NEG_INFINITY;
                sol.primal_residual = st.dinf;
                sol.dual_residual = f64::NAN;
            }
            _ => {
                sol.primal_objective = st.pobj;
                sol.dual_objective = st.dobj;
                sol.primal_residual = st.pres;
                sol.dual_residual = st.dres;
            }
        }
    }
}

/// Tolerances of one level (strict, or relaxed by `reduced_tol_factor`).
struct Tols {
    gap_abs: f64,
    gap_rel: f64,
    feas: f64,
    infeas: f64,
}

impl Tols {
    fn new(s: &SolverSettings, factor: f64) -> Self {
        Self {
            gap_abs: s.tol_gap_abs * factor,
            gap_rel: s.tol_gap_rel * factor,
            feas: s.tol_feas * factor,
            infeas: s.tol_infeas * factor,
        }
    }
}

/// Sentinel returned by `step` when the normal equations lost too much accuracy.
const NEED_PRECISION: f64 = -1.0;

/// `‖e₁‖²/‖d_x‖²` (relative residual of the corrector's first equation before refinement, squared)
/// beyond which the QR-based factor is used.
const PRECISION_LOSS: f64 = 1e-6;

/// Relative accuracy of the HKM corrector's step length (Cholesky bisection; the step taken is
/// the feasible end of the bracket, so at worst this fraction shorter than the boundary's).
const HKM_STEP_RTOL: f64 = 1.0 / 64.0;

/// Cholesky-test halvings of the predictor's step, which only sets `σ` (step known to within
/// 1/4; three halvings cost more tests and gave no fewer iterations on the filter LMI and SDPLIB).
const PREDICTOR_HALVINGS: u32 = 2;

/// Fraction of the step to the boundary of the cone that is taken.
const STEP_FRACTION: f64 = 0.99;

/// Iterations without improvement of the best iterate after which the method is stalled (once
/// the best iterate meets the relaxed tolerances).
const STALL_ITERATIONS: u32 = 5;

/// `merit ≤ 1` means the strict optimality test passes; `merit ≤ reduced_tol_factor` the relaxed.
fn merit(st: &State, tol: &Tols) -> f64 {
    let gap = (st.gap_abs / tol.gap_abs).min(st.gap_rel / tol.gap_rel);
    let m = (st.pres / tol.feas).max(st.dres / tol.feas).max(gap);
    if m.is_nan() { f64::INFINITY } else { m }
}

/// Termination test on the last residual evaluation.
fn classify(st: &State, tol: &Tols, relaxed: bool) -> Option<SolveStatus> {
    let finite = st.pobj.is_finite() && st.dobj.is_finite();
    if finite && st.pres <= tol.feas && st.dres <= tol.feas && (st.gap_abs <= tol.gap_abs || st.gap_rel <= tol.gap_rel)
    {
        return Some(if relaxed { SolveStatus::AlmostSolved } else { SolveStatus::Solved });
    }
    if st.pinf <= tol.infeas {
        return Some(if relaxed { SolveStatus::AlmostPrimalInfeasible } else { SolveStatus::PrimalInfeasible });
    }
    if st.dinf <= tol.infeas {
        return Some(if relaxed { SolveStatus::AlmostDualInfeasible } else { SolveStatus::DualInfeasible });
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::problem::{Block, Entry, SdpProblem};

    /// The HKM Schur matrix (group by group, and with the whole-block grouping) against the
    /// definition `tr(Fᵢ Y Fⱼ X⁻¹)` summed over dense matrices.
    #[test]
    fn hkm_schur_matches_definition() {
        let n = 9;
        let m = 5;
        let mut seed = 11u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let mut entries = vec![];
        for mat in 0..=m {
            for col in 0..n {
                for row in 0..=col {
                    if (row * 3 + col * 5 + mat * 7) % (mat + 3) == 0 {
                        entries.push(Entry { mat, block: 0, row, col, value: rnd() });
                    }
                }
            }
        }
        let p = SdpProblem::new(vec![Block::Psd(n)], vec![1.0; m], entries.clone()).unwrap();
        let mut ws = Workspace::new(&p, u128::MAX).unwrap();
        let unit = crate::scaling::Equilibration::IDENTITY;
        ws.load_values(&p, &unit);
        // Symmetric Y and X⁻¹ (definiteness does not matter for the identity).
        let mut sym = |shift: f64| {
            let mut a = vec![0.0; n * n];
            for j in 0..n {
                for i in 0..=j {
                    let v = rnd() + if i == j { shift } else { 0.0 };
                    a[i + j * n] = v;
                    a[j + i * n] = v;
                }
            }
            a
        };
        let (y, xi) = (sym(3.0), sym(2.0));
        let dense_f = |mat: usize| {
            let mut f = vec![0.0; n * n];
            for e in entries.iter().filter(|e| e.mat == mat) {
                f[e.row + e.col * n] = e.value;
                f[e.col + e.row * n] = e.value;
            }
            f
        };
        let mul = |a: &[f64], b: &[f64]| {
            let mut c = vec![0.0; n * n];
            for j in 0..n {
                for k in 0..n {
                    for i in 0..n {
                        c[i + j * n] += a[i + k * n] * b[k + j * n];
                    }
                }
            }
            c
        };
        let mp = m + 1;
        let mut reference = vec![0.0; mp * mp];
        for j in 0..mp {
            let g = mul(&mul(&y, &dense_f(j)), &xi);
            for i in j..mp {
                let fi = dense_f(i);
                reference[i + j * mp] = (0..n * n).map(|k| fi[k] * g[(k % n) * n + k / n]).sum();
            }
        }
        for (grouped, dense_columns) in [(false, false), (false, true), (true, false)] {
            let blk = &mut ws.blocks[0];
            blk.y.copy_from_slice(&y);
            blk.xinv.copy_from_slice(&xi);
            for j in 0..=m {
                if blk.kind[j] != SchurKind::Empty {
                    blk.kind[j] = if dense_columns { SchurKind::Dense } else { SchurKind::Pairwise };
                }
            }
            if grouped {
                let ng = blk.grp_row.len();
                blk.grouped = true;
                blk.gmat =
                    (0..=m).flat_map(|j| std::iter::repeat_n(j, blk.grp_start[j + 1] - blk.grp_start[j])).collect();
                blk.yt = vec![0.0; ng * n];
                blk.yt2 = vec![0.0; ng * n];
                blk.zg = vec![0.0; ng * ng];
                blk.zg2 = vec![0.0; ng * ng];
                blk.ag_row = Vec::with_capacity(ng);
                blk.ag_mat = Vec::with_capacity(ng);
                blk.ag_ent = Vec::with_capacity(ng + 1);
                blk.ag_idx = Vec::with_capacity(blk.grp_ents.len());
                blk.ag_val = Vec::with_capacity(blk.grp_ents.len());
                ws.load_values(&p, &unit);
            } else {
                blk.grouped = false;
            }
            ws.assemble_schur_hkm();
            for j in 0..mp {
                for i in j..mp {
                    let (a, b) = (ws.mhat[i + j * mp], reference[i + j * mp]);
                    assert!(
                        (a - b).abs() < 1e-12 * (1.0 + b.abs()),
                        "grouped {grouped} dense {dense_columns} ({i}, {j}): {a} vs {b}"
                    );
                }
            }
        }
    }

    /// All three Schur strategies give the same matrix.
    #[test]
    fn schur_strategies_agree() {
        let n = 6;
        let mut entries = vec![];
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let m = 5;
        for mat in 0..=m {
            for col in 0..n {
                for row in 0..=col {
                    if (row * 3 + col * 5 + mat * 7) % (mat + 2) == 0 {
                        entries.push(Entry { mat, block: 0, row, col, value: rnd() });
                    }
                }
            }
        }
        let p = SdpProblem::new(vec![Block::Psd(n)], vec![1.0; m], entries).unwrap();
        let mut ws = Workspace::new(&p, u128::MAX).unwrap();
        let unit = crate::scaling::Equilibration::IDENTITY;
        ws.load_values(&p, &unit);
        // A symmetric positive definite D.
        let blk = &mut ws.blocks[0];
        for j in 0..n {
            for i in 0..=j {
                let v = rnd() + if i == j { 3.0 } else { 0.0 };
                blk.d[i + j * n] = v;
                blk.d[j + i * n] = v;
            }
        }
        let mut results = vec![];
        for kind in [SchurKind::Pairwise, SchurKind::RankUpdate, SchurKind::Dense, SchurKind::LowRank] {
            let blk = &mut ws.blocks[0];
            for j in 0..=m {
                if blk.kind[j] != SchurKind::Empty {
                    blk.kind[j] = kind;
                }
            }
            blk.lr_first = 0;
            ws.assemble_schur();
            results.push(ws.mhat.clone());
        }
        let blk = &mut ws.blocks[0];
        let ng = blk.grp_row.len();
        blk.grouped = true;
        blk.gmat = (0..=m).flat_map(|j| std::iter::repeat_n(j, blk.grp_start[j + 1] - blk.grp_start[j])).collect();
        blk.yt = vec![0.0; ng * n];
        blk.zg = vec![0.0; ng * ng];
        blk.ag_row = Vec::with_capacity(ng);
        blk.ag_mat = Vec::with_capacity(ng);
        blk.ag_ent = Vec::with_capacity(ng + 1);
        blk.ag_idx = Vec::with_capacity(blk.grp_ents.len());
        blk.ag_val = Vec::with_capacity(blk.grp_ents.len());
        ws.load_values(&p, &unit);
        ws.assemble_schur();
        results.push(ws.mhat.clone());
        for r in &results[1..] {
            for (a, b) in r.iter().zip(&results[0]) {
                assert!((a - b).abs() < 1e-10 * (1.0 + b.abs()), "{a} vs {b}");
            }
        }
    }
}
