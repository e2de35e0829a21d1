//! The BDS/INS system against scikit-fuzzy: `tests/golden.csv`, written once by `tools/golden.py`
//! (scikit-fuzzy 0.5.0; the script rebuilds the system from the note, its rules from the score
//! description) on a 7 × 6 × 7 grid of `(N, RTK, d)`.

use fuzzy_inference::{Defuzzifier, FuzzySystem};

/// Output universe resolution of the script.
const UNIVERSE_POINTS: usize = 2801;

struct Row {
    x: [f64; 3],
    /// `(max rule strength, skfuzzy low-level sampled centroid, skfuzzy control centroid)`.
    fired: Option<(f64, f64, f64)>,
}

fn rows() -> Vec<Row> {
    let text = include_str!("golden.csv");
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    assert_eq!(lines.next(), Some("n,rtk,d,fired,firing,u_sampled,u_control"));
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            let num = |i: usize| f[i].parse::<f64>().unwrap();
            let x = [num(0), num(1), num(2)];
            let fired = (f[3] == "1").then(|| (num(4), num(5), num(6)));
            Row { x, fired }
        })
        .collect()
}

#[test]
fn matches_scikit_fuzzy() {
    let rows = rows();
    assert_eq!(rows.len(), 7 * 6 * 7);
    let sampled =
        FuzzySystem::bds_ins_default().with_defuzzifier(Defuzzifier::Sampled { points: UNIVERSE_POINTS }).unwrap();
    let exact = FuzzySystem::bds_ins_default();
    let (mut max_sampled, mut max_exact, mut max_exact_vs_sampled, mut no_rule) = (0.0_f64, 0.0_f64, 0.0_f64, 0);
    for row in &rows {
        let (s, e) = (sampled.evaluate(&row.x).unwrap(), exact.evaluate(&row.x).unwrap());
        let Some((firing, u_sampled, u_control)) = row.fired else {
            // skfuzzy: no rule fired; the crate returns its documented default.
            no_rule += 1;
            assert_eq!((s.centroid, e.centroid, s.output, e.output), (None, None, 25.0, 25.0), "{:?}", row.x);
            continue;
        };
        assert!((e.firing - firing).abs() < 1e-12, "{:?}: firing {} vs {firing}", row.x, e.firing);
        let (us, ue) = (s.centroid.unwrap(), e.centroid.unwrap());

        // Same samples, same formula up to rounding: skfuzzy's centroid integrates the linear
        // interpolant of the samples, which equals Σxμ/Σμ because μ vanishes at both universe ends.
        let d = (us - u_sampled).abs();
        max_sampled = max_sampled.max(d);
        assert!(d < 1e-6, "{:?}: sampled {us} vs skfuzzy {u_sampled}", row.x);
        assert!((s.output - 10_f64.powf(u_sampled)).abs() < 1e-6 * s.output);

        // skfuzzy.control inserts every set's clip points into the universe, so its piecewise-linear
        // aggregate misses only the kinks where two clipped sets cross between samples: at most 2
        // (Z/PM and PM/PB overlap; Z and PB only touch). A kink with slope jump Δs inside a cell of
        // width h changes the area by at most h²Δs/8 and the centroid by that times |x − c| / A.
        // Slopes are ±1/0.7, so Δs ≤ 2/0.7; |x − c| ≤ 2.8 (the universe); the area is at least the
        // strongest rule's clipped triangle, A ≥ 0.7 α (2 − α) ≥ 0.7 α.
        let h = 2.8 / (UNIVERSE_POINTS - 1) as f64;
        let tolerance = 2.0 * h * h * (2.0 / 0.7) / 8.0 * 2.8 / (0.7 * firing) + 1e-12;
        let d = (ue - u_control).abs();
        max_exact = max_exact.max(d);
        assert!(d <= tolerance, "{:?}: exact {ue} vs skfuzzy.control {u_control} (tolerance {tolerance:e})", row.x);
        max_exact_vs_sampled = max_exact_vs_sampled.max((ue - u_sampled).abs());
    }
    println!(
        "{} points ({no_rule} without a firing rule): max |Δu| sampled vs skfuzzy {max_sampled:.2e}, \
         exact vs skfuzzy.control {max_exact:.2e}, exact vs skfuzzy sampled {max_exact_vs_sampled:.2e}",
        rows.len()
    );
    assert!(no_rule > 0);
}
