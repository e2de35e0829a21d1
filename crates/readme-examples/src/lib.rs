//! The top-level README's Rust examples as a user's crate compiles them: this crate's only
//! dependency is the facade `port-estimation`, so an example that needs anything else (its own
//! `nalgebra` for a macro, say) fails to build here. `build.rs` extracts the blocks; the tests
//! run each.

/// What an example returns: its error, if any.
pub type Outcome = Result<(), Box<dyn std::error::Error>>;

/// An example.
pub type Example = fn() -> Outcome;

include!(concat!(env!("OUT_DIR"), "/examples.rs"));

#[cfg(test)]
mod tests {
    #[test]
    fn every_example_of_the_readme_runs() {
        assert!(!super::EXAMPLES.is_empty(), "the README has no Rust example");
        for (i, example) in super::EXAMPLES.iter().enumerate() {
            if let Err(e) = example() {
                panic!("README Rust block {}: {e}", i + 1);
            }
        }
    }
}
