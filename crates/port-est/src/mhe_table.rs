//! The optional `[mhe]` table of `MODEL.toml`: the settings of the moving-horizon estimators
//! (`--estimator rmhe` and `mhe`), read with `serde`, every complaint at the `file:line:column`
//! of the key's value. Structural checks here (names, lengths, finite numbers); the settings'
//! own validation (`MheSettings::validate`: blocks summing to the horizon, boxes containing 0,
//! `lambda_v > 1`, a diagonal `r`) runs when such an estimator is built, and its message is
//! reported at the key it names.
//!
//! Resources are checked before anything is allocated for them: the memory the estimator would
//! take ([`memory_estimate`], computed without overflow) against `--mhe-memory-limit`, block
//! lengths summed with checked arithmetic, `max_sweeps` against [`MAX_MHE_SWEEPS`]; each refusal
//! is at the key's `file:line:column`.

use std::ops::Range;

use estimators::mhe::{
    AlphaMap, ArrivalRecursion, BlockWeighting, BlockingPreset, InnerSolver, MheCost, MheSettings, PriorMean,
    WindowSolver,
};
use nalgebra::DVector;
use serde::Deserialize;
use toml::Spanned;

use crate::limits::{Limits, MAX_MHE_SWEEPS, show_bytes};

/// The `[mhe]` table as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct MheTable {
    horizon: Option<Spanned<usize>>,
    preset: Option<Spanned<String>>,
    blocks: Option<Spanned<Vec<usize>>>,
    block_weighting: Option<Spanned<String>>,
    lambda_v: Option<Spanned<f64>>,
    alpha: Option<Spanned<f64>>,
    alpha_map: Option<Spanned<String>>,
    w_lower: Spanned<Vec<f64>>,
    w_upper: Spanned<Vec<f64>>,
    v_lower: Spanned<Vec<f64>>,
    v_upper: Spanned<Vec<f64>>,
    solver: Option<Spanned<String>>,
    inner: Option<Spanned<String>>,
    max_sweeps: Option<Spanned<usize>>,
    tolerance: Option<Spanned<f64>>,
    arrival: Option<Spanned<String>>,
    theta: Option<Spanned<f64>>,
    prior_mean: Option<Spanned<String>>,
    output_constraint: Option<Spanned<bool>>,
}

/// A complaint about a key: its span and the message.
pub(crate) type Complaint = (Range<usize>, String);

