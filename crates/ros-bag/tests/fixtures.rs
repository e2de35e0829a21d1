//! The rows read from each fixture bag (written by Python's `mcap-ros2-support`) equal the rows
//! of the reference CSV written beside it by the same script, bit for bit, masks included.

mod common;

use common::{T0, assert_rows_equal, json_mapping, read_csv, ros2_mapping};
use ros_bag::{Bag, LogSpec, Stamps, TimeBase};

fn check(bag: &str, csv: &str, spec: LogSpec) {
    let bag = Bag::open(common::fixture(bag)).unwrap();
    let (header, want) = read_csv(csv, spec.input_keys().len());
    let keys: Vec<&str> = spec.input_keys().into_iter().chain(spec.output_keys()).collect();
    assert_eq!(&header[3..], keys.as_slice(), "{csv}: columns");
    let got = bag.read_rows(&spec).unwrap_or_else(|e| panic!("{csv}: {e}"));
    assert!(!want.is_empty());
    assert_rows_equal(&got, &want, csv);
    // Each window ends a step later, or at the next driving message (the next row's time).
    for (i, r) in got.iter().enumerate() {
        match spec.time_base() {
            TimeBase::FixedStep { ts, .. } => assert_eq!(r.end_ns, r.t_ns + (ts * 1e9).round() as i64, "{csv}"),
            _ => match got.get(i + 1) {
                Some(next) => assert_eq!(r.end_ns, next.t_ns, "{csv}: row {i}"),
                None => assert!(r.end_ns > r.t_ns, "{csv}: the last row"),
            },
        }
    }
}

#[test]
fn fixed_step_with_log_times_zstd_lz4_and_uncompressed_chunks() {
    for name in ["ros2_zstd", "ros2_lz4", "ros2_none"] {
        check(&format!("{name}.mcap"), &format!("{name}.fixed_logtime.csv"), ros2_mapping(LogSpec::fixed_step(0.01)));
    }
}

#[test]
fn fixed_step_with_header_stamps() {
    let spec = ros2_mapping(LogSpec::fixed_step(0.05)).stamps(Stamps::Header);
    check("ros2_zstd.mcap", "ros2_zstd.fixed_header.csv", spec);
}

#[test]
fn fixed_step_from_a_given_start() {
    let spec = ros2_mapping(LogSpec::fixed_step(0.02)).start_ns(T0 + 500_000_000);
    check("ros2_zstd.mcap", "ros2_zstd.fixed_start.csv", spec);
}

#[test]
fn one_step_per_imu_message_with_header_stamps_and_log_times() {
    check(
        "ros2_zstd.mcap",
        "ros2_zstd.imu_header.csv",
        ros2_mapping(LogSpec::per_message("/imu")).stamps(Stamps::Header),
    );
    check("ros2_zstd.mcap", "ros2_zstd.imu_logtime.csv", ros2_mapping(LogSpec::per_message("/imu")));
}

#[test]
fn json_messages_with_and_without_a_schema() {
    check("json.mcap", "json.fixed_logtime.csv", json_mapping(LogSpec::fixed_step(0.05)));
    check("json.mcap", "json.fixed_header.csv", json_mapping(LogSpec::fixed_step(0.05)).stamps(Stamps::Header));
}

#[test]
fn header_stamps_are_used_only_where_asked_and_available() {
    let bag = Bag::open(common::fixture("json.mcap")).unwrap();
    let rows = bag.rows(&json_mapping(LogSpec::fixed_step(0.05)).stamps(Stamps::Header)).unwrap();
    let mut used = rows.header_stamped();
    used.sort();
    assert_eq!(used, [("/pose_json".to_owned(), true), ("/speed_json".to_owned(), false)]);
    let rows = bag.rows(&json_mapping(LogSpec::fixed_step(0.05))).unwrap();
    assert!(rows.header_stamped().iter().all(|(_, h)| !h));
}

#[test]
fn the_gnss_dropout_leaves_a_second_of_steps_unmeasured() {
    let bag = Bag::open(common::fixture("ros2_zstd.mcap")).unwrap();
    let rows = bag.read_rows(&ros2_mapping(LogSpec::fixed_step(0.01))).unwrap();
    let gnss: Vec<bool> = rows.iter().map(|r| r.measured[0]).collect();
    let longest_gap = gnss.split(|m| *m).map(<[bool]>::len).max().unwrap();
    assert!((100..=112).contains(&longest_gap), "longest run without GNSS: {longest_gap} steps");
    let gyro = rows.iter().filter(|r| r.measured[2]).count();
    assert!(
        gyro * 100 >= rows.len() * 80,
        "the 100 Hz gyro (jittered) is in most 10 ms steps: {gyro} of {}",
        rows.len()
    );
    assert!(rows.iter().any(|r| r.y[1] == -1.0), "the int8 status reads as a number, negative too");
}
