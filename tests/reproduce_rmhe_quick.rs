//! End to end: `cargo xtask reproduce --paper rmhe --quick` writes every output, judges the four
//! claims, the estimators beat the raw measurement on the position, the coordinate rotation
//! with λv = 10 agrees with the exact saddle, and the deterministic part of the summary matches
//! the reviewed snapshot.

use std::path::PathBuf;

#[test]
fn quick_rmhe_reproduction_writes_everything_and_matches_its_snapshot() {
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("reproduce-rmhe-quick");
    let _ = std::fs::remove_dir_all(&out);
    let summary =
        xtask::reproduce::rmhe::reproduce(true, &out, xtask::reproduce::DEFAULT_SEED, None).expect("reproduction runs");
    for f in ["report.md", "summary.json"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    for (file, _) in &summary.figures {
        let svg = std::fs::read_to_string(out.join("figures").join(file)).unwrap();
        assert!(svg.contains("</svg>"), "{file}");
    }
    assert_eq!(summary.blocks.len(), 4);
    assert_eq!(summary.claims.len(), 4);
    for b in &summary.blocks {
        let get = |id: &str| b.variants.iter().find(|v| v.id == id).unwrap();
        for id in ["rmhe", "rmhe-op", "rmhe-of", "mhe", "saddle"] {
            let v = get(id);
            assert!(v.mse_after_5s[0] < b.raw_measurement_mse, "{id} {:?} {:?}: {:?}", b.case, b.prior, v.mse_after_5s);
        }
        // λv = 10: the rotation converges and equals the saddle to the solvers' tolerance.
        let (cr, ex) = (get("rmhe"), get("saddle"));
        assert_eq!(cr.converged_fraction, 1.0);
        for i in 0..4 {
            assert!(
                (cr.mse[i] - ex.mse[i]).abs() <= 1e-6 * ex.mse[i].max(1e-12),
                "state {i}: {} vs {}",
                cr.mse[i],
                ex.mse[i]
            );
        }
    }
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    for needle in ["## The paper's claims", "Table 2", "No number in", "![", "## Cost per update"] {
        assert!(report.contains(needle), "report.md lacks {needle:?}");
    }
    insta::assert_json_snapshot!("reproduce_rmhe_quick_summary", summary.deterministic_view());
}
