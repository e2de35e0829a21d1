#![doc = include_str!("../README.md")]
//!
//! ## This crate
//!
//! A facade over the workspace crates, for users who want one dependency: [`models`] (model
//! traits, discretisation, simulation), [`carrier_dynamics`] (the straddle carrier),
//! [`truck_dynamics`] (the 3-axle port truck), [`car_dynamics`] (the robust-MHE paper's car),
//! [`ellipsoid`] (set algebra), [`constrained_zonotope`] (constrained zonotopes, verified hulls), [`lmi`] (semidefinite programs and their backends),
//! [`estimators`] (estimator traits, registry and filters), [`vessel_dynamics`] and
//! [`vessel_control`] (the supply vessel and its dynamic-positioning controller),
//! [`bds_ins_dynamics`] (the BDS/INS error model and BDS simulator), [`fuzzy_inference`] (the
//! Mamdani engine) and
//! [`dense_kernels`]. Including the
//! README here also compiles and runs its example as a doctest.

pub use bds_ins_dynamics;
pub use car_dynamics;
pub use carrier_dynamics;
pub use constrained_zonotope;
pub use dense_kernels;
pub use ellipsoid;
pub use estimators;
pub use fuzzy_inference;
pub use lmi;
pub use models;
pub use truck_dynamics;
pub use vessel_control;
pub use vessel_dynamics;

/// What a first estimate needs, in one `use port_estimation::prelude::*;`: the matrices and
/// their macros ([`dmatrix!`](crate::dmatrix), [`dvector!`](crate::dvector), which need no
/// `nalgebra` of the caller's own), the setup, the estimators and what their steps return, and
/// a nonlinear model from two closures ([`ClosureModel`](models::ClosureModel), Jacobians by
/// automatic differentiation).
pub mod prelude {
    pub use crate::{dmatrix, dvector};
    pub use estimators::nalgebra::{DMatrix, DVector};
    pub use estimators::{
        AnyEstimator, ConstrainedZonotopeFilter, Estimate, EstimateKind, Estimator, EstimatorError,
        ExtendedKalmanFilter, KalmanFilter, SetMembershipFilter, Setup, StepModel, UnscentedKalmanFilter,
    };
    pub use models::{
        Angles, ClosureModel, ConstantModel, DifferentiableModel, Dims, DiscreteModel, Dual, Integrator, LinearModel,
        ModelError,
    };
}

/// A `DMatrix<f64>` from rows separated by `;`, entries by `,`: `dmatrix![1.0, 0.1; 0.0, 1.0]`
/// (as nalgebra's macro of that name, which needs `nalgebra` among the caller's own
/// dependencies; this one only needs this crate). Rows of different lengths do not compile.
#[macro_export]
macro_rules! dmatrix {
    ($($($x:expr),+ $(,)?);+ $(;)?) => {{
        const _: () = ::core::assert!(
            $crate::__private::same_lengths(&[$([$(::core::stringify!($x)),+].len()),+]),
            "dmatrix!: every row needs the same number of entries"
        );
        let rows: &[&[f64]] = &[$(&[$($x),+]),+];
        $crate::__private::from_rows(rows)
    }};
}

/// A `DVector<f64>` of the entries: `dvector![0.0, 1.5]` (see [`dmatrix!`](crate::dmatrix)).
#[macro_export]
macro_rules! dvector {
    ($($x:expr),+ $(,)?) => {
        $crate::estimators::nalgebra::DVector::<f64>::from_column_slice(&[$($x),+])
    };
}

/// What the macros expand to; not part of the API.
#[doc(hidden)]
pub mod __private {
    use estimators::nalgebra::DMatrix;

    /// Whether every length equals the first (checked at compile time by `dmatrix!`).
    #[must_use]
    pub const fn same_lengths(lengths: &[usize]) -> bool {
        let mut i = 1;
        while i < lengths.len() {
            if lengths[i] != lengths[0] {
                return false;
            }
            i += 1;
        }
        true
    }

    /// The matrix of `rows` (all of one length, as `dmatrix!` checked).
    #[must_use]
    pub fn from_rows(rows: &[&[f64]]) -> DMatrix<f64> {
        let cols = rows.first().map_or(0, |r| r.len());
        DMatrix::from_fn(rows.len(), cols, |i, j| rows[i][j])
    }
}
