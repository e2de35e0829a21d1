//! The BDS/INS fuzzy system's evaluation with the three defuzzifiers: the naive 1000-point sampled
//! centroid (the reference), the exact piecewise-linear centroid, and the precomputed grid.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use fuzzy_inference::{Defuzzifier, FuzzySystem};
use std::hint::black_box;

/// Inputs that fire one, two and several rules (fractional RTK codes mix two sets).
const INPUTS: [[f64; 3]; 4] = [[20.0, 3.0, 0.05], [20.0, 1.0, 0.5], [9.0, 3.5, 0.7], [15.0, 2.5, 1.1]];

fn fis(c: &mut Criterion) {
    // One iteration evaluates the four inputs: time per evaluation = reported time / 4.
    let mut group = c.benchmark_group("bds_ins_fis");
    group.throughput(Throughput::Elements(INPUTS.len() as u64));
    for (name, d) in [
        ("sampled_1000", Defuzzifier::SAMPLED_1000),
        ("exact", Defuzzifier::Exact),
        ("grid_33", Defuzzifier::Grid { points_per_axis: 33 }),
    ] {
        let Ok(system) = FuzzySystem::bds_ins_default().with_defuzzifier(d) else {
            panic!("defuzzifier {name} rejected");
        };
        group.bench_function(name, |b| {
            b.iter(|| {
                let mut acc = 0.0;
                for x in &INPUTS {
                    if let Ok(e) = system.evaluate(black_box(x)) {
                        acc += e.output;
                    }
                }
                acc
            })
        });
    }
    group.finish();
}

criterion_group!(benches, fis);
criterion_main!(benches);
