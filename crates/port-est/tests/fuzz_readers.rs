//! Bounded fuzzing of the readers (proptest, a few hundred cases per run): arbitrary and mutated
//! model files and data files never panic; an error always carries a position or a path.

use std::path::Path;

use port_est::data::{DataReader, DataRow};
use port_est::parse_model;
use proptest::prelude::*;

const MODEL: &str = "a = [[1.0, 0.01], [0.0, 0.99]]\nb = [[0.0], [0.01]]\nc = [[1.0, 0.0]]\nq = [[1e-4, 0.0], [0.0, 1e-4]]\nr = [[1e-2]]\np0 = [[1.0, 0.0], [0.0, 1.0]]\nx0 = [0.0, 0.0]\nu_lower = [-1.0]\nu_upper = [1.0]\n";
const DATA: &str = "k,u1,y1\n0,0.5,0.01\n1,0.5,0.02\n2,-0.5,0.015\n";

fn mutate(text: &str, at: usize, with: char) -> String {
    text_fuzz::replace_char(text, at, with.encode_utf8(&mut [0; 4]))
}

fn read_all(text: &str) {
    let Ok(mut r) = DataReader::from_text(Path::new("d.csv"), text, 1, 1) else { return };
    let mut row = DataRow::zeros(1, 1);
    while let Ok(true) = r.read_row(&mut row) {
        assert!(row.u.iter().chain(row.y.iter()).all(|v| v.is_finite()), "a non-finite value was accepted");
    }
}

fn chars() -> impl Strategy<Value = char> {
    prop::sample::select(vec!['0', '1', '-', '.', 'e', ' ', '\n', ',', '[', ']', '=', '"', 'n', '\u{feff}', 'é', '\r'])
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    #[test]
    fn mutated_models_never_panic(at in 0usize..1000, with in chars()) {
        let _ = parse_model(Path::new("m.toml"), &mutate(MODEL, at, with));
    }

    #[test]
    fn arbitrary_models_never_panic(text in "[ -~\n]{0,160}") {
        let _ = parse_model(Path::new("m.toml"), &text);
    }

    #[test]
    fn mutated_data_never_panic(at in 0usize..1000, with in chars(), at2 in 0usize..1000, with2 in chars()) {
        read_all(&mutate(&mutate(DATA, at, with), at2, with2));
    }

    #[test]
    fn arbitrary_data_never_panic(text in "[ -~\n\r]{0,160}") {
        read_all(&text);
    }
}

#[test]
fn the_seeds_are_valid() {
    assert!(parse_model(Path::new("m.toml"), MODEL).is_ok());
    let mut r = DataReader::from_text(Path::new("d.csv"), DATA, 1, 1).unwrap();
    let mut row = DataRow::zeros(1, 1);
    let mut n = 0;
    while r.read_row(&mut row).unwrap() {
        n += 1;
    }
    assert_eq!(n, 3);
}
