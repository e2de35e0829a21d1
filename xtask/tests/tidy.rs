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
//! * **No circles of files.** Inside a crate, no two files import each other through others (a
//!   strongly connected group in the graph of `use crate::…` and `crate::…` paths of library
//!   code): status and data types sit below the code that reports them. The groups that remain are
//!   listed in [`ACCEPTED_FILE_CYCLES`] with the reason, so that none is added unnoticed and a
//!   removed one must leave the list.
//! * **No unwrap on input.** Library code (`crates/*/src`, outside `#[cfg(test)]` modules) has no
//!   `.unwrap()` or `.expect(` unless the line or the one above carries a
//!   `// tidy: invariant — <why it cannot fail>` comment.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Workspace crates and the workspace crates each may depend on. `*-dynamics` is any vehicle
/// crate.
const LAYERS: &[(&str, &[&str])] = &[
    ("dense-kernels", &[]),
    ("counting-allocator", &[]),
    ("text-fuzz", &[]),
    ("fuzzy-inference", &[]),
    ("atomic-output", &[]),
    ("svg-plot", &[]),
    ("ros-bag", &["atomic-output"]),
    ("intervals", &[]),
    ("models", &["dense-kernels", "intervals"]),
    ("equation-models", &["models", "dense-kernels", "intervals"]),
    ("ellipsoid", &["dense-kernels"]),
    ("constrained-zonotope", &["dense-kernels", "intervals"]),
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

/// Lines of library code (before any `#[cfg(test)]`) that name a variant of the registry's
/// settings types.
fn settings_variants(text: &str) -> Vec<usize> {
    let mut hits = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let t = line.trim_start();
        if t.starts_with("#[cfg(test)]") {
            break;
        }
        let code = t.split("//").next().unwrap_or("");
        if code.contains("SettingsKind::") || code.contains("EstimatorSettings::") {
            hits.push(i + 1);
        }
    }
    hits
}

/// The command line and the Python package read every estimator's settings through the
/// registry (`registry::read_settings`, `SettingsKind::needs`, `EstimatorSettings::smf_solver`):
/// neither names a kind of settings, so a new kind touches the registry only. (`xtask` builds the
/// papers' typed settings on purpose.)
#[test]
fn only_the_registry_matches_on_kinds_of_settings() {
    let mut files = Vec::new();
    for dir in ["crates/port-est/src", "crates/port-estimation-py/src"] {
        rust_files(&root().join(dir), &mut files);
    }
    let hits: Vec<String> = files
        .iter()
        .flat_map(|f| {
            let lines = settings_variants(&std::fs::read_to_string(f).unwrap());
            lines.into_iter().map(move |l| format!("{}:{l}", f.display()))
        })
        .collect();
    assert!(hits.is_empty(), "kinds of settings named outside the registry:\n{}", hits.join("\n"));
    assert_eq!(settings_variants("let k = SettingsKind::None; // SettingsKind::Unscented\n"), vec![1]);
    assert!(settings_variants("// EstimatorSettings::None\n#[cfg(test)]\nEstimatorSettings::None").is_empty());
}

#[test]
fn the_name_scanner_sees_what_it_should() {
    let text = "fn a() {\n    let x = registry::build(\"kf\", s, None);\n    let p = \"kf_scripted\";\n    if id == names::KF {}\n    matches!(n, \"rmhe\" | \"mhe\");\n}\n#[cfg(test)]\nmod t { fn f() { build(\"kf\") } }\n";
    assert_eq!(name_dispatches(text, &["kf", "mhe", "rmhe"]), vec![2, 5]);
}

/// The groups of files that import each other and stay so, with why no layer is drawn between
/// them (crate, then the files' module paths in order).
const ACCEPTED_FILE_CYCLES: &[(&str, &[&str], &str)] = &[
    (
        "lmi",
        &["certificate", "solver"],
        "a solution records the certificate its check rejected, and the check reads solutions: one \
         vocabulary of outcomes in two files",
    ),
    (
        "svg-plot",
        &["clip", "layout", "legend", "render"],
        "a plot's parts lay themselves out with the renderer's primitives, which draws them",
    ),
];

/// A crate's source files by module path (`a::b`; `lib.rs`, `main.rs` and `mod.rs` name their
/// folder's module, the root being the empty path).
fn module_files(src: &Path) -> BTreeMap<String, PathBuf> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    files
        .into_iter()
        .map(|f| {
            let rel = f.strip_prefix(src).unwrap().with_extension("");
            let mut parts: Vec<String> =
                rel.components().map(|c| c.as_os_str().to_string_lossy().into_owned()).collect();
            if matches!(parts.last().map(String::as_str), Some("mod" | "lib" | "main")) {
                parts.pop();
            }
            (parts.join("::"), f)
        })
        .collect()
}

/// Library code of a file: before its first `#[cfg(test)]`, without comment lines.
fn library_code(text: &str) -> String {
    let code = text.split("#[cfg(test)]").next().unwrap_or("");
    code.lines().filter(|l| !l.trim_start().starts_with("//")).collect::<Vec<_>>().join("\n")
}

/// `prefix` joined with each path of the `use` tree `tree` (braces expanded).
fn expand_use(prefix: &[String], tree: &str, out: &mut Vec<Vec<String>>) {
    let tree = tree.trim();
    if let Some(inner) = tree.strip_prefix('{').and_then(|t| t.strip_suffix('}')) {
        let (mut depth, mut start) = (0, 0);
        for (i, ch) in inner.char_indices() {
            match ch {
                '{' => depth += 1,
                '}' => depth -= 1,
                ',' if depth == 0 => {
                    expand_use(prefix, &inner[start..i], out);
                    start = i + 1;
                }
                _ => {}
            }
        }
        expand_use(prefix, &inner[start..], out);
    } else if let Some(i) = tree.find("::{") {
        let mut p = prefix.to_vec();
        p.extend(tree[..i].split("::").map(str::to_owned));
        expand_use(&p, &tree[i + 2..], out);
    } else if !tree.is_empty() {
        let mut p = prefix.to_vec();
        p.extend(tree.split(" as ").next().unwrap_or("").split("::").map(|s| s.trim().to_owned()));
        out.push(p);
    }
}

