//! What Python sees when something goes wrong: `ValueError` for bad input (dimensions, NaN,
//! matrices that are not symmetric positive definite, unknown names, bad settings), the package's
//! `EstimationError` and its subclasses `NumericalError` and `InconsistentDataError` for what the
//! estimation itself runs into, `BagError` (a `ValueError`) for a bag that cannot be read, and
//! the Rust error's kind as the exception's `kind` attribute (`refused-input`, `outlier`, …), and
//! never a Rust panic (every call into the estimators runs under [`std::panic::catch_unwind`]; an
//! estimator that panicked is refused from then on).

use std::panic::{AssertUnwindSafe, catch_unwind};

use estimators::{ErrorKind, EstimatorError};
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyValueError};
use pyo3::prelude::*;

create_exception!(
    port_estimation,
    EstimationError,
    PyException,
    "Base class of the errors of the estimation itself (bad input raises ValueError instead).\n\n\
     Raised as such when an estimator cannot do what was asked (an update without the prediction it \
     is joint with, an operation the estimator does not offer, an SDP backend that cannot be set up) or \
     failed internally. After any exception the estimator's state is what it was before the call."
);
create_exception!(
    port_estimation,
    NumericalError,
    EstimationError,
    "A step failed numerically: the estimate overflowed or a covariance or shape lost positive \
     definiteness (usually an unstable model or noise sizes far out of scale). The estimator is \
     unchanged."
);
create_exception!(
    port_estimation,
    InconsistentDataError,
    EstimationError,
    "The measurement of a step provably contradicts the predicted set and the noise bounds of a \
     set-membership filter (an outlier, a biased sensor, noise beyond its bound or a wrong model).\n\n\
     Attributes\n----------\nstep : int\n    The filter's step (1 for its first step).\nexcess : float\n    \
     How far outside, relative to the set's extent in the separating direction.\nrow : int or None\n    \
     The row of the log in ``run`` (None for a single step).\n\n\
     The filter is unchanged; build it with ``inconsistency=\"flag\"`` to publish such steps marked \
     inconsistent instead, or ``\"restart\"`` to move the set to the data."
);

create_exception!(
    port_estimation,
    RunError,
    EstimationError,
    "A step of ``run`` after the first could not take its row (an input outside the estimator's box, \
     a value the model refuses): what a single call would refuse with ``ValueError``, raised as this \
     because the rows before were filtered.\n\n\
     Attributes\n----------\nrow : int\n    The row that failed; the estimator holds the estimate after \
     the row before it (a new ``run`` from this row continues the log)."
);

create_exception!(
    port_estimation,
    BagError,
    PyValueError,
    "A ROS 2 bag (MCAP) that cannot be read as asked: not MCAP, a damaged record, a schema or message \
     that does not decode, a topic's stamps going back, an input topic without messages. A \
     ``ValueError``; the message names the file and where (byte offset, topic, mapping key).\n\n\
     Attributes\n----------\npath : str\n    The bag.\nrows_read : int\n    The rows read before \
     the error (0 when it came before any).\noffset : int or None\n    The byte offset of the record \
     (the chunk, for a record inside one).\ntopic, key : str or None\n    The topic and the mapping key \
     the error is about."
);

/// [`RunError`] for `e` at `row` of a run.
pub fn run_error(py: Python<'_>, e: &EstimatorError, row: usize) -> PyErr {
    let err = RunError::new_err(format!("row {row}: {e}"));
    let _ = err.value(py).setattr("row", row);
    let _ = err.value(py).setattr("kind", e.kind().label());
    err
}

/// Whether an estimator error is the caller's input (a `ValueError`).
pub fn is_bad_input(e: &EstimatorError) -> bool {
    e.kind() == ErrorKind::RefusedInput
}

