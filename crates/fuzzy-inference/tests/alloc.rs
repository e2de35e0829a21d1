//! No heap allocation in an evaluation, with any defuzzifier (a counting global allocator, counting
//! only on this test's thread).

use counting_allocator::{Counting, count};
use fuzzy_inference::{Defuzzifier, FuzzySystem};

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn evaluation_does_not_allocate() {
    let inputs: Vec<[f64; 3]> = (0..500)
        .map(|k| {
            let k = k as f64;
            [(k * 0.37) % 30.0, (k * 0.13) % 5.5 - 0.2, (k * 0.011) % 2.5]
        })
        .collect();
    for d in [Defuzzifier::Exact, Defuzzifier::SAMPLED_1000, Defuzzifier::Grid { points_per_axis: 33 }] {
        let fis = FuzzySystem::bds_ins_default().with_defuzzifier(d).unwrap();
        let (sum, n) = count(|| inputs.iter().map(|x| fis.evaluate(x).map_or(f64::NAN, |e| e.output)).sum::<f64>());
        assert_eq!(n, 0, "{d:?} allocated");
        assert!(sum.is_finite() && sum > 0.0);
    }
}
