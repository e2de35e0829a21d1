//! Partial measurements for the set-membership filter (docs/partial-measurements.md, (P2)): a
//! step that measures the outputs `S` only is the step (13)–(29) for
//!
//! ```text
//! y_S = C_S x + v_S,    v_S ∈ 𝓔(0, R_SS)
//! ```
//!
//! — the projection of `𝓔(0, R)` onto the measured coordinates is `𝓔(0, R_SS)`, so every `v_S` of
//! a `v ∈ 𝓔(0, R)` lies in it and the certified containment carries over unchanged. The step for
//! `k` measured outputs runs in a filter of `k` outputs of its own (its solver and workspaces,
//! made the first time `k` outputs are measured and kept); the set, the step count and the
//! guarantee move into it for the step and back. A step with nothing measured is a prediction.

use nalgebra::{DMatrix, DVector};

use models::{LinearModel, StepModel};

use super::filter::{SetEstimate, SetMembershipFilter};
use super::update::UpdateSolver;
use crate::error::EstimatorError;
use crate::partial::{Measured, classify, gather_block, gather_rows};
use crate::traits::Setup;

/// The filter of `k` outputs for a partial step, and the gathered `C_S`, `y_S`, `R_SS`.
#[derive(Debug, Clone)]
pub(super) struct SubsetFilter<S: UpdateSolver> {
    filter: SetMembershipFilter<S>,
    c: DMatrix<f64>,
    y: DVector<f64>,
    r: DMatrix<f64>,
}

impl<S: UpdateSolver> SetMembershipFilter<S> {
    /// One step with the outputs where `measured` is true (the others' entries of `y` are not
    /// read and may be NaN): the step (13)–(29) with the measured rows of `C`, of `y` and the
    /// sub-block `R_SS` (module `smf::partial`); with every output measured, [`Self::step`];
    /// with none, [`Self::predict`]. On error the filter is unchanged. Allocation-free after the
    /// first step with that many outputs measured.
    ///
    /// # Errors
    /// As [`Self::step`]; a mask or `y` of another length than `m`
    /// ([`EstimatorError::DimensionMismatch`]); [`EstimatorError::Unsupported`] with a solver
    /// that cannot make one for fewer outputs ([`UpdateSolver::for_fewer_outputs`]: the SDP
    /// backends).
    pub fn step_partial<M: LinearModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
        measured: &[bool],
    ) -> Result<&SetEstimate, EstimatorError> {
        let Self { n, p, m, .. } = *self;
        crate::validate::check_model(model, n, p, m)?;
        let k = match classify(measured, u, y, (m, p), &mut self.partial.rows)? {
            Measured::All => return self.step(model, u, y),
            Measured::Nothing => return self.predict(model, u),
            Measured::Some(k) => k,
        };
        // Measured angle outputs are put on their branch here, over this filter's predicted set
        // (module `angles`); the filter of `k` outputs then takes them as ordinary data.
        let angle_outputs = LinearModel::angles(model).outputs;
        let off_branch = if angle_outputs.is_empty() {
            false
        } else {
            let rows = std::mem::take(&mut self.partial.rows);
            let found =
                self.branch_partial(&StepModel::new(model.a(), model.b(), model.c()), angle_outputs, &rows, u, y);
            self.partial.rows = rows;
            found?
        };
        let mut sub = match self.partial.take(k) {
            Some(sub) => sub,
            None => self.subset_filter(k)?,
        };
        let (y, r) = if angle_outputs.is_empty() { (y, &self.r) } else { (&self.angles.y, &self.angles.r) };
        let rows = &self.partial.rows;
        gather_rows(model.c(), rows, &mut sub.c);
        gather_block(r, rows, &mut sub.r);
        for (a, &i) in rows.iter().enumerate() {
            sub.y[a] = y[i];
        }
        let result = self.step_in(&mut sub, model, u);
        self.partial.put(k, sub);
        result?;
        if off_branch {
            self.mark_inconsistent();
        }
        Ok(&self.est)
    }

    /// The step in `sub` with the state moved in and back; on error the state is as it was.
    fn step_in<M: LinearModel + ?Sized>(
        &mut self,
        sub: &mut SubsetFilter<S>,
        model: &M,
        u: &DVector<f64>,
    ) -> Result<(), EstimatorError> {
        // This filter's settings as they are now (set without allocating; `R_SS` and `Q` were
        // accepted here already, so they are accepted there).
        sub.filter.set_noise(&self.q, &sub.r)?;
        sub.filter.policy = self.policy;
        sub.filter.time_budget = self.time_budget;
        std::mem::swap(&mut self.est, &mut sub.filter.est);
        sub.filter.steps = self.steps;
        sub.filter.guarantee_lost = self.guarantee_lost;
        let result = sub.filter.step(&StepModel::new(model.a(), model.b(), &sub.c), u, &sub.y).map(|_| ());
        std::mem::swap(&mut self.est, &mut sub.filter.est);
        if result.is_ok() {
            self.steps = sub.filter.steps;
            self.guarantee_lost = sub.filter.guarantee_lost;
            self.pending.armed = false;
        }
        result
    }

    /// A filter of `k` outputs with this one's input model (its other settings are copied at
    /// every step) and a solver of its own.
    fn subset_filter(&self, k: usize) -> Result<SubsetFilter<S>, EstimatorError> {
        let Some(solver) = self.solver.for_fewer_outputs() else {
            return Err(EstimatorError::Unsupported {
                estimator: "the set-membership filter with this solver",
                operation: "a partial measurement",
                reason: "its solver cannot be made again for fewer outputs: use the two-multiplier solver",
            });
        };
        let (n, rows) = (self.n, &self.partial.rows);
        let mut r = DMatrix::zeros(k, k);
        gather_block(&self.r, rows, &mut r);
        let setup = Setup {
            x0: self.est.center.clone(),
            p0: self.est.shape.clone(),
            process_noise: self.q.clone(),
            measurement_noise: r.clone(),
            inputs: self.p,
        };
        let mut filter = SetMembershipFilter::with_solver(setup, solver)?;
        filter.input = self.input.clone();
        filter.follow_kernels_of(self);
        Ok(SubsetFilter { filter, c: DMatrix::zeros(k, n), y: DVector::zeros(k), r })
    }
}
