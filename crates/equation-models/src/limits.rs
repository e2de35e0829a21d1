//! Limits against hostile model files, checked before anything is handed to the expression
//! library.

/// Largest model file, in bytes (1 MiB).
pub const MAX_FILE_BYTES: usize = 1 << 20;
/// Longest expression, in bytes, after the definitions and parameters are substituted (64 KiB).
pub const MAX_EXPRESSION_BYTES: usize = 64 << 10;
/// Most states, most inputs, most outputs (each).
pub const MAX_NAMES: usize = 256;
/// Most parameters, most definitions (each).
pub const MAX_SYMBOLS: usize = 1024;
/// Deepest nesting of parentheses in an expression after substitution.
pub const MAX_DEPTH: usize = 256;
/// Most operators (`+ - * / ^ ,` and function calls) in one expression after substitution.
/// The expression library's symbolic differentiation grows faster than linearly with the size
/// of an expression (a sum of 256 terms takes about half a second), hence this modest bound.
pub const MAX_OPERATORS: usize = 256;
/// Wall-clock budget, in seconds, for parsing and differentiating all the equations of a
/// model. The work runs on a worker thread with its own large stack
/// ([`COMPILE_STACK_BYTES`]); past the budget the model is refused and the worker is left to
/// finish in the background (its result is discarded).
pub const MAX_COMPILE_SECONDS: u64 = 10;
/// Stack of the worker thread that parses and differentiates (the expression library recurses
/// over the expression's structure).
pub const COMPILE_STACK_BYTES: usize = 256 << 20;
