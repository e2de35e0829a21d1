//! `port-est filter` and `port-est estimators` on models written as equations: the same file
//! format as the linear models (`q`, `r`, `p0`, `x0`, `[mhe]`, `[ukf]`) with a `[model]` table
//! instead of the matrices; data columns named after the model's inputs and outputs.

use std::path::Path;

use equation_models::EquationModel;
use estimators::DataChecks;
use models::rng::Xoshiro256StarStar;
use models::{AnyModel, DiscreteModel};
use nalgebra::DVector;
use port_est::data::DataReader;
use port_est::filter::{run_filter, select};
use port_est::{Error, StatusPolicy, parse_model};

/// A damped pendulum driven by a torque, integrated by RK4: nonlinear and differentiable.
const PENDULUM: &str = include_str!("fixtures/pendulum.toml");

/// The measurements of a simulated run of `text`'s model: `k,<inputs>,<outputs>` with the
/// model's names, Gaussian noise of covariances `q`, `r` (diagonal), and the true states.
fn simulate(text: &str, steps: usize, u: impl Fn(usize) -> f64, q: &[f64], r: &[f64]) -> (String, Vec<DVector<f64>>) {
    let model = EquationModel::from_toml_str_with_foreign_keys(text, "m.toml", &port_est::model::NOISE_KEYS).unwrap();
    let (inputs, outputs) = (model.input_names().join(","), model.output_names().join(","));
    let mut csv = format!("k,{inputs},{outputs}\n");
    let mut rng = Xoshiro256StarStar::seed_from_u64(7);
    let mut x = DVector::from_vec(vec![0.5, 0.0]);
    let mut truth = Vec::new();
    for k in 0..steps {
        let uk = DVector::from_element(1, u(k));
        let mut next = DVector::zeros(x.len());
        model.f(&x, &uk, &mut next).unwrap();
        for (i, s) in q.iter().enumerate() {
            next[i] += s.sqrt() * rng.standard_normal();
        }
        let mut y = DVector::zeros(r.len());
        model.h(&next, &uk, &mut y).unwrap();
        for (i, s) in r.iter().enumerate() {
            y[i] += s.sqrt() * rng.standard_normal();
        }
        csv.push_str(&format!("{k},{:e},{:e}\n", uk[0], y[0]));
        truth.push(next.clone());
        x = next;
    }
    (csv, truth)
}

fn run(model: &str, data: &str, estimator: &str) -> Result<String, Error> {
    run_checked(model, data, estimator, None)
}

fn run_checked(model: &str, data: &str, estimator: &str, checks: Option<DataChecks>) -> Result<String, Error> {
    let model = parse_model(Path::new("m.toml"), model)?;
    let (entry, solver) = select(estimator, None)?;
    let m = entry.measurement_len(model.outputs());
    let mut rows = DataReader::from_text_named(Path::new("d.csv"), data, model.inputs(), m, model.column_names())?;
    let mut out = Vec::new();
    run_filter(&model, &mut rows, entry, solver, StatusPolicy::Warn, checks, &mut out, Path::new("o.csv"))?;
    Ok(String::from_utf8(out).unwrap())
}

fn rows(csv: &str) -> Vec<Vec<f64>> {
    csv.lines().skip(1).map(|l| l.split(',').map(|v| v.parse().unwrap_or(f64::NAN)).collect()).collect()
}

#[test]
fn the_nonlinear_estimators_track_a_pendulum_written_as_equations() {
    let (data, truth) = simulate(PENDULUM, 200, |k| 0.5 * (0.05 * k as f64).sin(), &[1e-6, 1e-4], &[1e-4]);
    for est in ["ekf", "ukf", "mhe-ukf"] {
        let out = run(PENDULUM, &data, est).unwrap_or_else(|e| panic!("{est}: {e}"));
        let rows = rows(&out);
        assert_eq!(rows.len(), 200, "{est}");
        // After the first second the angle is within 0.03 rad (3σ of the sensor) of the truth,
        // and the unmeasured rate within 0.2 rad/s.
        for (k, (row, x)) in rows.iter().zip(&truth).enumerate().skip(20) {
            assert!((row[1] - x[0]).abs() < 0.03, "{est}: step {k}: θ̂ = {}, θ = {}", row[1], x[0]);
            assert!((row[2] - x[1]).abs() < 0.2, "{est}: step {k}: ω̂ = {}, ω = {}", row[2], x[1]);
        }
    }
    // The Gaussian filters publish a covariance: the rate's standard deviation, honest enough
    // that at most a few percent of the errors are beyond 3σ.
    let rows = rows(&run(PENDULUM, &data, "ekf").unwrap());
    let outside = rows.iter().zip(&truth).filter(|(r, x)| (r[2] - x[1]).abs() > 3.0 * r[4]).count();
    assert!(outside <= 10, "{outside} of 200 rate errors beyond 3σ");
}

