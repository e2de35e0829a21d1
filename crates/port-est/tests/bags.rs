//! ROS 2 bags as logs: `port-est filter --input run.mcap` through the model file's `[log]` table
//! gives, bit for bit, the output of the same rows written as CSV (the `ros-bag` fixtures: a bag
//! written by Python's `mcap-ros2-support`/`mcap` and its rows as a CSV, with a dropout: empty
//! cells are unmeasured outputs); the mapping's errors are named at their key; `inspect` lists
//! the topics and their fields.

use std::path::{Path, PathBuf};

use estimators::DataChecks;
use port_est::{Error, FilterOptions, GapPolicy, Limits, OnError, StatusPolicy, filter};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../ros-bag/tests/fixtures").join(name)
}

fn dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join("port-est-bags").join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A model of the JSON fixture: input `v` from `/speed_json`, outputs `x`, `valid`, `wz`.
const MODEL: &str = r#"
x0 = [0.0, 0.0]
p0 = [100.0, 100.0]
q = [1.0, 1.0]
r = [1.0, 1.0, 1.0]

[model]
states = ["px", "w"]
inputs = ["v"]
outputs = ["x", "valid", "wz"]

[f]
px = "px + 0.05 * v"
w = "w"

[h]
x = "px"
valid = "w"
wz = "w"
"#;

const LOG: &str = r#"
[log]
ts = 0.05

[log.fields]
v = { topic = "/speed_json", field = "v" }
x = { topic = "/pose_json", field = "x" }
valid = { topic = "/pose_json", field = "valid" }
wz = { topic = "/speed_json", field = "gyro[2]" }
"#;

fn options(d: &Path, input: PathBuf, output: &str, estimator: &str) -> FilterOptions {
    FilterOptions {
        model: d.join("m.toml"),
        input,
        output: d.join(output),
        estimator: estimator.into(),
        solver: None,
        gaps: GapPolicy::Error,
        exact_columns: false,
        status: StatusPolicy::Warn,
        checks: Some(DataChecks::OFF),
        on_error: OnError::Discard,
        limits: Limits::default(),
    }
}

#[test]
fn a_bag_gives_the_output_of_its_rows_as_csv_bit_for_bit() {
    for estimator in ["ekf", "ukf"] {
        let d = dir(estimator);
        std::fs::write(d.join("m.toml"), format!("{MODEL}{LOG}")).unwrap();
        let bag = filter(&options(&d, fixture("json.mcap"), "bag.csv", estimator)).unwrap();
        let csv = filter(&options(&d, fixture("json.fixed_logtime.csv"), "csv.csv", estimator)).unwrap();
        assert_eq!(bag.tally, csv.tally);
        let (a, b) =
            (std::fs::read_to_string(d.join("bag.csv")).unwrap(), std::fs::read_to_string(d.join("csv.csv")).unwrap());
        assert_eq!(a, b, "{estimator}");
        assert_eq!(a.lines().count(), 41);
        assert!(a.contains("+measured:wz"), "the dropout of /pose_json is a partial step");
    }
    // Known by its magic bytes without the extension.
    let d = dir("magic");
    std::fs::write(d.join("m.toml"), format!("{MODEL}{LOG}")).unwrap();
    std::fs::copy(fixture("json.mcap"), d.join("run.log")).unwrap();
    filter(&options(&d, d.join("run.log"), "o.csv", "ekf")).unwrap();
}

fn error_of(log: &str) -> String {
    let d = dir("errors");
    std::fs::write(d.join("m.toml"), format!("{MODEL}{log}")).unwrap();
    let e = filter(&options(&d, fixture("json.mcap"), "o.csv", "ekf")).unwrap_err();
    assert!(!d.join("o.csv").exists());
    e.to_string()
}

#[test]
fn mapping_errors_are_named() {
    let e = error_of(&LOG.replace("ts = 0.05", "ts = -1.0"));
    assert!(e.contains("m.toml:") && e.contains("`ts` = -1"), "{e}");
    let e = error_of(&LOG.replace("ts = 0.05", ""));
    assert!(e.contains("give one of `ts`"), "{e}");
    let e = error_of(&LOG.replace("wz = {", "speed = {"));
    assert!(e.contains("`speed` is not an input or output of the model"), "{e}");
    let e = error_of(&LOG.replace("wz = { topic = \"/speed_json\", field = \"gyro[2]\" }\n", ""));
    assert!(e.contains("no topic for `wz`"), "{e}");
    let e = error_of(&LOG.replace("/pose_json", "/pose"));
    assert!(e.contains("json.mcap") && e.contains("/pose"), "{e}");
    let e = error_of(&LOG.replace("field = \"x\"", "field = \"nope\""));
    assert!(e.contains("json.mcap") && e.contains("nope"), "{e}");
    let e = error_of("");
    assert!(e.contains("needs a `[log]` table"), "{e}");
}

#[test]
fn a_truncated_bag_is_an_error_naming_the_file() {
    let d = dir("truncated");
    std::fs::write(d.join("m.toml"), format!("{MODEL}{LOG}")).unwrap();
    let bytes = std::fs::read(fixture("json.mcap")).unwrap();
    std::fs::write(d.join("cut.mcap"), &bytes[..bytes.len() / 2]).unwrap();
    let e = filter(&options(&d, d.join("cut.mcap"), "o.csv", "ekf")).unwrap_err();
    assert!(matches!(e, Error::File { .. }), "{e}");
    assert!(e.to_string().contains("cut.mcap"), "{e}");
    assert!(!d.join("o.csv").exists());
}

#[test]
fn inspect_lists_topics_and_fields() {
    let mut out = Vec::new();
    port_est::bag::inspect(&fixture("ros2_zstd.mcap"), &mut out).unwrap();
    let text = String::from_utf8(out).unwrap();
    for want in ["/imu", "/gnss/fix", "sensor_msgs/msg/Imu", "angular_velocity.z", "latitude"] {
        assert!(text.contains(want), "{want} missing from\n{text}");
    }
    let e = port_est::bag::inspect(&fixture("json.fixed_logtime.csv"), &mut Vec::new()).unwrap_err();
    assert!(e.to_string().contains("json.fixed_logtime.csv"), "{e}");
}
