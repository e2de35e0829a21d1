//! The experiments: the paper's, as published, and extended scenarios where the filter has work
//! to do. Every choice the paper leaves open is stated here and repeated in the report.

use carrier_dynamics::{CarrierModel, CarrierParams};
use models::{Noise as BoundedNoise, SimulationConfig, StepMatrices};
use nalgebra::{DMatrix, DVector};

/// Sampling period of every scenario (the paper's 1 ms).
pub const TS: f64 = 1e-3;

/// Names and units of the four states, for figures and tables.
pub const STATES: [(&str, &str, &str); 4] = [
    ("beta", "sideslip angle β", "rad"),
    ("gamma", "yaw rate γ", "rad/s"),
    ("phi", "roll angle φ", "rad"),
    ("phidot", "roll rate φ̇", "rad/s"),
];

/// One experiment: the truth model, the data and what the filters are told.
pub struct Scenario {
    /// Short identifier (file names).
    pub id: String,
    /// One-line description for the report.
    pub title: String,
    /// Per-step matrices `(A_k, B_k, C)`, `k = 0..N`.
    pub steps: Vec<StepMatrices>,
    /// Simulation (true initial state, inputs, true noises, seed).
    pub sim: SimulationConfig,
    /// Initial centre given to the filters.
    pub x_hat0: DVector<f64>,
    /// Initial shape (set-membership) / covariance (Kalman).
    pub p0: DMatrix<f64>,
    /// Process-noise shape given to the filters (a covariance for the Kalman filter).
    pub q: DMatrix<f64>,
    /// Measurement-noise shape given to the filters (a covariance for the Kalman filter).
    pub r: DMatrix<f64>,
    /// Known input range `[lo, hi]` per input (used by the \[17\]-style filter without input).
    pub input_range: InputRange,
    /// Whether the SDP backends run on every step (else only on the first `sdp_steps`).
    pub sdp_steps: usize,
    /// Choices made where the paper is silent, for the report.
    pub notes: Vec<String>,
}

impl Scenario {
    /// Number of filter steps.
    pub fn len(&self) -> usize {
        self.steps.len()
    }

    /// Whether the scenario has no steps.
    pub fn is_empty(&self) -> bool {
        self.steps.is_empty()
    }
}

fn carrier_steps(params: CarrierParams, c: &DMatrix<f64>, n: usize) -> Result<Vec<StepMatrices>, String> {
    let d = CarrierModel::new(params).map_err(|e| e.to_string())?.discretize(TS).map_err(|e| e.to_string())?;
    let (a, b, _) = d.to_dynamic();
    Ok(vec![StepMatrices { a, b, c: c.clone() }; n])
}

fn err(e: impl std::fmt::Display) -> String {
    e.to_string()
}

/// Table 1 carrier, one container, 6 m/s, `N = 100`, exactly as §4 of the paper states it.
pub fn paper(seed: u64) -> Result<Scenario, String> {
    let n_steps = 100;
    let c = DMatrix::identity(4, 4);
    let steps = carrier_steps(CarrierParams::paper_preset(), &c, n_steps)?;
    let u_max = DVector::from_vec(vec![22.0, 16.0, 16.0, 21.0, 20.0, 15.0, 15.0, 19.0]);
    let inputs: Vec<DVector<f64>> = (0..n_steps).map(|k| &u_max * (k as f64 / n_steps as f64)).collect();
    Ok(Scenario {
        id: "paper".into(),
        title: "The experiment as published: Table 1 carrier, one container, 6 m/s, C = I, N = 100".into(),
        steps,
        sim: SimulationConfig {
            x0: DVector::from_vec(vec![3.0, -8.0, 2.0, 10.0]),
            inputs,
            process_noise: BoundedNoise::uniform_cube(4, 0.3).map_err(err)?,
            measurement_noise: BoundedNoise::uniform_cube(4, 0.5).map_err(err)?,
            seed,
        },
        x_hat0: DVector::from_vec(vec![-3.0, -8.0, 2.0, 10.0]),
        p0: DMatrix::identity(4, 4) * 10.0,
        q: DMatrix::identity(4, 4) * 5.0,
        r: DMatrix::identity(4, 4) * 8.0,
        input_range: (DVector::zeros(8), u_max),
        sdp_steps: n_steps,
        notes: vec![
            "Inputs u_k = (u_max/k_N)·k are used as printed (the paper gives no unit; read as radians they are not \
             physical steering angles, but the linear model does not care)."
                .into(),
            "True noises uniform per component, |w| ≤ 0.3, |v| ≤ 0.5 (seeded); the filters are given Q = 5 I, R = 8 I \
             (as ellipsoid shapes for the set-membership filters, as covariances for the Kalman filter)."
                .into(),
            "I_xeq of Table 1 read as the roll inertia about the CG (see the inconsistencies).".into(),
        ],
    })
}

