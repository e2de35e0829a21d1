//! A synthetic ROS 2 bag for measurements: `sensor_msgs/Imu` on `/imu` at 100 Hz and
//! `sensor_msgs/NavSatFix` on `/gnss/fix` at 10 Hz (one message in eleven), CDR with the standard
//! `ros2msg` schemas, zstd chunks (or `--compression none`), with a model file whose `[log]` table
//! maps it for `port-est filter` (a linear model: `-e kf`), and optionally the same rows as a CSV
//! log (`--csv`, written from the rows this crate reads). `--decode` times reading every message
//! into rows (one core) and prints the rate.
//!
//! ```sh
//! cargo run --release -p ros-bag --example synthetic_bag -- DIR MESSAGES [--csv] [--decode] [--compression none]
//! ```
//!
//! Writes `DIR/run.mcap`, `DIR/model.toml` and with `--csv` `DIR/run.csv`.

use std::collections::BTreeMap;
use std::io::{BufWriter, Write};
use std::path::PathBuf;
use std::time::Instant;

use mcap::records::MessageHeader;
use ros_bag::{Bag, CdrWriteError, CdrWriter, LogSpec};

/// The definitions a message's `std_msgs/Header` brings into its schema.
macro_rules! header_definitions {
    () => {
        "================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
"
    };
}

/// `sensor_msgs/msg/Imu` and what it uses (the standard definitions without their comments).
const IMU: &str = concat!(
    "std_msgs/Header header
geometry_msgs/Quaternion orientation
float64[9] orientation_covariance
geometry_msgs/Vector3 angular_velocity
float64[9] angular_velocity_covariance
geometry_msgs/Vector3 linear_acceleration
float64[9] linear_acceleration_covariance
",
    header_definitions!(),
    "================================================================================
MSG: geometry_msgs/Quaternion
float64 x 0
float64 y 0
float64 z 0
float64 w 1
================================================================================
MSG: geometry_msgs/Vector3
float64 x
float64 y
float64 z
"
);

/// `sensor_msgs/msg/NavSatFix` and what it uses.
const NAV_SAT_FIX: &str = concat!(
    "std_msgs/Header header
sensor_msgs/NavSatStatus status
float64 latitude
float64 longitude
float64 altitude
float64[9] position_covariance
uint8 COVARIANCE_TYPE_UNKNOWN = 0
uint8 position_covariance_type
",
    header_definitions!(),
    "================================================================================
MSG: sensor_msgs/NavSatStatus
int8 STATUS_FIX = 0
int8 status
uint16 service
"
);

const MODEL: &str = r#"# A point moving along a line: position p, speed v, yaw rate w; the IMU's acceleration drives
# v, its gyro measures w, the GNSS latitude (scaled) measures p.
a = [[1.0, 0.01, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.99]]
b = [[0.0], [0.01], [0.0]]
c = [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]
q = [[1e-6, 0.0, 0.0], [0.0, 1e-4, 0.0], [0.0, 0.0, 1e-4]]
r = [[1e-4, 0.0], [0.0, 1.0]]
p0 = [[100.0, 0.0, 0.0], [0.0, 100.0, 0.0], [0.0, 0.0, 1.0]]
x0 = [0.0, 0.0, 0.0]

[log]
ts = 0.01

[log.fields]
u1 = { topic = "/imu", field = "linear_acceleration.x" }
y1 = { topic = "/imu", field = "angular_velocity.z" }
y2 = { topic = "/gnss/fix", field = "latitude" }
"#;

fn imu(buf: &mut CdrWriter, t: u64, i: u64) -> Result<(), CdrWriteError> {
    buf.clear().header(t, "imu_link")?;
    let s = i as f64 * 1e-3;
    for v in [0.0, 0.0, 0.0, 1.0] {
        buf.f64(v);
    }
    for v in [-1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0] {
        buf.f64(v);
    }
    for v in [0.01 * s.cos(), 0.02, 0.3 * (0.7 * s).sin()] {
        buf.f64(v);
    }
    for v in [1e-4, 0.0, 0.0, 0.0, 1e-4, 0.0, 0.0, 0.0, 1e-4] {
        buf.f64(v);
    }
    for v in [(0.5 * s).sin(), 0.1 * s.cos(), 9.80665] {
        buf.f64(v);
    }
    for _ in 0..9 {
        buf.f64(0.0);
    }
    Ok(())
}

