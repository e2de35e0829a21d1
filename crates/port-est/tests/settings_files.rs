//! The settings files of `port-est truck` and `port-est bds-ins`: every error at the key's
//! `file:line:column`, matrices derived from several settings named by those settings; the rule
//! file of `--fis` matched by name, whatever the order of its input blocks.

use std::path::Path;

use port_est::bds_ins::{self, BdsInsOptions, RtkCoding};
use port_est::truck;

fn truck_error(text: &str) -> String {
    truck::check_settings(Path::new("c.toml"), text).unwrap_err().to_string()
}

fn bds_error(text: &str) -> String {
    bds_ins::check_settings(Path::new("c.toml"), text).unwrap_err().to_string()
}

const TRUCK: &str = "ts = 0.001
x0 = [10.0, 0.0, 0.0]
p0 = [[0.01, 0.0, 0.0], [0.0, 0.01, 0.0], [0.0, 0.0, 1e-4]]
q = [[1e-7, 0.0, 0.0], [0.0, 1e-7, 0.0], [0.0, 0.0, 1e-9]]
r = [[0.0025, 0.0, 0.0], [0.0, 0.0025, 0.0], [0.0, 0.0, 4e-6]]
";

#[test]
fn every_truck_settings_error_is_at_its_key() {
    truck::check_settings(Path::new("c.toml"), TRUCK).unwrap();
    truck::check_settings(Path::new("c.toml"), "").unwrap();
    let q = "q = [[1e-7, 0.0, 0.0], [0.0, 1e-7, 0.0], [0.0, 0.0, 1e-9]]";
    let cases = [
        // (line of TRUCK replaced, replacement, expected start, expected words)
        (q, "q = [[1e-7, 1e-3, 0.0], [0.0, 1e-7, 0.0], [0.0, 0.0, 1e-9]]", "c.toml:4:5: `q`: ", "not symmetric"),
        (
            q,
            "q = [[1e-7, 0.0, 0.0], [0.0, -1e-7, 0.0], [0.0, 0.0, 1e-9]]",
            "c.toml:4:5: `q`: ",
            "not positive definite",
        ),
        (q, "q = [[1e-7, 0.0], [0.0, 1e-7]]", "c.toml:4:5: `q`: ", "3 rows of 3 numbers"),
        (
            q,
            "q = [[nan, 0.0, 0.0], [0.0, 1e-7, 0.0], [0.0, 0.0, 1e-9]]",
            "c.toml:4:5: `q`: ",
            "(1, 1) = NaN is not finite",
        ),
        (
            "r = [[0.0025, 0.0, 0.0], [0.0, 0.0025, 0.0], [0.0, 0.0, 4e-6]]",
            "r = [[0.0025, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 4e-6]]",
            "c.toml:5:5: `r`: ",
            "not positive definite",
        ),
        (
            "p0 = [[0.01, 0.0, 0.0], [0.0, 0.01, 0.0], [0.0, 0.0, 1e-4]]",
            "p0 = [[0.01, 0.0, 0.0], [0.0, 0.01, 0.0], [0.0, 0.0, inf]]",
            "c.toml:3:6: `p0`: ",
            "not finite",
        ),
        ("ts = 0.001", "ts = -0.001", "c.toml:1:6: `ts`: ", "positive and finite"),
        ("ts = 0.001", "ts = 0.0", "c.toml:1:6: `ts`: ", "positive and finite"),
        ("ts = 0.001", "ts = \"fast\"", "c.toml:1:6: ", "invalid type"),
        ("x0 = [10.0, 0.0, 0.0]", "x0 = [10.0, 0.0]", "c.toml:2:6: `x0`: ", "expected 3 entries"),
        ("x0 = [10.0, 0.0, 0.0]", "x0 = [0.0, 0.0, 0.0]", "c.toml:2:6: `x0`: ", "V_x = 0 must be positive"),
        ("x0 = [10.0, 0.0, 0.0]", "x0 = [10.0, 0.0, 0.0]\nmystery = 1", "c.toml:3:1: ", "unknown field"),
    ];
    for (i, (from, to, at, words)) in cases.into_iter().enumerate() {
        let text = TRUCK.replace(from, to);
        assert_ne!(text, TRUCK, "case {i}");
        let e = truck_error(&text);
        assert!(e.starts_with(at) && e.contains(words), "case {i}: {e}");
    }
}

