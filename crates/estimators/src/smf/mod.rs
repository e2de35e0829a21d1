//! The improved set-membership filter of the paper, eqs (13)–(29), with certified containment.
//!
//! # One step
//!
//! Given `x_k ∈ 𝓔(x̂_k, P_k)`, `w_k ∈ 𝓔(0, Q)`, `v_{k+1} ∈ 𝓔(0, R)`:
//!
//! 1. `X₁ = A P_k Aᵀ`; an [`UpdateSolver`] solves (29) and returns `(L, τ)` (its `P` is not
//!    used). Unless the solver declares its `L` to be the closed-form gain for its `τ`
//!    ([`UpdateSolver::gain_is_closed_form`], true for the [`TwoMultiplierSolver`]), only `τ` is
//!    kept: `L` is replaced by the closed-form gain (G1) for the clamped `τ` (module
//!    [`two_multiplier`]), which for fixed `τ` minimises `Φ` below (in the
//!    Loewner order), so it is never worse than the solver's `L` and not sensitive to the
//!    `1/τᵢ` amplification of an inexact `L` when a multiplier is tiny;
//! 2. certification (below) recomputes `P_{k+1}` from `(L, τ)` and inflates it;
//! 3. the centre is (13) with the optimal free column zero:
//!    `x̂_{k+1} = (I − L C)(A x̂_k + B u_k) + L y_{k+1}`.
//!
//! # Certification
//!
//! Whatever solver produced `(L, τ)`, `τ` is first clamped onto the simplex by `clamp_tau`:
//! negative entries are set to 0, `τ` is rescaled to `Στ = 1` (scaling `τ` up by `c` divides `Φ`
//! by `c`, so this never hurts; the rescaling divides by the largest entry first, so it cannot
//! overflow), `τ₃ < ε·`[`TAU_FLOOR`] (below the rounding unit of the smallest allowed `τ₁`, `τ₂`) is
//! set to 0, then `τ₁, τ₂` are raised to [`TAU_FLOOR`] and the excess is taken off the largest
//! entry. The result satisfies, for any finite input that is not all zero or negative:
//! `τ₁ ≥ TAU_FLOOR`, `τ₂ ≥ TAU_FLOOR`, `τ₃ = 0` or `τ₃ ≥ ε·TAU_FLOOR`, and the floating-point sum
//! `τ₁ + τ₂ + τ₃ ≤ 1 − 2ε`, so the exact sum of the stored values is below 1. If `τ₃ = 0` the
//! measurement is not used and `L` is set to 0, the only gain (27) allows then. With
//! `K = I − L C`, (27) with the free column zero holds if and only if (Schur complement)
//!
//! ```text
//! P ⪰ Φ = K X₁ Kᵀ/τ₁ + K Q Kᵀ/τ₂ + L R Lᵀ/τ₃            (X₁ = A P_k Aᵀ exactly)
//! ```
//!
//! `Φ̂` is computed in floating point (unit roundoff `u = 2⁻⁵³`, `γ_k = k u/(1 − k u)`), with the
//! standard bounds `|fl(AB) − AB| ≤ γ_k |A||B|` and `‖|A||B|‖_F ≤ ‖A‖_F ‖B‖_F`:
//!
//! ```text
//! e_X = γ_{2n} ‖A‖²‖P_k‖                         (X̂₁ = fl(fl(A P_k) Aᵀ))
//! e_K = γ_{m+1} (√n + ‖L‖‖C‖),  κ = ‖K̂‖ + e_K     (K̂ = fl(I − L C))
//! E₁ = [γ_{2n+2}‖K̂‖²‖X̂₁‖ + (2‖K̂‖e_K + e_K²)‖X̂₁‖ + κ² e_X]/τ₁
//! E₂ = [γ_{2n+2}‖K̂‖²‖Q‖ + (2‖K̂‖e_K + e_K²)‖Q‖]/τ₂
//! E₃ = γ_{2m+2}‖L‖²‖R‖/τ₃
//! E  = E₁ + E₂ + E₃ + γ₄ (‖T̂₁‖ + ‖T̂₂‖ + ‖T̂₃‖)      (sums, divisions, symmetrisation)
//! ```
//!
//! (all norms Frobenius, which bound the spectral norm). `P_c = sym(Φ̂) + ε₂ I` with
//! `ε₂ = 2E + 4u‖Φ̂‖` (safety factor 2 for the rounding of the bound itself and second-order
//! terms) satisfies `P_c ⪰ Φ`. The centre has its own rounding error `δ`, bounded by
//!
//! ```text
//! e_z = γ_{n+p}(‖A‖‖x̂_k‖ + ‖B‖‖u‖),  ρ = 2[γ_{n+m+1}(‖K̂‖‖ẑ‖ + ‖L‖‖y‖) + e_K‖ẑ‖ + κ e_z]
//! ```
//!
//! and the error `e + δ` of the computed centre lies in the Minkowski sum
//! `𝓔(0, P_c) ⊕ 𝓔(0, ρ² I) ⊆ 𝓔(0, (1+s) P_c + (1+1/s) ρ² I)` for any `s > 0`; we take
//! `s = ρ √(n / tr P_c)` (the trace-optimal choice for the ball) and add `4u(1+s)‖P_c‖` to
//! the diagonal for the rounding of that last operation. So
//!
//! ```text
//! P_{k+1} = (1 + s) Φ̂ + ε I,   ε = (1+s) ε₂ + (1+1/s) ρ² + 4u(1+s)‖P_c‖
//! ```
//!
//! reported as [`Inflation`] `{ relative: s, absolute: ε }`; both are of order `10⁻¹⁵` relative
//! in ordinary cases. `x_{k+1} ∈ 𝓔(x̂_{k+1}, P_{k+1})` then holds exactly, whenever
//! `x_k ∈ 𝓔(x̂_k, P_k)`, for the stored `x̂_k`, `P_k`.
//!
//! # Fallback
//!
//! The solver's result is used when its status is [`UpdateStatus::Solved`] or
//! [`UpdateStatus::AlmostSolved`]. Accepting "almost solved" is safe: the published shape is
//! certified from `(L, τ)` whatever their quality (any point of the simplex is feasible), so an
//! inexact solve can only cost optimality, never containment.
//!
//! If the solver fails (another status, an error, or the optional per-step time budget
//! exceeded) or its `(L, τ)` is invalid (not finite; `τ` outside the simplex by more than
//! `10⁻⁶` — a negative entry or `Στ > 1 + 10⁻⁶` —, which a solver that reports success must not
//! return; the closed-form gain for its `τ` failing), the filter uses the previous step's `τ` (or `(⅓, ⅓, ⅓)` if it is not usable) with the closed-form optimal gain
//! for that `τ` (or, if even that fails, `τ = (½, ½, 0)`, `L = 0`: pure prediction). The same
//! happens if a finite `(L, τ)` that passed these checks gives a certified shape, centre or
//! inflation that is not finite (an overflow): the certification is redone with the fallback
//! `τ` and its gain ([`FallbackReason::InvalidSolution`]). Only if that fails too does the step
//! return [`EstimatorError::NumericalFailure`](crate::EstimatorError::NumericalFailure), with the filter unchanged. A solver whose gain is
//! closed-form but that returns `τ₃ = 0` (after clamping) with a non-zero `L` keeps its `τ` with
//! `L = 0`, the closed-form gain for `τ₃ = 0`, also reported as
//! [`FallbackReason::InvalidSolution`]. Every point of the simplex is feasible, so containment
//! still holds; [`StepReport::fallback`] says why.
//!
//! # Inputs
//!
//! With [`InputModel::BoundedDisturbance`] the guarantee covers only inputs in the declared box:
//! an input outside it is refused with [`EstimatorError::InputOutsideBounds`](crate::EstimatorError::InputOutsideBounds) before anything
//! changes.

mod angles;
pub mod certify;
pub mod consistency;
pub mod fallback;
pub mod filter;
pub(crate) mod gain;
pub mod input;
mod kernels;
pub mod lmi28;
pub mod nonlinear;
pub mod observer;
mod partial;
pub mod sdp_solver;
pub mod two_multiplier;
pub mod update;

pub use certify::Inflation;
pub use consistency::{Consistency, InconsistencyPolicy};
pub use fallback::FallbackReason;
pub use filter::{DETAILS, DIVERGENCE_FACTOR, SetEstimate, SetMembershipFilter, StepReport};
pub use input::InputModel;
pub use nonlinear::{NonlinearSetMembershipFilter, NonlinearSmfSettings, RemainderBounds};
pub use observer::ObservedSetMembershipFilter;
pub use sdp_solver::SdpUpdateSolver;
pub use two_multiplier::{TAU_FLOOR, TwoMultiplierSolver};
pub use update::{UpdateProblem, UpdateSolution, UpdateSolver, UpdateStatus};
