//! `cargo xtask`: the repository's automation entry point.
fn main() {}
