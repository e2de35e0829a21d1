//! The constrained-zonotope filters' sets in a model file: boxes (`*_radius`) or generator
//! matrices (`*_generators`), one form per set; mistakes reported at `file:line:column`.

mod common;

use std::path::{Path, PathBuf};

use common::DOUBLE_INTEGRATOR as MODEL;
use estimators::EstimateKind;
use port_est::{FilterOptions, filter, read_model};

fn dir(name: &str) -> PathBuf {
    common::fresh_dir("port-est-zonotopes", name)
}

fn options(d: &Path, model: &str, data: &str) -> FilterOptions {
    std::fs::write(d.join("model.toml"), model).unwrap();
    std::fs::write(d.join("data.csv"), data).unwrap();
    FilterOptions {
        estimator: "czf".into(),
        ..FilterOptions::new(d.join("model.toml"), d.join("data.csv"), d.join("out.csv"))
    }
}

/// A run with every noise on a vertex of `W = G_w □` (a skewed zonotope) and `V`, measured
/// from its own simulation.
fn data(gw: [[f64; 2]; 2], v: f64) -> (String, Vec<[f64; 2]>) {
    let mut x = [0.3, -0.2];
    let mut text = String::from("k,u1,y1\n");
    let mut truth = Vec::new();
    for k in 0..60 {
        let u = (0.1 * k as f64).sin();
        let s = [if k % 3 == 0 { 1.0 } else { -1.0 }, if k % 2 == 0 { 1.0 } else { -1.0 }];
        x = [x[0] + 0.1 * x[1] + gw[0][0] * s[0] + gw[0][1] * s[1], x[1] + 0.1 * u + gw[1][0] * s[0] + gw[1][1] * s[1]];
        let y = x[0] + if k % 5 < 2 { v } else { -v };
        text.push_str(&format!("{k},{u},{y}\n"));
        truth.push(x);
    }
    (text, truth)
}

#[test]
fn generator_matrices_are_read_and_a_diagonal_one_is_the_box() {
    let sets = "x0_radius = [0.5, 0.5]\nw_generators = [[0.01, 0.004], [-0.004, 0.01]]\nv_radius = [0.05]\n";
    let model = read_model_text("read", &format!("{MODEL}{sets}"));
    let b = model.boxes.as_ref().unwrap();
    assert_eq!(b.w.shape(), (2, 2));
    assert_eq!(b.w[(1, 0)], -0.004);
    let setup = model.setup(EstimateKind::GuaranteedConstrainedZonotope);
    assert_eq!(setup.process_noise, b.w);
    assert_eq!(setup.p0, nalgebra::DMatrix::from_diagonal(&nalgebra::dvector![0.5, 0.5]));
    // The box as a radius and as a diagonal generator matrix: the same run, bit for bit.
    let (text, truth) = data([[0.01, 0.004], [-0.004, 0.01]], 0.05);
    let run = |name: &str, sets: &str| {
        let d = dir(name);
        let o = options(&d, &format!("{MODEL}{sets}"), &text);
        filter(&o).unwrap();
        std::fs::read_to_string(d.join("out.csv")).unwrap()
    };
    let radius = run("radius", "x0_radius = [0.5, 0.5]\nw_radius = [0.014, 0.014]\nv_radius = [0.05]\n");
    let diagonal = run(
        "diagonal",
        "x0_generators = [[0.5, 0.0], [0.0, 0.5]]\nw_generators = [[0.014, 0.0], [0.0, 0.014]]\nv_generators = [[0.05]]\n",
    );
    assert_eq!(radius, diagonal);
    // The skewed zonotope: the truth (its noise on the zonotope's vertices) inside every interval,
    // and narrower than with the box around it.
    let skewed = run("skewed", sets);
    let widths = |csv: &str| -> Vec<f64> {
        csv.lines()
            .skip(1)
            .map(|l| {
                let v: Vec<f64> = l.split(',').take(7).map(|c| c.parse().unwrap()).collect();
                v[6] - v[4]
            })
            .collect()
    };
    for (k, line) in skewed.lines().skip(1).enumerate() {
        let v: Vec<f64> = line.split(',').take(7).map(|c| c.parse().unwrap()).collect();
        for i in 0..2 {
            assert!(v[3 + i] <= truth[k][i] && truth[k][i] <= v[5 + i], "step {k}, x{}", i + 1);
        }
    }
    let (ws, wr) = (widths(&skewed), widths(&radius));
    assert!(ws.iter().sum::<f64>() < wr.iter().sum::<f64>(), "{ws:?} against {wr:?}");
}

fn read_model_text(name: &str, text: &str) -> port_est::model::Model {
    let d = dir(name);
    std::fs::write(d.join("model.toml"), text).unwrap();
    read_model(&d.join("model.toml")).unwrap()
}

#[test]
fn mistakes_in_the_sets_are_reported_where_they_are() {
    let cases = [
        // Both forms for one set.
        (
            "x0_radius = [0.5, 0.5]\nx0_generators = [[0.5, 0.0], [0.0, 0.5]]\nw_radius = [0.01, 0.01]\nv_radius = [0.1]\n",
            9,
            "not both",
        ),
        // A set missing.
        ("x0_radius = [0.5, 0.5]\nw_generators = [[0.01], [0.01]]\n", 8, "`v` has no set"),
        // Rows that are not the state's dimension.
        ("x0_radius = [0.5, 0.5]\nw_generators = [[0.01, 0.0]]\nv_radius = [0.1]\n", 9, "expected 2 rows"),
        // A non-finite entry.
        ("x0_radius = [0.5, 0.5]\nw_generators = [[0.01, nan], [0.0, 0.01]]\nv_radius = [0.1]\n", 9, "not finite"),
    ];
    for (i, (sets, line, needle)) in cases.into_iter().enumerate() {
        let d = dir(&format!("mistake{i}"));
        std::fs::write(d.join("model.toml"), format!("{MODEL}{sets}")).unwrap();
        let e = read_model(&d.join("model.toml")).unwrap_err();
        let at = e.location().unwrap_or_else(|| panic!("case {i}: no location in {e}"));
        assert_eq!(at.line, line, "case {i}: {e}");
        assert!(e.to_string().contains(needle), "case {i}: {e}");
    }
    // Too many columns, refused before any filter is built.
    let wide = format!("[{}]", vec!["0.0"; port_est::model::MAX_GENERATOR_COLUMNS + 1].join(", "));
    let d = dir("wide");
    std::fs::write(
        d.join("model.toml"),
        format!("{MODEL}x0_radius = [0.5, 0.5]\nw_generators = [{wide}, {wide}]\nv_radius = [0.1]\n"),
    )
    .unwrap();
    let e = read_model(&d.join("model.toml")).unwrap_err().to_string();
    assert!(e.contains("columns, more than"), "{e}");
}
