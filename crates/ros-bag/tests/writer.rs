//! Estimates written as MCAP read back (by the `mcap` crate, by this crate and, when it is
//! installed, by Python's `mcap` reader) hold exactly the numbers written; nothing is left
//! behind on an error.

mod common;

use std::borrow::Cow;
use std::path::PathBuf;

use common::fixture;
use ros_bag::{Bag, ESTIMATE_SCHEMA, Error, Estimate, EstimateLayout, EstimateWriter, LogSpec, Spread};

const STATES: [&str; 3] = ["px", "py", "psi"];

/// Step k's centre, bounds and time: awkward numbers on purpose.
fn step(k: u64) -> (i64, [f64; 3], [f64; 3], [f64; 3]) {
    let t = common::T0 + k as i64 * 10_000_000;
    let x = [0.1 * k as f64 + 0.2, -1e-300 * k as f64, (k as f64).sqrt() / 3.0];
    let lo = x.map(|v| v - 0.5);
    let hi = x.map(|v| v + 1.0 / 3.0);
    (t, x, lo, hi)
}

fn write(path: &std::path::Path, n: u64, copy: &[&str]) {
    let layout = EstimateLayout::new("/estimate", STATES).spread(Spread::Bounds).status(true);
    let mut w = EstimateWriter::create(path, layout).unwrap();
    for k in 0..n {
        let (t, x, lo, hi) = step(k);
        let status = if k % 2 == 0 { "converged" } else { "predicted \"only\"" };
        w.write(&Estimate { lower: Some(&lo), upper: Some(&hi), status: Some(status), ..Estimate::new(k, t, &x) })
            .unwrap();
    }
    if !copy.is_empty() {
        let n = w.copy_topics(&Bag::open(fixture("ros2_zstd.mcap")).unwrap(), copy).unwrap();
        assert_eq!(n, 300);
    }
    w.finish().unwrap();
}

#[test]
fn the_mcap_crate_reads_back_exactly_what_was_written() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("est.mcap");
    write(&path, 200, &["/imu"]);
    let bytes = std::fs::read(&path).unwrap();
    let mut k = 0;
    let mut imu = Vec::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        if m.channel.topic == "/imu" {
            imu.push((m.log_time, m.data.into_owned()));
            continue;
        }
        assert_eq!(m.channel.topic, "/estimate");
        assert_eq!(m.channel.message_encoding, "json");
        let schema = m.channel.schema.as_ref().unwrap();
        assert_eq!((schema.name.as_str(), schema.encoding.as_str()), (ESTIMATE_SCHEMA, "jsonschema"));
        let (t, x, lo, hi) = step(k);
        assert_eq!((m.log_time, m.publish_time), (t as u64, t as u64));
        let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
        assert_eq!(v["k"], k);
        assert_eq!(v["t"].as_f64().unwrap().to_bits(), (t as f64 / 1e9).to_bits());
        for (i, s) in STATES.iter().enumerate() {
            assert_eq!(v["x"][s].as_f64().unwrap().to_bits(), x[i].to_bits(), "k = {k}, {s}");
            assert_eq!(v["lower"][s].as_f64().unwrap().to_bits(), lo[i].to_bits());
            assert_eq!(v["upper"][s].as_f64().unwrap().to_bits(), hi[i].to_bits());
        }
        assert_eq!(v["status"], if k % 2 == 0 { "converged" } else { "predicted \"only\"" });
        k += 1;
    }
    assert_eq!(k, 200);
    // The copied topic is the source's, message for message.
    let src = std::fs::read(fixture("ros2_zstd.mcap")).unwrap();
    let want: Vec<(u64, Vec<u8>)> = mcap::MessageStream::new(&src)
        .unwrap()
        .map(Result::unwrap)
        .filter(|m| m.channel.topic == "/imu")
        .map(|m| (m.log_time, m.data.into_owned()))
        .collect();
    assert_eq!(imu, want);
    // The schema is a JSON schema of plain numbers named after the states.
    let schema: serde_json::Value = serde_json::from_str(
        &EstimateLayout::new("/estimate", STATES).spread(Spread::Bounds).status(true).json_schema(),
    )
    .unwrap();
    assert_eq!(schema["properties"]["x"]["properties"]["psi"]["type"], "number");
}