#[test]
fn linear_estimators_are_refused_on_nonlinear_equations_and_the_listing_says_why() {
    let (data, _) = simulate(PENDULUM, 5, |_| 0.0, &[0.0, 0.0], &[0.0]);
    for est in ["kf", "smf"] {
        let e = run(PENDULUM, &data, est).unwrap_err().to_string();
        assert!(
            e.starts_with(&format!(
                "--estimator {est} needs the matrices A, B, C of a linear model; the equations of m.toml are not linear"
            )),
            "{e}"
        );
    }
    let model = parse_model(Path::new("m.toml"), PENDULUM).unwrap();
    let mut listing = Vec::new();
    port_est::write_estimators_for(&model, &mut listing).unwrap();
    let listing = String::from_utf8(listing).unwrap();
    assert!(listing.starts_with("m.toml: equations, second-order; n = 2 states, p = 1 inputs, m = 1 outputs"));
    let runs = listing.split("Does not run:").next().unwrap();
    for est in ["ekf", "ukf", "mhe-ukf"] {
        assert!(runs.contains(&format!("  {est} ")), "{est} runs:\n{listing}");
    }
    let not = listing.split("Does not run:").nth(1).unwrap();
    for est in ["kf", "smf", "rmhe", "fkf"] {
        assert!(not.contains(&format!("  {est} ")), "{est} does not run:\n{listing}");
    }
}

#[test]
fn functions_with_kinks_have_derivatives_and_every_nonlinear_estimator_runs() {
    // Friction as d·|ω|·ω... written with abs: differentiable away from ω = 0 (abs'(0) = 0).
    let model = PENDULUM.replace("- d * omega", "- d * abs(omega) * omega");
    let (data, truth) = simulate(&model, 100, |_| 0.2, &[1e-6, 1e-4], &[1e-4]);
    for est in ["ekf", "ukf", "mhe-ukf"] {
        let out = rows(&run(&model, &data, est).unwrap_or_else(|e| panic!("{est}: {e}")));
        assert!((out[99][1] - truth[99][0]).abs() < 0.03, "{est}");
    }
}

#[test]
fn a_linear_model_written_as_equations_equals_its_matrices_bit_for_bit() {
    let matrices = "a = [[1.0, 0.1], [-0.2, 0.95]]\nb = [[0.0], [0.1]]\nc = [[1.0, 0.0]]\n";
    let equations = "[model]\nstates = [\"p\", \"v\"]\ninputs = [\"force\"]\noutputs = [\"position\"]\n\
                     [f]\np = \"p + 0.1 * v\"\nv = \"-0.2 * p + 0.95 * v + 0.1 * force\"\n[h]\nposition = \"p\"\n";
    let noise = "q = [[1e-4, 0.0], [0.0, 1e-4]]\nr = [[1e-2]]\np0 = [[1.0, 0.0], [0.0, 1.0]]\nx0 = [0.0, 0.0]\n";
    let mut positional = String::from("k,u1,y1\n");
    let mut named = String::from("k,force,position\n");
    for k in 0..50 {
        let line = format!("{k},{},{}\n", (0.3 * k as f64).sin(), 0.02 * k as f64);
        positional.push_str(&line);
        named.push_str(&line);
    }
    for est in ["kf", "smf", "ekf", "ukf"] {
        // (Made-up data: not checked against the noise.)
        let off = Some(DataChecks::OFF);
        let a = run_checked(&format!("{matrices}{noise}"), &positional, est, off).unwrap();
        let b = run_checked(&format!("{noise}{equations}"), &named, est, off).unwrap();
        let c = run_checked(&format!("{noise}{equations}"), &positional, est, off).unwrap();
        assert_eq!(a, b, "{est}");
        assert_eq!(a, c, "{est}: positional columns still accepted");
    }
}

