//! Loading systems from TOML: layouts, defuzzifier choice, and `file:line:column` errors.

use fuzzy_inference::{Defuzzifier, FuzzyError, FuzzySystem, LoadError};

const SMALL: &str = r#"default_output = 0.5

[[inputs]]
name = "x"
range = [0.0, 10.0]
sets = [
    { name = "low", trapezoid = [-inf, -inf, 2.0, 6.0] },
    { name = "high", trapezoid = [4.0, 8.0, inf, inf] },
]

[output]
name = "y"
universe = [0.0, 1.0]
sets = [
    { name = "small", triangle = [0.0, 0.0, 0.5] },
    { name = "big", triangle = [0.5, 1.0, 1.0] },
]

[[rules]]
if = { x = "low" }
then = "small"

[[rules]]
if = { x = "high" }
then = "big"
"#;

fn load(text: &str) -> Result<FuzzySystem, LoadError> {
    FuzzySystem::from_toml_str(text, "test.toml")
}

#[test]
fn loads_a_small_system() {
    let sys = load(SMALL).unwrap();
    assert_eq!(sys.defuzzifier(), Defuzzifier::Exact);
    assert!((sys.evaluate(&[1.0]).unwrap().output - 0.5 / 3.0).abs() < 1e-12);
    let sys = load(&SMALL.replace("default_output = 0.5", "default_output = 0.5\ndefuzzifier = { grid = 9 }")).unwrap();
    assert_eq!(sys.defuzzifier(), Defuzzifier::Grid { points_per_axis: 9 });
    let sys =
        load(&SMALL.replace("default_output = 0.5", "default_output = 0.5\ndefuzzifier = { sampled = 1000 }")).unwrap();
    assert_eq!(sys.defuzzifier(), Defuzzifier::SAMPLED_1000);
}

fn error(text: &str) -> String {
    load(text).unwrap_err().to_string()
}

#[test]
fn errors_name_file_line_and_column() {
    // An unknown set in the second rule: the location is that rule's.
    let e = error(&SMALL.replace(r#"if = { x = "high" }"#, r#"if = { x = "huge" }"#));
    assert!(e.starts_with("test.toml:23:1: rule 1: variable `x` has no set `huge`"), "{e}");
    let e = load(&SMALL.replace(r#"then = "big""#, r#"then = "medium""#)).unwrap_err();
    assert!(
        matches!(&e, LoadError::Invalid { source: FuzzyError::UnknownSet { rule: 1, .. }, location } if location.line_column.is_some()),
        "{e}"
    );
    // Non-monotone corners: located at the input.
    let e = error(&SMALL.replace("[4.0, 8.0, inf, inf]", "[4.0, 3.0, inf, inf]"));
    assert!(e.starts_with("test.toml:3:1: input `x`, set `high`: corners must be non-decreasing"), "{e}");
    // NaN corner, infinite corner not a shoulder, empty universe.
    let e = error(&SMALL.replace("[0.0, 0.0, 0.5]", "[0.0, nan, 0.5]"));
    assert!(e.contains("output `y`, set `small`: a corner is NaN"), "{e}");
    let e = error(&SMALL.replace("[4.0, 8.0, inf, inf]", "[4.0, 8.0, 9.0, inf]"));
    assert!(e.contains("infinite corners are allowed only"), "{e}");
    let e = error(&SMALL.replace("universe = [0.0, 1.0]", "universe = [1.0, 1.0]"));
    assert!(e.starts_with("test.toml:11:1: output `y`: the interval [1, 1] must be finite with lo < hi"), "{e}");
    // Syntax and layout errors carry the parser's span.
    let e = error(&SMALL.replace("range = [0.0, 10.0]", "range = [0.0, 10.0"));
    assert!(e.starts_with("test.toml:6:1: missing comma"), "{e}");
    let e = error(&SMALL.replace("range = [0.0, 10.0]", "range = [0.0, \"ten\"]"));
    assert!(e.starts_with("test.toml:5:"), "{e}");
    let e = error(&SMALL.replace("name = \"x\"", "name = \"x\"\ncolour = 3"));
    assert!(e.starts_with("test.toml:5:1: unknown field `colour`"), "{e}");
    let e = error(&SMALL.replace("triangle = [0.0, 0.0, 0.5]", "triangle = [0.0, 0.0, 0.5], trapezoid = [0, 0, 1, 1]"));
    assert!(e.starts_with("test.toml:15:5: set `small`: give exactly one"), "{e}");
    let e = error(&SMALL.replace("default_output = 0.5", "default_output = 0.5\ndefuzzifier = { grid = 1 }"));
    // Located at the setting (it was the file alone before the limits were located).
    assert!(e.starts_with("test.toml:2:15: defuzzifier: grid needs >= 2 points"), "{e}");
    let e = FuzzySystem::from_toml_file("/nonexistent/system.toml").unwrap_err();
    assert!(matches!(e, LoadError::Io { .. }), "{e}");
}
