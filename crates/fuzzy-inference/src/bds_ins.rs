//! The BDS/INS fuzzy Kalman filter's measurement-noise scaling system (`docs/bds-ins-fuzzy-kf.md`,
//! "Fuzzy inference system", marked A: the project's design, consistent with the paper's expert
//! rules).

use crate::{FuzzyError, FuzzySystem, InputVariable, MembershipFunction, OutputScale, OutputVariable, Rule};

const INF: f64 = f64::INFINITY;

/// An `N` set and its outputs for `d = PS` and `d = PM` (empty: no rule).
type Cell = (&'static str, [&'static str; 2]);

/// Output set for each `(RTK, N)` row and `d = PS / PM` (the note's table); `d = PB` always gives `PB`,
/// and `(N = Z, fixed)` has no rule.
const TABLE: [(&str, [Cell; 4]); 4] = [
    ("fixed", [("PB", ["Z", "PM"]), ("PM", ["Z", "PM"]), ("PS", ["PM", "PM"]), ("Z", ["", ""])]),
    ("float", [("PB", ["PM", "PM"]), ("PM", ["PM", "PM"]), ("PS", ["PM", "PB"]), ("Z", ["PB", "PB"])]),
    ("differential", [("PB", ["PM", "PM"]), ("PM", ["PM", "PM"]), ("PS", ["PM", "PB"]), ("Z", ["PB", "PB"])]),
    ("single", [("PB", ["PM", "PB"]), ("PM", ["PM", "PB"]), ("PS", ["PB", "PB"]), ("Z", ["PB", "PB"])]),
];

/// The 45 rules, in the order of the note's table (RTK rows, N columns, then `d` = PS, PM, PB).
fn rules() -> Vec<Rule> {
    let mut rules = Vec::with_capacity(45);
    for (rtk, row) in TABLE {
        for (n, cells) in row {
            if cells[0].is_empty() {
                continue;
            }
            for (d, out) in [("PS", cells[0]), ("PM", cells[1]), ("PB", "PB")] {
                rules.push(Rule::new(&[("N", n), ("RTK", rtk), ("d", d)], out));
            }
        }
    }
    rules
}

/// The system with the `d` sets' corners `[2σ0, 3σ0, 4σ0, 6σ0, 5σ0, 8σ0]` given.
fn build(d: [f64; 6]) -> Result<FuzzySystem, FuzzyError> {
    let sets = |s: &[(&str, MembershipFunction)]| s.iter().map(|&(n, mf)| (n.to_owned(), mf)).collect();
    let tri = MembershipFunction::triangle;
    let trap = MembershipFunction::trapezoid;
    let [d2, d3, d4, d6, d5, d8] = d;
    let inputs = vec![
        InputVariable {
            name: "N".into(),
            range: (0.0, 100.0),
            sets: sets(&[
                ("Z", trap(0.0, 0.0, 3.0, 5.0)),
                ("PS", tri(4.0, 7.0, 10.0)),
                ("PM", tri(8.0, 12.0, 16.0)),
                ("PB", trap(14.0, 18.0, INF, INF)),
            ]),
        },
        InputVariable {
            name: "RTK".into(),
            range: (0.0, 5.0),
            sets: sets(&[
                ("single", tri(0.0, 1.0, 2.0)),
                ("differential", tri(1.0, 2.0, 3.0)),
                ("fixed", tri(2.0, 3.0, 4.0)),
                ("float", tri(3.0, 4.0, 5.0)),
            ]),
        },
        InputVariable {
            name: "d".into(),
            range: (0.0, 100.0),
            sets: sets(&[("PS", trap(0.0, 0.0, d2, d3)), ("PM", tri(d2, d4, d6)), ("PB", trap(d5, d8, INF, INF))]),
        },
    ];
    let output = OutputVariable {
        name: "log10_t".into(),
        universe: (-0.7, 2.1),
        sets: sets(&[("Z", tri(-0.7, 0.0, 0.7)), ("PM", tri(0.0, 0.7, 1.4)), ("PB", tri(0.7, 1.4, 2.1))]),
        scale: OutputScale::Log10,
    };
    FuzzySystem::new(inputs, output, rules(), BDS_INS_NO_RULE_OUTPUT)
}

/// The conservative scale `t = 25` returned by the BDS/INS system when no rule fires (for example a
/// "fixed" RTK code with `N <= 3`, or an RTK code outside 1–4).
pub const BDS_INS_NO_RULE_OUTPUT: f64 = 25.0;

impl FuzzySystem {
    /// The BDS/INS system of `docs/bds-ins-fuzzy-kf.md` with `σ0 = 0.2 m`; also shipped as
    /// `systems/bds_ins.toml`.
    ///
    /// Inputs `[N, RTK, d]`: satellites used (range 0–100), RTK status code (1 single, 2
    /// differential, 3 fixed, 4 float; range 0–5, so codes 0 and 5 fire nothing), the BDS-to-INS
    /// distance `d` in metres (range 0–100). Output: `t`, the measurement-noise scale, whose centroid
    /// is taken on `u = log10 t ∈ [−0.7, 2.1]`. 45 rules; `t = 25` when no rule fires.
    pub fn bds_ins_default() -> FuzzySystem {
        // tidy: invariant — a constant system, checked by the crate's tests.
        build([0.4, 0.6, 0.8, 1.2, 1.0, 1.6]).expect("the built-in BDS/INS system is valid")
    }

    /// The BDS/INS system for another nominal BDS horizontal σ0 (metres): the `d` sets scale with it.
    ///
    /// # Errors
    /// A [`FuzzyError`] if `sigma0` is not positive and finite (the sets would be invalid).
    pub fn bds_ins(sigma0: f64) -> Result<FuzzySystem, FuzzyError> {
        if !(sigma0 > 0.0 && sigma0.is_finite()) {
            return Err(FuzzyError::EmptyRange { context: "BDS/INS sigma0".into(), lo: 0.0, hi: sigma0 });
        }
        build([2.0, 3.0, 4.0, 6.0, 5.0, 8.0].map(|k| k * sigma0))
    }
}
