//! Bounded fuzzing of rule files (proptest, a few dozen cases): mutated and arbitrary files never
//! panic; a system that loads stays within the limits, and for the BDS/INS interface every
//! evaluation gives a positive, finite output within the outputs its universe allows.

use fuzzy_inference::{BDS_INS_INTERFACE, Defuzzifier, FuzzySystem, LoadError, MAX_RULES, MAX_SAMPLED_POINTS};
use proptest::prelude::*;
use text_fuzz::replace_char as mutate;

const SHIPPED: &str = include_str!("../systems/bds_ins.toml");

fn pieces() -> impl Strategy<Value = String> {
    text_fuzz::pieces(&[
        "10000000000",
        "1e10",
        "\"N\"",
        "\"d\"",
        "\"RTK\"",
        "\"x\"",
        "[",
        "]",
        "{",
        "}",
        "=",
        ",",
        "\n",
        "#",
        "[[rules]]\nif = { N = \"PB\" }\nthen = \"Z\"\n",
        "[[inputs]]\n",
        "{ sampled = 100000 }",
        "{ grid = 3 }",
    ])
}

fn check(text: &str) -> Result<(), TestCaseError> {
    match FuzzySystem::from_toml_str_for(text, "fis.toml", &BDS_INS_INTERFACE) {
        Ok(sys) => {
            prop_assert!(sys.rules().len() <= MAX_RULES);
            if let Defuzzifier::Sampled { points } = sys.defuzzifier() {
                prop_assert!(points <= MAX_SAMPLED_POINTS);
            }
            let (lo, hi) = sys.output().output_range();
            for x in [[0.0, 0.0, 0.0], [20.0, 3.0, 0.05], [5.0, 1.0, 2.0], [1e9, -4.0, f64::INFINITY], [9.0, 4.0, 0.7]]
            {
                let e = sys.evaluate(&x).map_err(|e| TestCaseError::fail(e.to_string()))?;
                prop_assert!(e.output.is_finite() && e.output > 0.0, "{x:?}: {}", e.output);
                prop_assert!(lo <= e.output * (1.0 + 1e-12) && e.output <= hi * (1.0 + 1e-12), "{x:?}: {}", e.output);
            }
        }
        Err(LoadError::Io { .. } | LoadError::TooLarge { .. }) => prop_assert!(false, "no file was read"),
        Err(e) => prop_assert!(e.to_string().starts_with("fis.toml"), "{e}"),
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn mutated_rule_files_never_panic(at in 0usize..6000, with in pieces(), at2 in 0usize..6000, with2 in pieces()) {
        check(&mutate(&mutate(SHIPPED, at, &with), at2, &with2))?;
    }

    #[test]
    fn arbitrary_rule_files_never_panic(text in "[ -~\n]{0,200}") {
        check(&text)?;
        let _ = FuzzySystem::from_toml_str(&text, "fis.toml");
    }
}

#[test]
fn the_seed_is_valid() {
    check(SHIPPED).unwrap();
}