#[test]
fn errors_of_a_model_written_as_equations_name_where() {
    let e = run(&PENDULUM.replace("sin(theta)", "sin(thta)"), "k,torque,angle\n0,0,0\n", "ekf").unwrap_err();
    assert!(e.to_string().starts_with("m.toml:21:1: equation `dxdt.omega` uses the unknown symbol `thta`"), "{e}");
    assert!(e.to_string().contains("thta"), "{e}");
    let e = run(&format!("a = [[1.0]]\n{PENDULUM}"), "", "ekf").unwrap_err().to_string();
    assert!(e.starts_with("m.toml:1:5: `a`: a model file gives either the matrices"), "{e}");
    let e = run(&PENDULUM.replace("x0 = [0.5, 0.0]", "x0 = [0.5]"), "", "ekf").unwrap_err().to_string();
    assert!(e.contains("`x0`: expected 2 entries, found 1"), "{e}");
    let e = run(&format!("{PENDULUM}[ukf]\nalpha = -1.0\n"), "", "ukf").unwrap_err().to_string();
    // A key of port-est's written after the equation tables belongs to the last table.
    let late = format!("{}\nr = [[1e-4]]\n", PENDULUM.replace("r = [[1e-4]]\n", ""));
    let e2 = run(&late, "", "ekf").unwrap_err().to_string();
    assert!(e2.contains("`r` belongs at the top of the file, before the first table"), "{e2}");
    assert!(e.contains("`ukf`: invalid setting UKF alpha = -1: must be > 0"), "{e}");
    let e = run(PENDULUM, "k,torque,theta\n0,0,0\n", "ekf").unwrap_err().to_string();
    assert!(e.starts_with("d.csv:1:10: the header has no column \"y1\" or \"angle\""), "{e}");
    let e = run("q = [[1.0]]\nr = [[1.0]]\np0 = [[1.0]]\nx0 = [0.0]\n", "", "kf").unwrap_err().to_string();
    assert!(e.starts_with("m.toml:1:1: missing `a`, `b`, `c` (a model file gives the matrices"), "{e}");
}

#[test]
fn an_equation_that_fails_at_some_step_is_named_with_the_step_and_the_values() {
    // sqrt of a negative angle: the model is undefined once the pendulum swings past 0.
    let model = PENDULUM.replace("angle = \"theta\"", "angle = \"sqrt(theta)\"");
    let mut data = String::from("k,torque,angle\n");
    for k in 0..60 {
        data.push_str(&format!("{k},0,{}\n", (0.5f64 * (1.0 - k as f64 / 40.0)).max(0.0).sqrt()));
    }
    let e = run(&model.replace("r = [[1e-4]]", "r = [[1.0]]"), &data, "ekf").unwrap_err().to_string();
    eprintln!("{e}");
    assert!(e.starts_with("d.csv:"), "{e}");
    assert!(e.contains("step k = ") && e.contains("h.angle") && e.contains("theta = "), "{e}");
    let model = EquationModel::from_toml_str_with_foreign_keys(&model, "m.toml", &port_est::model::NOISE_KEYS).unwrap();
    assert!(model.differentiable().is_some());
}

#[test]
fn the_nonlinear_set_membership_filter_bounds_a_pendulum_written_as_equations() {
    // The noise inside its ellipsoids (q, r as shapes), the initial state inside p0: every state
    // lies in the published intervals [lo, hi] (the bounding box of the guaranteed ellipsoid).
    let model =
        EquationModel::from_toml_str_with_foreign_keys(PENDULUM, "m.toml", &port_est::model::NOISE_KEYS).unwrap();
    let mut rng = Xoshiro256StarStar::seed_from_u64(3);
    let inside = |m: &[f64]| {
        models::Noise::uniform_ellipsoid(nalgebra::DMatrix::from_diagonal(&DVector::from_vec(m.to_vec()))).unwrap()
    };
    let (w, v, x0) = (inside(&[1e-6, 1e-4]), inside(&[1e-4]), inside(&[0.04, 0.04]));
    let mut x = DVector::from_vec(vec![0.5, 0.0]) + x0.sample(&mut rng);
    let mut data = String::from("k,torque,angle\n");
    let mut truth = Vec::new();
    for k in 0..300 {
        let u = DVector::from_element(1, 0.5 * (0.05 * k as f64).sin());
        let mut next = DVector::zeros(2);
        model.f(&x, &u, &mut next).unwrap();
        x = next + w.sample(&mut rng);
        let mut y = DVector::zeros(1);
        model.h(&x, &u, &mut y).unwrap();
        y += v.sample(&mut rng);
        data.push_str(&format!("{k},{:e},{:e}\n", u[0], y[0]));
        truth.push(x.clone());
    }
    let out = rows(&run(PENDULUM, &data, "smf-nl").unwrap());
    assert_eq!(out.len(), 300);
    // Columns: k, xhat1, xhat2, lo1, lo2, hi1, hi2, …
    for (k, (r, x)) in out.iter().zip(&truth).enumerate() {
        for i in 0..2 {
            assert!(
                r[3 + i] <= x[i] && x[i] <= r[5 + i],
                "step {k}: state {i} = {} not in [{}, {}]",
                x[i],
                r[3 + i],
                r[5 + i]
            );
        }
    }
    // And the set does not blow up: the angle's interval stays within a few sensor widths.
    let widest = out.iter().skip(20).map(|r| r[5] - r[3]).fold(0.0, f64::max);
    assert!(widest < 0.2, "widest angle interval {widest}");
    // The state's range in the file (omega within ±3 rad/s; the truth stays within ±2): still
    // contained, never wider than without it; a range the data contradict is an error at its row.
    assert!(truth.iter().all(|x| x[1].abs() < 3.0));
    let with_range = |lo: f64, hi: f64| {
        PENDULUM
            .replace("r = [[1e-4]]\n", &format!("r = [[1e-4]]\nx_lower = [-inf, {lo:?}]\nx_upper = [inf, {hi:?}]\n"))
    };
    let bounded = rows(&run(&with_range(-3.0, 3.0), &data, "smf-nl").unwrap());
    for (k, ((r, free), x)) in bounded.iter().zip(&out).zip(&truth).enumerate() {
        for i in 0..2 {
            assert!(r[3 + i] <= x[i] && x[i] <= r[5 + i], "bounded, step {k}: state {i} = {}", x[i]);
            assert!(r[5 + i] - r[3 + i] <= (free[5 + i] - free[3 + i]) * (1.0 + 1e-9), "step {k}, state {i}");
        }
    }
    let e = run(&with_range(5.0, 6.0), &data, "smf-nl").unwrap_err().to_string();
    assert!(e.starts_with("d.csv:2:") && e.contains("state 1 lies outside its declared bounds"), "{e}");
}