/// The keys given in the table and the spans of their values.
pub(crate) type KeySpans = Vec<(&'static str, Range<usize>)>;

fn choice<'a, T: Copy>(v: &Spanned<String>, key: &str, options: &'a [(&'a str, T)]) -> Result<T, Complaint> {
    options.iter().find(|(n, _)| *n == v.get_ref()).map(|(_, t)| *t).ok_or_else(|| {
        let names: Vec<&str> = options.iter().map(|(n, _)| *n).collect();
        (v.span(), format!("`mhe.{key}`: unknown value {:?} (one of: {})", v.get_ref(), names.join(", ")))
    })
}

fn vector(v: &Spanned<Vec<f64>>, key: &str, len: usize, allow_infinite: bool) -> Result<DVector<f64>, Complaint> {
    let x = v.get_ref();
    if x.len() != len {
        return Err((v.span(), format!("`mhe.{key}`: expected {len} entries, found {}", x.len())));
    }
    if let Some(j) = x.iter().position(|x| x.is_nan() || (!allow_infinite && !x.is_finite())) {
        return Err((v.span(), format!("`mhe.{key}`: entry {} is not a finite number", j + 1)));
    }
    Ok(DVector::from_column_slice(x))
}

/// The bytes a moving-horizon estimator allocates for a model with `n` states, `m` outputs and
/// `p` inputs, a horizon of `horizon` disturbances in `blocks` blocks: an estimate from above of
/// its buffers — the condensed window maps and rows, the Hessian-sized matrices of the window and
/// the box-QP's factor (three, counted as four; six with `clarabel`, whose QP copies them), the
/// ring buffers of the last `N + 2` steps. `None` when the count overflows `u128`.
#[must_use]
pub fn memory_estimate(n: usize, m: usize, p: usize, horizon: usize, blocks: usize, clarabel: bool) -> Option<u128> {
    let [n, m, p, horizon, blocks] = [n, m, p, horizon, blocks].map(|v| v as u128);
    let mul = |a: u128, b: u128| a.checked_mul(b);
    let add = |a: u128, b: u128| a.checked_add(b);
    // Unknowns of a full window: x_s and one disturbance per block (at most N + 1 vectors).
    let nz = mul(n, add(1, horizon.max(blocks))?)?;
    let samples = add(horizon, 1)?;
    let ring = add(horizon, 2)?;
    let hessians = mul(if clarabel { 6 } else { 4 }, mul(nz, nz)?)?;
    let window = mul(mul(samples, nz)?, add(n, m)?)?;
    let per_step = add(add(mul(2, mul(n, n)?)?, mul(m, n)?)?, add(mul(3, n)?, add(p, mul(4, m)?)?)?)?;
    let rings = mul(ring, per_step)?;
    let vectors = add(mul(12, nz)?, mul(samples, add(mul(4, m)?, mul(2, n)?)?)?)?;
    let f64s = add(add(hessians, window)?, add(rings, vectors)?)?;
    mul(f64s, 8)
}

impl MheTable {
    /// Refuses a horizon or block count whose estimator would exceed `limits`, before anything
    /// is allocated for it: at the key that makes the window large.
    fn check_resources(
        &self,
        n: usize,
        m: usize,
        p: usize,
        default_horizon: usize,
        limits: &Limits,
    ) -> Result<(), Complaint> {
        let horizon = self.horizon.as_ref().map_or(default_horizon, |h| *h.get_ref());
        let blocks = self.blocks.as_ref().map_or(0, |b| b.get_ref().len());
        let clarabel = self.inner.as_ref().is_some_and(|i| i.get_ref() == "clarabel")
            || self.output_constraint.as_ref().is_some_and(|o| *o.get_ref());
        let estimate = memory_estimate(n, m, p, horizon, blocks, clarabel);
        let limit = u128::from(limits.mhe_memory_bytes);
        if estimate.is_some_and(|e| e <= limit) {
            return Ok(());
        }
        let (key, span) = match (&self.horizon, &self.blocks, &self.preset) {
            (_, Some(b), _) if blocks > horizon => ("blocks", b.span()),
            (Some(h), ..) => ("horizon", h.span()),
            (None, Some(b), _) => ("blocks", b.span()),
            (None, None, Some(pr)) => ("preset", pr.span()),
            (None, None, None) => ("w_lower", self.w_lower.span()),
        };
        let need = estimate.map_or_else(|| "more than 2^128 bytes".to_owned(), |e| format!("about {}", show_bytes(e)));
        Err((
            span,
            format!(
                "`mhe.{key}`: a horizon of N = {horizon} in {} blocks needs {need} for n = {n} states and m = {m} \
                 outputs, more than the limit of {} (raise it with --mhe-memory-limit; a step's time grows as the \
                 cube of the window's n·(N + 1) unknowns)",
                if blocks == 0 { horizon } else { blocks },
                show_bytes(limit)
            ),
        ))
    }

    /// The settings for a model with `n` states, `m` outputs and `p` inputs (the prior and the
    /// weights are the model's `x0`, `p0`, `q`, `r`), and the spans of the keys given (for later
    /// complaints); the estimator's memory is checked against `limits` first.
    pub(crate) fn settings(
        &self,
        n: usize,
        m: usize,
        p: usize,
        limits: &Limits,
    ) -> Result<(MheSettings, KeySpans), Complaint> {
        let w = (vector(&self.w_lower, "w_lower", n, true)?, vector(&self.w_upper, "w_upper", n, true)?);
        let v = (vector(&self.v_lower, "v_lower", m, false)?, vector(&self.v_upper, "v_upper", m, false)?);
        let mut s = MheSettings::new(w, v);
        self.check_resources(n, m, p, s.horizon, limits)?;
        if let Some(b) = &self.blocks
            && b.get_ref().iter().try_fold(0_usize, |sum, &d| sum.checked_add(d)).is_none()
        {
            return Err((b.span(), "`mhe.blocks`: the block lengths overflow when summed (they must sum to N)".into()));
        }
        if let Some(sweeps) = &self.max_sweeps
            && *sweeps.get_ref() > MAX_MHE_SWEEPS
        {
            return Err((
                sweeps.span(),
                format!(
                    "`mhe.max_sweeps` = {}: at most {MAX_MHE_SWEEPS} sweeps (or Newton iterations) per window",
                    sweeps.get_ref()
                ),
            ));
        }
        let horizon = self.horizon.as_ref().map_or(s.horizon, |h| *h.get_ref());
        s.horizon = horizon;
        s.blocks = match (&self.preset, &self.blocks) {
            (Some(p), None) => {
                let preset = choice(
                    p,
                    "preset",
                    &[
                        ("rmhe", BlockingPreset::Rmhe),
                        ("rmhe-op", BlockingPreset::RmheOp),
                        ("rmhe-of", BlockingPreset::RmheOf),
                    ],
                )?;
                preset.lengths(horizon).map_err(|e| (p.span(), format!("`mhe.preset`: {e}")))?
            }
            (None, Some(b)) => b.get_ref().clone(),
            (None, None) => vec![1; horizon],
            (Some(p), Some(_)) => return Err((p.span(), "`mhe`: give `preset` or `blocks`, not both".into())),
        };
        if let Some(bw) = &self.block_weighting {
            s.block_weighting =
                choice(bw, "block_weighting", &[("length", BlockWeighting::Length), ("unit", BlockWeighting::Unit)])?;
        }
        s.cost = match (&self.lambda_v, &self.alpha) {
            (Some(l), None) => MheCost::MinMax { lambda_v: *l.get_ref() },
            (None, Some(a)) => {
                let map = match &self.alpha_map {
                    Some(m) => choice(
                        m,
                        "alpha_map",
                        &[
                            ("one-over-one-minus-alpha", AlphaMap::OneOverOneMinusAlpha),
                            ("one-over-alpha", AlphaMap::OneOverAlpha),
                        ],
                    )?,
                    None => AlphaMap::OneOverOneMinusAlpha,
                };
                MheCost::MinMax {
                    lambda_v: map.lambda_v(*a.get_ref()).map_err(|e| (a.span(), format!("`mhe.alpha`: {e}")))?,
                }
            }
            (None, None) => MheCost::MinMax { lambda_v: 10.0 },
            (Some(l), Some(_)) => return Err((l.span(), "`mhe`: give `lambda_v` or `alpha`, not both".into())),
        };
        let inner = match &self.inner {
            Some(i) => {
                choice(i, "inner", &[("active-set", InnerSolver::ActiveSet), ("clarabel", InnerSolver::Clarabel)])?
            }
            None => InnerSolver::ActiveSet,
        };
        let kind = match &self.solver {
            Some(sv) => choice(sv, "solver", &[("coordinate-rotation", true), ("exact-saddle", false)])?,
            None => true,
        };
        s.solver = if kind {
            WindowSolver::CoordinateRotation {
                max_sweeps: self.max_sweeps.as_ref().map_or(10, |v| *v.get_ref()),
                tolerance: self.tolerance.as_ref().map_or(1e-8, |v| *v.get_ref()),
                inner,
            }
        } else {
            WindowSolver::ExactSaddle {
                max_iterations: self.max_sweeps.as_ref().map_or(50, |v| *v.get_ref()),
                tolerance: self.tolerance.as_ref().map_or(1e-10, |v| *v.get_ref()),
            }
        };
        if let Some(a) = &self.arrival {
            let h_inf = choice(a, "arrival", &[("kalman", false), ("h-infinity", true)])?;
            s.arrival = if h_inf {
                ArrivalRecursion::HInfinity { theta: self.theta.as_ref().map_or(0.9, |t| *t.get_ref()) }
            } else {
                ArrivalRecursion::Kalman
            };
        }
        if let Some(p) = &self.prior_mean {
            s.prior_mean =
                choice(p, "prior_mean", &[("smoothed", PriorMean::Smoothed), ("filtered", PriorMean::Filtered)])?;
        }
        if let Some(o) = &self.output_constraint {
            s.output_constraint = *o.get_ref();
        }
        let mut keys: KeySpans = Vec::new();
        let mut key = |k: &'static str, span: Option<Range<usize>>| {
            if let Some(span) = span {
                keys.push((k, span));
            }
        };
        key("mhe.horizon", self.horizon.as_ref().map(Spanned::span));
        key("mhe.preset", self.preset.as_ref().map(Spanned::span));
        key("mhe.blocks", self.blocks.as_ref().map(Spanned::span));
        key("mhe.lambda_v", self.lambda_v.as_ref().map(Spanned::span));
        key("mhe.alpha", self.alpha.as_ref().map(Spanned::span));
        key("mhe.w_lower", Some(self.w_lower.span()));
        key("mhe.v_lower", Some(self.v_lower.span()));
        key("mhe.solver", self.solver.as_ref().map(Spanned::span));
        key("mhe.max_sweeps", self.max_sweeps.as_ref().map(Spanned::span));
        key("mhe.tolerance", self.tolerance.as_ref().map(Spanned::span));
        key("mhe.theta", self.theta.as_ref().map(Spanned::span));
        Ok((s, keys))
    }
}

/// The model-file key a message of `MheSettings::validate` is about (`None`: the table).
pub(crate) fn key_of_message(message: &str) -> &'static [&'static str] {
    if message.contains("block") {
        &["mhe.blocks", "mhe.preset", "mhe.horizon"]
    } else if message.contains("horizon") {
        &["mhe.horizon"]
    } else if message.contains("lambda_v") {
        &["mhe.lambda_v", "mhe.alpha"]
    } else if message.contains("box W") {
        &["mhe.w_lower"]
    } else if message.contains("box V") {
        &["mhe.v_lower"]
    } else if message.contains("theta") {
        &["mhe.theta"]
    } else if message.contains("sweeps") || message.contains("iterations") {
        &["mhe.max_sweeps", "mhe.tolerance", "mhe.solver"]
    } else if message.starts_with("R") {
        &["r"]
    } else if message.starts_with("Q") {
        &["q"]
    } else if message.starts_with("P0") {
        &["p0"]
    } else if message.starts_with("x0") || message.contains("x0") {
        &["x0"]
    } else {
        &[]
    }
}
