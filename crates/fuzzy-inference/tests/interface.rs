//! Rule files for a consumer that feeds fixed quantities: inputs matched by name (any block
//! order, unknown and missing names located), the default output checked against the universe,
//! and the limits on rules, sampled points and file size refused at their line, before anything
//! their size asks for is allocated (a counting allocator's largest request, not a clock).

use counting_allocator::{Counting, measure};
use fuzzy_inference::{
    BDS_INS_INTERFACE, FuzzyError, FuzzySystem, LoadError, MAX_FILE_BYTES, MAX_RULES, MAX_SAMPLED_POINTS,
};

#[global_allocator]
static GLOBAL: Counting = Counting;

const SHIPPED: &str = include_str!("../systems/bds_ins.toml");

/// The shipped file cut into its preamble, its three `[[inputs]]` blocks and the rest.
fn blocks() -> (String, Vec<String>, String) {
    let first = SHIPPED.find("# Satellites used").unwrap();
    let second = SHIPPED.find("# RTK status").unwrap();
    let third = SHIPPED.find("# Horizontal BDS-to-INS").unwrap();
    let rest = SHIPPED.find("# u = log10 t").unwrap();
    (
        SHIPPED[..first].to_owned(),
        vec![SHIPPED[first..second].to_owned(), SHIPPED[second..third].to_owned(), SHIPPED[third..rest].to_owned()],
        SHIPPED[rest..].to_owned(),
    )
}

fn with_order(order: [usize; 3]) -> String {
    let (head, inputs, rest) = blocks();
    let mut text = head;
    for i in order {
        text.push_str(&inputs[i]);
    }
    text.push_str(&rest);
    text
}

fn load(text: &str) -> Result<FuzzySystem, LoadError> {
    FuzzySystem::from_toml_str_for(text, "fis.toml", &BDS_INS_INTERFACE)
}

fn error(text: &str) -> String {
    load(text).unwrap_err().to_string()
}

#[test]
fn every_order_of_the_input_blocks_gives_the_same_system() {
    let reference = FuzzySystem::bds_ins_default();
    for order in [[0, 1, 2], [2, 1, 0], [1, 2, 0], [0, 2, 1], [1, 0, 2], [2, 0, 1]] {
        let text = with_order(order);
        // Loaded without its consumer's names, a permuted file is a different system…
        let plain = FuzzySystem::from_toml_str(&text, "fis.toml").unwrap();
        assert_eq!(plain.inputs()[0].name, ["N", "RTK", "d"][order[0]]);
        // …bound by name, it is the built-in one, input for input.
        let bound = load(&text).unwrap();
        assert_eq!(bound, reference, "{order:?}");
        for x in [[20.0, 3.0, 0.05], [9.0, 4.0, 0.7], [5.0, 1.0, 2.0], [13.0, 2.0, 0.9], [2.0, 3.0, 0.05]] {
            assert_eq!(bound.evaluate(&x).unwrap(), reference.evaluate(&x).unwrap(), "{order:?} {x:?}");
        }
    }
}

#[test]
fn documented_alternative_names_are_accepted() {
    let text = SHIPPED.replace("name = \"N\"", "name = \"satellites\"").replace("N = \"", "satellites = \"");
    let text = text.replace("name = \"d\"", "name = \"distance\"").replace(", d = \"", ", distance = \"");
    let bound = load(&text).unwrap();
    let reference = FuzzySystem::bds_ins_default();
    assert_eq!(bound.evaluate(&[9.0, 4.0, 0.7]).unwrap(), reference.evaluate(&[9.0, 4.0, 0.7]).unwrap());
}

#[test]
fn unknown_and_missing_names_are_errors_at_their_block() {
    // Renamed: the block of the unknown name (line 22 of the shipped file).
    let text = SHIPPED.replace("name = \"RTK\"", "name = \"status\"").replace("RTK = \"", "status = \"");
    let e = error(&text);
    assert!(e.starts_with("fis.toml:22:1: input `status` is not one of the quantities"), "{e}");
    assert!(e.contains("`N` or `satellites`") && e.contains("`RTK`") && e.contains("`d` or `distance`"), "{e}");
    // The same quantity twice.
    let text = SHIPPED.replace("name = \"d\"", "name = \"satellites\"").replace(", d = \"", ", satellites = \"");
    let e = error(&text);
    assert!(e.starts_with("fis.toml:34:1: inputs `N` and `satellites` both name the satellites used"), "{e}");
    // A quantity without an input: at the first input block.
    let (head, inputs, rest) = blocks();
    let rest = rest.replace(", d = \"PS\"", "").replace(", d = \"PM\"", "").replace(", d = \"PB\"", "");
    let e = error(&format!("{head}{}{}{rest}", inputs[0], inputs[1]));
    assert!(e.starts_with("fis.toml:11:1: no input for the BDS-to-INS horizontal distance [m]"), "{e}");
    // Outputs that cannot scale a covariance (a linear universe reaching 0): at `[output]`.
    let text = SHIPPED
        .replace("scale = \"log10\"", "scale = \"linear\"")
        .replace("default_output = 25.0", "default_output = 1.0");
    let e = error(&text);
    assert!(e.contains(":44:1: the system's outputs [-0.7, 2.1]") && e.contains("positive and finite"), "{e}");
}

