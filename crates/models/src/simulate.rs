//! Seeded, reproducible simulation of any discrete model with noise:
//! `x_{k+1} = f_k(x_k, u_k) + w_k`, `y_k = h_k(x_k, u_{k−1}) + v_k` — for a linear time-varying
//! model `x_{k+1} = A_k x_k + B_k u_k + w_k`, `y_k = C_k x_k + v_k` (the carrier paper's eqs
//! (8)–(11)).

use nalgebra::DVector;

use crate::angles::Angles;
use crate::error::{ModelError, check_dims, check_finite};
use crate::model::{Dims, DiscreteModel, LinearTimeVarying, StepMatrices};
use crate::noise::Noise;
use crate::rng::Xoshiro256StarStar;

/// What to simulate: `N = inputs.len()` steps from `x0`.
#[derive(Debug, Clone, PartialEq)]
pub struct SimulationConfig {
    /// Initial state `x_0` (length n).
    pub x0: DVector<f64>,
    /// Inputs `u_0 … u_{N−1}` (each of length p).
    pub inputs: Vec<DVector<f64>>,
    /// Process noise `w_k` (dimension n).
    pub process_noise: Noise,
    /// Measurement noise `v_k` (dimension q).
    pub measurement_noise: Noise,
    /// Seed of the run.
    pub seed: u64,
}

/// A simulated run of `N` steps. All sequences are indexed by time:
///
/// * `states[k] = x_k`, `k = 0..=N` (N + 1 entries);
/// * `inputs[k] = u_k`, `k = 0..N` (N entries);
/// * `process_noises[k] = w_k`, `k = 0..N`, with `x_{k+1} = f_k(x_k, u_k) + w_k`;
/// * `measurements[k] = y_k = h_k(x_k, u_{k−1}) + v_k` (`C_k x_k + v_k` for a linear model),
///   `k = 0..=N` (N + 1 entries, `y_0 = h_0(x_0, u_0)` included);
/// * `measurement_noises[k] = v_k`, `k = 0..=N`.
///
/// Estimator convention: step `k` consumes `u_k` and `y_{k+1}` = `measurements[k + 1]`;
/// `measurements[0]` is there for filters that start with a measurement update.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    /// `x_0 … x_N`.
    pub states: Vec<DVector<f64>>,
    /// `u_0 … u_{N−1}`.
    pub inputs: Vec<DVector<f64>>,
    /// `y_0 … y_N`.
    pub measurements: Vec<DVector<f64>>,
    /// `w_0 … w_{N−1}`.
    pub process_noises: Vec<DVector<f64>>,
    /// `v_0 … v_N`.
    pub measurement_noises: Vec<DVector<f64>>,
    /// The seed that produced the run.
    pub seed: u64,
}

impl Trajectory {
    /// Number of steps `N`.
    #[must_use]
    pub fn steps(&self) -> usize {
        self.inputs.len()
    }
}

/// The model of time index `k` with its checked shape (borrowed for time-invariant models).
enum StepOf<'a, M: ?Sized> {
    Fixed(&'a M),
    Linear(StepMatrices),
}

impl<M: DiscreteModel + ?Sized> StepOf<'_, M> {
    fn f(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        match self {
            StepOf::Fixed(m) => m.f(x, u, out),
            // nalgebra's products, in the order the carrier's published runs were made with
            // (bit-identical trajectories across the crate split).
            StepOf::Linear(m) => {
                out.copy_from(&(&m.a * x + &m.b * u));
                Ok(())
            }
        }
    }
    fn h(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        match self {
            StepOf::Fixed(m) => m.h(x, u, out),
            StepOf::Linear(m) => {
                out.copy_from(&(&m.c * x));
                Ok(())
            }
        }
    }
}

