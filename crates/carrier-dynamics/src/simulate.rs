//! Seeded, reproducible simulation of `x_{k+1} = A_k x_k + B_k u_k + w_k`,
//! `y_k = C_k x_k + v_k` with bounded noise (paper eqs (8)–(11)).

use nalgebra::{DMatrix, DVector};

use crate::error::{DynamicsError, check_dims, check_finite};
use crate::model::DiscreteCarrier;
use crate::noise::BoundedNoise;
use crate::rng::Xoshiro256StarStar;

/// The matrices of one time index `k`: `A_k`, `B_k` propagate `x_k` to `x_{k+1}`; `C_k`
/// measures `x_k` (`y_k = C_k x_k + v_k`).
#[derive(Debug, Clone, PartialEq)]
pub struct StepMatrices {
    /// `A_k` (n × n).
    pub a: DMatrix<f64>,
    /// `B_k` (n × p).
    pub b: DMatrix<f64>,
    /// `C_k` (q × n).
    pub c: DMatrix<f64>,
}

/// A discrete-time linear time-varying model: the matrices of every time index `k`
/// (speed or load may change along a run).
pub trait LinearTimeVarying {
    /// State dimension `n`.
    fn state_dim(&self) -> usize;
    /// Input dimension `p`.
    fn input_dim(&self) -> usize;
    /// Output dimension `q`.
    fn output_dim(&self) -> usize;
    /// `(A_k, B_k, C_k)` of time index `k`.
    ///
    /// # Errors
    /// Whatever building the model at `k` may fail with (e.g. an invalid speed).
    fn matrices(&self, k: usize) -> Result<StepMatrices, DynamicsError>;
}

/// A time-invariant model `(A, B, C)`.
#[derive(Debug, Clone, PartialEq)]
pub struct ConstantModel {
    matrices: StepMatrices,
}

impl ConstantModel {
    /// Validates dimensions (`A` n × n, `B` n × p, `C` q × n) and finiteness.
    ///
    /// # Errors
    /// [`DynamicsError::DimensionMismatch`] or [`DynamicsError::NonFiniteEntry`] naming the
    /// matrix.
    pub fn new(a: DMatrix<f64>, b: DMatrix<f64>, c: DMatrix<f64>) -> Result<Self, DynamicsError> {
        let n = a.nrows();
        check_dims("A", &a, n, n)?;
        check_dims("B", &b, n, b.ncols())?;
        check_dims("C", &c, c.nrows(), n)?;
        check_finite("A", &a)?;
        check_finite("B", &b)?;
        check_finite("C", &c)?;
        Ok(Self { matrices: StepMatrices { a, b, c } })
    }

    /// The constant matrices.
    #[must_use]
    pub fn matrices(&self) -> &StepMatrices {
        &self.matrices
    }
}

impl LinearTimeVarying for ConstantModel {
    fn state_dim(&self) -> usize {
        self.matrices.a.nrows()
    }
    fn input_dim(&self) -> usize {
        self.matrices.b.ncols()
    }
    fn output_dim(&self) -> usize {
        self.matrices.c.nrows()
    }
    fn matrices(&self, _k: usize) -> Result<StepMatrices, DynamicsError> {
        Ok(self.matrices.clone())
    }
}

impl LinearTimeVarying for DiscreteCarrier {
    fn state_dim(&self) -> usize {
        crate::STATE_DIM
    }
    fn input_dim(&self) -> usize {
        crate::INPUT_DIM
    }
    fn output_dim(&self) -> usize {
        crate::OUTPUT_DIM
    }
    fn matrices(&self, _k: usize) -> Result<StepMatrices, DynamicsError> {
        let (a, b, c) = self.to_dynamic();
        Ok(StepMatrices { a, b, c })
    }
}

/// A time-varying model given by a closure `k ↦ (A_k, B_k, C_k)` and its fixed dimensions.
pub struct FnModel<F> {
    dims: (usize, usize, usize),
    f: F,
}

impl<F> FnModel<F>
where
    F: Fn(usize) -> Result<StepMatrices, DynamicsError>,
{
    /// `state_dim` n, `input_dim` p, `output_dim` q and the per-step closure; the simulator
    /// checks every step's matrices against these dimensions.
    pub fn new(state_dim: usize, input_dim: usize, output_dim: usize, f: F) -> Self {
        Self { dims: (state_dim, input_dim, output_dim), f }
    }
}

impl<F> LinearTimeVarying for FnModel<F>
where
    F: Fn(usize) -> Result<StepMatrices, DynamicsError>,
{
    fn state_dim(&self) -> usize {
        self.dims.0
    }
    fn input_dim(&self) -> usize {
        self.dims.1
    }
    fn output_dim(&self) -> usize {
        self.dims.2
    }
    fn matrices(&self, k: usize) -> Result<StepMatrices, DynamicsError> {
        (self.f)(k)
    }
}