/// The pendulum with a second, slower sensor of the rate.
fn two_sensor_pendulum() -> String {
    PENDULUM
        .replace(r#"outputs = ["angle"]"#, r#"outputs = ["angle", "gyro"]"#)
        .replace("r = [[1e-4]]", "r = [[1e-4, 0.0], [0.0, 1e-3]]")
        .replace(r#"angle = "theta""#, "angle = \"theta\"\ngyro = \"omega\"")
}

#[test]
fn empty_output_cells_are_partial_steps_and_the_status_names_the_outputs_used() {
    let text = two_sensor_pendulum();
    let model = EquationModel::from_toml_str_with_foreign_keys(&text, "m.toml", &port_est::model::NOISE_KEYS).unwrap();
    // The gyro every row, the angle every fifth, nothing at all at k = 7.
    let mut csv = String::from("k,torque,angle,gyro\n");
    let mut x = DVector::from_vec(vec![0.5, 0.0]);
    let mut cells = Vec::new();
    for k in 0..40 {
        let u = DVector::from_element(1, 0.3);
        let mut next = DVector::zeros(2);
        model.f(&x, &u, &mut next).unwrap();
        x = next;
        let angle = (k % 5 == 0).then(|| format!("{:e}", x[0] + 0.01));
        let gyro = (k != 7).then(|| format!("{:e}", x[1] - 0.02));
        csv.push_str(&format!("{k},0.3,{},{}\n", angle.clone().unwrap_or_default(), gyro.clone().unwrap_or_default()));
        cells.push((u, DVector::from_vec(vec![x[0] + 0.01, x[1] - 0.02]), [angle.is_some(), gyro.is_some()]));
    }
    for est in ["ekf", "ukf", "czf-nl"] {
        let out = run(&text, &csv, est).unwrap_or_else(|e| panic!("{est}: {e}"));
        let lines: Vec<&str> = out.lines().skip(1).collect();
        assert_eq!(lines.len(), 40);
        assert!(lines[0].ends_with("converged"), "{est}: {}", lines[0]);
        assert!(lines[1].ends_with("+measured:gyro"), "{est}: {}", lines[1]);
        assert!(lines[7].contains("predicted") && !lines[7].contains("measured:"), "{est}: {}", lines[7]);
        // The same numbers as the library's partial steps.
        let file = parse_model(Path::new("m.toml"), &text).unwrap();
        let entry = estimators::registry::lookup(est).unwrap();
        let mut lib = entry.build(file.setup(entry.kind), None).unwrap();
        for (k, (u, y, measured)) in cells.iter().enumerate() {
            let e = lib.step_partial(&model, u, y, measured).unwrap();
            let cell: f64 = lines[k].split(',').nth(1).unwrap().parse().unwrap();
            assert_eq!(cell, e.center()[0], "{est}: step {k}");
        }
    }
    // An input cell may not be empty; the nonlinear MHE takes a partial row too.
    let e = run(&text, "k,torque,angle,gyro\n0,,0.1,0.2\n", "ekf").unwrap_err().to_string();
    assert!(e.starts_with("d.csv:2:3: torque is empty"), "{e}");
    let out = run(&text, "k,torque,angle,gyro\n0,0.1,,0.2\n", "mhe-ukf").unwrap();
    assert!(out.lines().nth(1).is_some_and(|l| l.ends_with("+measured:gyro")), "{out}");
}
