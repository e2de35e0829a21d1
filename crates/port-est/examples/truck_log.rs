//! Writes a logged slalom of the 3-axle truck (the digest's truth model, noise-free, 1 kHz) in the
//! `port-est truck` layout to standard output:
//!
//! ```sh
//! cargo run -p port-est --example truck_log -- 4 > truck.csv      # 4 s (default 12 s)
//! cargo run -p port-est -- truck --input truck.csv --output truck-estimates.csv
//! ```

use truck_dynamics::{Slalom, TruckParams, TruthConfig, simulate_truth};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let seconds: f64 = match std::env::args().nth(1) {
        Some(s) => s.parse().map_err(|_| format!("duration in seconds expected, got {s:?}"))?,
        None => 12.0,
    };
    let config = TruthConfig { duration: seconds, ..TruthConfig::digest() };
    let slalom = Slalom::digest();
    let truth = simulate_truth(&TruckParams::digest_preset(), &config, |t| slalom.angle(t))?;
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    port_est::truck::write_log(&mut out, port_est::truck::truth_rows(&truth))?;
    Ok(())
}
