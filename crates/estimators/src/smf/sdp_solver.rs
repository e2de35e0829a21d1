//! Solving (29) with any [`lmi::SdpBackend`]: the filter SDP (28) of
//! [`super::lmi28::FilterSdp`] is built on the first step, its numbers rewritten at each
//! later step, the backend set up once and called every step. Only `τ` is used (and `L`
//! read back with [`FilterSdp::read_gain`] for diagnostics): the SDP's `L` is not the exact
//! closed-form gain for its `τ` ([`UpdateSolver::gain_is_closed_form`] is `false`), so the filter
//! replaces it by that gain, then recomputes and certifies `P_{k+1}` itself.
//!
//! The first step allocates (building (28), setting the backend up, the solution buffer); later
//! steps rewrite the problem's numbers in place ([`FilterSdp::update`]) and, with a backend
//! whose solve does not allocate (the default [`lmi::DEFAULT_BACKEND`]), perform no heap
//! allocation (checked by `tests/alloc.rs`).

use super::lmi28::{FilterSdp, FilterSdpData};
use lmi::{SdpBackend, SdpSolution, SolverSettings};

use super::update::{UpdateProblem, UpdateSolution, UpdateSolver, UpdateStatus};
use crate::error::EstimatorError;

/// An [`UpdateSolver`] backed by an SDP solver.
pub struct SdpUpdateSolver {
    backend: Box<dyn SdpBackend>,
    sdp: Option<FilterSdp>,
    solution: Option<SdpSolution>,
}

impl std::fmt::Debug for SdpUpdateSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SdpUpdateSolver").field("backend", &self.backend.name()).finish()
    }
}

impl SdpUpdateSolver {
    /// Wraps a backend.
    pub fn new(backend: Box<dyn SdpBackend>) -> Self {
        Self { backend, sdp: None, solution: None }
    }

    /// The backend called `name` (see [`lmi::backend_names`]) with the given settings.
    pub fn by_name(name: &str, settings: SolverSettings) -> Result<Self, EstimatorError> {
        Ok(Self::new(lmi::backend_by_name(name, settings)?))
    }

    /// The backend's name.
    pub fn backend_name(&self) -> &'static str {
        self.backend.name()
    }

    /// The last raw SDP solution (for diagnostics).
    pub fn last_solution(&self) -> Option<&SdpSolution> {
        self.solution.as_ref()
    }
}

impl UpdateSolver for SdpUpdateSolver {
    fn name(&self) -> &str {
        self.backend.name()
    }

    fn prepare(&mut self, _n: usize, _m: usize) -> Result<(), EstimatorError> {
        // The SDP needs the first step's matrices; it is built then.
        self.sdp = None;
        self.solution = None;
        Ok(())
    }

    fn solve(
        &mut self,
        pr: &UpdateProblem<'_>,
        _warm: [f64; 3],
        out: &mut UpdateSolution,
    ) -> Result<(), EstimatorError> {
        let data = FilterSdpData { a: pr.a, c: pr.c, q: pr.q, r: pr.r, p: pr.p, x_hat: pr.x_hat };
        out.status = UpdateStatus::Unsolved;
        out.iterations = 0;
        match self.sdp.as_mut() {
            Some(sdp) => sdp.update(&data)?,
            None => {
                let sdp = FilterSdp::new(&data)?;
                self.backend.setup(sdp.problem())?;
                self.solution = Some(SdpSolution::new(sdp.problem()));
                self.sdp = Some(sdp);
            }
        }
        let (Some(sdp), Some(sol)) = (self.sdp.as_ref(), self.solution.as_mut()) else {
            return Err(EstimatorError::NumericalFailure("SDP not set up"));
        };
        self.backend.solve(sdp.problem(), sol)?;
        out.status = sol.status.into();
        out.iterations = sol.iterations;
        if sol.status.is_optimal() {
            out.tau = sdp.read_gain(&sol.x, &mut out.l)?;
        }
        Ok(())
    }
}
