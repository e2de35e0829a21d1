//! End to end: `cargo xtask reproduce --paper bds-ins --quick` writes every output, the plain KF is
//! consistent under nominal noise (a sanity bound: RMS error / σ near 1 before 600 s), the FKF with
//! the scripted `d` equals the KF before 600 s (t = 1), and the deterministic part of the summary
//! matches the reviewed snapshot.

use std::path::PathBuf;

#[test]
fn quick_bds_ins_reproduction_writes_everything_and_matches_its_snapshot() {
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("reproduce-bds-ins-quick");
    let _ = std::fs::remove_dir_all(&out);
    let summary = xtask::reproduce::bds_ins::reproduce(true, &out, xtask::reproduce::DEFAULT_SEED, None)
        .expect("reproduction runs");

    for f in ["report.md", "summary.json"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).expect("valid JSON");
    assert_eq!(json["readings"].as_array().unwrap().len(), 2);
    let svg_ok = |file: &str| {
        let svg = std::fs::read_to_string(out.join("figures").join(file)).unwrap();
        assert!(svg.starts_with("<svg") || svg.starts_with("<?xml"), "{file}");
        assert!(svg.contains("</svg>"), "{file}");
    };
    for r in &summary.readings {
        assert_eq!(r.figures.len(), 3, "{}", r.id);
        for (file, _) in &r.figures {
            svg_ok(file);
        }
        let csv = std::fs::read_to_string(out.join("csv").join(&r.csv)).unwrap();
        let mut lines = csv.lines();
        assert!(lines.next().unwrap().starts_with("k,kf_ex_seed0,kf_ey_seed0,"), "{}", r.csv);
        assert_eq!(lines.count(), summary.sizes.epochs_a + 1, "{}: k = 0..=1200", r.csv);
        let kf = &r.filters[0].windows[0];
        let scripted = &r.filters[1].windows[0];
        assert_eq!(r.filters[0].id, "kf");
        assert!((0.7..1.3).contains(&kf.consistency_x), "KF inconsistent before 600 s: {}", kf.consistency_x);
        assert_eq!(kf.mean_horizontal, scripted.mean_horizontal, "scripted FKF differs from the KF at t = 1");
    }
    for (file, _) in &summary.field.figures {
        svg_ok(file);
    }
    assert_eq!(summary.field.filters.len(), 2);
    assert_eq!(summary.claims.len(), 6);
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    for needle in ["## The paper's claims", "Table 1", "Which numbers are the paper's", "![", "## Cost per step"] {
        assert!(report.contains(needle), "report.md lacks {needle:?}");
    }
    insta::assert_json_snapshot!("reproduce_bds_ins_quick_summary", summary.deterministic_view());
}