/// The paths into its own crate that library code names: `use crate::…` trees and `crate::…` paths.
fn crate_paths(code: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(i) = rest.find("crate::") {
        let after = &rest[i + "crate::".len()..];
        let is_use = rest[..i].trim_end().ends_with("use");
        if is_use {
            let end = after.find(';').unwrap_or(after.len());
            let tree = after[..end].split_whitespace().collect::<Vec<_>>().join(" ");
            expand_use(&[], &tree, &mut out);
            rest = &after[end..];
        } else {
            let end = after.find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':')).unwrap_or(after.len());
            out.push(after[..end].split("::").filter(|s| !s.is_empty()).map(str::to_owned).collect());
            rest = &after[end..];
        }
    }
    out
}

/// Which module files each module file names (the longest module-file prefix of each path).
fn file_graph(modules: &BTreeMap<String, String>) -> BTreeMap<String, BTreeSet<String>> {
    modules
        .iter()
        .map(|(m, code)| {
            let targets = crate_paths(code)
                .into_iter()
                .filter_map(|p| {
                    (1..=p.len()).rev().map(|k| p[..k].join("::")).find(|prefix| modules.contains_key(prefix))
                })
                .filter(|t| t != m)
                .collect();
            (m.clone(), targets)
        })
        .collect()
}

/// The groups of two or more files that reach each other (Tarjan's strongly connected
/// components), each sorted.
fn file_cycles(graph: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    struct Tarjan<'g> {
        graph: &'g BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<&'g str, usize>,
        low: BTreeMap<&'g str, usize>,
        stack: Vec<&'g str>,
        groups: Vec<Vec<String>>,
    }
    impl<'g> Tarjan<'g> {
        fn visit(&mut self, v: &'g str) {
            let i = self.index.len();
            self.index.insert(v, i);
            self.low.insert(v, i);
            self.stack.push(v);
            for w in self.graph.get(v).into_iter().flatten() {
                let w = w.as_str();
                if !self.graph.contains_key(w) {
                    continue;
                }
                if !self.index.contains_key(w) {
                    self.visit(w);
                    let lw = self.low[w];
                    let lv = self.low.get_mut(v).unwrap();
                    *lv = (*lv).min(lw);
                } else if self.stack.contains(&w) {
                    let iw = self.index[w];
                    let lv = self.low.get_mut(v).unwrap();
                    *lv = (*lv).min(iw);
                }
            }
            if self.low[v] == self.index[v] {
                let mut group = Vec::new();
                while let Some(w) = self.stack.pop() {
                    group.push(w.to_owned());
                    if w == v {
                        break;
                    }
                }
                if group.len() > 1 {
                    group.sort();
                    self.groups.push(group);
                }
            }
        }
    }
    let mut t = Tarjan { graph, index: BTreeMap::new(), low: BTreeMap::new(), stack: Vec::new(), groups: Vec::new() };
    for v in graph.keys() {
        if !t.index.contains_key(v.as_str()) {
            t.visit(v);
        }
    }
    t.groups.sort();
    t.groups
}

#[test]
fn no_files_import_each_other_in_a_circle() {
    let mut crates: Vec<(String, PathBuf)> = std::fs::read_dir(root().join("crates"))
        .unwrap()
        .flatten()
        .map(|e| (e.file_name().to_string_lossy().into_owned(), e.path().join("src")))
        .filter(|(_, src)| src.is_dir())
        .collect();
    crates.push(("xtask".into(), root().join("xtask/src")));
    crates.sort();
    assert!(crates.len() > 15, "found only {} crates", crates.len());
    let mut found = Vec::new();
    for (name, src) in &crates {
        let modules: BTreeMap<String, String> = module_files(src)
            .into_iter()
            .map(|(m, f)| (m, library_code(&std::fs::read_to_string(f).unwrap())))
            .collect();
        for group in file_cycles(&file_graph(&modules)) {
            found.push(format!("{name}: {}", group.join(" ")));
        }
    }
    let accepted: Vec<String> =
        ACCEPTED_FILE_CYCLES.iter().map(|(c, files, _)| format!("{c}: {}", files.join(" "))).collect();
    assert_eq!(
        found, accepted,
        "files importing each other in a circle (draw a layer: the shared types below the code that uses them; \
         or, if none can be drawn, list the group in ACCEPTED_FILE_CYCLES with the reason)"
    );
}

#[test]
fn the_cycle_scanner_sees_what_it_should() {
    let modules: BTreeMap<String, String> = [
        ("", "mod a;\nmod b;"),
        ("a", "use crate::{b::{X, Y as Z}, c::W};\nfn f() { crate::d::e::g(); }"),
        ("b", "// use crate::a::Q;\npub(crate) use crate::a::P;"),
        ("c", "use crate::d::e;"),
        ("d::e", "#[cfg(test)]\nmod tests { use crate::c::T; }"),
        ("d", "pub mod e;"),
    ]
    .into_iter()
    .map(|(m, c)| (m.to_owned(), library_code(c)))
    .collect();
    let graph = file_graph(&modules);
    assert_eq!(graph["a"], BTreeSet::from(["b".to_owned(), "c".to_owned(), "d::e".to_owned()]));
    assert_eq!(file_cycles(&graph), [["a".to_owned(), "b".to_owned()]]);
}
