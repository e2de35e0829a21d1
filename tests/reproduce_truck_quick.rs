//! End to end: `cargo xtask reproduce --paper truck --quick` writes every output, the nominal EKF
//! stays within the digest's sanity bound (a nominal β RMSE above about 0.1° signals a bug), and
//! the deterministic part of its summary matches the reviewed snapshot.

use std::path::PathBuf;

#[test]
fn quick_truck_reproduction_writes_everything_and_matches_its_snapshot() {
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("reproduce-truck-quick");
    let _ = std::fs::remove_dir_all(&out);
    let summary = xtask::reproduce::truck::reproduce(true, &out, xtask::reproduce::DEFAULT_SEED, None)
        .expect("reproduction runs");

    for f in ["report.md", "summary.json"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).expect("valid JSON");
    assert_eq!(json["cases"].as_array().unwrap().len(), 5);
    let svg_ok = |file: &str| {
        let svg = std::fs::read_to_string(out.join("figures").join(file)).unwrap();
        assert!(svg.starts_with("<svg") || svg.starts_with("<?xml"), "{file}");
        assert!(svg.contains("</svg>"), "{file}");
    };
    for c in &summary.cases {
        assert_eq!(c.seeds.len(), summary.sizes.seeds);
        assert!(!c.figures.is_empty(), "{}", c.id);
        for (file, _) in &c.figures {
            svg_ok(file);
        }
        let csv = std::fs::read_to_string(out.join("csv").join(&c.csv)).unwrap();
        let mut lines = csv.lines();
        assert!(lines.next().unwrap().starts_with("t,vx,vx_hat,vx_sigma,vy,"), "{}", c.csv);
        assert_eq!(lines.count(), summary.sizes.steps + 1, "{}: k = 0..=steps", c.csv);
    }
    for (file, _) in &summary.figures {
        svg_ok(file);
    }
    let nominal = &summary.cases[0];
    assert_eq!(nominal.id, "nominal");
    let rmse = nominal.aggregate.beta_deg.whole.rmse.max;
    assert!(rmse < 0.1, "nominal β RMSE {rmse}° above the digest's sanity bound 0.1°");
    assert_eq!(summary.claims.len(), 3);
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    for needle in
        ["## The paper's claims", "Table 2", "No number in this report is the paper's", "![", "## Cost per step"]
    {
        assert!(report.contains(needle), "report.md lacks {needle:?}");
    }
    insta::assert_json_snapshot!("reproduce_truck_quick_summary", summary.deterministic_view());
}
