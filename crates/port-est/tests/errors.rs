//! Malformed inputs are reported at their `file:line:column`, and a failed run neither writes
//! nor damages anything.

use std::path::{Path, PathBuf};

use port_est::{Error, FilterOptions, filter};

#[macro_use]
mod common;

const MODEL: &str = concat!("# A damped oscillator.\n", oscillator_text!());

const DATA: &str = "k,u1,y1\n0,0.0,0.30\n1,0.2,0.29\n2,0.4,0.28\n";

/// A fresh directory with `model.toml` and `data.csv`.
fn setup(name: &str, model: &str, data: &str) -> (PathBuf, FilterOptions) {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("port-est-errors").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("model.toml"), model).unwrap();
    std::fs::write(dir.join("data.csv"), data).unwrap();
    let options = FilterOptions::new(dir.join("model.toml"), dir.join("data.csv"), dir.join("out.csv"));
    (dir, options)
}

/// Runs and expects an error at `file:line:column`; checks that no output (nor temporary
/// file) was left.
fn error_at(name: &str, model: &str, data: &str, file: &str, line: u64, column: u64) -> String {
    let (dir, options) = setup(name, model, data);
    let err = filter(&options).expect_err(name);
    let at = err.location().unwrap_or_else(|| panic!("{name}: no location in {err}"));
    assert_eq!((at.path.file_name().unwrap().to_str().unwrap(), at.line, at.column), (file, line, column), "{err}");
    let msg = err.to_string();
    assert!(msg.starts_with(&format!("{}:{line}:{column}: ", dir.join(file).display())), "{msg}");
    let mut left: Vec<String> =
        std::fs::read_dir(&dir).unwrap().flatten().map(|e| e.file_name().to_string_lossy().into_owned()).collect();
    left.sort();
    assert_eq!(left, ["data.csv", "model.toml"], "{name}: nothing written");
    msg
}

#[test]
fn a_bad_number_in_the_csv() {
    let m = error_at("bad-number", MODEL, "k,u1,y1\n0,0.0,0.30\n1, 0.2x ,0.29\n", "data.csv", 3, 4);
    assert!(m.ends_with("u1 = \"0.2x\" is not a number"), "{m}");
    let m = error_at("bad-k", MODEL, "k,u1,y1\n0.5,0.0,0.30\n", "data.csv", 2, 1);
    assert!(m.ends_with("k = \"0.5\" is not a nonnegative integer"), "{m}");
    let m = error_at("infinite", MODEL, "k,u1,y1\n0,0.0,inf\n", "data.csv", 2, 7);
    assert!(m.ends_with("y1 = \"inf\" is not finite"), "{m}");
}

#[test]
fn a_wrong_column_count_in_the_csv() {
    let m = error_at("short-row", MODEL, "k,u1,y1\n0,0.0,0.30\n1,0.2\n", "data.csv", 3, 1);
    assert!(m.contains("2 fields, expected 3"), "{m}");
    let m = error_at("long-row", MODEL, "k,u1,y1\n0,0.0,0.30,7\n", "data.csv", 2, 1);
    assert!(m.contains("4 fields, expected 3"), "{m}");
    let m = error_at("header", MODEL, "k,u1,u2\n", "data.csv", 1, 6);
    assert!(m.contains("the header has no column \"y1\" (model has p = 1 inputs, m = 1 outputs"), "{m}");
    assert!(m.contains("does not read: \"u2\" (column 3)"), "{m}");
}

#[test]
fn a_byte_order_mark_and_padding_do_not_shift_columns() {
    let m = error_at("bom", MODEL, "\u{feff}k , u1 ,y2\r\n", "data.csv", 1, 9);
    assert!(m.contains("the header has no column \"y1\""), "{m}");
    let m = error_at("bom-row", MODEL, "\u{feff}k,u1,y1\r\n\r\n0,0.0,  oops  \r\n", "data.csv", 3, 9);
    assert!(m.ends_with("y1 = \"oops\" is not a number"), "{m}");
}

#[test]
fn a_bad_toml_value() {
    let bad = MODEL.replace("r  = [[4e-4]]", "r  = [[\"4e-4\"]]");
    let m = error_at("toml-type", &bad, DATA, "model.toml", 6, 6);
    assert!(m.contains("a matrix (a list of rows), a diagonal (a list of numbers) or a number"), "{m}");
    let bad = MODEL.replace("q  =", "qq =");
    error_at("toml-key", &bad, DATA, "model.toml", 5, 1);
    let bad = MODEL.replace("x0 = [0.0, 0.0]", "x0 = [0.0, 0.0");
    error_at("toml-syntax", &bad, DATA, "model.toml", 8, 15);
}

#[test]
fn a_wrong_matrix_size() {
    let bad = MODEL.replace("b  = [[0.0], [0.01]]", "b  = [[0.0]]");
    let m = error_at("b-rows", &bad, DATA, "model.toml", 3, 6);
    assert!(m.ends_with("`b`: expected 2 rows, found 1"), "{m}");
    let bad = MODEL.replace("p0 = [[0.25, 0.0], [0.0, 0.25]]", "p0 = [[0.25, 0.0], [0.0]]");
    let m = error_at("p0-row", &bad, DATA, "model.toml", 7, 6);
    assert!(m.ends_with("`p0`: row 2 has 1 entries, expected 2"), "{m}");
    let bad = MODEL.replace("q  = [[1e-6, 0.0], [0.0, 1e-4]]", "q  = [[1e-6, 0.0], [0.0, -1e-4]]");
    let m = error_at("q-indefinite", &bad, DATA, "model.toml", 5, 6);
    assert!(m.contains("`q`: Q is not"), "{m}");
}

#[test]
fn the_output_may_not_be_an_input() {
    let (dir, mut options) = setup("same-file", MODEL, DATA);
    for (role, path) in [("input", dir.join(".").join("data.csv")), ("model", dir.join("model.toml"))] {
        options.output = path;
        let err = filter(&options).unwrap_err();
        assert!(matches!(err, Error::SameFile { role: r, .. } if r == role), "{err}");
    }
    assert_eq!(std::fs::read_to_string(dir.join("data.csv")).unwrap(), DATA, "the input is untouched");
    assert_eq!(std::fs::read_to_string(dir.join("model.toml")).unwrap(), MODEL);
}

#[test]
fn a_failed_run_keeps_the_previous_output() {
    let (dir, options) = setup("keep-old", MODEL, "k,u1,y1\n0,0.0,0.30\n1,0.2,oops\n");
    std::fs::write(&options.output, "previous\n").unwrap();
    let err = filter(&options).unwrap_err();
    assert_eq!(err.location().map(|l| (l.line, l.column)), Some((3, 7)), "{err}");
    assert_eq!(std::fs::read_to_string(dir.join("out.csv")).unwrap(), "previous\n");
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 3, "no temporary file left");
}