/// What to simulate: `N = inputs.len()` steps from `x0`.
#[derive(Debug, Clone, PartialEq)]
pub struct SimulationConfig {
    /// Initial state `x_0` (length n).
    pub x0: DVector<f64>,
    /// Inputs `u_0 … u_{N−1}` (each of length p).
    pub inputs: Vec<DVector<f64>>,
    /// Process noise `w_k` (dimension n).
    pub process_noise: BoundedNoise,
    /// Measurement noise `v_k` (dimension q).
    pub measurement_noise: BoundedNoise,
    /// Seed of the run.
    pub seed: u64,
}

/// A simulated run of `N` steps. All sequences are indexed by time:
///
/// * `states[k] = x_k`, `k = 0..=N` (N + 1 entries);
/// * `inputs[k] = u_k`, `k = 0..N` (N entries);
/// * `process_noises[k] = w_k`, `k = 0..N`, with `x_{k+1} = A_k x_k + B_k u_k + w_k`;
/// * `measurements[k] = y_k = C_k x_k + v_k`, `k = 0..=N` (N + 1 entries, `y_0` included);
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

fn check_step(model: &(impl LinearTimeVarying + ?Sized), k: usize) -> Result<StepMatrices, DynamicsError> {
    let (n, p, q) = (model.state_dim(), model.input_dim(), model.output_dim());
    let m = model.matrices(k)?;
    check_dims(&format!("A_{k}"), &m.a, n, n)?;
    check_dims(&format!("B_{k}"), &m.b, n, p)?;
    check_dims(&format!("C_{k}"), &m.c, q, n)?;
    check_finite(&format!("A_{k}"), &m.a)?;
    check_finite(&format!("B_{k}"), &m.b)?;
    check_finite(&format!("C_{k}"), &m.c)?;
    Ok(m)
}

