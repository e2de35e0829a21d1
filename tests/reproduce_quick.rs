//! End to end: `cargo xtask reproduce --quick` writes every output, the guarantee holds in every
//! scenario, and the deterministic part of its summary matches the reviewed snapshot.

use std::path::PathBuf;

#[test]
fn quick_reproduction_writes_everything_and_matches_its_snapshot() {
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("reproduce-quick");
    let _ = std::fs::remove_dir_all(&out);
    let summary = xtask::reproduce::carrier::reproduce(true, &out, xtask::reproduce::DEFAULT_SEED, None)
        .expect("reproduction runs");

    for f in ["report.md", "summary.json"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).expect("valid JSON");
    assert_eq!(json["scenarios"].as_array().unwrap().len(), 6);
    for s in &summary.scenarios {
        assert_eq!(s.figures.len(), 8, "{}: figures 3–10", s.id);
        for (file, _) in &s.figures {
            let svg = std::fs::read_to_string(out.join("figures").join(file)).unwrap();
            assert!(svg.starts_with("<svg") || svg.starts_with("<?xml"), "{file}");
            assert!(svg.contains("</svg>"), "{file}");
        }
        for m in &s.estimators {
            let csv = out.join("csv").join(format!("{}_{}.csv", s.id, xtask::reproduce::outputs::slug(&m.estimator)));
            let lines = std::fs::read_to_string(&csv).unwrap().lines().count();
            assert_eq!(lines, m.steps + 2, "{}: header + k = 0..=steps", csv.display());
            // The guarantee: no published set misses the truth (k ≥ 1; noise within its bounds).
            if let Some(outside) = m.steps_outside {
                assert_eq!(outside, 0, "{} / {}", s.id, m.estimator);
            }
        }
    }
    assert_eq!(summary.monte_carlo.steps_outside, 0);
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    for needle in ["## The paper's claims", "Inconsistencies", "Monte Carlo", "![Fig. 3"] {
        assert!(report.contains(needle), "report.md lacks {needle:?}");
    }
    insta::assert_json_snapshot!("reproduce_quick_summary", summary.deterministic_view());
}
