//! The `cargo xtask filter` example of the README, run exactly as documented.

use std::path::Path;

#[test]
fn readme_filter_example_runs_for_every_estimator() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    assert!(readme.contains("cargo xtask filter --model examples/filter/model.toml --input examples/filter/data.csv"));
    let out_dir = Path::new(env!("CARGO_TARGET_TMPDIR"));
    for (estimator, header_end) in
        [("smf", ",trace,tau1,tau2,tau3"), ("yang-li", ",trace,tau1,tau2,tau3"), ("kf", ",trace")]
    {
        let out = out_dir.join(format!("filter-example-{estimator}.csv"));
        let args: Vec<String> = [
            "--model",
            root.join("examples/filter/model.toml").to_str().unwrap(),
            "--input",
            root.join("examples/filter/data.csv").to_str().unwrap(),
            "--output",
            out.to_str().unwrap(),
            "--estimator",
            estimator,
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        xtask::filter::run(&args).unwrap();
        let text = std::fs::read_to_string(&out).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 41, "{estimator}: header and 40 steps");
        assert_eq!(lines[0], format!("k,xhat1,xhat2,lo1,lo2,hi1,hi2{header_end}"));
        for (i, line) in lines[1..].iter().enumerate() {
            let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
            assert_eq!(v[0], (i + 1) as f64, "rows are labelled k + 1");
            for s in 0..2 {
                assert!(v[3 + s] <= v[1 + s] && v[1 + s] <= v[5 + s], "{estimator}: lo <= xhat <= hi");
            }
        }
    }
}