/// The Python exception for an estimator's error; `row` is the log row of a whole-log run.
pub fn estimator_error(py: Python<'_>, e: &EstimatorError, row: Option<usize>) -> PyErr {
    let at = row.map(|r| format!("row {r}: ")).unwrap_or_default();
    let message = format!("{at}{e}");
    let err = match e {
        EstimatorError::InconsistentData { step, excess } => {
            let err = InconsistentDataError::new_err(message);
            let value = err.value(py);
            // Setting attributes on a fresh exception instance cannot fail short of memory
            // exhaustion; the exception is still raised if it did.
            let _ = value.setattr("step", *step);
            let _ = value.setattr("excess", *excess);
            err
        }
        EstimatorError::InconsistentWindow { step, samples, excess } => {
            let err = InconsistentDataError::new_err(message);
            let value = err.value(py);
            let _ = value.setattr("step", *step);
            let _ = value.setattr("excess", *excess);
            let _ = value.setattr("samples", *samples);
            err
        }
        EstimatorError::Outlier { step, nis, threshold, probability, worst } => {
            let err = InconsistentDataError::new_err(message);
            let value = err.value(py);
            let _ = value.setattr("step", *step);
            let _ = value.setattr("nis", *nis);
            let _ = value.setattr("threshold", *threshold);
            let _ = value.setattr("probability", *probability);
            // The output with the largest innovation in its own standard deviations.
            let _ = value.setattr("output", worst.map(|w| w.index));
            let _ = value.setattr("residual", worst.map(|w| w.residual));
            err
        }
        EstimatorError::SetMissed { step, .. } => {
            let err = InconsistentDataError::new_err(message);
            let _ = err.value(py).setattr("step", *step);
            err
        }
        EstimatorError::OutsideStateBounds { step, state, .. } => {
            let err = InconsistentDataError::new_err(message);
            let value = err.value(py);
            let _ = value.setattr("step", *step);
            let _ = value.setattr("state", *state);
            err
        }
        e => match e.kind() {
            ErrorKind::NumericalFailure => NumericalError::new_err(message),
            ErrorKind::RefusedInput => PyValueError::new_err(message),
            ErrorKind::Outlier | ErrorKind::InconsistentData => InconsistentDataError::new_err(message),
            _ => EstimationError::new_err(message),
        },
    };
    let _ = err.value(py).setattr("row", row);
    // The Rust error's kind (`refused-input`, `outlier`, `inconsistent-data`, `guarantee-lost`,
    // `numerical-failure`, `unsupported`), the same words as `estimators::ErrorKind::label`.
    let _ = err.value(py).setattr("kind", e.kind().label());
    err
}

/// A `ValueError` with `message`.
pub fn value_error(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(message.into())
}

/// What a guarded call returns: the estimator's result, or why it could not run.
#[non_exhaustive]
pub enum Guarded<T> {
    /// The call ran.
    Ran(T),
    /// The code panicked (with this message).
    Broken(String),
}

/// Runs `f` so that a panic inside stays in Rust: it becomes [`Guarded::Broken`] with the panic's
/// message (the panic hook has printed it to stderr too).
pub fn guard<T>(f: impl FnOnce() -> T) -> Guarded<T> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(v) => Guarded::Ran(v),
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| (*s).to_owned())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".to_owned());
            Guarded::Broken(what)
        }
    }
}

/// The Python error of an internal failure (`message` says what).
pub fn broken(message: String) -> PyErr {
    EstimationError::new_err(message)
}

/// The Python error of an estimator that panicked with `what`: it cannot be used any more (its
/// lock is poisoned).
pub fn panicked(what: &str) -> PyErr {
    broken(format!(
        "internal error in the estimator ({what}); it cannot be used any more: build a new one, and please report \
         this"
    ))
}

/// Runs `f` (binding code outside an estimator call: model evaluations, conversions) so that a
/// panic inside becomes an `EstimationError` instead of crossing into Python.
pub fn no_panic<T>(f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    match guard(f) {
        Guarded::Ran(r) => r,
        Guarded::Broken(what) => Err(broken(format!("internal error ({what}); please report this"))),
    }
}
