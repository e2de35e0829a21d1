//! An expression parsed once by the expression library, with its variables' slots, and its
//! symbolic partial derivatives.

use std::panic::{AssertUnwindSafe, catch_unwind};

use exmex::prelude::*;
use exmex::{Differentiate, FlatEx};

/// Expressions with at most this many variables are evaluated from a stack buffer.
const STACK_VARS: usize = 32;

/// Why an evaluation failed.
#[derive(Debug)]
pub(crate) enum EvalFailure {
    /// The value is NaN or infinite.
    NonFinite(f64),
    /// The expression library returned an error or panicked.
    Library(String),
}

/// A parsed expression and the slot (state, then input index) of each of its variables.
#[derive(Debug, Clone)]
pub(crate) struct Compiled {
    expr: FlatEx<f64>,
    /// `slots[k]` is the slot of the expression's `k`-th variable (alphabetical = slot order).
    slots: Vec<usize>,
}

fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_owned()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "panic".to_owned()
    }
}

/// Runs `f`, turning a panic of the expression library into an error message.
fn guarded<T>(f: impl FnOnce() -> Result<T, String>) -> Result<T, String> {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|p| Err(format!("panicked: {}", panic_message(p.as_ref()))))
}

/// The slot of an internal variable name `v0042` (with or without braces).
fn slot_of(name: &str) -> Option<usize> {
    name.trim_matches(|c| c == '{' || c == '}').strip_prefix('v')?.parse().ok()
}

impl Compiled {
    /// Parses `text` (already expanded: internal variable names of slots below `n_slots` only).
    pub(crate) fn parse(text: &str, n_slots: usize) -> Result<Self, String> {
        let expr = guarded(|| FlatEx::<f64>::parse(text).map_err(|e| e.to_string()))?;
        let slots = expr
            .var_names()
            .iter()
            .map(|n| slot_of(n).filter(|&s| s < n_slots).ok_or_else(|| format!("unexpected variable `{n}`")))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self { expr, slots })
    }

    /// The slots the expression's variables refer to.
    pub(crate) fn slots(&self) -> &[usize] {
        &self.slots
    }

    /// Whether the expression mentions no variable (its value is a constant).
    pub(crate) fn is_constant(&self) -> bool {
        let text = self.expr.unparse().as_bytes();
        !(0..text.len()).any(|i| {
            text[i] == b'v'
                && text.get(i + 1).is_some_and(u8::is_ascii_digit)
                && (i == 0 || !(text[i - 1].is_ascii_alphanumeric() || text[i - 1] == b'_'))
        })
    }

    /// `∂/∂(slot)` of the expression for each of its variables, as `(slot, derivative)`.
    pub(crate) fn partials(&self) -> Result<Vec<(usize, Compiled)>, String> {
        (0..self.slots.len())
            .map(|k| {
                let d = guarded(|| self.expr.clone().partial(k).map_err(|e| e.to_string()))?;
                Ok((self.slots[k], Compiled { expr: d, slots: self.slots.clone() }))
            })
            .collect()
    }

    /// Evaluates at states `x` and inputs `u` (slot `s < x.len()` is `x[s]`, the others
    /// `u[s - x.len()]`). No allocation for up to 32 variables.
    pub(crate) fn eval(&self, x: &[f64], u: &[f64]) -> Result<f64, EvalFailure> {
        let value = |s: usize| if s < x.len() { x[s] } else { u[s - x.len()] };
        let result = if self.slots.len() <= STACK_VARS {
            let mut buf = [0.0; STACK_VARS];
            for (b, &s) in buf.iter_mut().zip(&self.slots) {
                *b = value(s);
            }
            guarded(|| self.expr.eval(&buf[..self.slots.len()]).map_err(|e| e.to_string()))
        } else {
            let buf: Vec<f64> = self.slots.iter().map(|&s| value(s)).collect();
            guarded(|| self.expr.eval(&buf).map_err(|e| e.to_string()))
        };
        match result {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(v) => Err(EvalFailure::NonFinite(v)),
            Err(e) => Err(EvalFailure::Library(e)),
        }
    }
}
