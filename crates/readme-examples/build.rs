//! Extracts every ```` ```rust ```` block of the top-level README into `$OUT_DIR/examples.rs`,
//! each as a function `example_N` (rustdoc's hidden `# ` lines shown, the block's value its
//! result), so that `src/lib.rs` compiles them with the facade as the only dependency.

use std::fmt::Write as _;
use std::path::Path;

fn main() {
    let readme = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../README.md");
    println!("cargo::rerun-if-changed={}", readme.display());
    let text = std::fs::read_to_string(&readme).unwrap_or_else(|e| panic!("{}: {e}", readme.display()));
    let mut out = String::new();
    let mut block: Option<(usize, String)> = None;
    let mut count = 0;
    for (i, line) in text.lines().enumerate() {
        match &mut block {
            None if line.trim_start() == "```rust" => block = Some((i + 2, String::new())),
            None => {}
            Some((start, code)) if line.trim_start() == "```" => {
                count += 1;
                let _ = writeln!(
                    out,
                    "/// README.md, the Rust block from line {start}.\n\
                     #[allow(clippy::all, clippy::pedantic)]\n\
                     pub fn example_{count}() -> Outcome {{\n\
                     let run = || {{\n{code}}};\nrun()?;\nOk(())\n}}\n"
                );
                block = None;
            }
            Some((_, code)) => {
                let line = line.strip_prefix("# ").or_else(|| (line == "#").then_some("")).unwrap_or(line);
                code.push_str(line);
                code.push('\n');
            }
        }
    }
    let all: Vec<String> = (1..=count).map(|i| format!("example_{i}")).collect();
    let _ = writeln!(
        out,
        "/// Every Rust block of the README, in order.\n\
         pub const EXAMPLES: &[Example] = &[{}];",
        all.join(", ")
    );
    let dest = Path::new(&std::env::var("OUT_DIR").expect("OUT_DIR")).join("examples.rs");
    std::fs::write(&dest, out).unwrap_or_else(|e| panic!("{}: {e}", dest.display()));
}