/// The realistic sensor set and noise bounds of the extended scenarios.
pub struct Sensors {
    /// Output matrix: yaw rate, roll angle, roll rate (no sideslip sensor).
    pub c: DMatrix<f64>,
    /// Measurement-noise shape.
    pub r: DMatrix<f64>,
    /// Process-noise shape (model error per 1 ms step).
    pub q: DMatrix<f64>,
}

/// No sideslip sensor: a yaw-rate gyro (±0.002 rad/s ≈ 0.11 °/s), a roll-angle sensor
/// (±0.005 rad ≈ 0.3°) and a roll-rate gyro (±0.002 rad/s); process noise per step
/// ±(2e-4 rad, 5e-4 rad/s, 1e-5 rad, 5e-4 rad/s). Each box of half-widths `b` is covered by the
/// ellipsoid `𝓔(0, d·diag(b²))` (`d` its dimension), which is what the filters are given.
pub fn sensors() -> Sensors {
    let c = DMatrix::from_row_slice(3, 4, &[0., 1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1.]);
    let bv = [0.002, 0.005, 0.002];
    let bw = [2e-4, 5e-4, 1e-5, 5e-4];
    let r = DMatrix::from_diagonal(&DVector::from_iterator(3, bv.iter().map(|b| 3.0 * b * b)));
    let q = DMatrix::from_diagonal(&DVector::from_iterator(4, bw.iter().map(|b| 4.0 * b * b)));
    Sensors { c, r, q }
}

/// A box of inputs `[lo, hi]`.
pub type InputRange = (DVector<f64>, DVector<f64>);

/// A slalom: front rows steer `5° sin(2π·0.2·t)`, rear rows counter-steer with half the angle.
pub fn slalom_inputs(n_steps: usize) -> (Vec<DVector<f64>>, InputRange) {
    let amp = 5f64.to_radians();
    let profile = [1.0, 1.0, -0.5, -0.5];
    let inputs = (0..n_steps)
        .map(|k| {
            let d = amp * (2.0 * std::f64::consts::PI * 0.2 * k as f64 * TS).sin();
            DVector::from_iterator(8, (0..8).map(|j| d * profile[j % 4]))
        })
        .collect();
    let hi = DVector::from_iterator(8, (0..8).map(|j| amp * f64::abs(profile[j % 4])));
    (inputs, (-&hi, hi))
}

