//! Writes a simulated BDS/INS log in the `port-est bds-ins` layout to standard output: the
//! reproduction's field route (open 300 s, fully occluded 120 s with 20 % of the epochs without a
//! fix, half occluded 180 s) at 10 m/s due east, occlusion scale `s` (default 0.5 m); the INS
//! solution is the truth plus the simulated INS error state, the BDS fix the truth plus the
//! simulated BDS error. `examples/bds-ins/data.csv` was written by this program with the defaults.
//!
//! ```sh
//! cargo run -p port-est --example bds_ins_log -- 0.5 > bds-ins.csv
//! cargo run -p port-est -- bds-ins --input bds-ins.csv --output bds-ins-estimates.csv
//! ```

use std::io::Write;

use bds_ins_dynamics::{BdsSimulator, InsErrorModel, InsNoise, InsParams, Zone, idx, scenario, simulate_error_states};
use models::Xoshiro256StarStar;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let s: f64 = match std::env::args().nth(1) {
        Some(v) => v.parse().map_err(|_| format!("occlusion scale in metres expected, got {v:?}"))?,
        None => 0.5,
    };
    let mut zones = scenario::field_zones(s);
    zones[1] = Zone { availability: 0.8, ..zones[1].clone() };
    let bds = BdsSimulator::new(zones, scenario::PAPER_PERIOD, 7)?;
    let model = InsErrorModel::new(InsParams::digest(), InsNoise::digest())?.discretize(scenario::PAPER_PERIOD)?;
    let mut rng = Xoshiro256StarStar::seed_from_u64(2024);
    let errors = simulate_error_states(&model, &scenario::initial_error(), bds.len(), &mut rng)?;
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    writeln!(out, "k,u1,u2,u3,y1,y2,y3,y4,y5")?;
    let heading = std::f64::consts::FRAC_PI_2;
    for epoch in bds {
        let t = epoch.k as f64 * scenario::PAPER_PERIOD;
        let (x, y) = (scenario::PAPER_SPEED * t, 0.0);
        let e = &errors[epoch.k];
        write!(out, "{},{:.4},{:.4},{:.6}", epoch.k - 1, x + e[idx::DX], y + e[idx::DY], heading + e[idx::DPSI])?;
        match epoch.fix {
            Some(f) => writeln!(
                out,
                ",{:.4},{:.4},{:.6},{},{}",
                x + f.error[0],
                y + f.error[1],
                heading + f.error[2],
                f.satellites,
                f.rtk.code()
            )?,
            None => writeln!(out, ",0,0,0,0,0")?,
        }
    }
    Ok(())
}
