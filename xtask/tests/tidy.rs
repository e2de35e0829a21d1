//! Repository checks as ordinary tests (rust-analyzer's "tidy" style):
//!
//! * **Layering.** Each library crate may depend (in `[dependencies]`; tests and benches may use
//!   more) only on the workspace crates its layer allows: the dense kernels at the bottom, then
//!   vehicle-free models and set algebra and SDPs, then vehicles (which know nothing of
//!   estimation), then estimators (which know nothing of vehicles), then the tools. A new crate
//!   must be added to [`LAYERS`].
//! * **Rooms of one job.** No Rust source file of the repository has more than 1 000 lines.
//! * **One registry.** Only `estimators::registry` dispatches on estimator names: library code of
//!   the command line, of the reproduction and of the Python binding compares, matches or looks up
//!   no estimator name written as a literal (it uses `registry::names` or the registry's rows).
//! * **No unwrap on input.** Library code (`crates/*/src`, outside `#[cfg(test)]` modules) has no
//!   `.unwrap()` or `.expect(` unless the line or the one above carries a
//!   `// tidy: invariant — <why it cannot fail>` comment.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Workspace crates and the workspace crates each may depend on. `*-dynamics` is any vehicle
/// crate.
const LAYERS: &[(&str, &[&str])] = &[
    ("dense-kernels", &[]),
    ("counting-allocator", &[]),
    ("fuzzy-inference", &[]),
    ("atomic-output", &[]),
    ("svg-plot", &[]),
    ("ros-bag", &["atomic-output"]),
    ("intervals", &[]),
    ("models", &["dense-kernels", "intervals"]),
    ("equation-models", &["models", "intervals"]),
    ("ellipsoid", &["dense-kernels"]),
    ("constrained-zonotope", &["intervals"]),
    ("lmi", &["dense-kernels"]),
    ("*-dynamics", &["models", "dense-kernels", "intervals"]),
    ("vessel-control", &["models", "dense-kernels", "vessel-dynamics", "estimators"]),
    (
        "estimators",
        &["models", "dense-kernels", "ellipsoid", "constrained-zonotope", "intervals", "lmi", "fuzzy-inference"],
    ),
    (
        "port-est",
        &[
            "estimators",
            "models",
            "dense-kernels",
            "ellipsoid",
            "lmi",
            "*-dynamics",
            "fuzzy-inference",
            "atomic-output",
            "equation-models",
            "ros-bag",
        ],
    ),
    (
        "port-estimation-py",
        &[
            "estimators",
            "models",
            "dense-kernels",
            "ellipsoid",
            "lmi",
            "port-est",
            "constrained-zonotope",
            "*-dynamics",
            "fuzzy-inference",
            "equation-models",
            "ros-bag",
        ],
    ),
    // The README's examples as a user's crate: the facade only.
    ("readme-examples", &["port-estimation"]),
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn layer_of(name: &str) -> Option<&'static [&'static str]> {
    let key = if name.ends_with("-dynamics") { "*-dynamics" } else { name };
    LAYERS.iter().find(|(n, _)| *n == key).map(|(_, deps)| *deps)
}

fn allowed(deps: &[&str], dep: &str) -> bool {
    deps.iter().any(|d| *d == dep || (*d == "*-dynamics" && dep.ends_with("-dynamics")))
}

/// `(crate name, its [dependencies] that are workspace crates)` for every crate under `crates/`.
fn crate_dependencies() -> BTreeMap<String, Vec<String>> {
    let mut out = BTreeMap::new();
    let crates_dir = root().join("crates");
    let names: Vec<String> = std::fs::read_dir(&crates_dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.path().join("Cargo.toml").is_file())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    for dir in &names {
        let manifest: toml::Table =
            std::fs::read_to_string(crates_dir.join(dir).join("Cargo.toml")).unwrap().parse().unwrap();
        let name = manifest["package"]["name"].as_str().unwrap().to_owned();
        let deps = manifest
            .get("dependencies")
            .and_then(|d| d.as_table())
            .map(|t| t.keys().filter(|k| names.iter().any(|n| n == *k)).cloned().collect())
            .unwrap_or_default();
        out.insert(name, deps);
    }
    out
}

#[test]
fn crates_respect_the_layering() {
    let mut violations = Vec::new();
    let deps = crate_dependencies();
    assert!(deps.len() >= 6, "found only {:?}", deps.keys());
    for (name, ds) in &deps {
        let Some(layer) = layer_of(name) else {
            violations.push(format!("crate {name} is not in the tidy test's LAYERS table: add it with its layer"));
            continue;
        };
        for d in ds {
            if !allowed(layer, d) {
                violations.push(format!("{name} depends on {d}, which its layer does not allow"));
            }
        }
    }
    assert!(violations.is_empty(), "layering violations:\n{}", violations.join("\n"));
}

