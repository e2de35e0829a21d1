//! examples/multi-rate: a GNSS at 10 Hz with a 5 s dropout, a compass at 10 Hz, a gyro and a
//! wheel-speed sensor at 100 Hz, empty cells where a sensor did not report, the heading turning
//! through more than a full circle. `port-est filter` runs the Gaussian filters and `czf-nl`
//! through it; the estimates follow the simulation's truth (its end state, from the generator's
//! run: x 13.99 m, y 5.87 m, ψ 7.27 rad, v 3.92 m/s).

use std::path::Path;

use port_est::data::DataReader;
use port_est::filter::{run_filter, select};
use port_est::{StatusPolicy, read_model};

fn run(estimator: &str) -> String {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/multi-rate");
    let model = read_model(&dir.join("model.toml")).unwrap();
    let (entry, solver) = select(estimator, None).unwrap();
    let (p, m) = (model.inputs(), entry.measurement_len(model.outputs()));
    let mut data = DataReader::open_named(&dir.join("data.csv"), p, m, model.column_names()).unwrap();
    let mut out = Vec::new();
    run_filter(&model, &mut data, entry, solver, StatusPolicy::Warn, None, &mut out, Path::new("o.csv"))
        .unwrap_or_else(|e| panic!("{estimator}: {e}"));
    String::from_utf8(out).unwrap()
}

#[test]
fn the_filters_run_through_the_partial_rows_the_dropout_and_the_compass_wrap() {
    for estimator in ["ekf", "ukf", "czf-nl"] {
        let out = run(estimator);
        let lines: Vec<&str> = out.lines().collect();
        assert_eq!(lines.len(), 2001, "{estimator}");
        assert!(lines[1].ends_with("converged"), "{estimator}: {}", lines[1]);
        assert!(lines[2].ends_with("+measured:gyro;wheel_speed"), "{estimator}: {}", lines[2]);
        assert!(lines[801].ends_with("+measured:gyro;wheel_speed;compass"), "{estimator}: {}", lines[801]);
        let last: Vec<f64> = lines[2000].split(',').skip(1).take(4).map(|v| v.parse().unwrap()).collect();
        let truth = [13.986, 5.868, 7.275, 3.922];
        let tolerance = [1.0, 1.0, 0.05, 0.2];
        for i in 0..4 {
            assert!((last[i] - truth[i]).abs() < tolerance[i], "{estimator}: state {i}: {} vs {}", last[i], truth[i]);
        }
        if estimator == "czf-nl" {
            // The certified interval holds the end state.
            let cells: Vec<f64> = lines[2000].split(',').skip(5).take(8).map(|v| v.parse().unwrap()).collect();
            for i in 0..4 {
                assert!(cells[i] <= truth[i] + 1e-3 && truth[i] - 1e-3 <= cells[4 + i], "state {i}: {cells:?}");
            }
        }
    }
}
