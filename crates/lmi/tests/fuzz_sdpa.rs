//! Bounded fuzzing of the SDPA reader (proptest, a few hundred cases per run): arbitrary text and
//! mutations of a valid file never panic, and whatever is accepted is a consistent problem.

use proptest::prelude::*;

const VALID: &str = "\"a small problem\"\n2 =mdim\n2 =nblocks\n{2, -1}\n1.0 2.0\n0 1 1 1 1.0\n0 2 1 1 -1.0\n1 1 1 1 1.0\n1 1 1 2 0.5\n2 1 2 2 1.0\n2 2 1 1 1.0\n";

fn mutate(text: &str, at: usize, with: char) -> String {
    text_fuzz::replace_char(text, at, with.encode_utf8(&mut [0; 4]))
}

fn check(text: &str) {
    if let Ok(p) = lmi::read_sdpa(text) {
        // Accepted problems are consistent: a written copy reads back identically.
        let again = lmi::read_sdpa(&lmi::write_sdpa(&p)).expect("a written problem reads back");
        assert!(again.same_structure(&p));
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_text_never_panics(text in "[ -~\n\t{}=,.0-9eE+-]{0,200}") {
        check(&text);
    }

    #[test]
    fn mutated_valid_files_never_panic(at in 0usize..1000, with in prop::sample::select(vec![
        '0', '1', '9', '-', '+', '.', 'e', ' ', '\n', '{', '}', ',', 'x', '\u{0}', 'é',
    ])) {
        check(&mutate(VALID, at, with));
    }

    #[test]
    fn huge_and_odd_numbers_never_panic(
        m in prop::sample::select(vec!["0", "1", "2", "-1", "99999999999999999999", "1e400", "nan", "200000"]),
        block in prop::sample::select(vec!["2", "-1", "0", "-99999999", "3000000000", "1e9"]),
        value in prop::sample::select(vec!["1.0", "nan", "inf", "-inf", "1e400", "1e-400", "0x10"]),
    ) {
        let text = format!("{m} =mdim\n1 =nblocks\n{block}\n1.0\n0 1 1 1 {value}\n1 1 1 1 1.0\n");
        check(&text);
    }
}

#[test]
fn the_seed_file_is_valid() {
    let p = lmi::read_sdpa(VALID).expect("the seed of the mutations is a valid file");
    assert_eq!(p.num_vars(), 2);
}
