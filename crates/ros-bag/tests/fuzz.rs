//! Damaged bags: truncations at every few bytes and random byte flips of the valid fixtures give
//! errors or rows, never a panic, and no allocation beyond a few MiB.

mod common;

use common::{fixture, json_mapping, ros2_mapping};
use ros_bag::{Bag, LogSpec, Stamps};

#[global_allocator]
static GLOBAL: counting_allocator::Counting = counting_allocator::Counting;

/// The largest single allocation allowed while reading a damaged fixture (they are < 64 KiB).
const LARGEST: usize = 4 << 20;

/// Opens, inspects and reads `bytes` in every way; returns how many rows came out.
fn exercise(bytes: &[u8], dir: &std::path::Path, json: bool) -> usize {
    let p = dir.join("f.mcap");
    std::fs::write(&p, bytes).unwrap();
    let (n, usage) = counting_allocator::measure(|| {
        let Ok(bag) = Bag::open(&p) else { return 0 };
        let _ = bag.inspect().to_string();
        let specs = if json {
            vec![
                json_mapping(LogSpec::fixed_step(0.05)),
                json_mapping(LogSpec::per_message("/speed_json")).stamps(Stamps::Header),
            ]
        } else {
            vec![
                ros2_mapping(LogSpec::fixed_step(0.01)),
                ros2_mapping(LogSpec::per_message("/imu")).stamps(Stamps::Header),
            ]
        };
        let mut n = 0;
        for spec in specs {
            if let Ok(rows) = bag.rows(&spec) {
                n += rows.filter(Result::is_ok).count();
            }
        }
        n
    });
    assert!(usage.largest <= LARGEST, "an allocation of {} bytes", usage.largest);
    n
}

/// xorshift64*: a fixed, seeded sequence.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
}

#[test]
fn truncations_never_panic() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["ros2_none.mcap", "ros2_lz4.mcap", "json.mcap"] {
        let bytes = std::fs::read(fixture(name)).unwrap();
        let full = exercise(&bytes, dir.path(), name == "json.mcap");
        assert!(full > 0);
        let step = (bytes.len() / 150).max(1);
        for len in (0..bytes.len()).step_by(step) {
            let n = exercise(&bytes[..len], dir.path(), name == "json.mcap");
            assert!(n <= full, "{name} cut at {len}: {n} rows, more than the {full} of the whole file");
        }
    }
}

#[test]
fn byte_flips_never_panic() {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    for name in ["ros2_none.mcap", "ros2_zstd.mcap", "ros2_lz4.mcap", "json.mcap"] {
        let bytes = std::fs::read(fixture(name)).unwrap();
        for _ in 0..120 {
            let mut b = bytes.clone();
            for _ in 0..1 + rng.next() % 4 {
                let i = (rng.next() % b.len() as u64) as usize;
                b[i] = match rng.next() % 3 {
                    0 => b[i] ^ (1 << (rng.next() % 8)),
                    1 => 0xff,
                    _ => rng.next() as u8,
                };
            }
            exercise(&b, dir.path(), name == "json.mcap");
        }
    }
}

#[test]
fn lengths_set_to_extremes_never_panic_nor_allocate() {
    // Every 4-byte and 8-byte aligned word of the uncompressed bag set to a huge length in turn.
    let dir = tempfile::tempdir().unwrap();
    let bytes = std::fs::read(fixture("ros2_none.mcap")).unwrap();
    let mut rng = Rng(42);
    for _ in 0..300 {
        let mut b = bytes.clone();
        let i = (rng.next() % (b.len() as u64 - 8)) as usize;
        let v: &[u8] = match rng.next() % 3 {
            0 => &0x8000_0000u32.to_le_bytes(),
            1 => &u32::MAX.to_le_bytes(),
            _ => &(1u64 << 62).to_le_bytes(),
        };
        b[i..i + v.len()].copy_from_slice(v);
        exercise(&b, dir.path(), false);
    }
}