#[test]
fn the_default_output_must_be_an_output_the_universe_allows() {
    for bad in ["0.1", "126.0", "-25.0", "1e300"] {
        let e = error(&SHIPPED.replace("default_output = 25.0", &format!("default_output = {bad}")));
        assert!(e.starts_with("fis.toml:7:18: the default output"), "{bad}: {e}");
        assert!(e.contains("lies outside the system's outputs [0.199") && e.contains("through 10^u"), "{bad}: {e}");
        // Also without an interface.
        let plain = FuzzySystem::from_toml_str(
            &SHIPPED.replace("default_output = 25.0", &format!("default_output = {bad}")),
            "fis.toml",
        );
        assert!(matches!(plain, Err(LoadError::Invalid { source: FuzzyError::DefaultOutsideUniverse { .. }, .. })));
    }
    assert!(load(&SHIPPED.replace("default_output = 25.0", "default_output = 125.0")).is_ok());
}

#[test]
fn defuzzifier_resolutions_beyond_the_limit_are_refused_at_their_line_before_allocating() {
    for setting in ["{ sampled = 10000000000 }", "{ sampled = 1e10 }", "{ sampled = 100001 }", "{ grid = 100000 }"] {
        let text = SHIPPED.replace("defuzzifier = \"exact\"", &format!("defuzzifier = {setting}"));
        let (e, usage) = measure(|| error(&text));
        // Nothing near the sample grid's size (8 bytes per point): no buffer beyond the text's scale.
        assert!(usage.largest <= 64 * text.len(), "{setting}: a request of {} bytes", usage.largest);
        assert!(e.starts_with("fis.toml:8:"), "{setting}: {e}");
    }
    let e = error(&SHIPPED.replace("defuzzifier = \"exact\"", "defuzzifier = { sampled = 10000000000 }"));
    assert!(e.contains(&MAX_SAMPLED_POINTS.to_string()) && e.contains("MAX_SAMPLED_POINTS"), "{e}");
    let at_limit = format!("defuzzifier = {{ sampled = {MAX_SAMPLED_POINTS} }}");
    assert!(load(&SHIPPED.replace("defuzzifier = \"exact\"", &at_limit)).is_ok());
}

#[test]
fn more_rules_than_the_limit_are_refused_at_the_first_one_beyond() {
    let rule = "[[rules]]\nif = { N = \"PB\", RTK = \"fixed\", d = \"PS\" }\nthen = \"Z\"\n\n";
    let text = format!("{SHIPPED}\n{}", rule.repeat(MAX_RULES));
    let (e, usage) = measure(|| error(&text));
    assert!(e.contains(&format!("{} rules, the limit is {MAX_RULES}", MAX_RULES + 45)), "{e}");
    // The rule beyond the limit: 45 shipped rules, then the added ones 4 lines each.
    let shipped_lines = SHIPPED.lines().count() + 1;
    let line = shipped_lines + 1 + 4 * (MAX_RULES - 45);
    assert!(e.starts_with(&format!("fis.toml:{line}:1: ")), "{e}");
    // Parsing the text costs buffers of its own scale; nothing beyond that is requested.
    assert!(usage.largest <= 64 * text.len(), "a request of {} bytes", usage.largest);
}

#[cfg(unix)]
#[test]
fn an_endless_file_is_refused_at_the_size_limit() {
    let (e, usage) = measure(|| FuzzySystem::from_toml_file_for("/dev/zero", &BDS_INS_INTERFACE).unwrap_err());
    assert!(matches!(e, LoadError::TooLarge { limit: MAX_FILE_BYTES, .. }), "{e}");
    assert!(e.to_string().contains("MAX_FILE_BYTES"), "{e}");
    // An endless file is read to one byte past the limit, no further.
    assert!(usage.largest <= 4 * MAX_FILE_BYTES as usize, "a request of {} bytes", usage.largest);
}
