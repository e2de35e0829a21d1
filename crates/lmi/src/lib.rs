//! Block-diagonal semidefinite programs, stated once and solved by interchangeable backends.
//!
//! * [`problem`]: the data-only problem in SDPA standard form ([`SdpProblem`]), with the
//!   naming of "primal" and "dual" used throughout.
//! * [`solver`]: the [`SdpBackend`] trait (set up once per structure, solve many times),
//!   [`SolverSettings`] and the outcome ([`SdpSolution`], [`SolveStatus`]).
//!
//! This crate knows nothing about vehicles: it states semidefinite programs and solves them.

pub mod builder;
pub mod certificate;
pub mod error;
pub mod ipm;
pub mod problem;
pub mod registry;
mod scaling;
pub mod sdpa;

pub mod solver;
pub mod svec;

#[cfg(feature = "clarabel")]
pub mod clarabel_backend;
#[cfg(feature = "clarabel")]
pub use clarabel_backend::ClarabelBackend;

pub use certificate::{CertificateFailure, RejectedCertificate, check_certificate};
pub use error::LmiError;
pub use ipm::{FaerIpm, SearchDirection};
pub use problem::{Block, Entry, SdpProblem};
pub use registry::{DEFAULT_BACKEND, backend_by_name, backend_names};
pub use sdpa::{read_sdpa, read_sdpa_file, write_sdpa};
pub use solver::{
    DEFAULT_MEMORY_LIMIT, SdpBackend, SdpSolution, SolveStart, SolveStatus, SolverSettings, SolverSettingsBuilder,
};
