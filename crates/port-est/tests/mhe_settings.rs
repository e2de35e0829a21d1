//! `port-est filter --estimator rmhe|mhe`: the `[mhe]` table of the model file, its errors at
//! `file:line:column`, and a missing table named as such.

use std::path::{Path, PathBuf};

use port_est::{FilterOptions, filter};

mod common;
use common::OSCILLATOR as MODEL;

const TABLE: &str = "[mhe]
horizon = 6
blocks = [5, 1]
lambda_v = 10.0
w_lower = [-1e-3, -1e-2]
w_upper = [1e-3, 1e-2]
v_lower = [-0.02]
v_upper = [0.02]
";

fn dir() -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join("port-est-mhe");
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn run(name: &str, model: &str, estimator: &str) -> Result<u64, String> {
    let d = dir();
    let model_path = d.join(format!("{name}.toml"));
    std::fs::write(&model_path, model).unwrap();
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/filter/data.csv");
    let output = d.join(format!("{name}.csv"));
    let _ = std::fs::remove_file(&output);
    let r =
        filter(&FilterOptions { estimator: estimator.into(), ..FilterOptions::new(model_path, data, output.clone()) })
            .map(|s| s.tally.steps)
            .map_err(|e| e.to_string());
    if r.is_err() {
        assert!(!output.exists(), "{name}: no output on error");
    }
    r
}

#[test]
fn both_moving_horizon_estimators_run_with_a_table() {
    for est in ["rmhe", "mhe"] {
        assert_eq!(run(&format!("ok-{est}"), &format!("{MODEL}{TABLE}"), est), Ok(40));
    }
    let alpha = format!(
        "{MODEL}{}",
        TABLE.replace("lambda_v = 10.0", "alpha = 0.9\nalpha_map = \"one-over-alpha\"\nsolver = \"exact-saddle\"")
    );
    assert_eq!(run("alpha", &alpha, "rmhe"), Ok(40));
}

#[test]
fn a_missing_table_is_named() {
    let e = run("missing", MODEL, "rmhe").unwrap_err();
    assert!(e.contains("needs the noise boxes w_lower, w_upper, v_lower, v_upper in the model file"), "{e}");
}

#[test]
fn bad_settings_point_at_their_key() {
    let cases = [
        // (replacement of a line of TABLE, expected location and words)
        ("blocks = [5, 1]", "blocks = [4, 1]", "missing.toml:10:10", "sum to 5"),
        ("lambda_v = 10.0", "lambda_v = 1.0", ":11:12", "lambda_v"),
        ("v_lower = [-0.02]", "v_lower = [0.5]", ":14:11", "box V"),
        ("w_lower = [-1e-3, -1e-2]", "w_lower = [-1e-3]", ":12:11", "expected 2 entries"),
        ("blocks = [5, 1]", "preset = \"rmhe-xx\"", ":10:10", "unknown value"),
        ("lambda_v = 10.0", "lambda_v = 10.0\nsolver = \"newton\"", ":12:10", "unknown value"),
        ("horizon = 6", "horizon = 6\nmystery = 1", ":", "unknown setting(s) mystery"),
    ];
    for (i, (from, to, at, words)) in cases.into_iter().enumerate() {
        let text = format!("{MODEL}{}", TABLE.replace(from, to));
        let e = run(&format!("bad{i}"), &text, "rmhe").unwrap_err();
        let at = at.replace("missing", &format!("bad{i}"));
        assert!(e.contains(&at) && e.contains(words), "case {i}: {e}");
    }
}

#[test]
fn a_measurement_outside_the_boxes_stops_the_run_at_its_line_or_is_flagged() {
    // 2 500 times V's half-width on line 22 (k = 20): no disturbance inside W explains it.
    let d = dir();
    let clean =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/filter/data.csv")).unwrap();
    let text: String =
        clean
            .lines()
            .map(|l| {
                if l.starts_with("20,") {
                    format!("{},50.0\n", l.rsplit_once(',').unwrap().0)
                } else {
                    format!("{l}\n")
                }
            })
            .collect();
    let input = d.join("outlier.csv");
    std::fs::write(&input, text).unwrap();
    let model = d.join("outlier.toml");
    std::fs::write(&model, format!("{MODEL}{TABLE}")).unwrap();
    let options = |estimator: &str, checks: Option<estimators::DataChecks>| FilterOptions {
        estimator: estimator.into(),
        checks,
        ..FilterOptions::new(model.clone(), input.clone(), d.join(format!("outlier-{estimator}.csv")))
    };
    for estimator in ["rmhe", "mhe"] {
        let e = filter(&options(estimator, None)).unwrap_err().to_string();
        assert!(e.contains("outlier.csv:22:"), "{estimator}: {e}");
        assert!(e.contains("inconsistent with the noise boxes at step 21"), "{estimator}: {e}");
        let flag = estimators::DataChecks::with_policy(estimators::InconsistencyPolicy::FlagAndContinue);
        let summary = filter(&options(estimator, Some(flag))).unwrap();
        assert_eq!(summary.tally.steps, 40, "{estimator}");
        let written = std::fs::read_to_string(d.join(format!("outlier-{estimator}.csv"))).unwrap();
        let flagged = written.lines().filter(|l| l.contains("inconsistent")).count();
        assert_eq!(flagged, 7, "{estimator}: the 7 windows (N = 6) holding line 22\n{written}");
    }
}
