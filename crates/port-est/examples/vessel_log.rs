//! Writes a simulated log of the supply vessel for `port-est filter --model examples/models/vessel.toml`:
//! the compiled vessel of `vessel-dynamics` (the paper's Euler model at 0.1 s) driven through a
//! slow manoeuvre, with Gaussian process and measurement noise of the model file's `q` and `r`.
//!
//! ```sh
//! cargo run -p port-est --example vessel_log -- examples/models/vessel.toml examples/vessel 1000
//! ```
//!
//! writes `DIR/data.csv` (header `k`, then the model file's input and output names) and
//! `DIR/truth.csv` (`k,x,y,psi,u,v,r`: the true state after step `k`, to compare estimates with).
//! The truth is the compiled model, not the equations the estimators read: two implementations.
//! A fourth argument `bounded` draws the noises uniformly inside the ellipsoids `q`, `r` (the
//! set-membership filters' assumption) instead of Gaussian with those covariances, and the
//! initial state inside `p0` around `x0`:
//!
//! ```sh
//! cargo run -p port-est --example vessel_log -- examples/models/vessel.toml examples/vessel-bounded 1000 bounded
//! ```

use std::fmt::Write as _;
use std::path::PathBuf;

use models::rng::Xoshiro256StarStar;
use models::{DiscreteModel, Noise};
use nalgebra::DVector;
use vessel_dynamics::{DiscreteVessel, VesselParams};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (model, dir, steps, bounded) = match args.as_slice() {
        [model, dir, steps] => (model, dir, steps, false),
        [model, dir, steps, kind] if kind == "bounded" => (model, dir, steps, true),
        _ => return Err("usage: vessel_log MODEL.toml DIR STEPS [bounded]".into()),
    };
    let steps: usize = steps.parse().map_err(|e| format!("STEPS {steps:?}: {e}"))?;
    if !(1..=1_000_000).contains(&steps) {
        return Err("STEPS must be between 1 and 1000000".into());
    }
    let file = port_est::read_model(model.as_ref())?;
    let (inputs, outputs) = file.column_names().ok_or("the model file is not written as equations")?;
    let vessel = DiscreteVessel::paper(VesselParams::paper())?;
    if (file.states(), file.inputs(), file.outputs()) != (6, 3, 3) {
        return Err("the model file is not the vessel's (6 states, 3 inputs, 3 outputs)".into());
    }
    let chol = |m: &nalgebra::DMatrix<f64>, what: &str| {
        m.clone().cholesky().map(|c| c.l()).ok_or_else(|| format!("`{what}` is not positive definite"))
    };
    let (lq, lr) = (chol(&file.q, "q")?, chol(&file.r, "r")?);

    let mut rng = Xoshiro256StarStar::seed_from_u64(2016);
    let in_ellipsoid = |m: &nalgebra::DMatrix<f64>| Noise::uniform_ellipsoid(m.clone());
    let (w, v, x0) = (in_ellipsoid(&file.q)?, in_ellipsoid(&file.r)?, in_ellipsoid(&file.p0)?);
    let mut x = file.x0.clone();
    if bounded {
        x += x0.sample(&mut rng);
    }
    let (mut next, mut y) = (DVector::zeros(6), DVector::zeros(3));
    let mut data = format!("k,{},{}\n", inputs.join(","), outputs.join(","));
    let mut truth = String::from("k,x,y,psi,u,v,r\n");
    for k in 0..steps {
        // Surge ahead, sway and yaw back and forth (forces in N, moment in N m).
        let t = 0.1 * k as f64;
        let tau = DVector::from_vec(vec![
            1e5 * (1.0 + (std::f64::consts::TAU * t / 120.0).sin()),
            5e4 * (std::f64::consts::TAU * t / 90.0).sin(),
            1e6 * (std::f64::consts::TAU * t / 60.0).sin(),
        ]);
        vessel.f(&x, &tau, &mut next)?;
        next += if bounded { w.sample(&mut rng) } else { &lq * DVector::from_fn(6, |_, _| rng.standard_normal()) };
        vessel.h(&next, &tau, &mut y)?;
        y += if bounded { v.sample(&mut rng) } else { &lr * DVector::from_fn(3, |_, _| rng.standard_normal()) };
        let row: Vec<String> = tau.iter().chain(y.iter()).map(|v| format!("{v:e}")).collect();
        writeln!(data, "{k},{}", row.join(","))?;
        let state: Vec<String> = next.iter().map(|v| format!("{v:e}")).collect();
        writeln!(truth, "{k},{}", state.join(","))?;
        x.copy_from(&next);
    }
    let dir = PathBuf::from(dir);
    std::fs::create_dir_all(&dir)?;
    atomic_output::write_atomic(dir.join("data.csv"), data.as_bytes())?;
    atomic_output::write_atomic(dir.join("truth.csv"), truth.as_bytes())?;
    eprintln!("{steps} steps written to {} and {}", dir.join("data.csv").display(), dir.join("truth.csv").display());
    Ok(())
}
