//! Limits against hostile model files, checked before anything is handed to the expression
//! library.

/// Largest model file, in bytes (1 MiB).
pub const MAX_FILE_BYTES: usize = 1 << 20;
/// Longest expression, in bytes, after the definitions and parameters are substituted (64 KiB).
pub const MAX_EXPRESSION_BYTES: usize = 64 << 10;
/// Most states, most inputs, most outputs (each).
pub const MAX_NAMES: usize = 256;
/// Most parameters, most definitions (each).
pub const MAX_SYMBOLS: usize = 4096;
/// Deepest nesting of parentheses in an expression after substitution.
pub const MAX_DEPTH: usize = 256;
/// Most operators (`+ - * / ^ ,` and function calls) in one expression after substitution.
pub const MAX_OPERATORS: usize = 4096;
