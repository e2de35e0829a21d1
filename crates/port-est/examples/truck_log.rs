//! Writes a logged slalom of the 3-axle truck (the digest's truth model, noise-free, 1 kHz) in the
//! `port-est truck` layout to standard output:
//!
//! ```sh
//! cargo run -p port-est --example truck_log -- 4 > truck.csv      # 4 s (default 12 s)
//! cargo run -p port-est -- truck --input truck.csv --output truck-estimates.csv
//! ```

use std::io::Write;

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
    writeln!(out, "k,u1,u2,u3,u4,u5,u6,u7,y1,y2,y3")?;
    for k in 0..truth.len().saturating_sub(1) {
        let (Some(u), Some(y)) = (truth.estimator_input(k), truth.measurement(k + 1)) else { break };
        write!(out, "{k},{}", u.delta)?;
        for w in u.omega {
            write!(out, ",{w}")?;
        }
        writeln!(out, ",{},{},{}", y[0], y[1], y[2])?;
    }
    Ok(())
}