fn check_matrices(m: StepMatrices, dims: Dims, k: usize) -> Result<StepMatrices, ModelError> {
    let Dims { states: n, inputs: p, outputs: q } = dims;
    check_dims(&format!("A_{k}"), &m.a, n, n)?;
    check_dims(&format!("B_{k}"), &m.b, n, p)?;
    check_dims(&format!("C_{k}"), &m.c, q, n)?;
    check_finite(&format!("A_{k}"), &m.a)?;
    check_finite(&format!("B_{k}"), &m.b)?;
    check_finite(&format!("C_{k}"), &m.c)?;
    Ok(m)
}

/// Simulates `N = config.inputs.len()` steps of a time-invariant discrete model (nonlinear or
/// linear): `x_{k+1} = f(x_k, u_k) + w_k`, `y_{k+1} = h(x_{k+1}, u_k) + v_{k+1}`,
/// `y_0 = h(x_0, u_0)` (zero input if there are no steps).
///
/// Randomness: the process noise draws from `Xoshiro256StarStar::seed_from_u64(seed)` and the
/// measurement noise from a copy of it advanced by one [`Xoshiro256StarStar::jump`], so the
/// two sequences are independent streams and changing one noise model leaves the other's draws
/// unchanged. `w_k` is the `k`-th draw of its stream and `v_k` the `k`-th of its own.
///
/// Angle outputs ([`DiscreteModel::angles`]) are published wrapped to `(−π, π]`, as a sensor
/// reports them: `y = wrap(h(x) + v)`; states are not wrapped.
///
/// # Errors
/// [`ModelError::DimensionMismatch`] / [`ModelError::NonFiniteEntry`] naming `x_0`, `u_k` or a
/// noise model; [`ModelError::InvalidAngles`]; evaluation errors of the model; [`ModelError::Diverged`] if a state or a
/// measurement is not finite.
pub fn simulate<M>(model: &M, config: &SimulationConfig) -> Result<Trajectory, ModelError>
where
    M: DiscreteModel + ?Sized,
{
    let angles = model.angles();
    angles.validate(model.dims())?;
    run(model.dims(), |_| Ok(StepOf::Fixed(model)), config, angles)
}

/// Simulates `N = config.inputs.len()` steps of a linear time-varying model:
/// `x_{k+1} = A_k x_k + B_k u_k + w_k`, `y_k = C_k x_k + v_k`. `model.matrices(k)` is called once
/// for each `k = 0..=N` (`A_N`, `B_N` are unused) and checked against `model.dims()`. Noise
/// streams as in [`simulate`].
///
/// # Errors
/// As [`simulate`], and errors returned by `model.matrices(k)` or naming `A_k`/`B_k`/`C_k`.
pub fn simulate_ltv<M>(model: &M, config: &SimulationConfig) -> Result<Trajectory, ModelError>
where
    M: LinearTimeVarying + ?Sized,
{
    let dims = model.dims();
    run::<StepMatrices, _>(
        dims,
        |k| Ok(StepOf::Linear(check_matrices(model.matrices(k)?, dims, k)?)),
        config,
        Angles::NONE,
    )
}

