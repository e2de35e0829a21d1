//! Shared helpers of port-est's integration tests: the model files they start from and fresh
//! scratch folders.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// The text of a damped oscillator's model file (two states, one input, one output), as a
/// literal for `concat!`.
macro_rules! oscillator_text {
    () => {
        "a  = [[1.0, 0.01], [-0.01, 0.998]]
b  = [[0.0], [0.01]]
c  = [[1.0, 0.0]]
q  = [[1e-6, 0.0], [0.0, 1e-4]]
r  = [[4e-4]]
p0 = [[0.25, 0.0], [0.0, 0.25]]
x0 = [0.0, 0.0]
"
    };
}

/// A damped oscillator (two states, one input, one output) as a model file.
pub const OSCILLATOR: &str = oscillator_text!();

/// The oscillator with an `[mhe]` table of its noise boxes.
pub const OSCILLATOR_WITH_NOISE_BOXES: &str = concat!(
    oscillator_text!(),
    "[mhe]
w_lower = [-1e-3, -1e-2]
w_upper = [1e-3, 1e-2]
v_lower = [-0.02]
v_upper = [0.02]
"
);

/// A double integrator (position measured, acceleration as input) as a model file.
pub const DOUBLE_INTEGRATOR: &str = include_str!("../fixtures/double_integrator.toml");

/// An empty folder `name` under `group` in the tests' scratch space (emptied if it was there).
pub fn fresh_dir(group: &str, name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(group).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}
