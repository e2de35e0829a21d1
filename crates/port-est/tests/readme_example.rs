//! The example of the crate's README (`examples/filter/` of the workspace), run for every
//! registered estimator.

use std::path::{Path, PathBuf};

use estimators::EstimateKind;
use estimators::registry::{ESTIMATORS, SmfSolver, names};
use port_est::{FilterOptions, filter};

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn out_dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join("port-est").join(name);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn the_readme_documents_the_example() {
    let readme = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md")).unwrap();
    assert!(readme.contains(
        "port-est filter --model examples/filter/model.toml --input examples/filter/data.csv --output out.csv"
    ));
}

#[test]
fn readme_filter_example_runs_for_every_estimator() {
    let root = workspace();
    let dir = out_dir("readme");
    let smf = ESTIMATORS.iter().find(|e| e.name == names::SMF).unwrap();
    let sdp_solvers = SmfSolver::names().into_iter().filter(|s| *s != SmfSolver::TWO_MULTIPLIER);
    // Every estimator with its default solver (but those that read more measurement columns than
    // the example has: the fuzzy-adaptive filter's receiver status), and the set-membership filter
    // through every SDP backend of this build.
    let plain = ESTIMATORS.iter().filter(|e| e.extra_measurements == 0);
    let runs = plain.map(|e| (e, None)).chain(sdp_solvers.map(|s| (smf, Some(s))));
    for (info, solver) in runs {
        let label = format!("{}{}", info.name, solver.map_or(String::new(), |s| format!("-{s}")));
        let output = dir.join(format!("{label}.csv"));
        let summary = filter(&FilterOptions {
            estimator: info.name.to_owned(),
            solver: solver.map(str::to_owned),
            ..FilterOptions::new(
                root.join("examples/filter/model.toml"),
                root.join("examples/filter/data.csv"),
                output.clone(),
            )
        })
        .unwrap_or_else(|e| panic!("{label}: {e}"));
        assert_eq!(summary.tally.steps, 40, "{label}");

        let text = std::fs::read_to_string(&output).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 41, "{label}: header and 40 steps");
        // Columns named after what they are: no bounds for point estimates.
        let expected = match info.kind {
            EstimateKind::GuaranteedEllipsoid => {
                "k,xhat1,xhat2,lo1,lo2,hi1,hi2,trace_shape,tau1,tau2,tau3,iterations,status"
            }
            EstimateKind::Gaussian => "k,xhat1,xhat2,sd1,sd2,trace_cov,status",
            EstimateKind::GuaranteedConstrainedZonotope => {
                "k,xhat1,xhat2,lo1,lo2,hi1,hi2,generators,constraints,status"
            }
            _ => "k,xhat1,xhat2,iterations,status",
        };
        assert_eq!(lines[0], expected, "{label}");
        for (i, line) in lines[1..].iter().enumerate() {
            let cells: Vec<&str> = line.split(',').collect();
            assert_eq!(cells.len(), lines[0].split(',').count(), "{label}: row {i}");
            let status = cells[cells.len() - 1];
            assert!(
                ["converged", "not-converged", "fallback"].contains(&status),
                "{label}: row {i} has status {status}"
            );
            let v: Vec<f64> = cells[..cells.len() - 1].iter().map(|x| x.parse().unwrap()).collect();
            assert!(v.iter().all(|x| x.is_finite()), "{label}: row {i} is finite");
            assert_eq!(v[0], (i + 1) as f64, "{label}: rows are labelled k + 1");
            match info.kind {
                EstimateKind::GuaranteedEllipsoid => {
                    assert!(v[7] > 0.0, "{label}: trace");
                    for s in 0..2 {
                        // The interval is the ellipsoid's projection cut by the interval observer,
                        // which may leave the ellipsoid's centre outside it.
                        assert!(v[3 + s] <= v[5 + s], "{label}: lo <= hi at row {i}");
                    }
                    assert!(v[8..11].iter().all(|t| *t >= 0.0), "{label}: multipliers are nonnegative");
                }
                EstimateKind::Gaussian => assert!(v[3] > 0.0 && v[4] > 0.0 && v[5] > 0.0, "{label}: sd and trace"),
                EstimateKind::GuaranteedConstrainedZonotope => {
                    for s in 0..2 {
                        assert!(v[3 + s] <= v[1 + s] && v[1 + s] <= v[5 + s], "{label}: lo <= xhat <= hi at row {i}");
                    }
                    assert!(v[7] >= 1.0, "{label}: generators");
                }
                _ => {}
            }
        }
    }
    // Nothing but the outputs is left behind (no temporary files).
    assert!(std::fs::read_dir(&dir).unwrap().flatten().all(|e| !e.file_name().to_string_lossy().ends_with(".tmp")));
}
