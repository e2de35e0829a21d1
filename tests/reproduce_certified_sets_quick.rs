//! End to end: `cargo xtask reproduce --paper certified-sets --quick --runs 1` writes its report,
//! judges its seven targets honestly at the small sizes (containment and growth "not met at these
//! sizes" although nothing was missed), and meets the six-tank and carrier targets.

use std::path::PathBuf;

use xtask::reproduce::{DEFAULT_SEED, Options, certified_sets};

#[test]
fn quick_certified_sets_run_judges_every_target() {
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("reproduce-certified-sets-quick");
    let _ = std::fs::remove_dir_all(&out);
    std::fs::create_dir_all(&out).unwrap();
    let opts = Options { quick: true, seed: DEFAULT_SEED, runs: Some(1) };
    let s = certified_sets::reproduce(&opts, &out).expect("the benchmark runs");
    for f in ["report.md", "summary.json"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    assert_eq!(s.claims.len(), 7);
    // CORA's published comparison: only the t = 9.5 s hulls, three observers.
    assert_eq!(s.six_tank.cora.len(), 3);
    // The mean of the per-state least widths (FRad-A but x4, x5 from FRad-B): 4.2489.
    assert!((s.six_tank.cora_best_mean - 4.2489).abs() < 1e-4, "{}", s.six_tank.cora_best_mean);
    assert_eq!(s.claims[0].verdict, "met", "{}", s.claims[0].evidence);
    assert_eq!(s.six_tank.unclean_steps, 0);
    for c in &s.campaign {
        assert_eq!(c.misses, 0, "{}", c.name);
        assert!(c.stopped.is_empty(), "{}: {:?}", c.name, c.stopped);
        assert_eq!(c.runs, 1);
    }
    // Too few steps to judge the containment and growth targets: said so, not "met".
    assert!(s.claims[1].verdict.starts_with("not met at these sizes"), "{}", s.claims[1].verdict);
    assert!(s.claims[2].verdict.starts_with("not met at these sizes"), "{}", s.claims[2].verdict);
    assert!(s.claims[3].verdict.starts_with("not met at these sizes"), "{}", s.claims[3].verdict);
    assert!(s.claims[4].verdict.starts_with("not met at these sizes"), "{}", s.claims[4].verdict);
    assert_eq!(s.claims[5].verdict, "met", "{}", s.claims[5].evidence);
    let carrier = s.campaign.iter().find(|c| c.name == "carrier").unwrap();
    let e = carrier.ellipsoid.as_ref().unwrap();
    assert_eq!((e.misses, e.observer_misses), (0, 0));
    // The interval observer never widens smf's interval (it only cuts it).
    assert!(e.observer_width_ratio.iter().all(|r| *r <= 1.0), "{:?}", e.observer_width_ratio);
    assert!(e.median_width_ratio.iter().all(|r| *r <= 1.0), "{:?}", e.median_width_ratio);
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    for needle in
        ["## Targets", "CORA FRad-A (published)", "## Boundary noise", "`smf` beside `czf`", "range-bearing circling"]
    {
        assert!(report.contains(needle), "report.md lacks {needle:?}");
    }
}
