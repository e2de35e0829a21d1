//! `[estimator.NAME]` tables of a model file: each estimator's settings by the registry's
//! keywords, read by the registry's one settings reader (the one that reads Python's keyword
//! arguments), every mistake at the key's `file:line:column`.

mod common;

use std::path::PathBuf;

use common::DOUBLE_INTEGRATOR as MODEL;
use estimators::registry::{self, EstimatorSettings};
use port_est::{FilterOptions, filter, read_model};

fn dir(name: &str) -> PathBuf {
    common::fresh_dir("port-est-estimator-tables", name)
}

fn model_error(name: &str, text: &str) -> String {
    let d = dir(name);
    std::fs::write(d.join("m.toml"), text).unwrap();
    read_model(&d.join("m.toml")).unwrap_err().to_string()
}

/// Runs `estimator` over 60 steps of a simulated run (the output measured with noise on the
/// boundary of `±0.05`); the output file's text.
fn run(name: &str, model: &str, estimator: &str, solver: Option<&str>) -> Result<String, String> {
    let d = dir(name);
    let mut data = String::from("k,u1,y1\n");
    let mut x = [0.3, -0.2];
    for k in 0..60 {
        let u = (0.1 * k as f64).sin();
        x = [x[0] + 0.1 * x[1], x[1] + 0.1 * u];
        let y = x[0] + if k % 5 < 2 { 0.05 } else { -0.05 };
        data.push_str(&format!("{k},{u},{y}\n"));
    }
    std::fs::write(d.join("model.toml"), model).unwrap();
    std::fs::write(d.join("data.csv"), data).unwrap();
    let options = FilterOptions {
        estimator: estimator.into(),
        solver: solver.map(Into::into),
        ..FilterOptions::new(d.join("model.toml"), d.join("data.csv"), d.join("out.csv"))
    };
    filter(&options).map_err(|e| e.to_string())?;
    Ok(std::fs::read_to_string(d.join("out.csv")).unwrap())
}

/// The values of the column `name` of an output file.
fn column(out: &str, name: &str) -> Vec<f64> {
    let mut lines = out.lines();
    let j = lines.next().unwrap().split(',').position(|c| c == name).unwrap();
    lines.map(|l| l.split(',').nth(j).unwrap().parse().unwrap()).collect()
}

#[test]
fn every_keyword_of_every_estimator_is_read_from_its_table() {
    // A value of no keyword's type (an inline table): refused as that key's value, at its line
    // and column, never as an unknown setting.
    let mut checked = 0;
    for entry in registry::ESTIMATORS {
        for keyword in entry.settings.keywords() {
            // (The moving-horizon estimators' noise boxes from an `[mhe]` table.)
            let mhe = "[mhe]\nw_lower = [-1.0, -1.0]\nw_upper = [1.0, 1.0]\nv_lower = [-1.0]\nv_upper = [1.0]\n";
            let text = format!("{MODEL}{mhe}[estimator.{}]\n{} = {{ wrong = 1 }}\n", entry.name, keyword.name);
            let e = model_error("keyword", &text);
            let column = keyword.name.len() + 4;
            let at = format!("m.toml:14:{column}: `estimator.{}.{}`: must be ", entry.name, keyword.name);
            assert!(e.contains(&at), "{} {}: {e}", entry.name, keyword.name);
            checked += 1;
        }
    }
    assert!(checked > 40, "{checked}");
}

