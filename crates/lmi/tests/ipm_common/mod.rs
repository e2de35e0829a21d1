//! Problems shared by the `lmi` tests.

#![allow(dead_code)]

use lmi::{Block, Entry, SdpProblem};

/// A problem from `(matrix, block, row, col, value)` tuples.
pub fn problem(blocks: Vec<Block>, c: Vec<f64>, entries: &[(usize, usize, usize, usize, f64)]) -> SdpProblem {
    let entries = entries.iter().map(|&(mat, block, row, col, value)| Entry { mat, block, row, col, value }).collect();
    SdpProblem::new(blocks, c, entries).unwrap()
}

/// The set-membership filter's LMI for (n, m) = (4, 3): variables P (symmetric), L (n×m), g,
/// τ₁, τ₂, τ₃; block [[P, Π], [Πᵀ, Θ]] with Π = [g, (I − LC)AE, I − LC, −L],
/// Θ = diag(1 − τ₁ − τ₂ − τ₃, τ₁I, τ₂Q⁻¹, τ₃R⁻¹); minimise tr P.
pub fn filter_lmi() -> SdpProblem {
    let a = [
        [0.755139296689566, -0.019699090506075354, -0.04774305144944732, -0.0018915821287349352],
        [-0.009311961979518266, 0.9417205179851139, 0.0002699108914448061, 1.0206142568712238e-05],
        [-0.0007011828373116359, -3.020454597046461e-05, 0.9998073936269428, 0.00999272470285723],
        [-0.13392137898100265, -0.005464612817309362, -0.03728944211821784, 0.9985252052798118],
    ];
    let (n, m) = (4usize, 3usize);
    let cm = |j: usize, k: usize| if k == j + 1 { 1.0 } else { 0.0 }; // C = [0 I]
    let e = 0.5f64.sqrt(); // chol(0.5 I)
    let ae = |i: usize, k: usize| a[i][k] * e;
    let cae = |j: usize, k: usize| (0..n).map(|l| cm(j, l) * ae(l, k)).sum::<f64>();
    let (qinv, rinv) = (100.0, 20.0);
    let big = n + 1 + n + n + m;
    let (col_g, col_ae, col_i, col_l) = (n, n + 1, n + 1 + n, n + 1 + 2 * n);
    let (th0, th1, th2, th3) = (n, n + 1, n + 1 + n, n + 1 + 2 * n);
    let mut c = vec![];
    let mut ent = vec![];
    let mut var = 0;
    // P
    for j in 0..n {
        for i in 0..=j {
            var += 1;
            c.push(if i == j { 1.0 } else { 0.0 });
            ent.push((var, 0, i, j, 1.0));
        }
    }
    // L
    for i in 0..n {
        for j in 0..m {
            var += 1;
            c.push(0.0);
            for k in 0..n {
                let v = -cae(j, k);
                if v != 0.0 {
                    ent.push((var, 0, i, col_ae + k, v));
                }
                if cm(j, k) != 0.0 {
                    ent.push((var, 0, i, col_i + k, -cm(j, k)));
                }
            }
            ent.push((var, 0, i, col_l + j, -1.0));
        }
    }
    // g
    for i in 0..n {
        var += 1;
        c.push(0.0);
        ent.push((var, 0, i, col_g, 1.0));
    }
    // τ₁, τ₂, τ₃
    for (start, size, scale) in [(th1, n, 1.0), (th2, n, qinv), (th3, m, rinv)] {
        var += 1;
        c.push(0.0);
        ent.push((var, 0, th0, th0, -1.0));
        for k in 0..size {
            ent.push((var, 0, start + k, start + k, scale));
        }
    }
    // Constant part X₀ = −F₀: Θ₀₀ = 1, AE and I in Π.
    ent.push((0, 0, th0, th0, -1.0));
    for i in 0..n {
        for k in 0..n {
            if ae(i, k) != 0.0 {
                ent.push((0, 0, i, col_ae + k, -ae(i, k)));
            }
        }
        ent.push((0, 0, i, col_i + i, -1.0));
    }
    assert_eq!(big, 16);
    problem(vec![Block::Psd(big)], c, &ent)
}

/// A small feasible SDP with the closed-form optimum 1, its data multiplied by `s_obj` (the
/// objective `c`) and `s_con` (every `Fᵢ`, `F₀` included):
///
/// ```text
/// minimise (x₁ + x₂)/2   s.t.  [[x₁, 1], [1, x₂]] ⪰ 0,   x₁ ≥ 1/4,   x₂ ≥ 0
/// ```
///
/// `x₁x₂ ≥ 1` with `x₁, x₂ > 0`, so `(x₁ + x₂)/2 ≥ √(x₁x₂) ≥ 1` with equality at `x = (1, 1)`
/// (the bound `x₁ ≥ 1/4` is inactive). The dual `Y = [[½, −½], [−½, ½]] ⊕ 0` attains
/// `tr(F₀Y) = 1`. Scaling every `Fᵢ` (and `F₀`) by the same factor leaves `x` and the optimum
/// unchanged; scaling `c` scales the optimum.
pub fn known_optimum(s_obj: f64, s_con: f64) -> SdpProblem {
    let entries = [
        (1, 0, 0, 0, 1.0),
        (2, 0, 1, 1, 1.0),
        (0, 0, 0, 1, -1.0),
        (1, 1, 0, 0, 1.0),
        (0, 1, 0, 0, 0.25),
        (2, 1, 1, 1, 1.0),
    ]
    .map(|(mat, block, row, col, value)| (mat, block, row, col, value * s_con));
    problem(vec![Block::Psd(2), Block::Nonneg(2)], vec![0.5 * s_obj, 0.5 * s_obj], &entries)
}