#[test]
fn a_truck_matrix_derived_from_ts_is_named_by_ts() {
    // The default Q = ts·diag(…) underflows to a matrix the filter cannot use.
    let e = truck_error("ts = 1e-320\n");
    assert!(e.starts_with("c.toml:1:6: `ts`: the default process noise Q = ts·diag(1e-4, 1e-4, 1e-6)"), "{e}");
    assert!(e.contains("give `q`"), "{e}");
    // With its own `q`, the same `ts` is the model's business only.
    let ok = format!("ts = 1e-6\n{}", TRUCK.lines().skip(1).collect::<Vec<_>>().join("\n"));
    truck::check_settings(Path::new("c.toml"), &ok).unwrap();
}

#[test]
fn every_bds_ins_settings_error_is_at_its_key_and_derived_matrices_name_their_settings() {
    bds_ins::check_settings(Path::new("c.toml"), "").unwrap();
    let ok = "ts = 0.5\nlatitude_deg = 45.0\nsigma0 = 0.05\nheading_sigma_deg = 0.3\naccel_white = 1e-3\ngyro_white = 1e-5\n";
    bds_ins::check_settings(Path::new("c.toml"), ok).unwrap();
    let cases = [
        ("ts = 0.5", "ts = -1.0", "c.toml:1:6: `ts`: ", "positive and finite"),
        ("latitude_deg = 45.0", "latitude_deg = 120.0", "c.toml:2:16: `latitude_deg`: ", "[-89, 89] degrees"),
        ("latitude_deg = 45.0", "latitude_deg = nan", "c.toml:2:16: `latitude_deg`: ", "finite"),
        ("sigma0 = 0.05", "sigma0 = 0.0", "c.toml:3:10: `sigma0`: ", "positive and finite"),
        ("accel_white = 1e-3", "accel_white = -1e-3", "c.toml:5:15: `accel_white`: ", "non-negative"),
        // Squares that overflow or underflow: the derived covariance named with its setting.
        ("sigma0 = 0.05", "sigma0 = 1e200", "c.toml:3:10: `sigma0`: ", "a variance of the measurement covariance R"),
        ("sigma0 = 0.05", "sigma0 = 1e-200", "c.toml:3:10: `sigma0`: ", "a variance of the measurement covariance R"),
        (
            "heading_sigma_deg = 0.3",
            "heading_sigma_deg = 1e300",
            "c.toml:4:21: `heading_sigma_deg`: ",
            "measurement covariance R",
        ),
        ("gyro_white = 1e-5", "gyro_white = 1e200", "c.toml:6:14: `gyro_white`: ", "derived from `accel_white`"),
        ("accel_white = 1e-3", "accel_white = 1e200", "c.toml:5:15: `accel_white`: ", "derived from `accel_white`"),
        ("ts = 0.5", "ts = 1e300", "c.toml:1:6: `ts`: ", "derived from `accel_white`, `gyro_white`, `ts`"),
        (
            "gyro_white = 1e-5",
            "gyro_white = 1e-5\np0_sigma = [1.0]",
            "c.toml:7:12: `p0_sigma`: ",
            "expected 13 entries",
        ),
    ];
    for (i, (from, to, at, words)) in cases.into_iter().enumerate() {
        let text = ok.replace(from, to);
        assert_ne!(text, ok, "case {i}");
        let e = bds_error(&text);
        assert!(e.starts_with(at) && e.contains(words), "case {i}: {e}");
    }
    let p0 = format!("p0_sigma = [{}]\n", ["1e200"; 13].join(", "));
    let e = bds_error(&p0);
    assert!(e.starts_with("c.toml:1:12: `p0_sigma`: its square inf, a variance of the initial covariance P0"), "{e}");
    assert!(e.ends_with("(entry 1)"), "{e}");
    let p0 = format!("p0_sigma = [{}, 0.0]\n", ["1.0"; 12].join(", "));
    assert!(bds_error(&p0).starts_with("c.toml:1:12: `p0_sigma`: entry 13 = 0 must be positive"));
}

