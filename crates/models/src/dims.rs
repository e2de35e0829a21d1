//! The sizes of a model, below everything that checks them.

/// Dimensions of a model: `n` states, `p` inputs, `m` outputs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Dims {
    /// States `n`.
    pub states: usize,
    /// Inputs `p`.
    pub inputs: usize,
    /// Outputs `m`.
    pub outputs: usize,
}

impl Dims {
    /// `(n, p, m)`.
    #[must_use]
    pub fn new(states: usize, inputs: usize, outputs: usize) -> Self {
        Self { states, inputs, outputs }
    }
}