#[test]
fn this_crate_reads_the_estimates_and_the_copied_topic_back() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("est.mcap");
    write(&path, 50, &["/imu"]);
    let bag = Bag::open(&path).unwrap();
    // The copied topic follows the estimates in the file: a reorder window spans the run.
    let spec = LogSpec::per_message("/estimate")
        .reorder_window(10.0)
        .input("px", "/estimate", "x.px")
        .input("upper_psi", "/estimate", "upper.psi")
        .output("gyro", "/imu", "angular_velocity.z");
    let rows = bag.read_rows(&spec).unwrap();
    assert_eq!(rows.len(), 49);
    for r in &rows {
        let (t, x, _, hi) = step(r.k);
        assert_eq!((r.t_ns, r.u[0].to_bits(), r.u[1].to_bits()), (t, x[0].to_bits(), hi[2].to_bits()));
        assert!(r.measured[0]);
    }
    let info = bag.inspect();
    let est = info.topics.iter().find(|t| t.topic == "/estimate").unwrap();
    assert_eq!((est.count, est.message_type.as_str()), (50, ESTIMATE_SCHEMA));
    assert!(est.numeric_fields.contains(&"x.px".to_owned()), "{:?}", est.numeric_fields);
}

#[test]
fn nothing_is_left_behind_on_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("est.mcap");
    {
        let mut w =
            EstimateWriter::create(&path, EstimateLayout::new("/e", ["a", "b"]).spread(Spread::StdDev)).unwrap();
        w.write(&Estimate { std_dev: Some(&[1.0, 2.0]), ..Estimate::new(0, 5, &[1.0, 2.0]) }).unwrap();
        let e = w.write(&Estimate::new(1, 6, &[1.0, 2.0])).unwrap_err();
        assert!(matches!(&e, Error::Config(m) if m.contains("`std`")), "{e}");
        let e = w.write(&Estimate { std_dev: Some(&[1.0]), ..Estimate::new(1, 6, &[1.0, 2.0]) }).unwrap_err();
        assert!(matches!(e, Error::Config(_)));
        let e = w.write(&Estimate { std_dev: Some(&[1.0, 1.0]), ..Estimate::new(1, -6, &[1.0, 2.0]) }).unwrap_err();
        assert!(matches!(e, Error::Config(_)));
        let e = w.copy_topics(&Bag::open(fixture("ros2_none.mcap")).unwrap(), &["/nope"]).unwrap_err();
        assert!(matches!(e, Error::UnknownTopic { .. }));
        // Abandoned here (dropped without finish).
    }
    assert!(!path.exists());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "no temporary file either");
    // A copy that meets a damaged bag fails, and the output is not published.
    let bytes = std::fs::read(fixture("ros2_none.mcap")).unwrap();
    let damaged = dir.path().join("damaged.mcap");
    std::fs::write(&damaged, &bytes[..bytes.len() / 2]).unwrap();
    {
        let mut w = EstimateWriter::create(&path, EstimateLayout::new("/e", ["a"])).unwrap();
        assert!(matches!(w.copy_topics(&Bag::open(&damaged).unwrap(), &["/imu"]), Err(Error::Corrupt { .. })));
    }
    assert!(!path.exists());
    assert!(matches!(
        EstimateWriter::create(dir.path().join("no/such/dir/e.mcap"), EstimateLayout::new("/e", ["a"])),
        Err(Error::Io { .. })
    ));
    assert!(matches!(EstimateWriter::create(&path, EstimateLayout::new("/e", ["a", "a"])), Err(Error::Config(_))));
}

#[test]
fn non_finite_numbers_are_written_as_null() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("est.mcap");
    let mut w = EstimateWriter::create(&path, EstimateLayout::new("/e", ["a", "b"])).unwrap();
    w.write(&Estimate::new(0, 1, &[f64::NAN, f64::INFINITY])).unwrap();
    w.finish().unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let m = mcap::MessageStream::new(&bytes).unwrap().next().unwrap().unwrap();
    assert_eq!(m.data, Cow::Borrowed(&br#"{"k":0,"t":1e-9,"x":{"a":null,"b":null}}"#[..]));
}

fn python() -> Option<PathBuf> {
    let p = std::env::var_os("ROS_BAG_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../target/python-venv/bin/python"));
    let ok =
        std::process::Command::new(&p).args(["-c", "import mcap.reader"]).output().is_ok_and(|o| o.status.success());
    ok.then_some(p)
}