/// Simulates `N = config.inputs.len()` steps of `model`.
///
/// Randomness: the process noise draws from `Xoshiro256StarStar::seed_from_u64(seed)` and the
/// measurement noise from a copy of it advanced by one [`Xoshiro256StarStar::jump`], so the
/// two sequences are independent streams and changing one noise model leaves the other's draws
/// unchanged. `w_k` is the `k`-th draw of its stream and `v_k` the `k`-th of its own.
/// `model.matrices(k)` is called once for each `k = 0..=N` (`A_N`, `B_N` are unused).
///
/// # Errors
/// [`DynamicsError::DimensionMismatch`] / [`DynamicsError::NonFiniteEntry`] naming `x_0`,
/// `u_k`, a noise model, or `A_k`/`B_k`/`C_k`; errors returned by `model.matrices(k)`;
/// [`DynamicsError::Diverged`] if a state overflows.
pub fn simulate<M>(model: &M, config: &SimulationConfig) -> Result<Trajectory, DynamicsError>
where
    M: LinearTimeVarying + ?Sized,
{
    let (n, p, q) = (model.state_dim(), model.input_dim(), model.output_dim());
    check_dims("initial state x_0", &config.x0, n, 1)?;
    check_finite("initial state x_0", &config.x0)?;
    for (k, u) in config.inputs.iter().enumerate() {
        check_dims(&format!("input u_{k}"), u, p, 1)?;
        check_finite(&format!("input u_{k}"), u)?;
    }
    let noise_dims = |what: &str, noise: &BoundedNoise, dim: usize| {
        if noise.dim() == dim {
            Ok(())
        } else {
            Err(DynamicsError::DimensionMismatch {
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

    let mut current = check_step(model, 0)?;
    let mut x = config.x0.clone();
    let v0 = config.measurement_noise.sample(&mut v_rng);
    measurements.push(&current.c * &x + &v0);
    measurement_noises.push(v0);
    for (k, u) in config.inputs.iter().enumerate() {
        let w = config.process_noise.sample(&mut w_rng);
        let next_x = &current.a * &x + &current.b * u + &w;
        if next_x.iter().any(|e| !e.is_finite()) {
            return Err(DynamicsError::Diverged { step: k + 1 });
        }
        let next = check_step(model, k + 1)?;
        let v = config.measurement_noise.sample(&mut v_rng);
        measurements.push(&next.c * &next_x + &v);
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
    use crate::{CarrierModel, CarrierParams};

    fn carrier_config(seed: u64, steps: usize) -> SimulationConfig {
        let u_max =
            DVector::from_row_slice(&[22.0, 16.0, 16.0, 21.0, 20.0, 15.0, 15.0, 19.0]) * (std::f64::consts::PI / 180.0);
        SimulationConfig {
            x0: DVector::from_row_slice(&[0.03, -0.08, 0.02, 0.1]),
            inputs: (0..steps).map(|k| &u_max * (k as f64 / steps as f64)).collect(),
            process_noise: BoundedNoise::uniform_cube(4, 1e-3).unwrap(),
            measurement_noise: BoundedNoise::ellipsoid_boundary(DMatrix::identity(4, 4) * 1e-4).unwrap(),
            seed,
        }
    }

    #[test]
    fn same_seed_same_run_and_recursion_holds() {
        let d = CarrierModel::new(CarrierParams::paper_preset()).unwrap().discretize(1e-3).unwrap();
        let cfg = carrier_config(42, 100);
        let t1 = simulate(&d, &cfg).unwrap();
        let t2 = simulate(&d, &cfg).unwrap();
        assert_eq!(t1, t2);
        assert_eq!(t1.steps(), 100);
        assert_eq!(t1.states.len(), 101);
        assert_eq!(t1.measurements.len(), 101);
        assert_eq!(t1.measurement_noises.len(), 101);
        assert_eq!(t1.process_noises.len(), 100);
        let other = simulate(&d, &SimulationConfig { seed: 43, ..cfg.clone() }).unwrap();
        assert_ne!(other.process_noises, t1.process_noises);
        assert_ne!(other.measurement_noises, t1.measurement_noises);
        assert_eq!(other.states[0], t1.states[0]);
        // Manual propagation with the fixed-size matrices.
        let mut x = nalgebra::Vector4::from_column_slice(cfg.x0.as_slice());
        for k in 0..100 {
            let y = x + nalgebra::Vector4::from_column_slice(t1.measurement_noises[k].as_slice());
            assert!((y - nalgebra::Vector4::from_column_slice(t1.measurements[k].as_slice())).amax() < 1e-15);
            let u = nalgebra::SVector::<f64, 8>::from_column_slice(t1.inputs[k].as_slice());
            let w = nalgebra::Vector4::from_column_slice(t1.process_noises[k].as_slice());
            x = d.a_p * x + d.b_p * u + w;
            let got = &t1.states[k + 1];
            assert!((x - nalgebra::Vector4::from_column_slice(got.as_slice())).amax() < 1e-12);
        }
        // Noises respect their bounds.
        for w in &t1.process_noises {
            assert!(w.amax() <= 1e-3);
        }
        for v in &t1.measurement_noises {
            assert!((v.norm_squared() / 1e-4 - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn noise_streams_are_independent_of_each_other() {
        let d = CarrierModel::new(CarrierParams::paper_preset()).unwrap().discretize(1e-3).unwrap();
        let cfg = carrier_config(7, 20);
        let a = simulate(&d, &cfg).unwrap();
        let b = simulate(&d, &SimulationConfig { measurement_noise: BoundedNoise::none(4), ..cfg.clone() }).unwrap();
        assert_eq!(a.process_noises, b.process_noises);
        assert_eq!(a.states, b.states);
        assert_eq!(b.measurements, b.states);
    }

    #[test]
    fn time_varying_model_is_used_per_step() {
        // Scalar system x_{k+1} = (k+1) x_k + (k+2) u_k, y_k = (10 + k) x_k.
        let model = FnModel::new(1, 1, 1, |k: usize| {
            Ok(StepMatrices {
                a: DMatrix::from_element(1, 1, (k + 1) as f64),
                b: DMatrix::from_element(1, 1, (k + 2) as f64),
                c: DMatrix::from_element(1, 1, (10 + k) as f64),
            })
        });
        let cfg = SimulationConfig {
            x0: DVector::from_element(1, 1.0),
            inputs: vec![DVector::from_element(1, 1.0); 3],
            process_noise: BoundedNoise::none(1),
            measurement_noise: BoundedNoise::none(1),
            seed: 0,
        };
        let t = simulate(&model, &cfg).unwrap();
        // x1 = 1·1 + 2 = 3, x2 = 2·3 + 3 = 9, x3 = 3·9 + 4 = 31.
        let xs: Vec<f64> = t.states.iter().map(|x| x[0]).collect();
        assert_eq!(xs, [1.0, 3.0, 9.0, 31.0]);
        let ys: Vec<f64> = t.measurements.iter().map(|y| y[0]).collect();
        assert_eq!(ys, [10.0, 33.0, 108.0, 403.0]);

        // The carrier accelerating from 4 to 8 m/s: each step uses its own speed.
        let ts = 0.01;
        let carrier = FnModel::new(4, 8, 4, |k: usize| {
            let v = 4.0 + 0.04 * k as f64;
            let (a, b, c) =
                CarrierModel::new(CarrierParams::paper_preset().with_speed(v))?.discretize(ts)?.to_dynamic();
            Ok(StepMatrices { a, b, c })
        });
        let mut cfg = carrier_config(1, 100);
        cfg.process_noise = BoundedNoise::none(4);
        let t = simulate(&carrier, &cfg).unwrap();
        let mut x = cfg.x0.clone();
        for k in 0..100 {
            let m = carrier.matrices(k).unwrap();
            x = &m.a * &x + &m.b * &cfg.inputs[k];
        }
        assert!((&x - &t.states[100]).amax() < 1e-12);
        let constant =
            CarrierModel::new(CarrierParams::paper_preset().with_speed(4.0)).unwrap().discretize(ts).unwrap();
        let tc = simulate(&constant, &cfg).unwrap();
        assert!((&tc.states[100] - &t.states[100]).amax() > 1e-6);
    }

    #[test]
    fn simulation_errors_are_named() {
        let ok = ConstantModel::new(DMatrix::identity(2, 2), DMatrix::zeros(2, 1), DMatrix::identity(1, 2)).unwrap();
        assert_eq!(ok.matrices().c.shape(), (1, 2));
        let cfg = SimulationConfig {
            x0: DVector::zeros(2),
            inputs: vec![DVector::zeros(1); 2],
            process_noise: BoundedNoise::none(2),
            measurement_noise: BoundedNoise::none(1),
            seed: 0,
        };
        simulate(&ok, &cfg).unwrap();
        let msg = |c: SimulationConfig| simulate(&ok, &c).unwrap_err().to_string();
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
            msg(SimulationConfig { process_noise: BoundedNoise::none(3), ..cfg.clone() }),
            "process noise w_k: expected 2x1, got 3x1"
        );
        assert_eq!(
            msg(SimulationConfig { measurement_noise: BoundedNoise::none(2), ..cfg.clone() }),
            "measurement noise v_k: expected 1x1, got 2x1"
        );

        let e = ConstantModel::new(DMatrix::zeros(2, 3), DMatrix::zeros(2, 1), DMatrix::zeros(1, 2)).unwrap_err();
        assert_eq!(e.to_string(), "A: expected 2x2, got 2x3");
        let e = ConstantModel::new(DMatrix::zeros(2, 2), DMatrix::zeros(3, 1), DMatrix::zeros(1, 2)).unwrap_err();
        assert_eq!(e.to_string(), "B: expected 2x1, got 3x1");
        let e = ConstantModel::new(DMatrix::zeros(2, 2), DMatrix::zeros(2, 1), DMatrix::zeros(1, 3)).unwrap_err();
        assert_eq!(e.to_string(), "C: expected 1x2, got 1x3");
        let e = ConstantModel::new(DMatrix::zeros(2, 2), DMatrix::from_element(2, 1, f64::NAN), DMatrix::zeros(1, 2))
            .unwrap_err();
        assert_eq!(e.to_string(), "B has a non-finite entry at (0, 0)");

        // Per-step matrices from a closure are checked at every step.
        let wrong_at_1 = FnModel::new(2, 1, 1, |k: usize| {
            Ok(StepMatrices {
                a: DMatrix::identity(2, 2),
                b: DMatrix::zeros(2, 1),
                c: if k == 1 { DMatrix::zeros(1, 3) } else { DMatrix::zeros(1, 2) },
            })
        });
        let e = simulate(&wrong_at_1, &cfg).unwrap_err();
        assert_eq!(e.to_string(), "C_1: expected 1x2, got 1x3");
        let nan_at_2 = FnModel::new(2, 1, 1, |k: usize| {
            Ok(StepMatrices {
                a: DMatrix::from_element(2, 2, if k == 2 { f64::NAN } else { 0.0 }),
                b: DMatrix::zeros(2, 1),
                c: DMatrix::zeros(1, 2),
            })
        });
        let e = simulate(&nan_at_2, &cfg).unwrap_err();
        assert_eq!(e.to_string(), "A_2 has a non-finite entry at (0, 0)");
        // A model error at some step is passed through.
        let stopping = FnModel::new(4, 8, 4, |k: usize| {
            let (a, b, c) = CarrierModel::new(CarrierParams::paper_preset().with_speed(1.0 - k as f64))?
                .discretize(0.01)?
                .to_dynamic();
            Ok(StepMatrices { a, b, c })
        });
        let e = simulate(&stopping, &carrier_config(0, 3)).unwrap_err();
        assert_eq!(e.to_string(), "parameter v (forward speed) must be positive, got 0");
        // Divergence.
        let exploding =
            ConstantModel::new(DMatrix::identity(2, 2) * 1e200, DMatrix::zeros(2, 1), DMatrix::identity(1, 2)).unwrap();
        let e =
            simulate(&exploding, &SimulationConfig { x0: DVector::from_element(2, 1.0), ..cfg.clone() }).unwrap_err();
        assert_eq!(e.to_string(), "simulation diverged: state x_2 has a non-finite entry");
    }
}
