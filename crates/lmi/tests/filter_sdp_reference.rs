//! LMI (28)/(29) on the reference case of the `lmi` issue, solved by every compiled backend.
//!
//! Reference (an independent solver): `tr P_{k+1} = 0.98464424`, `τ ≈ (0.55710, 0.10383,
//! 0.33907)`, zero free first column.

use lmi::filter_sdp::{FilterSdp, FilterSdpData};
use lmi::{SolveStatus, SolverSettings, backend_by_name, backend_names};
use nalgebra::{DMatrix, DVector};

fn reference_data() -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, DVector<f64>) {
    #[rustfmt::skip]
    let a = DMatrix::from_row_slice(4, 4, &[
        0.755139296689566, -0.019699090506075354, -0.04774305144944732, -0.0018915821287349352,
        -0.009311961979518266, 0.9417205179851139, 0.0002699108914448061, 1.0206142568712238e-05,
        -0.0007011828373116359, -3.020454597046461e-05, 0.9998073936269428, 0.00999272470285723,
        -0.13392137898100265, -0.005464612817309362, -0.03728944211821784, 0.9985252052798118,
    ]);
    let c = DMatrix::from_row_slice(3, 4, &[0., 1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1.]);
    (
        a,
        c,
        DMatrix::identity(4, 4) * 0.01,
        DMatrix::identity(3, 3) * 0.05,
        DMatrix::identity(4, 4) * 0.5,
        DVector::zeros(4),
    )
}

#[test]
fn every_backend_matches_the_reference_optimum() {
    let names = backend_names();
    if names.is_empty() {
        eprintln!("no SDP backend compiled in; nothing to check");
        return;
    }
    let (a, c, q, r, p, x) = reference_data();
    let data = FilterSdpData { a: &a, c: &c, q: &q, r: &r, p: &p, x_hat: &x };
    let sdp = FilterSdp::new(&data).unwrap();
    assert_eq!(sdp.problem().blocks()[0].size(), 16);
    for name in names {
        let mut backend = backend_by_name(name, SolverSettings::default()).unwrap();
        let sol = backend.setup_and_solve(sdp.problem()).unwrap();
        assert_eq!(sol.status, SolveStatus::Solved, "{name}");
        let f = sdp.read(&sol.x, &data).unwrap();
        let tr = f.p_next.trace();
        assert!((tr - 0.98464424).abs() < 1e-7 * 0.98464424, "{name}: trace {tr}");
        for (t, r) in f.tau.iter().zip([0.55710, 0.10383, 0.33907]) {
            assert!((t - r).abs() < 1e-4, "{name}: tau {:?}", f.tau);
        }
        assert!(f.g.amax() < 1e-6, "{name}: g = {}", f.g);
        eprintln!("{name}: tr P = {tr:.10}, tau = {:?}, iterations {}, {:?}", f.tau, sol.iterations, sol.solve_time);
    }
}
