//! Simulates the digest's slalom with the truth model and prints peaks and timing.
use truck_dynamics::{Slalom, TruckParams, TruthConfig, simulate_truth};

fn main() -> Result<(), truck_dynamics::TruckError> {
    let slalom = Slalom::digest();
    let start = std::time::Instant::now();
    let run = simulate_truth(&TruckParams::digest_preset(), &TruthConfig::digest(), |t| slalom.angle(t))?;
    let elapsed = start.elapsed();
    let max = |f: &dyn Fn(&truck_dynamics::TruthSample) -> f64| {
        run.samples.iter().map(f).fold(0.0_f64, |m, v| m.max(v.abs()))
    };
    println!("samples {} in {elapsed:?}", run.len());
    println!("max |a_y| = {:.3} m/s^2", max(&|s| s.ay));
    println!("max |gamma| = {:.3} deg/s", max(&|s| s.gamma).to_degrees());
    println!("max |beta| = {:.3} deg", max(&|s| s.beta).to_degrees());
    println!("max |Y| = {:.3} m", max(&|s| s.y));
    println!("max |V_x - v| = {:.4} m/s", max(&|s| s.vx - 70.0 / 3.6));
    println!("max |a_x| = {:.4} m/s^2", max(&|s| s.ax));
    let last = run.samples.last().unwrap();
    println!("last: {last:?}");
    for k in (0..run.len()).step_by(1000) {
        let s = &run.samples[k];
        println!(
            "t {:5.2} delta {:7.3} deg vx {:8.4} vy {:7.4} gamma {:7.3} deg/s ay {:7.3} beta {:7.3} deg Y {:7.3} fz {:?}",
            s.t,
            s.delta.to_degrees(),
            s.vx,
            s.vy,
            s.gamma.to_degrees(),
            s.ay,
            s.beta.to_degrees(),
            s.y,
            s.fz.map(|f| (f / 100.0).round() / 10.0)
        );
    }
    Ok(())
}
