//! A model seen through the capabilities it offers, for estimators chosen at run time.
//!
//! Each estimator asks only for the capability it needs (argmin's pattern): the Kalman and
//! set-membership filters need a [`LinearModel`], the extended Kalman filter a
//! [`DifferentiableModel`], the unscented filter only a [`DiscreteModel`]. An estimator chosen by
//! name (a command line, the Python package) receives the model as `&dyn AnyModel` and takes the
//! capability it needs, or reports which one is missing. Every linear model is differentiable and
//! discrete, every differentiable model discrete.
//!
//! The workspace's models implement [`AnyModel`] themselves; for any other model, wrap a reference
//! in the view of its strongest capability: [`LinearView`], [`DifferentiableView`] or
//! [`DiscreteView`].
//!
//! ```
//! use models::{AnyModel, Capability, ConstantModel, DiscreteView};
//! use nalgebra::DMatrix;
//!
//! let m = ConstantModel::new(DMatrix::identity(2, 2), DMatrix::zeros(2, 1), DMatrix::identity(1, 2)).unwrap();
//! assert_eq!(Capability::of(&m), Capability::Linear);
//! // The same model offered as f and h only.
//! assert_eq!(Capability::of(&DiscreteView(&m)), Capability::Discrete);
//! assert!(Capability::Discrete.is_offered_by(&m));
//! ```

use crate::enclosure::SecondOrderModel;
use crate::model::{ConstantModel, DifferentiableModel, DiscreteModel, LinearModel, StepMatrices, StepModel};

/// What an estimator may ask of a model, weakest first.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[non_exhaustive]
pub enum Capability {
    /// `f` and `h` ([`DiscreteModel`]).
    Discrete,
    /// `f`, `h` and their Jacobians ([`DifferentiableModel`]).
    Differentiable,
    /// `f`, `h`, their Jacobians and rigorous enclosures of them and of their Hessians over boxes
    /// ([`SecondOrderModel`]; every linear model offers them, with zero Hessians).
    SecondOrder,
    /// `A`, `B`, `C` ([`LinearModel`]).
    Linear,
}

impl Capability {
    /// A short label: `discrete`, `differentiable`, `linear`.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            Capability::Discrete => "discrete",
            Capability::Differentiable => "differentiable",
            Capability::SecondOrder => "second-order",
            Capability::Linear => "linear",
        }
    }

    /// What a model must provide, in words (for error messages).
    #[must_use]
    pub fn requirement(self) -> &'static str {
        match self {
            Capability::Discrete => "f and h",
            Capability::Differentiable => "f, h and their Jacobians",
            Capability::SecondOrder => "f, h and enclosures of their Jacobians and Hessians over boxes",
            Capability::Linear => "the matrices A, B, C of a linear model",
        }
    }

    /// The strongest capability `model` offers.
    #[must_use]
    pub fn of(model: &dyn AnyModel) -> Self {
        if model.linear().is_some() {
            Capability::Linear
        } else if model.second_order().is_some() {
            Capability::SecondOrder
        } else if model.differentiable().is_some() {
            Capability::Differentiable
        } else {
            Capability::Discrete
        }
    }

    /// Whether `model` offers this capability.
    #[must_use]
    pub fn is_offered_by(self, model: &dyn AnyModel) -> bool {
        self <= Capability::of(model)
    }
}

/// A model that says which capabilities it offers (module documentation). Object safe:
/// estimators built at run time step on `&dyn AnyModel`.
pub trait AnyModel {
    /// The model as `f` and `h`.
    fn discrete(&self) -> &dyn DiscreteModel;
    /// The model with Jacobians, if it has them.
    fn differentiable(&self) -> Option<&dyn DifferentiableModel> {
        None
    }
    /// The model with enclosures of its derivatives over boxes, if it has them.
    fn second_order(&self) -> Option<&dyn SecondOrderModel> {
        None
    }
    /// The model's matrices, if it is linear.
    fn linear(&self) -> Option<&dyn LinearModel> {
        None
    }
}

/// Implements [`AnyModel`] for linear model types (all three capabilities).
macro_rules! any_linear {
    ($($t:ty),*) => {$(
        impl AnyModel for $t {
            fn discrete(&self) -> &dyn DiscreteModel {
                self
            }
            fn differentiable(&self) -> Option<&dyn DifferentiableModel> {
                Some(self)
            }
            fn second_order(&self) -> Option<&dyn SecondOrderModel> {
                Some(self)
            }
            fn linear(&self) -> Option<&dyn LinearModel> {
                Some(self)
            }
        }
    )*};
}

any_linear!(StepModel<'_>, StepMatrices, ConstantModel);

/// Any [`LinearModel`] offered with all three capabilities.
#[derive(Debug, Clone, Copy)]
pub struct LinearView<'a, M: ?Sized>(pub &'a M);

/// Any [`DifferentiableModel`] offered as differentiable (and discrete).
#[derive(Debug, Clone, Copy)]
pub struct DifferentiableView<'a, M: ?Sized>(pub &'a M);

/// Any [`DiscreteModel`] offered as `f` and `h` only.
#[derive(Debug, Clone, Copy)]
pub struct DiscreteView<'a, M: ?Sized>(pub &'a M);

