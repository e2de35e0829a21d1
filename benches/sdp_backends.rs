//! SDP backends side by side: the filter LMI (28) for (n, m) = (4, 3), (4, 4), (8, 4) — setup +
//! solve and solve only — and SDPLIB `hinf1`, `control1`, `truss1`, for every backend compiled in
//! (`cargo bench --bench sdp_backends`; add `--features clarabel` for Clarabel).
//!
//! Every line uses the whitened statement of (28) ([`Formulation::Whitened`]); the earlier
//! method's figures on (28) as stated are quoted in `docs/sdp.md` §3.5.
//! `faer-ipm-hkm` is `faer-ipm` with the HKM direction ([`lmi::FaerIpm::set_direction`]).
//! `faer-ipm-warm` solves, in turn, 8 nearby problems of the same structure (the case's values
//! moved by up to 0.1 % along a smooth path, as the filter's SDP moves from one step to the
//! next), each warm-started from the previous one's solution ([`SolverSettings::warm_start`]);
//! `faer-ipm-cold-path` solves the same 8 problems from the default start, for the ratio.

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use estimators::smf::lmi28::{FilterSdp, FilterSdpData, Formulation};
use lmi::{FaerIpm, SdpBackend, SdpSolution, SearchDirection, SolverSettings, backend_by_name, backend_names};
use nalgebra::{DMatrix, DVector};

/// A deterministic stable `n × n` system with `m` outputs (the reference case of `lmi`'s tests
/// for n = 4, m = 3; otherwise a lightly coupled damped chain).
fn filter_case(n: usize, m: usize, form: Formulation) -> FilterSdp {
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
    // Measure the last m states (the first, like the sideslip, is unmeasured when m < n).
    let c = DMatrix::from_fn(m, n, |i, j| if j == n - m + i { 1.0 } else { 0.0 });
    let q = DMatrix::identity(n, n) * 0.01;
    let r = DMatrix::identity(m, m) * 0.05;
    let p = DMatrix::identity(n, n) * 0.5;
    let x = DVector::zeros(n);
    FilterSdp::with_formulation(&FilterSdpData { a: &a, c: &c, q: &q, r: &r, p: &p, x_hat: &x }, form)
        .expect("valid case")
}

/// `count` problems of `p`'s structure along a closed smooth path: value `k` of problem `j` is
/// multiplied by `1 + 10⁻³ sin(2πj/count + 0.7k)`.
fn nearby_path(p: &lmi::SdpProblem, count: usize) -> Vec<lmi::SdpProblem> {
    (0..count)
        .map(|j| {
            let phase = std::f64::consts::TAU * j as f64 / count as f64;
            let values: Vec<f64> = p
                .entries()
                .iter()
                .enumerate()
                .map(|(k, e)| e.value * (1.0 + 1e-3 * (phase + 0.7 * k as f64).sin()))
                .collect();
            let mut q = p.clone();
            q.set_values(p.c(), &values).expect("same structure");
            q
        })
        .collect()
}

fn filter_lmi(crit: &mut Criterion) {
    let mut group = crit.benchmark_group("filter_lmi_28");
    for (n, m) in [(4, 3), (4, 4), (8, 4)] {
        let sdp = filter_case(n, m, Formulation::Whitened);
        let problem = sdp.problem();
        for name in backend_names() {
            let label = format!("{name}/n{n}m{m}");
            group.bench_function(BenchmarkId::new("setup+solve", &label), |b| {
                b.iter(|| {
                    let mut backend = backend_by_name(name, SolverSettings::default()).unwrap();
                    black_box(backend.setup_and_solve(black_box(problem)).unwrap().status)
                })
            });
            let mut backend = backend_by_name(name, SolverSettings::default()).unwrap();
            backend.setup(problem).unwrap();
            let mut sol = SdpSolution::new(problem);
            group.bench_function(BenchmarkId::new("solve", &label), |b| {
                b.iter(|| {
                    backend.solve(black_box(problem), &mut sol).unwrap();
                    black_box(sol.status)
                })
            });
        }
        // Warm starts along a path of nearby problems, and the same path solved cold.
        let path = nearby_path(problem, 8);
        for (label, warm_start) in [("faer-ipm-warm", true), ("faer-ipm-cold-path", false)] {
            let settings = SolverSettings::builder().warm_start(warm_start).build().unwrap();
            let mut backend = FaerIpm::new(settings).unwrap();
            backend.setup(problem).unwrap();
            let mut sol = SdpSolution::new(problem);
            let mut k = 0;
            group.bench_function(BenchmarkId::new("solve", format!("{label}/n{n}m{m}")), |b| {
                b.iter(|| {
                    k = (k + 1) % path.len();
                    backend.solve(black_box(&path[k]), &mut sol).unwrap();
                    black_box(sol.status)
                })
            });
        }
        // The HKM direction on the same statement.
        let mut hkm = FaerIpm::new(SolverSettings::default()).unwrap();
        hkm.set_direction(SearchDirection::Hkm);
        hkm.setup(problem).unwrap();
        let mut sol = SdpSolution::new(problem);
        group.bench_function(BenchmarkId::new("solve", format!("faer-ipm-hkm/n{n}m{m}")), |b| {
            b.iter(|| {
                hkm.solve(black_box(problem), &mut sol).unwrap();
                black_box(sol.status)
            })
        });
    }
    group.finish();
}

fn sdplib(crit: &mut Criterion) {
    let Some(dir) = xtask::sdplib::suite::sdplib_dir() else {
        eprintln!("SDPLIB directory not found (set SDPLIB_DIR); skipping the SDPLIB benchmarks");
        return;
    };
    let mut group = crit.benchmark_group("sdplib");
    group.sample_size(20);
    for name in ["hinf1", "control1", "truss1"] {
        let problem = lmi::read_sdpa_file(&dir.join(format!("{name}.dat-s"))).expect("SDPLIB file");
        for backend_name in backend_names() {
            let mut backend = backend_by_name(backend_name, SolverSettings::default()).unwrap();
            backend.setup(&problem).unwrap();
            let mut sol = SdpSolution::new(&problem);
            group.bench_function(BenchmarkId::new(backend_name, name), |b| {
                b.iter(|| {
                    backend.solve(black_box(&problem), &mut sol).unwrap();
                    black_box(sol.status)
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, filter_lmi, sdplib);
criterion_main!(benches);