#[test]
fn mistakes_in_a_table_are_at_their_key() {
    let e = model_error("name", &format!("{MODEL}[estimator.czff]\norder = 3\n"));
    assert!(e.contains("`estimator.czff`: no estimator is called \"czff\" (one of: "), "{e}");
    assert!(e.contains("m.toml:8:1:"), "{e}");
    let e = model_error("unknown", &format!("{MODEL}[estimator.czf]\norder = 3\nordr = 4\n"));
    assert!(e.contains("m.toml:10:8: `estimator.czf.ordr`: unknown setting(s) ordr for estimator czf"), "{e}");
    assert!(e.contains("(it takes: order, max_constraints,"), "{e}");
    let e = model_error("choice", &format!("{MODEL}[estimator.smf]\ninconsistency = \"maybe\"\n"));
    assert!(e.contains("m.toml:9:17: `estimator.smf.inconsistency`: unknown value \"maybe\" (one of: error,"), "{e}");
    let e = model_error("length", &format!("{MODEL}[estimator.czf]\nx_lower = [0.0]\nx_upper = [1.0]\n"));
    assert!(e.contains("m.toml:9:11: `estimator.czf.x_lower`: expected 2 entries, found 1"), "{e}");
    let e = model_error("half", &format!("{MODEL}[estimator.czf]\nx_upper = [1.0, 1.0]\n"));
    assert!(e.contains("m.toml:9:11: `estimator.czf.x_upper`: give both x_lower and x_upper, or neither"), "{e}");
    let e = model_error("kf", &format!("{MODEL}[estimator.kf]\nhorizon = 3\n"));
    assert!(e.contains("`estimator.kf.horizon`: unknown setting(s) horizon for estimator kf (it takes: no settings)"));
}

#[test]
fn a_table_sets_its_estimator_and_the_command_line_solver_goes_over_it() {
    let sets = "x0_radius = [0.5, 0.5]\nw_radius = [0.01, 0.01]\nv_radius = [0.05]\n";
    let default = run("czf-default", &format!("{MODEL}{sets}"), "czf", None).unwrap();
    let table = "[estimator.czf]\norder = 2\nmax_constraints = 1\n";
    let order_two = run("czf-order", &format!("{MODEL}{sets}{table}"), "czf", None).unwrap();
    let (many, few) = (column(&default, "generators"), column(&order_two, "generators"));
    assert!(many.iter().any(|&g| g > 4.0), "{many:?}");
    assert!(few.iter().all(|&g| g <= 4.0), "order 2 keeps 2 n = 4 generators: {few:?}");
    // The table of another estimator changes nothing here.
    let other = format!("{MODEL}{sets}{}", table.replace("czf", "czf-nl"));
    let other = run("czf-other", &other, "czf", None).unwrap();
    assert_eq!(other, default);
    // `--solver` over the table's: an SDP backend named in the file, the exact method on the
    // command line, gives the exact method's run bit for bit.
    let exact = run("smf", MODEL, "smf", None).unwrap();
    let table = format!("{MODEL}[estimator.smf]\nsolver = \"{}\"\n", registry::SmfSolver::names()[1]);
    assert_eq!(run("smf-cli", &table, "smf", Some("two-multiplier")).unwrap(), exact);
    // The paper's filter alone, without the interval observer: another run.
    let alone = run("smf-alone", &format!("{MODEL}[estimator.smf]\ninterval_observer = false\n"), "smf", None);
    assert_ne!(alone.unwrap(), exact);
}

#[test]
fn a_moving_horizon_estimator_takes_its_boxes_from_its_own_table() {
    let boxes = "w_lower = [-1e-2, -1e-2]\nw_upper = [1e-2, 1e-2]\nv_lower = [-0.06]\nv_upper = [0.06]\n";
    let e = run("rmhe-none", MODEL, "rmhe", None).unwrap_err();
    assert!(e.contains("needs the noise boxes w_lower, w_upper, v_lower, v_upper in the model file"), "{e}");
    let shared = run("rmhe-mhe", &format!("{MODEL}[mhe]\n{boxes}horizon = 4\n"), "rmhe", None).unwrap();
    let own = run("rmhe-own", &format!("{MODEL}[estimator.rmhe]\n{boxes}horizon = 4\n"), "rmhe", None).unwrap();
    assert_eq!(own, shared);
    // The estimator's table over the shared one.
    let over = format!("{MODEL}[mhe]\n{boxes}horizon = 4\n[estimator.rmhe]\nhorizon = 5\n");
    assert_ne!(run("rmhe-over", &over, "rmhe", None).unwrap(), shared);
    // Read the same as Rust's typed settings.
    let d = dir("typed");
    std::fs::write(d.join("m.toml"), &over).unwrap();
    let model = read_model(&d.join("m.toml")).unwrap();
    let table = model.settings_table("rmhe");
    let entry = registry::entry("rmhe").unwrap();
    let read = registry::read_settings(entry.settings, "rmhe", &model.keyword_context(), &mut table.reader(&[]));
    let Ok(Some(EstimatorSettings::MovingHorizon(s))) = read else { panic!("{read:?}") };
    let mut expected = model.mhe.clone().unwrap();
    expected.horizon = 5;
    expected.blocks = vec![1; 5];
    assert_eq!(*s, expected);
}

