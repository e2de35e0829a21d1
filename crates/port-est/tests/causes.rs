//! Errors that name the real cause: a data cell too large for the estimator's arithmetic is its
//! row's fault (with the value), whichever estimator, magnitude or column; an unstable or
//! overflowing model is the model's.

use std::path::Path;

use port_est::data::DataReader;
use port_est::filter::{run_filter, select};
use port_est::{Error, StatusPolicy, parse_model};

const MODEL: &str = include_str!("../../../examples/filter/model.toml");
const DATA: &str = include_str!("../../../examples/filter/data.csv");

fn run(model: &str, data: &str, estimator: &str, solver: Option<&str>) -> Result<u64, Error> {
    let model = parse_model(Path::new("m.toml"), model)?;
    let (entry, solver) = select(estimator, solver)?;
    let mut data = DataReader::from_text(Path::new("d.csv"), data, model.inputs(), entry.measurement_len(1))?;
    let mut out = Vec::new();
    run_filter(&model, &mut data, entry, solver, StatusPolicy::Warn, None, &mut out, Path::new("o.csv"))
        .map(|s| s.tally.steps)
}

/// The example log with cell `column` (1: u1, 2: y1) of data line `line` set to `value`.
fn with_cell(line: usize, column: usize, value: &str) -> String {
    let mut lines: Vec<String> = DATA.lines().map(str::to_owned).collect();
    let mut cells: Vec<String> = lines[line - 1].split(',').map(str::to_owned).collect();
    cells[column] = value.to_owned();
    lines[line - 1] = cells.join(",");
    lines.join("\n") + "\n"
}

#[test]
fn a_cell_too_large_for_the_arithmetic_is_its_rows_fault_with_its_value() {
    let estimators: [(&str, Option<&str>); 5] =
        [("smf", None), ("smf", Some("faer-ipm")), ("yang-li-with-input", None), ("rmhe", None), ("mhe", None)];
    let mut failures = 0;
    for (estimator, solver) in estimators {
        for value in ["1e155", "1e160", "-1e200", "1e300", "1.7e308"] {
            for (column, name) in [(1, "u1"), (2, "y1")] {
                let Err(e) = run(MODEL, &with_cell(12, column, value), estimator, solver) else { continue };
                let e = e.to_string();
                assert!(!e.contains("cause is the model"), "{estimator} {name} = {value}: {e}");
                if e.contains("numerical failure") {
                    failures += 1;
                    // At the cell, with its value (an input's effect may surface a step later in
                    // the window of a moving-horizon estimator: the message points back at it).
                    let shown = format!("{name} = {:e}", value.parse::<f64>().unwrap());
                    assert!(e.contains(&shown), "{estimator} {name} = {value}: {e}");
                    let col = if column == 1 { 4 } else { 13 };
                    assert!(e.starts_with(&format!("d.csv:12:{col}: ")), "{estimator} {name} = {value}: {e}");
                }
            }
        }
    }
    assert!(failures >= 20, "only {failures} numerical failures: the test lost its point");
}

#[test]
fn an_overflowing_model_is_the_models_fault() {
    let all: &[&str] = &["smf", "kf", "rmhe"];
    for (from, to, estimators) in [
        ("a  = [[1.0, 0.01], [-0.01, 0.998]]", "a  = [[1e100, 0.0], [0.0, 1e100]]", all),
        ("a  = [[1.0, 0.01], [-0.01, 0.998]]", "a  = [[1e200, 0.01], [-0.01, 1e200]]", all),
        // (A covariance this large is no failure for the Kalman filter or the MHE.)
        ("q  = [[1e-6, 0.0], [0.0, 1e-4]]", "q  = [[1e300, 0.0], [0.0, 1e300]]", &["smf"]),
    ] {
        let model = MODEL.replace(from, to);
        assert_ne!(model, MODEL);
        for &estimator in estimators {
            let e = run(&model, DATA, estimator, None).unwrap_err().to_string();
            assert!(e.contains("the cause is the model in m.toml"), "{estimator} with {to}: {e}");
        }
    }
}