fn run<'a, M, F>(dims: Dims, mut at: F, config: &SimulationConfig, angles: Angles<'_>) -> Result<Trajectory, ModelError>
where
    M: DiscreteModel + ?Sized + 'a,
    F: FnMut(usize) -> Result<StepOf<'a, M>, ModelError>,
{
    let Dims { states: n, inputs: p, outputs: q } = dims;
    check_dims("initial state x_0", &config.x0, n, 1)?;
    check_finite("initial state x_0", &config.x0)?;
    for (k, u) in config.inputs.iter().enumerate() {
        check_dims(&format!("input u_{k}"), u, p, 1)?;
        check_finite(&format!("input u_{k}"), u)?;
    }
    let noise_dims = |what: &str, noise: &Noise, dim: usize| {
        if noise.dim() == dim {
            Ok(())
        } else {
            Err(ModelError::DimensionMismatch {
                what: what.to_owned(),
                expected_rows: dim,
                expected_cols: 1,
                rows: noise.dim(),
                cols: 1,
            })
        }
    };
    noise_dims("process noise w_k", &config.process_noise, n)?;
    noise_dims("measurement noise v_k", &config.measurement_noise, q)?;

    let steps = config.inputs.len();
    let mut w_rng = Xoshiro256StarStar::seed_from_u64(config.seed);
    let mut v_rng = w_rng.clone();
    v_rng.jump();

    let mut states = Vec::with_capacity(steps + 1);
    let mut measurements = Vec::with_capacity(steps + 1);
    let mut process_noises = Vec::with_capacity(steps);
    let mut measurement_noises = Vec::with_capacity(steps + 1);

    let zero_u = DVector::zeros(p);
    let mut current = at(0)?;
    let mut x = config.x0.clone();
    let v0 = config.measurement_noise.sample(&mut v_rng);
    let mut y = DVector::zeros(q);
    current.h(&x, config.inputs.first().unwrap_or(&zero_u), &mut y)?;
    y += &v0;
    angles.wrap_outputs(y.as_mut_slice());
    measurements.push(y);
    measurement_noises.push(v0);
    for (k, u) in config.inputs.iter().enumerate() {
        let w = config.process_noise.sample(&mut w_rng);
        let mut next_x = DVector::zeros(n);
        current.f(&x, u, &mut next_x)?;
        next_x += &w;
        if next_x.iter().any(|e| !e.is_finite()) {
            return Err(ModelError::Diverged { step: k + 1 });
        }
        let next = at(k + 1)?;
        let v = config.measurement_noise.sample(&mut v_rng);
        let mut y = DVector::zeros(q);
        next.h(&next_x, u, &mut y)?;
        y += &v;
        angles.wrap_outputs(y.as_mut_slice());
        if y.iter().any(|e| !e.is_finite()) {
            return Err(ModelError::Diverged { step: k + 1 });
        }
        measurements.push(y);
        measurement_noises.push(v);
        process_noises.push(w);
        states.push(std::mem::replace(&mut x, next_x));
        current = next;
    }
    states.push(x);
    Ok(Trajectory {
        states,
        inputs: config.inputs.clone(),
        measurements,
        process_noises,
        measurement_noises,
        seed: config.seed,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{ConstantModel, FnModel};
    use nalgebra::DMatrix;

    /// A lightly damped 2-state oscillator with two inputs and one output.
    fn oscillator() -> ConstantModel {
        ConstantModel::new(
            DMatrix::from_row_slice(2, 2, &[0.99, 0.05, -0.05, 0.98]),
            DMatrix::from_row_slice(2, 2, &[0.01, 0.0, 0.0, 0.02]),
            DMatrix::from_row_slice(1, 2, &[1.0, 0.5]),
        )
        .unwrap()
    }

    fn config(seed: u64, steps: usize) -> SimulationConfig {
        SimulationConfig {
            x0: DVector::from_row_slice(&[0.3, -0.8]),
            inputs: (0..steps).map(|k| DVector::from_row_slice(&[1.0, -(k as f64) / steps as f64])).collect(),
            process_noise: Noise::uniform_cube(2, 1e-3).unwrap(),
            measurement_noise: Noise::ellipsoid_boundary(DMatrix::identity(1, 1) * 1e-4).unwrap(),
            seed,
        }
    }

    #[test]
    fn same_seed_same_run_and_recursion_holds() {
        let m = oscillator();
        let cfg = config(42, 100);
        let t1 = simulate_ltv(&m, &cfg).unwrap();
        assert_eq!(t1, simulate_ltv(&m, &cfg).unwrap());
        // The generic simulator gives the same run for the same linear model (to rounding).
        let t3 = simulate(&m, &cfg).unwrap();
        for (a, b) in t1.states.iter().zip(&t3.states) {
            assert!((a - b).amax() < 1e-14);
        }
        assert_eq!(t1.steps(), 100);
        assert_eq!(t1.states.len(), 101);
        assert_eq!(t1.measurements.len(), 101);
        assert_eq!(t1.measurement_noises.len(), 101);
        assert_eq!(t1.process_noises.len(), 100);
        let other = simulate_ltv(&m, &SimulationConfig { seed: 43, ..cfg.clone() }).unwrap();
        assert_ne!(other.process_noises, t1.process_noises);
        assert_ne!(other.measurement_noises, t1.measurement_noises);
        let s = m.matrices();
        let mut x = cfg.x0.clone();
        for k in 0..100 {
            let y = &s.c * &x + &t1.measurement_noises[k];
            assert!((y - &t1.measurements[k]).amax() < 1e-15);
            x = &s.a * &x + &s.b * &t1.inputs[k] + &t1.process_noises[k];
            assert!((&x - &t1.states[k + 1]).amax() < 1e-15);
        }
        for w in &t1.process_noises {
            assert!(w.amax() <= 1e-3);
        }
        for v in &t1.measurement_noises {
            assert!((v.norm_squared() / 1e-4 - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn noise_streams_are_independent_of_each_other() {
        let m = oscillator();
        let cfg = config(7, 20);
        let a = simulate_ltv(&m, &cfg).unwrap();
        let b = simulate_ltv(&m, &SimulationConfig { measurement_noise: Noise::none(1), ..cfg.clone() }).unwrap();
        assert_eq!(a.process_noises, b.process_noises);
        assert_eq!(a.states, b.states);
    }

    /// `x⁺ = x + 0.1 sin(x) u`, `y = x² + u`: a nonlinear model for the generic simulator.
    struct Nonlinear;
    impl DiscreteModel for Nonlinear {
        fn dims(&self) -> Dims {
            Dims::new(1, 1, 1)
        }
        fn f(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
            out[0] = x[0] + 0.1 * x[0].sin() * u[0];
            Ok(())
        }
        fn h(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
            if u[0] < 0.0 {
                return Err(ModelError::Evaluation("u must be non-negative".into()));
            }
            out[0] = x[0] * x[0] + u[0];
            Ok(())
        }
    }

    #[test]
    fn nonlinear_models_and_gaussian_noise() {
        let cfg = SimulationConfig {
            x0: DVector::from_element(1, 1.0),
            inputs: vec![DVector::from_element(1, 2.0); 3],
            process_noise: Noise::none(1),
            measurement_noise: Noise::none(1),
            seed: 0,
        };
        let t = simulate(&Nonlinear, &cfg).unwrap();
        let mut x = 1.0_f64;
        for k in 0..3 {
            // y_k = h(x_k, u_{k−1}) (u_0 for y_0).
            assert_eq!(t.measurements[k][0], x * x + 2.0);
            x += 0.1 * x.sin() * 2.0;
            assert_eq!(t.states[k + 1][0], x);
        }
        let g =
            SimulationConfig { measurement_noise: Noise::gaussian(DMatrix::identity(1, 1)).unwrap(), ..cfg.clone() };
        let tg = simulate(&Nonlinear, &g).unwrap();
        assert_eq!(tg.states, t.states);
        assert_ne!(tg.measurements, t.measurements);
        // A model error is passed through.
        let bad = SimulationConfig { inputs: vec![DVector::from_element(1, -1.0)], ..cfg };
        assert_eq!(simulate(&Nonlinear, &bad).unwrap_err().to_string(), "u must be non-negative");
    }

    #[test]
    fn time_varying_model_is_used_per_step() {
        // Scalar system x_{k+1} = (k+1) x_k + (k+2) u_k, y_k = (10 + k) x_k.
        let model = FnModel::new(Dims::new(1, 1, 1), |k: usize| {
            Ok(StepMatrices {
                a: DMatrix::from_element(1, 1, (k + 1) as f64),
                b: DMatrix::from_element(1, 1, (k + 2) as f64),
                c: DMatrix::from_element(1, 1, (10 + k) as f64),
            })
        });
        let cfg = SimulationConfig {
            x0: DVector::from_element(1, 1.0),
            inputs: vec![DVector::from_element(1, 1.0); 3],
            process_noise: Noise::none(1),
            measurement_noise: Noise::none(1),
            seed: 0,
        };
        let t = simulate_ltv(&model, &cfg).unwrap();
        let xs: Vec<f64> = t.states.iter().map(|x| x[0]).collect();
        assert_eq!(xs, [1.0, 3.0, 9.0, 31.0]);
        let ys: Vec<f64> = t.measurements.iter().map(|y| y[0]).collect();
        assert_eq!(ys, [10.0, 33.0, 108.0, 403.0]);
    }

    #[test]
    fn simulation_errors_are_named() {
        let ok = ConstantModel::new(DMatrix::identity(2, 2), DMatrix::zeros(2, 1), DMatrix::identity(1, 2)).unwrap();
        let cfg = SimulationConfig {
            x0: DVector::zeros(2),
            inputs: vec![DVector::zeros(1); 2],
            process_noise: Noise::none(2),
            measurement_noise: Noise::none(1),
            seed: 0,
        };
        simulate_ltv(&ok, &cfg).unwrap();
        let msg = |c: SimulationConfig| simulate_ltv(&ok, &c).unwrap_err().to_string();
        assert_eq!(
            msg(SimulationConfig { x0: DVector::zeros(3), ..cfg.clone() }),
            "initial state x_0: expected 2x1, got 3x1"
        );
        assert_eq!(
            msg(SimulationConfig { x0: DVector::from_element(2, f64::NAN), ..cfg.clone() }),
            "initial state x_0 has a non-finite entry at (0, 0)"
        );
        let mut bad_u = cfg.clone();
        bad_u.inputs[1] = DVector::zeros(2);
        assert_eq!(msg(bad_u), "input u_1: expected 1x1, got 2x1");
        let mut bad_u = cfg.clone();
        bad_u.inputs[0] = DVector::from_element(1, f64::INFINITY);
        assert_eq!(msg(bad_u), "input u_0 has a non-finite entry at (0, 0)");
        assert_eq!(
            msg(SimulationConfig { process_noise: Noise::none(3), ..cfg.clone() }),
            "process noise w_k: expected 2x1, got 3x1"
        );
        assert_eq!(
            msg(SimulationConfig { measurement_noise: Noise::none(2), ..cfg.clone() }),
            "measurement noise v_k: expected 1x1, got 2x1"
        );
        let e = ConstantModel::new(DMatrix::zeros(2, 3), DMatrix::zeros(2, 1), DMatrix::zeros(1, 2)).unwrap_err();
        assert_eq!(e.to_string(), "A: expected 2x2, got 2x3");
        let e = ConstantModel::new(DMatrix::zeros(2, 2), DMatrix::from_element(2, 1, f64::NAN), DMatrix::zeros(1, 2))
            .unwrap_err();
        assert_eq!(e.to_string(), "B has a non-finite entry at (0, 0)");
        let wrong_at_1 = FnModel::new(Dims::new(2, 1, 1), |k: usize| {
            Ok(StepMatrices {
                a: DMatrix::identity(2, 2),
                b: DMatrix::zeros(2, 1),
                c: if k == 1 { DMatrix::zeros(1, 3) } else { DMatrix::zeros(1, 2) },
            })
        });
        assert_eq!(simulate_ltv(&wrong_at_1, &cfg).unwrap_err().to_string(), "C_1: expected 1x2, got 1x3");
        let nan_at_2 = FnModel::new(Dims::new(2, 1, 1), |k: usize| {
            Ok(StepMatrices {
                a: DMatrix::from_element(2, 2, if k == 2 { f64::NAN } else { 0.0 }),
                b: DMatrix::zeros(2, 1),
                c: DMatrix::zeros(1, 2),
            })
        });
        assert_eq!(simulate_ltv(&nan_at_2, &cfg).unwrap_err().to_string(), "A_2 has a non-finite entry at (0, 0)");
        let exploding =
            ConstantModel::new(DMatrix::identity(2, 2) * 1e200, DMatrix::zeros(2, 1), DMatrix::identity(1, 2)).unwrap();
        let e = simulate_ltv(&exploding, &SimulationConfig { x0: DVector::from_element(2, 1.0), ..cfg.clone() })
            .unwrap_err();
        assert_eq!(e.to_string(), "simulation diverged: state x_2 has a non-finite entry");
    }
}