#[test]
fn python_mcap_reads_the_same_numbers() {
    let Some(py) = python() else {
        eprintln!("skipped: no Python with the `mcap` package (set ROS_BAG_PYTHON or make target/python-venv)");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("est.mcap");
    write(&path, 30, &[]);
    let script = r#"
import json, sys
from mcap.reader import make_reader
with open(sys.argv[1], "rb") as f:
    for schema, channel, message in make_reader(f).iter_messages():
        d = json.loads(message.data)
        print(channel.topic, schema.name, message.log_time, d["k"], repr(d["x"]["px"]), repr(d["x"]["psi"]), repr(d["upper"]["py"]))
"#;
    let out = std::process::Command::new(py).args(["-c", script]).arg(&path).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 30);
    for (k, line) in lines.iter().enumerate() {
        let c: Vec<&str> = line.split(' ').collect();
        let (t, x, _, hi) = step(k as u64);
        assert_eq!(c[..4], ["/estimate", ESTIMATE_SCHEMA, &t.to_string(), &k.to_string()]);
        let f = |s: &str| s.parse::<f64>().unwrap().to_bits();
        assert_eq!([f(c[4]), f(c[5]), f(c[6])], [x[0].to_bits(), x[2].to_bits(), hi[1].to_bits()], "{line}");
    }
}

/// The messages of a bag in file order: (topic, sequence, log time, publish time, bytes).
fn stream(path: &std::path::Path) -> Vec<(String, u32, u64, u64, Vec<u8>)> {
    let bytes = std::fs::read(path).unwrap();
    mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(Result::unwrap)
        .map(|m| (m.channel.topic.clone(), m.sequence, m.log_time, m.publish_time, m.data.into_owned()))
        .collect()
}

#[test]
fn topics_copied_beside_the_estimates_are_the_sources_interleaved_by_log_time() {
    let dir = tempfile::tempdir().unwrap();
    let source = fixture("ros2_zstd.mcap");
    let want = stream(&source);
    let bag = Bag::open(&source).unwrap();
    let path = dir.path().join("est.mcap");
    let mut out = EstimateWriter::create(&path, EstimateLayout::new("/estimate", STATES)).unwrap();
    let mut copy = ros_bag::TopicCopy::all(&bag, &out);
    for k in 0..150 {
        let (t, x, _, _) = step(k);
        copy.until(&mut out, t as u64).unwrap();
        out.write(&Estimate::new(k, t, &x)).unwrap();
    }
    copy.rest(&mut out).unwrap();
    assert_eq!(copy.copied(), want.len() as u64);
    out.finish().unwrap();
    let got = stream(&path);
    // Every topic, message for message (bytes, sequence, both times), in the source's order.
    let copied: Vec<_> = got.iter().filter(|m| m.0 != "/estimate").cloned().collect();
    assert_eq!(copied, want);
    // Before each estimate at t: the source's messages up to the first one after t.
    let mut before = 0;
    for m in &got {
        if m.0 == "/estimate" {
            let t = m.2;
            assert_eq!(before, want.iter().position(|w| w.2 > t).unwrap_or(want.len()), "estimate at {t}");
        } else {
            before += 1;
        }
    }
    // The copied schemas and channels are the source's.
    let info = Bag::open(&path).unwrap().inspect();
    let imu = info.topics.iter().find(|t| t.topic == "/imu").unwrap();
    assert_eq!((imu.message_type.as_str(), imu.message_encoding.as_str()), ("sensor_msgs/msg/Imu", "cdr"));

    // A bag with estimates of its own: copying all of it leaves them out; naming them is refused.
    let again = dir.path().join("again.mcap");
    let first = Bag::open(&path).unwrap();
    let mut out = EstimateWriter::create(&again, EstimateLayout::new("/estimate", ["a"])).unwrap();
    let e = ros_bag::TopicCopy::only(&first, &["/imu", "/estimate"], &out).unwrap_err();
    assert!(matches!(&e, Error::Config(m) if m.contains("`/estimate`")), "{e}");
    let e = ros_bag::TopicCopy::only(&first, &["/nope"], &out).unwrap_err();
    assert!(matches!(&e, Error::UnknownTopic { available, .. } if available.contains(&"/imu".to_owned())), "{e}");
    assert_eq!(ros_bag::TopicCopy::all(&first, &out).rest(&mut out).unwrap(), want.len() as u64);
    let mut only = ros_bag::TopicCopy::only(&first, &["/gnss/fix"], &out).unwrap();
    let gnss = want.iter().filter(|m| m.0 == "/gnss/fix").count() as u64;
    assert_eq!(only.rest(&mut out).unwrap(), gnss);
}
