//! End to end: `cargo xtask reproduce --paper dp-vessel --quick` writes every output, the
//! thrust never leaves its limits, the UKF never needs its positive-definiteness guard, and the
//! deterministic part of its summary matches the reviewed snapshot.

use std::path::PathBuf;

#[test]
fn quick_dp_vessel_reproduction_writes_everything_and_matches_its_snapshot() {
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("reproduce-dp-vessel-quick");
    let _ = std::fs::remove_dir_all(&out);
    let summary = xtask::reproduce::dp_vessel::reproduce(true, &out, xtask::reproduce::DEFAULT_SEED, None)
        .expect("reproduction runs");

    for f in ["report.md", "summary.json"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).expect("valid JSON");
    let scenarios = xtask::reproduce::dp_vessel::run::SCENARIOS.len();
    let estimators = xtask::reproduce::dp_vessel::run::ESTIMATORS.len();
    assert_eq!(json["results"].as_array().unwrap().len(), scenarios * estimators);
    let svg_ok = |file: &str| {
        let svg = std::fs::read_to_string(out.join("figures").join(file)).unwrap();
        assert!(svg.starts_with("<svg") || svg.starts_with("<?xml"), "{file}");
        assert!(svg.contains("</svg>"), "{file}");
    };
    for r in &summary.results {
        assert_eq!(r.seeds.len(), summary.sizes.seeds);
        assert_eq!(r.figures.is_empty(), !r.scenario.figures, "{}", r.csv);
        for (file, _) in &r.figures {
            svg_ok(file);
        }
        let csv = std::fs::read_to_string(out.join("csv").join(&r.csv)).unwrap();
        let mut lines = csv.lines();
        assert!(lines.next().unwrap().starts_with("t,x,y,psi,u,v,r,x_hat,"), "{}", r.csv);
        assert_eq!(lines.count(), summary.sizes.steps + 1, "{}: k = 0..=steps", r.csv);
        // Saturation respected: no commanded step change exceeds the full range 2·limit.
        for i in 0..3 {
            assert!(r.aggregate.max_jump[i].max <= 2.0 + 1e-12, "axis {i}: a jump beyond the full range");
        }
        // Every run arrives near the target eventually and the estimate is finite.
        assert_eq!(r.aggregate.arrival_s.missing, 0, "{} / {} never arrived", r.scenario.id, r.estimator);
        assert!(r.aggregate.rmse[0].mean.is_finite());
    }
    for (file, _) in &summary.figures {
        svg_ok(file);
    }
    assert_eq!(summary.claims.len(), 4);
    // The MHE whose arrival UKF keeps its own mean is, on this nearly linear model without
    // constraints, the extended Kalman filter (position RMSE within 5 %).
    for r in summary.results.iter().filter(|r| r.estimator == "mhe-ukf-own") {
        let ekf = summary.results.iter().find(|e| e.estimator == "ekf" && e.scenario.id == r.scenario.id).unwrap();
        for i in 0..2 {
            let (a, b) = (r.aggregate.rmse[i].mean, ekf.aggregate.rmse[i].mean);
            assert!((a - b).abs() <= 0.05 * b, "{}: MHE {a} vs EKF {b}", r.scenario.id);
        }
    }
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    for needle in
        ["## The paper's claims", "## Table 1", "No number in this report is the paper's", "![", "## Cost per step"]
    {
        assert!(report.contains(needle), "report.md lacks {needle:?}");
    }
    insta::assert_json_snapshot!("reproduce_dp_vessel_quick_summary", summary.deterministic_view());
}
