//! ROS 2 bags as logs: `port-est filter --input run.mcap` through the model file's `[log]` table
//! gives, bit for bit, the output of the same rows written as CSV (the `ros-bag` fixtures: a bag
//! written by Python's `mcap-ros2-support`/`mcap` and its rows as a CSV, with a dropout: empty
//! cells are unmeasured outputs); the mapping's errors are named at their key; `inspect` lists
//! the topics and their fields.

mod common;

use std::path::{Path, PathBuf};

use estimators::DataChecks;
use port_est::{Error, FilterOptions, OnError, filter};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../ros-bag/tests/fixtures").join(name)
}

fn dir(name: &str) -> PathBuf {
    common::fresh_dir("port-est-bags", name)
}

/// A model of the JSON fixture (input `v` from `/speed_json`, outputs `x`, `valid`, `wz`) and its
/// `[log]` table.
const MODEL: &str = include_str!("../../ros-bag/tests/fixtures/json_model.toml");
const LOG: &str = include_str!("../../ros-bag/tests/fixtures/json_log.toml");

fn options(d: &Path, input: PathBuf, output: &str, estimator: &str) -> FilterOptions {
    FilterOptions {
        estimator: estimator.into(),
        checks: Some(DataChecks::OFF),
        ..FilterOptions::new(d.join("m.toml"), input, d.join(output))
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
    let dir = fixture("");
    let e = port_est::bag::inspect(&dir, &mut Vec::new()).unwrap_err().to_string();
    assert!(e.contains("is a directory"), "{e}");
    // The path is said once.
    let e = port_est::bag::inspect(Path::new("/nonexistent.mcap"), &mut Vec::new()).unwrap_err().to_string();
    assert_eq!(e.matches("/nonexistent.mcap").count(), 1, "{e}");
}

/// The messages of `topic` in the bag at `path`, as JSON.
fn messages(path: &Path, topic: &str) -> Vec<(u64, serde_json::Value)> {
    let bytes = std::fs::read(path).unwrap();
    mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(|m| m.unwrap())
        .filter(|m| m.channel.topic == topic)
        .map(|m| (m.log_time, serde_json::from_slice(&m.data).unwrap()))
        .collect()
}

#[test]
fn estimates_written_as_a_bag_hold_the_csv_numbers() {
    let d = dir("bag-output");
    std::fs::write(d.join("m.toml"), format!("{MODEL}{LOG}")).unwrap();
    for (estimator, spread) in [("ekf", "std"), ("smf", "lower")] {
        let csv = filter(&options(&d, fixture("json.mcap"), "out.csv", estimator)).unwrap();
        let bag = filter(&options(&d, fixture("json.mcap"), "out.mcap", estimator)).unwrap();
        assert_eq!(csv.tally, bag.tally);
        let text = std::fs::read_to_string(d.join("out.csv")).unwrap();
        let rows: Vec<Vec<&str>> = text.lines().skip(1).map(|l| l.split(',').collect()).collect();
        let msgs = messages(&d.join("out.mcap"), port_est::bag::ESTIMATE_TOPIC);
        assert_eq!(msgs.len(), rows.len(), "{estimator}");
        assert!(text.contains("+measured:wz"), "{estimator}: partial steps (their status is compared below)");
        let t0: u64 = 1_700_000_000_123_456_789;
        for (i, ((t, m), row)) in msgs.iter().zip(&rows).enumerate() {
            // Step k's estimate x_{k+1} at the end of its window, t0 + (k + 1) ts.
            assert_eq!(*t, t0 + (i as u64 + 1) * 50_000_000, "{estimator}: row {i}");
            assert_eq!(m["k"].as_u64(), Some(i as u64));
            for (j, state) in ["px", "w"].iter().enumerate() {
                let x: f64 = row[1 + j].parse().unwrap();
                assert_eq!(m["x"][state].as_f64().unwrap().to_bits(), x.to_bits(), "{estimator}: row {i}");
                let a: f64 = row[3 + j].parse().unwrap();
                assert_eq!(m[spread][state].as_f64().unwrap().to_bits(), a.to_bits(), "{estimator}: row {i}");
            }
            assert_eq!(m["status"].as_str(), Some(*row.last().unwrap()), "{estimator}: row {i}");
        }
    }
    // Refused: a CSV input, keep-partial, the input as output.
    let e = filter(&options(&d, fixture("json.fixed_logtime.csv"), "o.mcap", "ekf")).unwrap_err();
    assert!(e.to_string().contains("only from a bag input"), "{e}");
    let mut keep = options(&d, fixture("json.mcap"), "o.mcap", "ekf");
    keep.on_error = OnError::KeepPartial;
    assert!(filter(&keep).unwrap_err().to_string().contains("keep-partial"));
    std::fs::copy(fixture("json.mcap"), d.join("in.mcap")).unwrap();
    let same = FilterOptions { output: d.join("in.mcap"), ..options(&d, d.join("in.mcap"), "x", "ekf") };
    assert!(filter(&same).unwrap_err().to_string().contains("is the input"));
    // A failing run publishes nothing.
    std::fs::write(d.join("m.toml"), format!("{MODEL}{}", LOG.replace("field = \"x\"", "field = \"nope\""))).unwrap();
    assert!(filter(&options(&d, fixture("json.mcap"), "failed.mcap", "ekf")).is_err());
    assert!(!d.join("failed.mcap").exists());
    assert!(!std::fs::read_dir(&d).unwrap().any(|e| e.unwrap().file_name().to_string_lossy().ends_with(".tmp")));
}

/// A model of the ROS 2 fixtures, shared with the Python tests.
const ROS2_MODEL: &str = include_str!("../../ros-bag/tests/fixtures/ros2_model.toml");

#[test]
fn ros2_bags_of_standard_messages_give_their_rows_output() {
    let d = dir("ros2");
    std::fs::write(d.join("m.toml"), ROS2_MODEL).unwrap();
    let mut want = String::new();
    for name in ["ros2_zstd", "ros2_lz4", "ros2_none"] {
        let csv = filter(&options(&d, fixture(&format!("{name}.fixed_logtime.csv")), "csv.csv", "ekf")).unwrap();
        want = std::fs::read_to_string(d.join("csv.csv")).unwrap();
        assert!(want.lines().count() > 30 && csv.tally.predicted > 0, "{name}: the dropout is there");
        let got = filter(&options(&d, fixture(&format!("{name}.mcap")), "bag.csv", "ekf")).unwrap();
        assert_eq!(got.tally, csv.tally, "{name}");
        assert_eq!(std::fs::read_to_string(d.join("bag.csv")).unwrap(), want, "{name}");
    }
    // A bag cut in the middle: with --on-error keep-partial the steps before the damage are kept,
    // and they are the intact bag's first rows.
    let bytes = std::fs::read(fixture("ros2_none.mcap")).unwrap();
    std::fs::write(d.join("cut.mcap"), &bytes[..bytes.len() / 2]).unwrap();
    let mut keep = options(&d, d.join("cut.mcap"), "cut.csv", "ekf");
    keep.on_error = OnError::KeepPartial;
    let e = filter(&keep).unwrap_err();
    assert!(e.to_string().contains("cut.mcap"), "{e}");
    let partial = std::fs::read_to_string(d.join("cut.partial.csv")).unwrap();
    let kept = partial.lines().count();
    assert!(kept > 1 && kept < want.lines().count(), "{kept} lines kept");
    assert!(want.starts_with(&partial), "the kept steps are the intact bag's");
}

/// The outputs of a run on `input` as CSV and as a bag: the CSV's rows and the bag's messages.
fn csv_and_bag(d: &Path, input: PathBuf, estimator: &str, copy: port_est::CopyTopics) -> (String, PathBuf) {
    let csv = filter(&options(d, input.clone(), "out.csv", estimator)).unwrap();
    let bag = filter(&FilterOptions { copy_topics: copy, ..options(d, input, "out.mcap", estimator) }).unwrap();
    assert_eq!(csv.tally, bag.tally);
    (std::fs::read_to_string(d.join("out.csv")).unwrap(), d.join("out.mcap"))
}

/// The bag's estimates equal the CSV's rows: centre, spread (`std`, columns 3..) and status.
fn assert_same_numbers(csv: &str, msgs: &[(u64, serde_json::Value)], states: &[&str]) {
    let rows: Vec<Vec<&str>> = csv.lines().skip(1).map(|l| l.split(',').collect()).collect();
    assert_eq!(msgs.len(), rows.len());
    let n = states.len();
    for (i, ((_, m), row)) in msgs.iter().zip(&rows).enumerate() {
        assert_eq!(m["k"].as_u64(), Some(i as u64));
        for (j, state) in states.iter().enumerate() {
            let bits = |s: &str| s.parse::<f64>().unwrap().to_bits();
            assert_eq!(m["x"][state].as_f64().unwrap().to_bits(), bits(row[1 + j]), "row {i}");
            assert_eq!(m["std"][state].as_f64().unwrap().to_bits(), bits(row[1 + n + j]), "row {i}");
        }
        assert_eq!(m["status"].as_str(), Some(*row.last().unwrap()), "row {i}");
    }
}

#[test]
fn estimates_per_driving_message_are_stamped_at_the_next_one() {
    let d = dir("per-message");
    let log = LOG.replace("ts = 0.05", "driving = \"/speed_json\"");
    std::fs::write(d.join("m.toml"), format!("{MODEL}{log}")).unwrap();
    let (csv, out) = csv_and_bag(&d, fixture("json.mcap"), "ekf", port_est::CopyTopics::None);
    let msgs = messages(&out, port_est::bag::ESTIMATE_TOPIC);
    assert_same_numbers(&csv, &msgs, &["px", "w"]);
    // Step k's window is (t_k, t_{k+1}], t_{k+1} the next driving message: its estimate's time.
    let spec = ros_bag::LogSpec::per_message("/speed_json")
        .input("v", "/speed_json", "v")
        .output("x", "/pose_json", "x")
        .output("valid", "/pose_json", "valid")
        .output("wz", "/speed_json", "gyro[2]");
    let rows = ros_bag::Bag::open(fixture("json.mcap")).unwrap().read_rows(&spec).unwrap();
    assert_eq!(rows.len(), msgs.len());
    for (i, ((t, m), r)) in msgs.iter().zip(&rows).enumerate() {
        let next = rows.get(i + 1).map_or(r.end_ns, |n| n.t_ns);
        assert_eq!((*t as i64, r.end_ns), (next, next), "row {i}");
        assert_eq!(m["t"].as_f64().unwrap().to_bits(), (next as f64 / 1e9).to_bits());
    }
}

/// Every message of a bag in file order: (topic, sequence, log time, publish time, bytes).
fn all_messages(path: &Path) -> Vec<(String, u32, u64, u64, Vec<u8>)> {
    let bytes = std::fs::read(path).unwrap();
    mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(|m| m.unwrap())
        .map(|m| (m.channel.topic.clone(), m.sequence, m.log_time, m.publish_time, m.data.into_owned()))
        .collect()
}

#[test]
fn copied_topics_are_the_inputs_byte_for_byte_beside_the_estimates() {
    let d = dir("copy");
    std::fs::write(d.join("m.toml"), ROS2_MODEL).unwrap();
    let input = fixture("ros2_zstd.mcap");
    let source = all_messages(&input);
    let states = ["lat", "v", "yaw_rate"];
    let (csv, out) = csv_and_bag(&d, input.clone(), "ekf", port_est::CopyTopics::All);
    assert_same_numbers(&csv, &messages(&out, port_est::bag::ESTIMATE_TOPIC), &states);
    let got = all_messages(&out);
    let copied: Vec<_> = got.iter().filter(|m| m.0 != port_est::bag::ESTIMATE_TOPIC).cloned().collect();
    assert_eq!(copied, source, "every topic, message for message, in the input's order");
    // Interleaved by time: an estimate comes after the input's messages up to its time.
    let first = got.iter().position(|m| m.0 == port_est::bag::ESTIMATE_TOPIC).unwrap();
    assert!(got[..first].iter().all(|m| m.2 <= got[first].2) && first > 0);
    // Some topics, named.
    let only = port_est::CopyTopics::Only(vec!["/imu".into(), "/gnss/fix".into()]);
    let (_, out) = csv_and_bag(&d, input.clone(), "ekf", only);
    let copied: Vec<_> = all_messages(&out).into_iter().filter(|m| m.0 != port_est::bag::ESTIMATE_TOPIC).collect();
    let want: Vec<_> = source.iter().filter(|m| m.0 == "/imu" || m.0 == "/gnss/fix").cloned().collect();
    assert_eq!(copied, want);
    // Refused before anything is written: an unknown topic (naming what exists), a CSV output.
    let bad = port_est::CopyTopics::Only(vec!["/nope".into()]);
    let o = FilterOptions { copy_topics: bad, ..options(&d, input.clone(), "bad.mcap", "ekf") };
    let e = filter(&o).unwrap_err().to_string();
    assert!(e.contains("--copy-topics") && e.contains("/nope") && e.contains("/imu"), "{e}");
    assert!(!d.join("bad.mcap").exists());
    let o = FilterOptions { copy_topics: port_est::CopyTopics::All, ..options(&d, input, "bad.csv", "ekf") };
    assert!(filter(&o).unwrap_err().to_string().contains("--output OUT.mcap"));
    assert!(!d.join("bad.csv").exists());
}

#[test]
fn the_readmes_complete_example_maps_the_multi_rate_model() {
    // The [log] table of examples/ros2-bag (the script's LOG) is the README's, and fits the model.
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let script = std::fs::read_to_string(root.join("examples/ros2-bag/ros2_bag_example.py")).unwrap();
    let log = script.split("LOG = \"\"\"").nth(1).and_then(|s| s.split("\"\"\"").next()).unwrap();
    let readme = std::fs::read_to_string(root.join("crates/port-est/README.md")).unwrap();
    assert!(readme.contains(&format!("```toml{log}```")), "the README shows the example's [log] table");
    let model = std::fs::read_to_string(root.join("examples/multi-rate/model.toml")).unwrap();
    let parsed = port_est::parse_model(Path::new("model.toml"), &format!("{model}{log}")).unwrap();
    let spec = parsed.log.unwrap();
    assert_eq!(spec.input_keys(), ["a", "delta"]);
    assert_eq!(spec.output_keys(), ["gnss_x", "gnss_y", "gyro", "wheel_speed", "compass"]);
}
