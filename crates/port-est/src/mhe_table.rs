//! The optional `[mhe]` table of `MODEL.toml`: the settings of the moving-horizon estimators
//! (`--estimator rmhe` and `mhe`), read by the registry's settings reader
//! ([`estimators::registry::read_moving_horizon`], the keywords of `port-est estimators`) through
//! [`crate::keyword_table`], every complaint at the `file:line:column` of the key's value. The
//! settings' own validation (`MheSettings::validate`: blocks summing to the horizon, boxes
//! containing 0, `lambda_v > 1`, a diagonal `r`) runs when such an estimator is built, and its
//! message is reported at the key it names.
//!
//! Resources are checked before anything is allocated for them: the memory the estimator would
//! take ([`memory_estimate`], computed without overflow) against `--mhe-memory-limit`, block
//! lengths summed with checked arithmetic, `max_sweeps` against
//! [`MAX_MHE_SWEEPS`](crate::limits::MAX_MHE_SWEEPS).

pub use estimators::mhe::memory_estimate;

/// The model-file key a message of `MheSettings::validate` is about (`None`: the table).
pub(crate) fn key_of_message(message: &str) -> &'static [&'static str] {
    if message.contains("block") {
        &["mhe.blocks", "mhe.preset", "mhe.horizon"]
    } else if message.contains("horizon") {
        &["mhe.horizon"]
    } else if message.contains("lambda_v") {
        &["mhe.lambda_v", "mhe.alpha"]
    } else if message.contains("box W") {
        &["mhe.w_lower"]
    } else if message.contains("box V") {
        &["mhe.v_lower"]
    } else if message.contains("theta") {
        &["mhe.theta"]
    } else if message.contains("sweeps") || message.contains("iterations") {
        &["mhe.max_sweeps", "mhe.tolerance", "mhe.solver"]
    } else if message.starts_with("R") {
        &["r"]
    } else if message.starts_with("Q") {
        &["q"]
    } else if message.starts_with("P0") {
        &["p0"]
    } else if message.starts_with("x0") || message.contains("x0") {
        &["x0"]
    } else {
        &[]
    }
}
