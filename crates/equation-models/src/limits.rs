//! Limits against hostile model files, checked while reading, before anything is evaluated.
//!
//! Each definition and equation is compiled on its own (definitions are shared values, not
//! substituted), so the per-expression limits apply to each expression as written; the total
//! number of operators bounds the size of the compiled graph, hence the time and memory of
//! compiling and of every evaluation.

/// Largest model file, in bytes (1 MiB).
pub const MAX_FILE_BYTES: usize = 1 << 20;
/// Longest expression (one definition or equation as written), in bytes (64 KiB).
pub const MAX_EXPRESSION_BYTES: usize = 64 << 10;
/// Most states, most inputs, most outputs (each).
pub const MAX_NAMES: usize = 256;
/// Most parameters, most definitions (each).
pub const MAX_SYMBOLS: usize = 1024;
/// Deepest nesting of parentheses in one expression.
pub const MAX_DEPTH: usize = 256;
/// Most operators (`+ - * / ^ ,` and function calls) in one expression as written.
pub const MAX_OPERATORS: usize = 256;
/// Most operators in all definitions and equations together: the compiled graph has at most
/// about twice as many nodes, and an evaluation of the Jacobians works on
/// `8 · nodes · (states + 1)` bytes of scratch memory per thread.
pub const MAX_TOTAL_OPERATORS: usize = 8192;
/// Wall-clock budget, in seconds, for reading and compiling a model file. Compiling is linear in
/// the size of the file, far below the budget; it runs on a worker thread with its own stack
/// ([`COMPILE_STACK_BYTES`]), and past the budget the model is refused and the worker is left to
/// finish in the background (its result is discarded).
pub const MAX_COMPILE_SECONDS: u64 = 10;
/// Stack of the worker thread that reads and compiles (the parser recurses over the nesting of
/// an expression, at most [`MAX_DEPTH`] levels).
pub const COMPILE_STACK_BYTES: usize = 16 << 20;
