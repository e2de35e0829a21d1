//! A small Mamdani fuzzy inference engine whose system is data.
//!
//! A [`FuzzySystem`] is a list of [`InputVariable`]s (named triangular/trapezoidal
//! [`MembershipFunction`]s on a range), an [`OutputVariable`] (named sets on a universe), a list of
//! [`Rule`]s (`IF x IS A AND y IS B THEN out IS C`) and the output to return when no rule fires. It is
//! validated at construction ([`FuzzyError`] names what is wrong; nothing panics on input) and can be
//! loaded from TOML ([`FuzzySystem::from_toml_str`], [`FuzzySystem::from_toml_file`]), so rules change
//! without recompiling.
//!
//! Inference: AND = min, implication = min (clipping), aggregation = max, then the centroid of the
//! aggregated membership by one of three [`Defuzzifier`]s: sampled on `n` points (the reference),
//! exact for the piecewise-linear aggregate (the default), or a precomputed grid with multilinear
//! interpolation. [`FuzzySystem::evaluate`] allocates nothing.
//!
//! Inputs are evaluated in the order of the system's variables; a consumer that feeds fixed
//! quantities binds them by name ([`Interface`], [`FuzzySystem::bind`],
//! [`FuzzySystem::from_toml_str_for`]), so that a rule file's inputs may come in any order.
//!
//! Limits (each an error naming it, never a hang or an abort): [`MAX_RULES`] rules,
//! [`MAX_INPUT_SETS`] input sets, [`MAX_OUTPUT_SETS`] output sets, [`MAX_SAMPLED_POINTS`] points
//! of the sampled centroid, `2^22` nodes of the grid centroid, [`MAX_FILE_BYTES`] of a system
//! file.
//!
//! [`FuzzySystem::bds_ins_default`] is the 45-rule measurement-noise scaling system of the BDS/INS
//! fuzzy Kalman filter (`docs/bds-ins-fuzzy-kf.md`), also shipped as `systems/bds_ins.toml`:
//!
//! ```
//! use fuzzy_inference::FuzzySystem;
//! let fis = FuzzySystem::bds_ins_default();
//! // 20 satellites, RTK float, 5 cm from the INS prediction: t ≈ 5.
//! let e = fis.evaluate(&[20.0, 4.0, 0.05]).unwrap();
//! assert!((e.output - 5.01).abs() < 0.01);
//! ```

mod bds_ins;
mod defuzz;
mod error;
mod interface;
mod membership;
mod system;
mod toml_io;

pub use bds_ins::BDS_INS_NO_RULE_OUTPUT;
pub use defuzz::MAX_OUTPUT_SETS;
pub use error::{FuzzyError, LoadError, Location};
pub use interface::{BDS_INS_INTERFACE, Interface, Quantity};
pub use membership::MembershipFunction;
pub use system::{
    Antecedent, Defuzzifier, Evaluation, FuzzySystem, InputVariable, MAX_INPUT_SETS, MAX_RULES, MAX_SAMPLED_POINTS,
    OutputScale, OutputVariable, Rule,
};
pub use toml_io::MAX_FILE_BYTES;
