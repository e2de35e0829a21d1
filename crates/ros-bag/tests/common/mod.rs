//! Shared helpers of the integration tests: fixture paths, the reference CSVs, the mappings.

#![allow(dead_code)]

use std::path::PathBuf;

use ros_bag::{LogSpec, Row};

pub fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures").join(name)
}

/// The rows of a reference CSV (`k,t_ns,t,inputs…,outputs…`; an empty cell is unmeasured).
pub fn read_csv(name: &str, n_inputs: usize) -> (Vec<String>, Vec<Row>) {
    let text = std::fs::read_to_string(fixture(name)).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(str::to_owned).collect();
    let rows = lines
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            assert_eq!(c.len(), header.len(), "{name}: {l}");
            let num = |s: &str| s.parse::<f64>().unwrap();
            let outs = &c[3 + n_inputs..];
            Row {
                k: c[0].parse().unwrap(),
                t_ns: c[1].parse().unwrap(),
                t: num(c[2]),
                // Not in the CSV: `check` tests it from the time base.
                end_ns: -1,
                u: c[3..3 + n_inputs].iter().map(|s| num(s)).collect(),
                y: outs.iter().map(|s| if s.is_empty() { f64::NAN } else { num(s) }).collect(),
                measured: outs.iter().map(|s| !s.is_empty()).collect(),
            }
        })
        .collect();
    (header, rows)
}

/// Rows equal bit for bit (unmeasured outputs: NaN on both sides).
pub fn assert_rows_equal(got: &[Row], want: &[Row], what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: number of rows");
    for (g, w) in got.iter().zip(want) {
        assert_eq!((g.k, g.t_ns), (w.k, w.t_ns), "{what}: k and t_ns");
        assert_eq!(g.t.to_bits(), w.t.to_bits(), "{what}: t of k = {}", w.k);
        assert_eq!(g.measured, w.measured, "{what}: mask of k = {}", w.k);
        let bits = |v: &[f64]| v.iter().map(|x| if x.is_nan() { u64::MAX } else { x.to_bits() }).collect::<Vec<_>>();
        assert_eq!(bits(&g.u), bits(&w.u), "{what}: u of k = {}: {:?} vs {:?}", w.k, g.u, w.u);
        assert_eq!(bits(&g.y), bits(&w.y), "{what}: y of k = {}: {:?} vs {:?}", w.k, g.y, w.y);
    }
}

/// The mapping of the ROS 2 fixtures (`make_bags.py`'s `ROS2_INPUTS`, `ROS2_OUTPUTS`).
pub fn ros2_mapping(spec: LogSpec) -> LogSpec {
    spec.input("a", "/imu", "linear_acceleration.x")
        .input("delta", "/cmd_vel", "twist.angular.z")
        .output("gnss_lat", "/gnss/fix", "latitude")
        .output("gnss_status", "/gnss/fix", "status.status")
        .output("gyro", "/imu", "angular_velocity.z")
        .output("wheel_speed", "/odom", "twist.twist.linear.x")
        .output("gyro_var", "/imu", "angular_velocity_covariance[8]")
}

/// The mapping of the JSON fixture.
pub fn json_mapping(spec: LogSpec) -> LogSpec {
    spec.input("v", "/speed_json", "v").output("x", "/pose_json", "x").output("valid", "/pose_json", "valid").output(
        "wz",
        "/speed_json",
        "gyro[2]",
    )
}

/// `make_bags.py`'s `T0`.
pub const T0: i64 = 1_700_000_000_123_456_789;
