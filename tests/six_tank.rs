//! CORA's six-tank observer benchmark (examples/six-tank): the constrained-zonotope filter on
//! CORA's published data, against CORA's saved final hulls.

use equation_models::EquationModel;
use estimators::{ConstrainedZonotopeFilter, ConstrainedZonotopeSettings, Estimate, Setup};
use nalgebra::{DMatrix, DVector};

const FOREIGN: &[&str] = &["x0", "p0", "q", "r", "u_lower", "u_upper", "x_lower", "x_upper", "mhe", "ukf"];

/// CORA's first measurement (at t = 0), which the log's rows cannot hold (examples/six-tank/README.md).
const Y1: [f64; 3] = [18.587107801413037, 20.225990245627816, 19.112251238495777];

fn root() -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn model() -> EquationModel {
    let path = root().join("examples/six-tank/model.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    EquationModel::from_toml_str_with_foreign_keys(&text, &path.display().to_string(), FOREIGN).unwrap()
}

fn log() -> Vec<(DVector<f64>, DVector<f64>)> {
    let text = std::fs::read_to_string(root().join("examples/six-tank/data.csv")).unwrap();
    text.lines()
        .skip(1)
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|c| c.trim().parse().unwrap()).collect();
            (DVector::from_column_slice(&v[1..4]), DVector::from_column_slice(&v[4..7]))
        })
        .collect()
}

fn setup() -> Setup {
    Setup {
        x0: DVector::from_element(6, 20.0),
        p0: DMatrix::identity(6, 6) * 4.0,
        process_noise: DMatrix::identity(6, 6) * 0.001,
        measurement_noise: DMatrix::identity(3, 3) * 0.2,
        inputs: 3,
    }
}

/// CORA's FRad-A final hull widths (cora_hulls.csv).
const CORA_FRAD_A: [f64; 6] = [0.4899944388, 0.4895336085, 15.9242087201, 0.6331563638, 0.4206899815, 7.5405482463];

#[test]
fn six_tank_widths() {
    let model = model();
    for (order, nc) in [(10, 6), (20, 12), (40, 24)] {
        let settings = ConstrainedZonotopeSettings { order, max_constraints: nc, ..Default::default() };
        let mut f = ConstrainedZonotopeFilter::new(setup(), settings).unwrap();
        f.update(&model, &DVector::from_column_slice(&Y1)).unwrap();
        for (u, y) in log() {
            f.step(&model, &u, &y).unwrap();
        }
        let e = f.estimate();
        let w: Vec<f64> = (0..6).map(|i| e.bounds(i).map(|(l, h)| h - l).unwrap()).collect();
        eprintln!("order {order} nc {nc}: {w:?} mean {} (CORA {:?})", w.iter().sum::<f64>() / 6.0, CORA_FRAD_A);
    }
}

#[test]
fn six_tank_debug() {
    let model = model();
    let settings = ConstrainedZonotopeSettings { order: 10, max_constraints: 6, ..Default::default() };
    let mut f = ConstrainedZonotopeFilter::new(setup(), settings).unwrap();
    f.update(&model, &DVector::from_column_slice(&Y1)).unwrap();
    for (u, y) in log() {
        let e = f.step(&model, &u, &y).unwrap();
        let (l, h) = e.bounds(5).unwrap();
        let (l5, h5) = e.bounds(4).unwrap();
        let s = e.set();
        let zh = s.interval_hull().unwrap();
        eprintln!("x6 [{l}, {h}] w {} | x5 w {} | set x6 [{}, {}] rep {:?}", h - l, h5 - l5, zh.lower[5], zh.upper[5], e.report());
    }
}
