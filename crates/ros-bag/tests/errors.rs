//! Every kind of bad input gives its typed error, naming what and where.

mod common;

use std::collections::BTreeMap;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use common::{fixture, ros2_mapping};
use mcap::records::MessageHeader;
use ros_bag::{Bag, CdrWriter, Error, LogSpec, Row, Stamps};

struct Channel<'a> {
    topic: &'a str,
    encoding: &'a str,
    schema: Option<(&'a str, &'a str, &'a str)>,
}

const VALUE: Channel<'static> = Channel {
    topic: "/value",
    encoding: "cdr",
    schema: Some(("test_msgs/msg/Value", "ros2msg", "float64 x\nfloat64[] data\n")),
};

/// A bag of `channels` and `messages` (channel index, log time, bytes), unchunked unless
/// `chunked`.
fn bag(dir: &Path, channels: &[Channel<'_>], messages: &[(usize, u64, Vec<u8>)], chunked: bool) -> PathBuf {
    let path = dir.join("test.mcap");
    let file = BufWriter::new(std::fs::File::create(&path).unwrap());
    let mut w = mcap::WriteOptions::new().use_chunks(chunked).create(file).unwrap();
    let ids: Vec<u16> = channels
        .iter()
        .map(|c| {
            let schema = c.schema.map_or(0, |(n, e, t)| w.add_schema(n, e, t.as_bytes()).unwrap());
            w.add_channel(schema, c.topic, c.encoding, &BTreeMap::new()).unwrap()
        })
        .collect();
    for (i, (c, t, data)) in messages.iter().enumerate() {
        let h = MessageHeader { channel_id: ids[*c], sequence: i as u32, log_time: *t, publish_time: *t };
        w.write_to_known_channel(&h, data).unwrap();
    }
    w.finish().unwrap();
    drop(w);
    path
}

fn value(x: f64, data: &[f64]) -> Vec<u8> {
    let mut c = CdrWriter::new();
    c.f64(x).u32(data.len() as u32);
    for d in data {
        c.f64(*d);
    }
    c.bytes().to_vec()
}

fn rows_then_error(bag: &Bag, spec: &LogSpec) -> (Vec<Row>, Option<Error>) {
    let mut rows = Vec::new();
    for r in bag.rows(spec).unwrap() {
        match r {
            Ok(r) => rows.push(r),
            Err(e) => return (rows, Some(e)),
        }
    }
    (rows, None)
}

fn imu_error(field: &str) -> Error {
    let bag = Bag::open(fixture("ros2_zstd.mcap")).unwrap();
    bag.rows(&LogSpec::fixed_step(0.01).input("gyro", "/imu", field)).unwrap_err()
}

#[test]
fn an_unknown_topic_lists_the_topics() {
    let bag = Bag::open(fixture("ros2_zstd.mcap")).unwrap();
    let e = bag.rows(&LogSpec::fixed_step(0.01).input("a", "/nope", "x")).unwrap_err();
    match &e {
        Error::UnknownTopic { key, topic, available } => {
            assert_eq!((key.as_str(), topic.as_str()), ("a", "/nope"));
            assert_eq!(available, &["/cmd_vel", "/gnss/fix", "/imu", "/odom"]);
        }
        other => panic!("{other}"),
    }
    assert!(e.to_string().contains("/gnss/fix"), "{e}");
    let e = bag.rows(&ros2_mapping(LogSpec::per_message("/nope"))).unwrap_err();
    assert!(matches!(e, Error::UnknownTopic { ref key, .. } if key == "time base"), "{e}");
}

#[test]
fn an_unknown_field_names_the_key_and_lists_the_numeric_fields() {
    let e = imu_error("angular_velocity.w");
    let Error::UnknownField { key, topic, reason, available, .. } = &e else { panic!("{e}") };
    assert_eq!((key.as_str(), topic.as_str()), ("gyro", "/imu"));
    assert!(reason.contains("`geometry_msgs/Vector3` has no field `w`"), "{reason}");
    for f in ["angular_velocity.z", "orientation_covariance[0..=8]", "header.stamp.sec", "orientation.w"] {
        assert!(available.iter().any(|a| a == f), "{f} in {available:?}");
    }
    assert!(!available.iter().any(|a| a.contains("frame_id")), "strings are not numeric fields");
    for (field, why) in [
        ("orientation_covariance[9]", "at most 9"),
        ("orientation_covariance", "give an index"),
        ("angular_velocity", "is a message"),
        ("angular_velocity.z.q", "is a number"),
        ("angular_velocity[0]", "not an array"),
    ] {
        let e = imu_error(field);
        assert!(matches!(&e, Error::UnknownField { reason, .. } if reason.contains(why)), "{field}: {e}");
    }
}

#[test]
fn a_string_field_is_not_numeric_and_a_bad_path_is_named() {
    let e = imu_error("header.frame_id");
    assert!(matches!(&e, Error::NonNumeric { key, found, .. } if key == "gyro" && found == "string"), "{e}");
    let e = imu_error("a..b");
    assert!(matches!(&e, Error::BadFieldPath { key, field, .. } if key == "gyro" && field == "a..b"), "{e}");
}

#[test]
fn other_encodings_are_refused_by_name_when_mapped() {
    let dir = tempfile::tempdir().unwrap();
    for (enc, schema) in [
        ("ros1", Some(("std_msgs/Float64", "ros1msg", "float64 data\n"))),
        ("protobuf", Some(("pkg.Value", "protobuf", "binary"))),
        ("cdr", Some(("pkg/msg/Value", "ros2idl", "module pkg {};"))),
        ("cdr", None),
    ] {
        let odd = Channel { topic: "/odd", encoding: enc, schema };
        let path = bag(dir.path(), &[VALUE, odd], &[(0, 1, value(1.0, &[])), (1, 2, vec![1, 2, 3])], true);
        let b = Bag::open(&path).unwrap();
        let e = b.rows(&LogSpec::fixed_step(0.1).input("u", "/odd", "data")).unwrap_err();
        assert!(
            matches!(&e, Error::UnsupportedEncoding { topic, message_encoding, .. } if topic == "/odd" && message_encoding == enc),
            "{e}"
        );
        // Unmapped, the topic is no obstacle.
        let rows = b.read_rows(&LogSpec::fixed_step(0.1).input("u", "/value", "x")).unwrap();
        assert_eq!(rows.len(), 1);
    }
}

#[test]
fn a_schema_that_does_not_parse_names_its_line() {
    let dir = tempfile::tempdir().unwrap();
    let bad =
        Channel { topic: "/bad", encoding: "cdr", schema: Some(("p/msg/Bad", "ros2msg", "float64 x\nfloat64[x] y\n")) };
    let path = bag(dir.path(), &[bad], &[(0, 1, CdrWriter::new().f64(1.0).bytes().to_vec())], true);
    let e = Bag::open(&path).unwrap().rows(&LogSpec::fixed_step(0.1).input("u", "/bad", "x")).unwrap_err();
    assert!(matches!(&e, Error::Schema { schema, line: 2, .. } if schema == "p/msg/Bad"), "{e}");
    assert!(e.to_string().contains("float64[x] y"), "{e}");
}

#[test]
fn an_undecodable_message_names_topic_time_and_offset() {
    let dir = tempfile::tempdir().unwrap();
    let msgs = [
        (0, 1_000, value(1.0, &[2.0])),
        (0, 2_000, value(2.0, &[])),
        (0, 3_000, value(3.0, &[])),
        (0, 4_000, vec![0, 1, 0, 0, 7, 7]),
    ];
    let path = bag(dir.path(), &[VALUE], &msgs, false);
    let b = Bag::open(&path).unwrap();
    let (rows, e) = rows_then_error(&b, &LogSpec::fixed_step(1e-6).reorder_window(0.0).input("u", "/value", "x"));
    let e = e.unwrap();
    let Error::Undecodable { topic, log_time, location, .. } = &e else { panic!("{e}") };
    assert_eq!((topic.as_str(), *log_time, location.in_chunk), ("/value", 4_000, None));
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(bytes[location.offset as usize], 0x05, "the offset is the message record's");
    assert_eq!(u64::from_le_bytes(bytes[location.offset as usize + 15..][..8].try_into().unwrap()), 4_000);
    // The steps whose windows closed before the last stamp read (3 µs): t = 1 µs (1, 2] only.
    assert_eq!(rows.len(), 1, "the rows before it stand");
    assert_eq!(rows[0].u, [1.0]);
}

#[test]
fn a_huge_sequence_length_is_refused_before_allocating() {
    let dir = tempfile::tempdir().unwrap();
    let mut huge = CdrWriter::new().f64(1.0).u32(1 << 31).bytes().to_vec();
    huge.extend_from_slice(&[0; 64]);
    let path = bag(dir.path(), &[VALUE], &[(0, 1, huge)], true);
    let b = Bag::open(&path).unwrap();
    for field in ["x", "data[3]"] {
        let (r, usage) =
            counting_allocator::measure(|| b.read_rows(&LogSpec::fixed_step(0.1).input("u", "/value", field)));
        let e = r.unwrap_err();
        assert!(matches!(&e, Error::Undecodable { reason, .. } if reason.contains("2147483648")), "{e}");
        assert!(usage.largest < 1 << 20, "largest allocation {} bytes", usage.largest);
    }
}

#[test]
fn an_index_past_a_sequence_in_one_message_is_a_missing_field() {
    let dir = tempfile::tempdir().unwrap();
    let path = bag(dir.path(), &[VALUE], &[(0, 1, value(1.0, &[1.0, 2.0, 3.0])), (0, 2, value(1.0, &[1.0]))], true);
    let b = Bag::open(&path).unwrap();
    let e = b.read_rows(&LogSpec::fixed_step(0.1).input("third", "/value", "data[2]")).unwrap_err();
    assert!(
        matches!(&e, Error::MissingField { key, log_time: 2, reason, .. } if key == "third" && reason.contains("holds 1")),
        "{e}"
    );
}

#[test]
fn stamps_going_back_within_a_topic_are_an_error_with_both_times() {
    let dir = tempfile::tempdir().unwrap();
    let msgs = [(0, 3_000, value(1.0, &[])), (0, 2_000, value(2.0, &[]))];
    let path = bag(dir.path(), &[VALUE], &msgs, false);
    let e = Bag::open(&path).unwrap().read_rows(&LogSpec::fixed_step(0.001).input("u", "/value", "x")).unwrap_err();
    let Error::OutOfOrder { topic, previous, time, location } = &e else { panic!("{e}") };
    assert_eq!((topic.as_str(), *previous, *time), ("/value", 3_000, 2_000));
    assert!(location.offset > 8);
}

#[test]
fn a_message_later_in_the_file_than_the_reorder_window_is_late() {
    let dir = tempfile::tempdir().unwrap();
    let other = Channel { topic: "/other", ..VALUE };
    let s = 1_000_000_000u64;
    let mut msgs: Vec<_> = (0..10).map(|i| (0, i * s / 2, value(i as f64, &[]))).collect();
    msgs.push((1, s, value(9.0, &[]))); // stamped 1 s, after /value reached 4.5 s
    let path = bag(dir.path(), &[VALUE, other], &msgs, false);
    let b = Bag::open(&path).unwrap();
    let spec = LogSpec::fixed_step(0.5).input("u", "/value", "x").output("y", "/other", "x");
    let (rows, e) = rows_then_error(&b, &spec.clone().reorder_window(1.0));
    let e = e.unwrap();
    assert!(matches!(&e, Error::Late { topic, time, .. } if topic == "/other" && *time == s as i64), "{e}");
    assert!(!rows.is_empty());
    // A window of 4 s takes it.
    let rows = b.read_rows(&spec.reorder_window(4.0)).unwrap();
    assert!(rows.iter().any(|r| r.measured[0] && r.y[0] == 9.0));
}

#[test]
fn an_input_without_messages_and_a_zero_header_stamp() {
    let dir = tempfile::tempdir().unwrap();
    let silent = Channel { topic: "/silent", ..VALUE };
    let path = bag(dir.path(), &[VALUE, silent], &[(0, 5, value(1.0, &[]))], true);
    let e = Bag::open(&path).unwrap().read_rows(&LogSpec::fixed_step(0.1).input("s", "/silent", "x")).unwrap_err();
    assert!(matches!(&e, Error::NeverPublished { key, topic } if key == "s" && topic == "/silent"), "{e}");

    let stamped = Channel {
        topic: "/stamped",
        encoding: "cdr",
        schema: Some((
            "p/msg/S",
            "ros2msg",
            "std_msgs/Header header\nfloat64 x\n===\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n",
        )),
    };
    let msg = CdrWriter::new().i32(0).u32(0).string("f").unwrap().f64(2.5).bytes().to_vec();
    let path = bag(dir.path(), &[stamped], &[(0, 5, msg)], false);
    let b = Bag::open(&path).unwrap();
    let e = b.read_rows(&LogSpec::fixed_step(0.1).input("x", "/stamped", "x").stamps(Stamps::Header)).unwrap_err();
    assert!(matches!(&e, Error::ZeroStamp { topic, log_time: 5, .. } if topic == "/stamped"), "{e}");
    // With log times it reads (the built-in Time definition stands in for the missing one).
    let rows = b.read_rows(&LogSpec::fixed_step(0.1).input("x", "/stamped", "x")).unwrap();
    assert_eq!(rows[0].u, [2.5]);
}

#[test]
fn bad_specs_and_files_that_are_not_mcap() {
    let bag = Bag::open(fixture("ros2_none.mcap")).unwrap();
    for spec in [
        LogSpec::fixed_step(0.01),
        LogSpec::fixed_step(0.0).input("a", "/imu", "angular_velocity.z"),
        LogSpec::fixed_step(f64::NAN).input("a", "/imu", "angular_velocity.z"),
        LogSpec::fixed_step(0.01).input("a", "/imu", "angular_velocity.z").output("a", "/imu", "angular_velocity.x"),
        LogSpec::fixed_step(0.01).input("a", "/imu", "angular_velocity.z").reorder_window(-1.0),
    ] {
        assert!(matches!(bag.rows(&spec), Err(Error::Config(_))), "{spec:?}");
    }
    let dir = tempfile::tempdir().unwrap();
    for bytes in [&b""[..], b"hello, world", b"\x89MCAP0\r"] {
        let p = dir.path().join("x.mcap");
        std::fs::write(&p, bytes).unwrap();
        assert!(matches!(Bag::open(&p), Err(Error::NotMcap { .. })));
    }
    assert!(matches!(Bag::open(dir.path().join("missing.mcap")), Err(Error::Io { .. })));
}

/// The top-level records of an MCAP file: (offset, opcode, length).
fn records(bytes: &[u8]) -> Vec<(usize, u8, usize)> {
    let mut out = Vec::new();
    let mut pos = 8;
    while pos + 9 <= bytes.len() - 8 {
        let len = u64::from_le_bytes(bytes[pos + 1..pos + 9].try_into().unwrap()) as usize;
        out.push((pos, bytes[pos], len));
        if bytes[pos] == 0x02 {
            break;
        }
        pos += 9 + len;
    }
    out
}

#[test]
fn a_truncated_file_gives_the_rows_before_the_damage_then_names_the_record() {
    for name in ["ros2_none", "ros2_lz4", "ros2_zstd"] {
        let bytes = std::fs::read(fixture(&format!("{name}.mcap"))).unwrap();
        let spec = ros2_mapping(LogSpec::fixed_step(0.01));
        let full = Bag::open(fixture(&format!("{name}.mcap"))).unwrap().read_rows(&spec).unwrap();
        let chunks: Vec<_> = records(&bytes).into_iter().filter(|r| r.1 == 0x06).collect();
        assert!(chunks.len() >= 2, "{name}: {} chunks", chunks.len());
        let dir = tempfile::tempdir().unwrap();
        // Cut inside the last chunk: the rows before it stand, the error names that chunk.
        let (at, _, len) = *chunks.last().unwrap();
        let cut = at + 9 + len / 2;
        let p = dir.path().join("cut.mcap");
        std::fs::write(&p, &bytes[..cut]).unwrap();
        let b = Bag::open(&p).unwrap();
        let (rows, e) = rows_then_error(&b, &spec);
        let e = e.unwrap_or_else(|| panic!("{name}: no error"));
        let Error::Corrupt { record, location, .. } = &e else { panic!("{name}: {e}") };
        assert_eq!((record.as_str(), location.offset), ("chunk", at as u64), "{name}: {e}");
        assert!(e.to_string().contains("truncated"), "{e}");
        assert!(rows.len() > full.len() / 3, "{name}: {} of {} rows before the damage", rows.len(), full.len());
        common::assert_rows_equal(&rows, &full[..rows.len()], name);
    }
}

#[test]
fn a_damaged_chunk_is_named_by_its_offset() {
    let bytes = std::fs::read(fixture("ros2_zstd.mcap")).unwrap();
    let chunks: Vec<_> = records(&bytes).into_iter().filter(|r| r.1 == 0x06).collect();
    let (at, _, len) = chunks[1];
    let mut bad = bytes.clone();
    bad[at + 9 + len - 100] ^= 0x5a; // inside the compressed records
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("bad.mcap");
    std::fs::write(&p, &bad).unwrap();
    let b = Bag::open(&p).unwrap();
    let (rows, e) = rows_then_error(&b, &ros2_mapping(LogSpec::fixed_step(0.01)));
    let e = e.unwrap();
    assert!(
        matches!(&e, Error::Corrupt { record, location, .. } if record == "chunk" && location.offset == at as u64),
        "{e}"
    );
    assert!(!rows.is_empty());
    let i = b.inspect();
    assert!(i.error.is_some(), "inspect reports the damage too");
}