const SHIPPED: &str = include_str!("../../fuzzy-inference/systems/bds_ins.toml");

fn run_bds(fis: Option<&str>) -> Result<String, port_est::Error> {
    let log = include_str!("../../../examples/bds-ins/data.csv");
    let mut data = port_est::data::DataReader::from_text(Path::new("d.csv"), log, 3, 5)?;
    let mut out = Vec::new();
    bds_ins::run_log(None, fis.map(|t| (Path::new("fis.toml"), t)), RtkCoding::Paper, &mut data, &mut out)?;
    Ok(String::from_utf8(out).unwrap())
}

#[test]
fn a_rule_file_with_its_inputs_in_any_order_gives_the_same_run() {
    let first = SHIPPED.find("# Satellites used").unwrap();
    let second = SHIPPED.find("# RTK status").unwrap();
    let third = SHIPPED.find("# Horizontal BDS-to-INS").unwrap();
    let rest = SHIPPED.find("# u = log10 t").unwrap();
    let (n, rtk, d) = (&SHIPPED[first..second], &SHIPPED[second..third], &SHIPPED[third..rest]);
    let reference = run_bds(Some(SHIPPED)).unwrap();
    for (a, b, c) in [(d, rtk, n), (rtk, n, d), (d, n, rtk)] {
        let text = format!("{}{a}{b}{c}{}", &SHIPPED[..first], &SHIPPED[rest..]);
        // (Not assert_eq!: a difference would print two whole logs.)
        assert!(run_bds(Some(&text)).unwrap() == reference, "the order of the input blocks changed the run");
    }
    // A misnamed input is refused at its block, not fed the wrong quantity.
    let renamed = SHIPPED.replace("name = \"d\"", "name = \"dist\"").replace(", d = \"", ", dist = \"");
    let e = run_bds(Some(&renamed)).unwrap_err().to_string();
    assert!(e.starts_with("--fis: fis.toml:34:1: input `dist` is not one of the quantities"), "{e}");
}

#[test]
fn the_fis_option_reads_by_name_from_a_file() {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join("port-est-settings-fis");
    std::fs::create_dir_all(&d).unwrap();
    let fis = d.join("reordered.toml");
    let first = SHIPPED.find("# Satellites used").unwrap();
    let third = SHIPPED.find("# Horizontal BDS-to-INS").unwrap();
    let rest = SHIPPED.find("# u = log10 t").unwrap();
    let text = format!("{}{}{}{}", &SHIPPED[..first], &SHIPPED[third..rest], &SHIPPED[first..third], &SHIPPED[rest..]);
    std::fs::write(&fis, text).unwrap();
    let input = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/bds-ins/data.csv");
    let run = |fis: Option<&Path>, output: &str| {
        let options = BdsInsOptions { fis: fis.map(Path::to_owned), ..BdsInsOptions::new(&input, d.join(output)) };
        bds_ins::bds_ins(&options).unwrap();
        std::fs::read_to_string(d.join(output)).unwrap()
    };
    let shipped = d.join("shipped.toml");
    std::fs::write(&shipped, SHIPPED).unwrap();
    assert!(run(Some(&fis), "reordered.csv") == run(Some(&shipped), "shipped.csv"), "the order changed the run");
}
