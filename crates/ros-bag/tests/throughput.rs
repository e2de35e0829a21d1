//! Reading speed on a synthetic bag of about 100 MB (ignored by default):
//! `cargo test -p ros-bag --release --test throughput -- --ignored --nocapture`.

use std::collections::BTreeMap;
use std::io::BufWriter;
use std::time::Instant;

use mcap::records::MessageHeader;
use ros_bag::{Bag, CdrWriter, LogSpec};

const IMU: &str = "std_msgs/Header header\nfloat64[9] orientation_covariance\nfloat64 wz\nfloat64 ax\nfloat64[27] more\n\
===\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n";

fn imu(t: u64, wz: f64, ax: f64) -> Vec<u8> {
    let mut b = CdrWriter::new();
    b.header(t, "imu_link").unwrap();
    for &v in [0.0; 9].iter().chain(&[wz, ax]).chain(&[0.5; 27]) {
        b.f64(v);
    }
    b.bytes().to_vec()
}

#[test]
#[ignore = "a measurement, not a check"]
fn rows_per_second_on_a_100_mb_bag() {
    let dir = tempfile::tempdir().unwrap();
    for (name, compression) in [("none", None), ("zstd", Some(mcap::Compression::Zstd))] {
        let path = dir.path().join(format!("big-{name}.mcap"));
        let file = BufWriter::new(std::fs::File::create(&path).unwrap());
        let mut w = mcap::WriteOptions::new().compression(compression).create(file).unwrap();
        let s = w.add_schema("sensor_msgs/msg/Imu", "ros2msg", IMU.as_bytes()).unwrap();
        let imu_c = w.add_channel(s, "/imu", "cdr", &BTreeMap::new()).unwrap();
        let gnss_c = w.add_channel(s, "/gnss", "cdr", &BTreeMap::new()).unwrap();
        let t0 = 1_700_000_000_000_000_000u64;
        let n = 300_000u64; // 50 min at 100 Hz
        for i in 0..n {
            let t = t0 + i * 10_000_000;
            let h = MessageHeader { channel_id: imu_c, sequence: i as u32, log_time: t, publish_time: t };
            w.write_to_known_channel(&h, &imu(t, (i as f64).sin(), (i as f64 * 0.1).cos())).unwrap();
            if i % 10 == 3 {
                let h = MessageHeader { channel_id: gnss_c, sequence: i as u32, log_time: t + 3, publish_time: t + 3 };
                w.write_to_known_channel(&h, &imu(t, i as f64, 1.0)).unwrap();
            }
        }
        w.finish().unwrap();
        drop(w);
        let size = std::fs::metadata(&path).unwrap().len();
        let bag = Bag::open(&path).unwrap();
        let start = Instant::now();
        let info = bag.inspect();
        let inspect = start.elapsed();
        assert_eq!(info.topics[1].count, n);
        let spec = LogSpec::fixed_step(0.01)
            .input("wz", "/imu", "wz")
            .input("ax", "/imu", "ax")
            .output("x", "/gnss", "wz")
            .output("cov", "/imu", "orientation_covariance[4]");
        let start = Instant::now();
        let rows = bag.rows(&spec).unwrap().map(Result::unwrap).count();
        let read = start.elapsed();
        println!(
            "{name}: {:.0} MB, {} messages, inspect {:.2} s; {rows} rows in {:.2} s = {:.0} rows/s, {:.0} MB/s",
            size as f64 / 1e6,
            n + n / 10,
            inspect.as_secs_f64(),
            read.as_secs_f64(),
            rows as f64 / read.as_secs_f64(),
            size as f64 / 1e6 / read.as_secs_f64()
        );
    }
}
