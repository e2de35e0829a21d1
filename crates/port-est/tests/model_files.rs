//! The vehicles' model files of `examples/models/` as `port-est` reads them, and the supply
//! vessel's example log (`examples/vessel/`, written by `examples/vessel_log.rs` from the compiled
//! vessel) filtered by the nonlinear estimators through its model file, as the README shows.

use std::path::{Path, PathBuf};

use port_est::{FilterOptions, filter, read_model, write_estimators_for};

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn out_dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join("port-est").join(name);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(str::to_owned).collect();
    let rows = lines.map(|l| l.split(',').map(|v| v.parse().unwrap_or(f64::NAN)).collect()).collect();
    (header, rows)
}

#[test]
fn every_vehicle_file_is_read_and_says_what_runs_on_it() {
    // (file, n, p, m, an estimator that runs, one that does not)
    let cases = [
        ("carrier", 4, 8, 4, "smf", "rmhe"),
        ("car", 4, 1, 1, "rmhe", "yang-li"),
        ("vessel", 6, 3, 3, "mhe-ukf", "kf"),
        ("bds-ins", 13, 0, 3, "kf", "rmhe"),
        ("truck", 3, 7, 3, "ekf", "smf"),
    ];
    for (name, n, p, m, runs, not) in cases {
        let path = workspace().join(format!("examples/models/{name}.toml"));
        let model = read_model(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!((model.states(), model.inputs(), model.outputs()), (n, p, m), "{name}");
        let mut listing = Vec::new();
        write_estimators_for(&model, &mut listing).unwrap();
        let listing = String::from_utf8(listing).unwrap();
        let (yes, no) = listing.split_once("Does not run:").unwrap_or((&listing, ""));
        assert!(yes.contains(&format!("\n  {runs} ")), "{name}: {runs} should run:\n{listing}");
        assert!(no.contains(&format!("\n  {not} ")), "{name}: {not} should not run:\n{listing}");
    }
}

#[test]
fn the_vessel_log_is_tracked_by_the_nonlinear_estimators_of_its_model_file() {
    let root = workspace();
    let (_, truth) = csv(&root.join("examples/vessel/truth.csv"));
    let dir = out_dir("vessel");
    for estimator in ["ekf", "ukf", "mhe-ukf"] {
        let output = dir.join(format!("{estimator}.csv"));
        let summary = filter(&FilterOptions {
            estimator: estimator.to_owned(),
            status: port_est::StatusPolicy::Error,
            ..FilterOptions::new(
                root.join("examples/models/vessel.toml"),
                root.join("examples/vessel/data.csv"),
                output.clone(),
            )
        })
        .unwrap_or_else(|e| panic!("{estimator}: {e}"));
        assert_eq!(summary.tally.steps, truth.len() as u64, "{estimator}");
        let (header, rows) = csv(&output);
        assert_eq!(header[..7], ["k", "xhat1", "xhat2", "xhat3", "xhat4", "xhat5", "xhat6"]);
        // After 10 s: the positions within 0.6 m RMS of the truth (the GNSS noise is 1 m), the
        // heading within 0.25 rad RMS (its sensor's noise: 0.32 rad).
        let settled = &rows[100..];
        let rms = |i: usize| {
            let sum: f64 = settled.iter().zip(&truth[100..]).map(|(r, t)| (r[1 + i] - t[1 + i]).powi(2)).sum();
            (sum / settled.len() as f64).sqrt()
        };
        let (x, y, psi) = (rms(0), rms(1), rms(2));
        assert!(x < 0.6 && y < 0.6 && psi < 0.25, "{estimator}: RMS errors x {x}, y {y}, ψ {psi}");
        // The Gaussian filters' standard deviations are honest: fewer than 1 % of the state errors
        // beyond 3σ (a Gaussian gives 0.27 %).
        if let Some(sd) = header.iter().position(|h| h == "sd1") {
            let beyond = rows
                .iter()
                .zip(&truth)
                .flat_map(|(r, t)| (0..6).map(move |i| (r[1 + i] - t[1 + i]).abs() > 3.0 * r[sd + i]))
                .filter(|&b| b)
                .count();
            assert!(beyond * 100 < rows.len() * 6, "{estimator}: {beyond} state errors beyond 3σ");
        }
    }
}

#[test]
fn the_readmes_show_the_vessel_example() {
    let command = "port-est filter --model examples/models/vessel.toml --input examples/vessel/data.csv";
    for readme in ["README.md", "crates/port-est/README.md"] {
        let text = std::fs::read_to_string(workspace().join(readme)).unwrap();
        assert!(text.contains(command), "{readme}");
    }
}

#[test]
fn a_builtin_vehicle_is_its_compiled_model_with_its_files_noise() {
    let root = workspace();
    let dir = out_dir("builtin");
    let run = |model: &str, estimator: &str| {
        let output = dir.join(format!("{}-{estimator}.csv", model.replace([':', '/'], "-")));
        filter(&FilterOptions {
            estimator: estimator.to_owned(),
            status: port_est::StatusPolicy::Error,
            ..FilterOptions::new(
                if model.starts_with("builtin:") { model.into() } else { root.join(model) },
                root.join("examples/vessel/data.csv"),
                output.clone(),
            )
        })
        .unwrap_or_else(|e| panic!("{model} {estimator}: {e}"));
        csv(&output).1
    };
    // The compiled vessel and its equations agree to rounding over the whole log.
    for estimator in ["ekf", "ukf"] {
        let (compiled, equations) = (run("builtin:vessel", estimator), run("examples/models/vessel.toml", estimator));
        assert_eq!(compiled.len(), equations.len());
        for (a, b) in compiled.iter().zip(&equations) {
            for (x, y) in a.iter().zip(b).filter(|(x, _)| x.is_finite()) {
                assert!((x - y).abs() <= 1e-9 * x.abs().max(1.0), "{estimator}: {x} against {y}");
            }
        }
    }
    for vehicle in port_est::builtin::BUILTINS {
        let model = read_model(Path::new(&format!("builtin:{}", vehicle.name))).unwrap();
        assert!(model.column_names().is_some(), "{}", vehicle.name);
    }
    let e = read_model(Path::new("builtin:tug")).unwrap_err().to_string();
    assert!(e.starts_with("unknown built-in model \"tug\" (known: builtin:carrier, builtin:car"), "{e}");
}