fn fix(buf: &mut CdrWriter, t: u64, i: u64) -> Result<(), CdrWriteError> {
    buf.clear().header(t, "gnss")?;
    buf.u8(0); // status.status (int8)
    buf.u16(1); // status.service
    let s = i as f64 * 1e-3;
    for v in [51.95 + 1e-5 * (0.1 * s).sin(), 4.05, 12.5] {
        buf.f64(v);
    }
    for v in [0.25, 0.0, 0.0, 0.0, 0.25, 0.0, 0.0, 0.0, 1.0] {
        buf.f64(v);
    }
    buf.u8(2); // position_covariance_type: diagonal known
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let flag = |f: &str| args.iter().any(|a| a == f);
    let positional: Vec<&String> = args
        .iter()
        .enumerate()
        .filter(|(i, a)| !a.starts_with("--") && (*i == 0 || args[i - 1] != "--compression"))
        .map(|(_, a)| a)
        .collect();
    let [dir, n] = positional[..] else {
        return Err("usage: synthetic_bag DIR MESSAGES [--csv] [--decode] [--compression zstd|none]".into());
    };
    let (dir, n): (PathBuf, u64) = (dir.into(), n.parse()?);
    let compression = match args.iter().position(|a| a == "--compression").and_then(|i| args.get(i + 1)) {
        Some(c) if c == "none" => None,
        _ => Some(mcap::Compression::Zstd),
    };
    std::fs::create_dir_all(&dir)?;
    std::fs::write(dir.join("model.toml"), MODEL)?;
    let path = dir.join("run.mcap");
    let start = Instant::now();
    let mut w = mcap::WriteOptions::new()
        .compression(compression)
        .profile("ros2")
        .create(BufWriter::new(std::fs::File::create(&path)?))?;
    let imu_schema = w.add_schema("sensor_msgs/msg/Imu", "ros2msg", IMU.as_bytes())?;
    let fix_schema = w.add_schema("sensor_msgs/msg/NavSatFix", "ros2msg", NAV_SAT_FIX.as_bytes())?;
    let imu_channel = w.add_channel(imu_schema, "/imu", "cdr", &BTreeMap::new())?;
    let fix_channel = w.add_channel(fix_schema, "/gnss/fix", "cdr", &BTreeMap::new())?;
    let t0 = 1_700_000_000_000_000_000u64;
    let mut buf = CdrWriter::new();
    let (mut i, mut written, mut fixes) = (0u64, 0u64, 0u32);
    while written < n {
        let t = t0 + i * 10_000_000;
        imu(&mut buf, t, i)?;
        let h = MessageHeader { channel_id: imu_channel, sequence: i as u32, log_time: t, publish_time: t };
        w.write_to_known_channel(&h, buf.bytes())?;
        written += 1;
        if i % 10 == 3 && written < n {
            let t = t + 3_000_000;
            fix(&mut buf, t, i)?;
            let h = MessageHeader { channel_id: fix_channel, sequence: fixes, log_time: t, publish_time: t };
            w.write_to_known_channel(&h, buf.bytes())?;
            fixes += 1;
            written += 1;
        }
        i += 1;
    }
    w.finish()?;
    drop(w);
    let size = std::fs::metadata(&path)?.len();
    println!(
        "{}: {written} messages ({i} /imu, {fixes} /gnss/fix), {:.0} MB, written in {:.1} s",
        path.display(),
        size as f64 / 1e6,
        start.elapsed().as_secs_f64()
    );
    let spec = LogSpec::fixed_step(0.01)
        .input("u1", "/imu", "linear_acceleration.x")
        .output("y1", "/imu", "angular_velocity.z")
        .output("y2", "/gnss/fix", "latitude");
    let bag = Bag::open(&path)?;
    if flag("--decode") {
        // Every message decoded (three fields and the stamps), aligned into rows: one core.
        for _ in 0..3 {
            let start = Instant::now();
            let rows = bag.rows(&spec)?.try_fold(0u64, |n, r| r.map(|_| n + 1))?;
            let s = start.elapsed().as_secs_f64();
            println!(
                "decode: {written} messages into {rows} rows in {s:.3} s = {:.2} M messages/s",
                written as f64 / s / 1e6
            );
        }
    }
    if flag("--csv") {
        let csv = dir.join("run.csv");
        let mut out = BufWriter::new(std::fs::File::create(&csv)?);
        writeln!(out, "k,u1,y1,y2")?;
        for row in bag.rows(&spec)? {
            let r = row?;
            let cell = |j: usize| if r.measured[j] { r.y[j].to_string() } else { String::new() };
            writeln!(out, "{},{},{},{}", r.k, r.u[0], cell(0), cell(1))?;
        }
        out.flush()?;
        println!("{}: the same rows as CSV", csv.display());
    }
    Ok(())
}
