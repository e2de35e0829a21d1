//! `port-est bds-ins` end to end on the shipped example: the README documents it, the corrected
//! position is far better than the INS alone, epochs without a fix are predictions, and a bad row
//! leaves no output.

use std::path::{Path, PathBuf};

use port_est::bds_ins::{BdsInsOptions, bds_ins};

fn example() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/bds-ins/data.csv")
}

fn out_dir() -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join("port-est").join("bds-ins");
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn options(input: PathBuf, output: PathBuf) -> BdsInsOptions {
    BdsInsOptions::new(input, output)
}

#[test]
fn the_readme_documents_the_example() {
    let readme = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md")).unwrap();
    assert!(readme.contains("port-est bds-ins --input examples/bds-ins/data.csv --output out.csv"));
}

#[test]
fn the_example_runs_and_corrects_the_ins() {
    let out = out_dir().join("example.csv");
    let s = bds_ins(&options(example(), out.clone())).unwrap();
    assert_eq!((s.epochs, s.outages), (600, 30));
    let text = std::fs::read_to_string(&out).unwrap();
    let (mut sq, mut ins_sq, mut n) = (0.0, 0.0, 0.0);
    for line in text.lines().skip(101) {
        let v: Vec<f64> = line.split(',').take(6).map(|c| c.parse().unwrap()).collect();
        // The example drives due east at 10 m/s from the origin: x = 10 k at epoch k.
        let (tx, ty) = (10.0 * v[0], 0.0);
        sq += (v[1] - tx).powi(2) + (v[2] - ty).powi(2);
        ins_sq += (v[1] + v[4] - tx).powi(2) + (v[2] + v[5] - ty).powi(2);
        n += 1.0;
    }
    let (rms, ins_rms) = ((sq / n).sqrt(), (ins_sq / n).sqrt());
    assert!(rms < 1.0 && ins_rms > 100.0 * rms, "corrected {rms} m, INS alone {ins_rms} m");
    // The plain Kalman filter on the same file.
    let plain = out_dir().join("plain.csv");
    bds_ins(&BdsInsOptions { fuzzy: false, ..options(example(), plain.clone()) }).unwrap();
    let plain = std::fs::read_to_string(&plain).unwrap();
    let scales: Vec<&str> =
        plain.lines().skip(1).filter_map(|l| l.split(',').nth(10)).filter(|t| !t.is_empty()).collect();
    assert_eq!(scales.len(), 570);
    assert!(scales.iter().all(|t| *t == "1e0"), "the plain KF has t = 1");
}

#[test]
fn a_bad_row_leaves_no_output() {
    let dir = out_dir();
    let input = dir.join("bad.csv");
    let mut text = std::fs::read_to_string(example()).unwrap();
    text.push_str("600,6010,0,1.57,6010,0,1.57,-1,3\n");
    std::fs::write(&input, text).unwrap();
    let out = dir.join("bad-out.csv");
    let _ = std::fs::remove_file(&out);
    let e = bds_ins(&options(input, out.clone())).unwrap_err().to_string();
    assert!(e.contains("bad.csv:602:29: y4 = -1 satellites is not a count"), "{e}");
    assert!(!out.exists());
}
