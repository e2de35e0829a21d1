//! The interior-point iteration (homogeneous self-dual embedding, NT or HKM direction, Mehrotra
//! predictor–corrector). See the module documentation of [`crate::ipm`] for the equations.
//!
//! This module holds the driver (warm and cold attempts, the iteration loop, the best iterate)
//! and the state shared by its parts: [`start`] (starting points), [`termination`] (residuals,
//! tests, the solution written out), [`nt`] and [`hkm`] (scaling and Schur matrix of each
//! direction), [`nonneg`] (nonnegative blocks, the same under both), [`factor`] (Cholesky or QR
//! factor of the Schur matrix), [`newton`] (predictor–corrector step and Newton solves) and
//! [`step_length`] (largest feasible steps).

mod factor;
mod hkm;
mod newton;
mod nonneg;
mod nt;
mod start;
mod step_length;
mod termination;

/// Problems for the engine's unit tests.
#[cfg(test)]
mod test_data {
    use crate::problem::Entry;

    /// Pseudo-random numbers in `[−0.5, 0.5)` from a 64-bit linear congruential generator.
    pub(super) fn lcg(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        }
    }

    /// The upper-triangle entries of `F₀ … F_m` (one `n × n` block), sparse by a fixed pattern:
    /// entry `(row, col)` of `F_mat` is present when `3 row + 5 col + 7 mat` is a multiple of
    /// `mat + spacing`; values from `rnd`, drawn in the order mat, col, row.
    pub(super) fn sparse_entries(n: usize, m: usize, spacing: usize, rnd: &mut impl FnMut() -> f64) -> Vec<Entry> {
        let mut entries = vec![];
        for mat in 0..=m {
            for col in 0..n {
                for row in 0..=col {
                    if (row * 3 + col * 5 + mat * 7) % (mat + spacing) == 0 {
                        entries.push(Entry { mat, block: 0, row, col, value: rnd() });
                    }
                }
            }
        }
        entries
    }
}

use std::time::Instant;

use faer::dyn_stack::MemStack;

use crate::solver::{SdpSolution, SolveStart, SolveStatus, SolverSettings};

use super::dense;
use super::workspace::{BlockWs, Workspace};

use newton::NEED_PRECISION;
use termination::{Tols, classify, merit};

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

/// Iterations without improvement of the best iterate after which the method is stalled (once
/// the best iterate meets the relaxed tolerances).
const STALL_ITERATIONS: u32 = 5;

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
}
