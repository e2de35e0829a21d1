//! Who caused a numerical failure of `port-est filter`: this row's numbers, an earlier row's
//! that the estimate still carries, or the model. Decided by trying the failed step again from the
//! same state (a failed step leaves the estimator unchanged) with moderate data in the row's place.

use estimators::AnyEstimator;
use models::AnyModel;
use nalgebra::DVector;

use crate::data::{DataRow, RowSource};
use crate::error::{Error, Location};
use crate::model::Model;

/// The largest data cell (in magnitude) of the rows stepped so far, where it is.
#[derive(Debug, Default)]
pub(crate) struct LargestCell(Option<(f64, String, Location)>);

impl LargestCell {
    /// Notes the cells of `row` (inputs and the model's `m` outputs) once its step succeeded.
    pub(crate) fn observe(&mut self, row: &DataRow, m: usize, data: &dyn RowSource) {
        let cells = row.u.iter().chain(row.y.iter().take(m));
        let Some((j, v)) = cells.enumerate().max_by(|a, b| a.1.abs().total_cmp(&b.1.abs())) else { return };
        if self.0.as_ref().is_none_or(|(big, ..)| v.abs() > big.abs()) {
            let column = 1 + j;
            let name = data.columns().get(column).cloned().unwrap_or_default();
            self.0 = Some((*v, name, data.locate(Some(column))));
        }
    }
}

/// The error for a numerical failure (`what`) of `row`'s step, after finding its cause: `est`
/// is tried again (and spent: the run stops here).
pub(crate) fn numerical_failure(
    what: &str,
    est: &mut AnyEstimator,
    model: &Model,
    sm: &dyn AnyModel,
    row: &DataRow,
    last_u: Option<&DVector<f64>>,
    largest: &LargestCell,
    data: &dyn RowSource,
) -> Error {
    let (p, m) = (model.inputs(), model.outputs());
    let k = row.k;
    let x = est.estimate().center().clone_owned();
    // The measurement the estimate predicts, `h(f(x, u))` (`None` where the model fails there).
    let predict = |u: &DVector<f64>| {
        let dm = sm.discrete();
        let mut next = DVector::zeros(model.states());
        dm.f(&x, u, &mut next).ok()?;
        let mut y = DVector::zeros(m);
        dm.h(&next, u, &mut y).ok()?;
        Some(y)
    };
    let mut retry = |u: &DVector<f64>, predicted: &Option<DVector<f64>>| {
        let Some(predicted) = predicted.as_ref().filter(|p| p.iter().all(|v| v.is_finite())) else {
            return false;
        };
        let mut y = row.y.clone();
        y.rows_mut(0, m).copy_from(predicted);
        est.step(sm, u, &y).is_ok()
    };
    let model_error = || {
        let message = format!(
            "step k = {k}: numerical failure: {what}; the cause is the model in {} (its {}, `q`, `r`, `p0`), not the \
             data (the step fails with moderate numbers too)",
            model.path().display(),
            if model.column_names().is_some() { "equations" } else { "`a`, `b`, `c`" }
        );
        Error::At { at: data.locate(Some(0)), message }
    };

    // The row's measurement replaced by its prediction.
    let predicted = predict(&row.u);
    if retry(&row.u, &predicted) {
        let Some(predicted) = predicted else { return model_error() };
        let Some(i) =
            (0..m).max_by(|&a, &b| (row.y[a] - predicted[a]).abs().total_cmp(&(row.y[b] - predicted[b]).abs()))
        else {
            return model_error();
        };
        let column = 1 + p + i;
        let name = &data.columns()[column];
        if row.y[i].abs() >= predicted[i].abs() {
            let message = format!(
                "step k = {k}: numerical failure: {what}: caused by this row's {name} = {:e}, too large for the \
                 estimator's arithmetic (the same step succeeds with the predicted measurement in its place)",
                row.y[i]
            );
            return Error::At { at: data.locate(Some(column)), message };
        }
        // The prediction is the huge number: the estimate carries an earlier row's value.
        return match &largest.0 {
            Some((v, earlier, at)) if v.abs() >= 1e-3 * predicted[i].abs() => {
                let message = format!(
                    "step k = {k} (line {}): numerical failure: {what}: caused by this earlier cell, {earlier} = {v:e}, \
                     which drove the estimate's prediction of {name} to {:e}",
                    data.locate(Some(0)).line,
                    predicted[i]
                );
                Error::At { at: at.clone(), message }
            }
            _ => model_error(),
        };
    }
    // Also the row's input replaced by the previous row's (the input range's middle, or 0, at
    // the first row).
    let moderate = match (last_u, &model.input_range) {
        (Some(u), _) => u.clone(),
        (None, Some((lo, hi))) => (lo + hi) / 2.0,
        (None, None) => DVector::zeros(p),
    };
    if p > 0 && retry(&moderate, &predict(&moderate)) {
        if let Some(j) = (0..p).max_by(|&a, &b| row.u[a].abs().total_cmp(&row.u[b].abs())) {
            let name = &data.columns()[1 + j];
            let message = format!(
                "step k = {k}: numerical failure: {what}: caused by this row's {name} = {:e}, too large for the \
                 estimator's arithmetic (the same step succeeds with the previous row's input in its place)",
                row.u[j]
            );
            return Error::At { at: data.locate(Some(1 + j)), message };
        }
    }
    model_error()
}