fn extended(
    id: &str,
    title: &str,
    steps: Vec<StepMatrices>,
    seed: u64,
    sdp_steps: usize,
    notes: Vec<String>,
) -> Result<Scenario, String> {
    let s = sensors();
    let (inputs, input_range) = slalom_inputs(steps.len());
    let p0 = DMatrix::from_diagonal(&DVector::from_vec(vec![
        0.1f64.powi(2),
        0.1f64.powi(2),
        0.04f64.powi(2),
        0.1f64.powi(2),
    ]));
    let mut all_notes = vec![
        "C measures γ, φ, φ̇ (no sideslip sensor): bounds ±0.002 rad/s, ±0.005 rad, ±0.002 rad/s; process noise \
         ±(2e-4, 5e-4, 1e-5, 5e-4) per 1 ms step; the filters get the covering ellipsoids Q, R."
            .into(),
        "Both noises drawn on the boundary of those ellipsoids, in random directions (seeded).".into(),
        "Slalom steering: front rows 5° sin(2π·0.2 t), rear rows −2.5° sin(2π·0.2 t); the [17]-style filter without \
         input knows only this range."
            .into(),
        "x₀ = (0.01, 0, 0.005, 0), x̂₀ = 0, P₀ = diag(0.1², 0.1², 0.04², 0.1²) (x₀ inside the initial set).".into(),
    ];
    all_notes.extend(notes);
    Ok(Scenario {
        id: id.into(),
        title: title.into(),
        sim: SimulationConfig {
            x0: DVector::from_vec(vec![0.01, 0.0, 0.005, 0.0]),
            inputs,
            process_noise: BoundedNoise::ellipsoid_boundary(s.q.clone()).map_err(err)?,
            measurement_noise: BoundedNoise::ellipsoid_boundary(s.r.clone()).map_err(err)?,
            seed,
        },
        steps,
        x_hat0: DVector::zeros(4),
        p0,
        q: s.q,
        r: s.r,
        input_range,
        sdp_steps,
        notes: all_notes,
    })
}

/// No sideslip sensor, one container, 6 m/s, `n_steps` at 1 kHz.
pub fn no_sideslip(n_steps: usize, sdp_steps: usize, seed: u64) -> Result<Scenario, String> {
    let steps = carrier_steps(CarrierParams::paper_preset(), &sensors().c, n_steps)?;
    extended(
        "no_sideslip",
        &format!("Extended: no sideslip sensor, one container, 6 m/s, {} s at 1 kHz", n_steps as f64 * TS),
        steps,
        seed,
        sdp_steps,
        vec![],
    )
}

/// No sideslip sensor with `containers` containers (0, 1 or 2), 6 m/s.
pub fn load(containers: usize, n_steps: usize, sdp_steps: usize, seed: u64) -> Result<Scenario, String> {
    let params = CarrierParams::for_load(containers).map_err(err)?;
    let steps = carrier_steps(params, &sensors().c, n_steps)?;
    extended(
        &format!("load{containers}"),
        &format!("Extended: load of {containers} container(s), no sideslip sensor, 6 m/s, {} s", n_steps as f64 * TS),
        steps,
        seed,
        sdp_steps,
        vec!["Load model of carrier-dynamics: 25 t containers; see its documentation.".into()],
    )
}

/// No sideslip sensor, one container, speed ramping linearly from 2 to 8 m/s along the run:
/// `A_p`, `B_p` change at every step (exact ZOH at each speed).
pub fn speed_schedule(n_steps: usize, sdp_steps: usize, seed: u64) -> Result<Scenario, String> {
    let c = sensors().c;
    let mut steps = Vec::with_capacity(n_steps);
    for k in 0..n_steps {
        let v = 2.0 + 6.0 * k as f64 / (n_steps.max(2) - 1) as f64;
        let d =
            CarrierModel::new(CarrierParams::paper_preset().with_speed(v)).map_err(err)?.discretize(TS).map_err(err)?;
        let (a, b, _) = d.to_dynamic();
        steps.push(StepMatrices { a, b, c: c.clone() });
    }
    extended(
        "speed_schedule",
        &format!(
            "Extended: speed 2 → 8 m/s over {} s (time-varying A_p, B_p), no sideslip sensor",
            n_steps as f64 * TS
        ),
        steps,
        seed,
        sdp_steps,
        vec!["Speed ramps linearly from 2 to 8 m/s; the filters get the matrices of each step.".into()],
    )
}