#[test]
fn a_setting_the_estimator_refuses_is_at_its_key() {
    let sets = "x0_radius = [0.5, 0.5]\nw_radius = [0.01, 0.01]\nv_radius = [0.05]\n";
    // Order 1 leaves no room for the default 8 constraints: the filter refuses it when built.
    let text = format!("{MODEL}{sets}[estimator.czf]\nmax_constraints = 8\norder = 1\n");
    let e = run("refused", &text, "czf", None).unwrap_err();
    assert!(
        e.contains("model.toml:12:19: `estimator.czf.max_constraints`: invalid setting max_constraints = 8"),
        "{e}"
    );
}

#[test]
fn a_file_cannot_lift_the_memory_limit_it_is_read_under() {
    let boxes = "w_lower = [-1e-2, -1e-2]\nw_upper = [1e-2, 1e-2]\nv_lower = [-0.06]\nv_upper = [0.06]\n";
    for table in ["mhe", "estimator.rmhe"] {
        let text = format!("{MODEL}[{table}]\n{boxes}memory_limit = 1000000000000\nhorizon = 20000\n");
        let e = model_error("ceiling", &text);
        assert!(e.contains(&format!("m.toml:13:16: `{table}.memory_limit`: 1000000000000 bytes is above")), "{e}");
        assert!(e.contains("the limit of 256 MiB this file is read under (raise that with --mhe-memory-limit)"), "{e}");
    }
    // Below the command line's limit it lowers it.
    let text = format!("{MODEL}[mhe]\n{boxes}memory_limit = 1000\n");
    let e = model_error("lowered", &text);
    assert!(e.contains("more than the limit of 1000 B"), "{e}");
}

#[test]
fn a_rule_file_named_in_a_table_is_read_beside_the_model_file() {
    let d = dir("fis");
    std::fs::write(d.join("m.toml"), format!("{MODEL}[estimator.fkf]\nfis = \"rules/none.toml\"\n")).unwrap();
    let e = read_model(&d.join("m.toml")).unwrap_err().to_string();
    let beside = d.join("rules/none.toml");
    assert!(e.contains("m.toml:9:7: `estimator.fkf.fis`: "), "{e}");
    assert!(e.contains(&beside.display().to_string()), "the path beside the model file: {e}");
}

#[test]
fn the_readme_s_tables_are_read_as_it_says() {
    // The crate README's example of `[estimator.NAME]` tables, appended to a model file with the
    // moving-horizon estimators' noise boxes.
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap();
    let start = readme.find("[estimator.czf]").expect("the README shows `[estimator.czf]`");
    let block = &readme[start..start + readme[start..].find("```").unwrap()];
    let block: String = block.lines().map(|l| format!("{}\n", l.trim())).collect();
    let d = dir("readme");
    std::fs::write(d.join("m.toml"), format!("{}{block}", common::OSCILLATOR_WITH_NOISE_BOXES)).unwrap();
    let model = read_model(&d.join("m.toml")).unwrap_or_else(|e| panic!("{e}"));
    for (name, order, max_constraints) in [("czf", 30, 8), ("czf-nl", 1, 0)] {
        match port_est::filter::estimator_settings(&model, name).unwrap() {
            Some(EstimatorSettings::ConstrainedZonotope(s)) => {
                assert_eq!((s.order, s.max_constraints), (order, max_constraints), "{name}");
            }
            other => panic!("{name}: {other:?}"),
        }
    }
    let Some(EstimatorSettings::MovingHorizon(mhe)) = port_est::filter::estimator_settings(&model, "rmhe").unwrap()
    else {
        panic!("rmhe's settings are a moving-horizon estimator's")
    };
    assert_eq!(mhe.horizon, 10);
}
