//! Timing probe of `faer-ipm` on the filter LMI (28) for (n, m) = (4, 3), (4, 4), (8, 4).
//! Not a timed test: `cargo test --release -p lmi --test ipm_perf -- --ignored --nocapture`.
//! `IPM_PERF_REPS` sets the number of solves per case; `IPM_PERF_LOOP=secs` keeps solving the
//! case for that long; `IPM_PERF_CASE=k` runs case `k` only (for a profiler).

use std::time::Instant;

use lmi::filter_sdp::{FilterSdp, FilterSdpData};
use lmi::{FaerIpm, SdpBackend, SdpSolution, SolverSettings};
use nalgebra::{DMatrix, DVector};

#[allow(clippy::type_complexity)]
fn case(n: usize, m: usize) -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, DVector<f64>) {
    #[rustfmt::skip]
    let a4 = [
        0.755139296689566, -0.019699090506075354, -0.04774305144944732, -0.0018915821287349352,
        -0.009311961979518266, 0.9417205179851139, 0.0002699108914448061, 1.0206142568712238e-05,
        -0.0007011828373116359, -3.020454597046461e-05, 0.9998073936269428, 0.00999272470285723,
        -0.13392137898100265, -0.005464612817309362, -0.03728944211821784, 0.9985252052798118,
    ];
    let a = if n == 4 {
        DMatrix::from_row_slice(4, 4, &a4)
    } else {
        DMatrix::from_fn(n, n, |i, j| match (i as isize) - (j as isize) {
            0 => 0.95 - 0.01 * i as f64,
            -1 => 0.05,
            1 => -0.03,
            _ => 0.002 * ((i * 7 + j * 3) % 5) as f64,
        })
    };
    let c = DMatrix::from_fn(m, n, |i, j| if j == n - m + i { 1.0 } else { 0.0 });
    (
        a,
        c,
        DMatrix::identity(n, n) * 0.01,
        DMatrix::identity(m, m) * 0.05,
        DMatrix::identity(n, n) * 0.5,
        DVector::zeros(n),
    )
}

#[test]
#[ignore = "timing only"]
fn filter_lmi_timing() {
    let reps: usize = std::env::var("IPM_PERF_REPS").ok().and_then(|s| s.parse().ok()).unwrap_or(2000);
    let looping: Option<f64> = std::env::var("IPM_PERF_LOOP").ok().and_then(|s| s.parse().ok());
    let only: Option<usize> = std::env::var("IPM_PERF_CASE").ok().and_then(|s| s.parse().ok());
    for (k, (n, m)) in [(4, 3), (4, 4), (8, 4)].into_iter().enumerate() {
        if only.is_some_and(|o| o != k) {
            continue;
        }
        let (a, c, q, r, p, x) = case(n, m);
        let data = FilterSdpData { a: &a, c: &c, q: &q, r: &r, p: &p, x_hat: &x };
        let sdp = FilterSdp::new(&data).unwrap();
        let verbose = std::env::var_os("IPM_VERBOSE").is_some();
        let mut ipm = FaerIpm::new(SolverSettings::builder().verbose(verbose).build().unwrap()).unwrap();
        ipm.setup(sdp.problem()).unwrap();
        let mut sol = SdpSolution::new(sdp.problem());
        if let Some(secs) = looping {
            let t = Instant::now();
            while t.elapsed().as_secs_f64() < secs {
                ipm.solve(sdp.problem(), &mut sol).unwrap();
            }
            return;
        }
        let mut times = Vec::with_capacity(reps);
        for _ in 0..reps {
            let t = Instant::now();
            ipm.solve(sdp.problem(), &mut sol).unwrap();
            times.push(t.elapsed().as_secs_f64() * 1e6);
        }
        times.sort_by(f64::total_cmp);

        let read = sdp.read(&sol.x, &data).unwrap();
        println!(
            "(n, m) = ({n}, {m}): {} in {} it, median {:.1} us (p10 {:.1}, p90 {:.1}), tr P {:.10}, tau {:.6?}, gap {:.1e}, pres {:.1e}, dres {:.1e}",
            sol.status,
            sol.iterations,
            times[reps / 2],
            times[reps / 10],
            times[reps * 9 / 10],
            read.p_next.trace(),
            read.tau,
            sol.relative_gap(),
            sol.primal_residual,
            sol.dual_residual
        );
    }
}