#[test]
fn layering_rules_reject_what_the_architecture_forbids() {
    // The checker itself: models must not reach estimators, lmi not filters, estimators not
    // vehicles.
    assert!(!allowed(layer_of("models").unwrap(), "estimators"));
    assert!(!allowed(layer_of("lmi").unwrap(), "estimators"));
    assert!(!allowed(layer_of("estimators").unwrap(), "carrier-dynamics"));
    assert!(!allowed(layer_of("truck-dynamics").unwrap(), "estimators"));
    assert!(allowed(layer_of("port-est").unwrap(), "truck-dynamics"));
    assert!(allowed(layer_of("port-estimation-py").unwrap(), "port-est"));
    assert!(!allowed(layer_of("port-est").unwrap(), "port-estimation-py"));
    assert!(layer_of("some-new-crate").is_none());
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// Lines of library code with an unannotated `.unwrap()` / `.expect(`: everything before the
/// first `#[cfg(test)]` of a file (the repository keeps unit tests in a trailing module), minus
/// comments.
fn unannotated_unwraps(text: &str) -> Vec<usize> {
    let mut hits = Vec::new();
    let mut previous = "";
    for (i, line) in text.lines().enumerate() {
        let t = line.trim_start();
        if t.starts_with("#[cfg(test)]") {
            break;
        }
        let code = t.split("//").next().unwrap_or("");
        let flagged = code.contains(".unwrap()") || code.contains(".expect(");
        let annotated = line.contains("tidy: invariant") || previous.contains("tidy: invariant");
        if flagged && !annotated && !t.starts_with("//") {
            hits.push(i + 1);
        }
        previous = line;
    }
    hits
}

#[test]
fn library_code_does_not_unwrap() {
    let mut files = Vec::new();
    for e in std::fs::read_dir(root().join("crates")).unwrap().flatten() {
        let src = e.path().join("src");
        if src.is_dir() {
            rust_files(&src, &mut files);
        }
    }
    assert!(files.len() > 20, "found only {} files", files.len());
    let mut hits = Vec::new();
    for f in &files {
        // A `tests.rs` is a unit-test module kept in a file of its own (`#[cfg(test)] mod tests;`).
        let test_module = f.file_name().is_some_and(|n| n == "tests.rs");
        if test_module
            || f.file_name().is_some_and(|n| n == "main.rs")
            || f.components().any(|c| c.as_os_str() == "examples")
        {
            continue;
        }
        for line in unannotated_unwraps(&std::fs::read_to_string(f).unwrap()) {
            hits.push(format!("{}:{line}", f.display()));
        }
    }
    assert!(
        hits.is_empty(),
        "unwrap/expect in library code (return a typed error, or annotate `// tidy: invariant — why`):\n{}",
        hits.join("\n")
    );
}

#[test]
fn the_unwrap_scanner_sees_what_it_should() {
    let text = "fn a() {\n    x.unwrap();\n    // tidy: invariant — checked above\n    y.expect(\"ok\");\n    // z.unwrap() in a comment\n}\n#[cfg(test)]\nmod tests { fn t() { q.unwrap(); } }\n";
    assert_eq!(unannotated_unwraps(text), vec![2]);
}

/// Every `.rs` file of the repository (crates, xtask, the facade's src, tests and benches).
fn all_rust_files() -> Vec<PathBuf> {
    let mut files = Vec::new();
    for dir in ["crates", "xtask", "src", "tests", "benches"] {
        let d = root().join(dir);
        if d.is_dir() {
            rust_files(&d, &mut files);
        }
    }
    files.retain(|f| !f.components().any(|c| c.as_os_str() == "target"));
    files
}

#[test]
fn no_source_file_is_over_a_thousand_lines() {
    let files = all_rust_files();
    assert!(files.len() > 100, "found only {} files", files.len());
    let long: Vec<String> = files
        .iter()
        .filter_map(|f| {
            let n = std::fs::read_to_string(f).unwrap().lines().count();
            (n > 1000).then(|| format!("{}: {n} lines", f.display()))
        })
        .collect();
    assert!(long.is_empty(), "files over 1 000 lines (split them by job):\n{}", long.join("\n"));
}

/// Lines of library code (before the first `#[cfg(test)]`, outside comments) that dispatch on
/// one of `names` written as a literal: compare with it, match it, look it up in the registry or
/// default to it.
fn name_dispatches(text: &str, names: &[&str]) -> Vec<usize> {
    let mut hits = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let t = line.trim_start();
        if t.starts_with("#[cfg(test)]") {
            break;
        }
        if t.starts_with("//") {
            continue;
        }
        let code = t.split("//").next().unwrap_or("");
        let hit = names.iter().any(|n| {
            let q = format!("\"{n}\"");
            [
                format!("== {q}"),
                format!("!= {q}"),
                format!("{q} =>"),
                format!("{q} |"),
                format!("| {q}"),
                format!("build({q}"),
                format!("entry({q}"),
                format!("lookup({q}"),
                format!("default_value = {q}"),
            ]
            .iter()
            .any(|p| code.contains(p.as_str()))
        });
        if hit {
            hits.push(i + 1);
        }
    }
    hits
}

#[test]
fn only_the_registry_dispatches_on_estimator_names() {
    let names: Vec<&str> = estimators::registry::ESTIMATORS.iter().map(|e| e.name).collect();
    let mut files = Vec::new();
    for dir in ["crates/port-est/src", "xtask/src", "crates/vessel-control/src", "crates/port-estimation-py/src"] {
        rust_files(&root().join(dir), &mut files);
    }
    assert!(files.len() > 20, "found only {} files", files.len());
    let mut hits = Vec::new();
    for f in &files {
        for line in name_dispatches(&std::fs::read_to_string(f).unwrap(), &names) {
            hits.push(format!("{}:{line}", f.display()));
        }
    }
    assert!(
        hits.is_empty(),
        "estimator names dispatched on outside the registry (use estimators::registry::names or the rows):\n{}",
        hits.join("\n")
    );
}

#[test]
fn the_name_scanner_sees_what_it_should() {
    let text = "fn a() {\n    let x = registry::build(\"kf\", s, None);\n    let p = \"kf_scripted\";\n    if id == names::KF {}\n    matches!(n, \"rmhe\" | \"mhe\");\n}\n#[cfg(test)]\nmod t { fn f() { build(\"kf\") } }\n";
    assert_eq!(name_dispatches(text, &["kf", "mhe", "rmhe"]), vec![2, 5]);
}