impl<M: LinearModel + ?Sized> LinearModel for LinearView<'_, M> {
    fn a(&self) -> &nalgebra::DMatrix<f64> {
        self.0.a()
    }
    fn b(&self) -> &nalgebra::DMatrix<f64> {
        self.0.b()
    }
    fn c(&self) -> &nalgebra::DMatrix<f64> {
        self.0.c()
    }
    fn angles(&self) -> crate::Angles<'_> {
        LinearModel::angles(self.0)
    }
}

impl<M: LinearModel + ?Sized> AnyModel for LinearView<'_, M> {
    fn discrete(&self) -> &dyn DiscreteModel {
        self
    }
    fn differentiable(&self) -> Option<&dyn DifferentiableModel> {
        Some(self)
    }
    fn second_order(&self) -> Option<&dyn SecondOrderModel> {
        Some(self)
    }
    fn linear(&self) -> Option<&dyn LinearModel> {
        Some(self)
    }
}

/// Forwards [`DiscreteModel`] from a view to the model it wraps.
macro_rules! forward_discrete {
    ($view:ident, $bound:ident) => {
        impl<M: $bound + ?Sized> DiscreteModel for $view<'_, M> {
            fn dims(&self) -> crate::Dims {
                self.0.dims()
            }
            fn f(
                &self,
                x: &nalgebra::DVector<f64>,
                u: &nalgebra::DVector<f64>,
                out: &mut nalgebra::DVector<f64>,
            ) -> Result<(), crate::ModelError> {
                self.0.f(x, u, out)
            }
            fn h(
                &self,
                x: &nalgebra::DVector<f64>,
                u: &nalgebra::DVector<f64>,
                out: &mut nalgebra::DVector<f64>,
            ) -> Result<(), crate::ModelError> {
                self.0.h(x, u, out)
            }
            fn angles(&self) -> crate::Angles<'_> {
                self.0.angles()
            }
        }
    };
}

forward_discrete!(DiscreteView, DiscreteModel);
forward_discrete!(DifferentiableView, DifferentiableModel);

impl<M: DiscreteModel + ?Sized> AnyModel for DiscreteView<'_, M> {
    fn discrete(&self) -> &dyn DiscreteModel {
        self
    }
}

impl<M: DifferentiableModel + ?Sized> AnyModel for DifferentiableView<'_, M> {
    fn discrete(&self) -> &dyn DiscreteModel {
        self
    }
    fn differentiable(&self) -> Option<&dyn DifferentiableModel> {
        Some(self)
    }
}

impl<M: DifferentiableModel + ?Sized> DifferentiableModel for DifferentiableView<'_, M> {
    fn f_jacobian(
        &self,
        x: &nalgebra::DVector<f64>,
        u: &nalgebra::DVector<f64>,
        out: &mut nalgebra::DMatrix<f64>,
    ) -> Result<(), crate::ModelError> {
        self.0.f_jacobian(x, u, out)
    }
    fn h_jacobian(
        &self,
        x: &nalgebra::DVector<f64>,
        u: &nalgebra::DVector<f64>,
        out: &mut nalgebra::DMatrix<f64>,
    ) -> Result<(), crate::ModelError> {
        self.0.h_jacobian(x, u, out)
    }
    fn f_with_jacobian(
        &self,
        x: &nalgebra::DVector<f64>,
        u: &nalgebra::DVector<f64>,
        out: &mut nalgebra::DVector<f64>,
        jacobian: &mut nalgebra::DMatrix<f64>,
    ) -> Result<(), crate::ModelError> {
        self.0.f_with_jacobian(x, u, out, jacobian)
    }
    fn h_with_jacobian(
        &self,
        x: &nalgebra::DVector<f64>,
        u: &nalgebra::DVector<f64>,
        out: &mut nalgebra::DVector<f64>,
        jacobian: &mut nalgebra::DMatrix<f64>,
    ) -> Result<(), crate::ModelError> {
        self.0.h_with_jacobian(x, u, out, jacobian)
    }
}

impl<M: crate::DifferentiableContinuousModel> AnyModel for crate::Discretized<M> {
    fn discrete(&self) -> &dyn DiscreteModel {
        self
    }
    fn differentiable(&self) -> Option<&dyn DifferentiableModel> {
        Some(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    #[test]
    fn capabilities_are_ordered_and_offered() {
        let m = ConstantModel::new(DMatrix::identity(2, 2), DMatrix::zeros(2, 1), DMatrix::identity(1, 2)).unwrap();
        assert_eq!(Capability::of(&m), Capability::Linear);
        assert_eq!(Capability::of(&LinearView(&m)), Capability::Linear);
        assert_eq!(Capability::of(&DifferentiableView(&m)), Capability::Differentiable);
        assert_eq!(Capability::of(&DiscreteView(&m)), Capability::Discrete);
        assert!(Capability::Linear.is_offered_by(&m));
        assert!(!Capability::Linear.is_offered_by(&DifferentiableView(&m)));
        assert!(Capability::Differentiable.is_offered_by(&DifferentiableView(&m)));
        assert!(!Capability::Differentiable.is_offered_by(&DiscreteView(&m)));
        // The views evaluate the wrapped model.
        let (x, u) = (DVector::from_vec(vec![1.0, 2.0]), DVector::zeros(1));
        let mut out = DVector::zeros(1);
        DiscreteView(&m).h(&x, &u, &mut out).unwrap();
        assert_eq!(out[0], 1.0);
        let mut j = DMatrix::zeros(2, 2);
        DifferentiableView(&m).f_jacobian(&x, &u, &mut j).unwrap();
        assert_eq!(j, DMatrix::identity(2, 2));
    }
}
