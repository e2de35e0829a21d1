//! The Helmberg–Kojima–Monteiro direction on the dense blocks (`docs/sdp.md` §3.6): the scaling
//! from Cholesky factors, the Schur matrix `tr(Fᵢ Y Fⱼ X⁻¹)`, and the block formulas of the
//! Newton step (unscaled).

use faer::dyn_stack::MemStack;

use super::Ws;
use super::nonneg::{assemble_diag, scale_diag};
use crate::ipm::dense::{self, view};
use crate::ipm::workspace::{BlockWs, Ent, SchurKind, Workspace};

/// HKM version of the NT whole-block assembly: with `ξ_a = X⁻¹ w_a`, `η_a = Y w_a`,
/// `Zˣ = Wᵀ X⁻¹ W`, `Zʸ = Wᵀ Y W`, a pair of active groups `a ∈ i`, `h ∈ j` adds
/// `ξ_h[c_a] η_a[c_h] + ξ_a[c_h] η_h[c_a] + Zˣ_ah Y[c_a, c_h] + Zʸ_ah X⁻¹[c_a, c_h]` to `M̂ᵢⱼ`.
#[inline(always)]
fn assemble_grouped_hkm(blk: &mut BlockWs, mhat: &mut [f64], mp: usize) {
    let n = blk.n;
    let na = blk.ag_row.len();
    let (yy, xi) = (&blk.y, &blk.xinv);
    for a in 0..na {
        let xa = &mut blk.gy[a * n..a * n + n];
        let ya = &mut blk.gy2[a * n..a * n + n];
        xa.fill(0.0);
        ya.fill(0.0);
        for e in blk.ag_ent[a]..blk.ag_ent[a + 1] {
            let (o, v) = (blk.ag_idx[e], blk.ag_val[e]);
            for ((p, q), (s, t)) in
                xa.iter_mut().zip(ya.iter_mut()).zip(xi[o * n..o * n + n].iter().zip(&yy[o * n..o * n + n]))
            {
                *p += v * s;
                *q += v * t;
            }
        }
        for o in 0..n {
            blk.yt[o * na + a] = xa[o];
            blk.yt2[o * na + a] = ya[o];
        }
    }
    for a in 0..na {
        let hend = blk.ag_start[blk.ag_mat[a] + 1];
        let zx = &mut blk.zg[a * na..a * na + hend];
        let zy = &mut blk.zg2[a * na..a * na + hend];
        zx.fill(0.0);
        zy.fill(0.0);
        for e in blk.ag_ent[a]..blk.ag_ent[a + 1] {
            let (o, v) = (blk.ag_idx[e], blk.ag_val[e]);
            for ((p, q), (s, t)) in zx
                .iter_mut()
                .zip(zy.iter_mut())
                .zip(blk.yt[o * na..o * na + hend].iter().zip(&blk.yt2[o * na..o * na + hend]))
            {
                *p += v * s;
                *q += v * t;
            }
        }
    }
    for a in 0..na {
        let i = blk.ag_mat[a];
        let c = blk.ag_row[a];
        let (xa, ya) = (&blk.gy[a * n..a * n + n], &blk.gy2[a * n..a * n + n]);
        let (yc, xic) = (&yy[c * n..c * n + n], &xi[c * n..c * n + n]);
        let (xtc, ytc) = (&blk.yt[c * na..c * na + na], &blk.yt2[c * na..c * na + na]);
        let (zx, zy) = (&blk.zg[a * na..a * na + na], &blk.zg2[a * na..a * na + na]);
        let mut h0 = 0;
        while h0 < blk.ag_start[i + 1] {
            let j = blk.ag_mat[h0];
            let h1 = blk.ag_start[j + 1];
            let mut s = 0.0;
            for h in h0..h1 {
                let ch = blk.ag_row[h];
                s += xtc[h] * ya[ch] + xa[ch] * ytc[h] + zx[h] * yc[ch] + zy[h] * xic[ch];
            }
            mhat[i + j * mp] += s;
            h0 = h1;
        }
    }
}

/// Adds `⟨H, sym(Y H X⁻¹)⟩ = ‖L₁⁻¹ H L₂‖² = ⟨H Y, X⁻¹ H⟩` to `den`, `H = F₀ − A(q)` in `tmp2`:
/// the block's part of the `τ` row's coefficient.
#[inline(always)]
pub(super) fn add_tau_term(blk: &mut BlockWs, den: &mut f64) {
    let n = blk.n;
    dense::mul(&mut blk.tmp, n, view(&blk.tmp2, n), view(&blk.y, n));
    dense::mul(&mut blk.g, n, view(&blk.xinv, n), view(&blk.tmp2, n));
    *den += dense::dot(&blk.tmp, &blk.g);
}

/// The predictor's right-hand side: HKM keeps `w_s` unscaled, `w_s = −Y`.
#[inline(always)]
pub(super) fn affine_rhs(blk: &mut BlockWs) {
    for (w, y) in blk.ws.iter_mut().zip(&blk.y) {
        *w = -y;
    }
}

/// The corrector's right-hand side: `(Y + ΔY)(X + ΔX) = σμI` linearised with the predictor's
/// second-order term, times `X⁻¹`, gives `ΔY = w_s − sym(Y ΔX X⁻¹)` with
/// `w_s = σμX⁻¹ − Y − sym(ΔYₐ ΔXₐ X⁻¹)`; `smu = σμ`.
#[inline(always)]
pub(super) fn corrector_rhs(blk: &mut BlockWs, smu: f64) {
    let n = blk.n;
    dense::mul(&mut blk.k, n, view(&blk.dxs_a, n), view(&blk.xinv, n));
    dense::mul(&mut blk.tmp, n, view(&blk.dys_a, n), view(&blk.k, n));
    dense::symmetrize(&mut blk.tmp, n);
    for ((w, t), (xi, y)) in blk.ws.iter_mut().zip(&blk.tmp).zip(blk.xinv.iter().zip(&blk.y)) {
        *w = smu * xi - y - t;
    }
}

/// From `ΔX` (`e`), unscaled: `Δx̃ = ΔX`, `Δỹ = ΔY = w_s − sym(Y ΔX X⁻¹)` (copied to `dy` if
/// `with_dy`).
#[inline(always)]
pub(super) fn recover_direction(blk: &mut BlockWs, ws: Ws, with_dy: bool) {
    let n = blk.n;
    blk.dxs.copy_from_slice(&blk.e);
    dense::mul(&mut blk.k, n, view(&blk.e, n), view(&blk.xinv, n));
    dense::mul(&mut blk.tmp, n, view(&blk.y, n), view(&blk.k, n));
    dense::symmetrize(&mut blk.tmp, n);
    if ws == Ws::Zero {
        for (dy, t) in blk.dys.iter_mut().zip(&blk.tmp) {
            *dy = -t;
        }
    } else {
        for (dy, (w, t)) in blk.dys.iter_mut().zip(blk.ws.iter().zip(&blk.tmp)) {
            *dy = w - t;
        }
    }
    if with_dy {
        blk.dy.copy_from_slice(&blk.dys);
    }
}

impl Workspace {
    /// HKM scaling of every block (`docs/sdp.md` §3.6): Cholesky factors `X = L₁L₁ᵀ`,
    /// `Y = L₂L₂ᵀ`, their inverses (`l1`, `l2`), `X⁻¹` and `sym(Y r_z X⁻¹)` (`drd`); `false` if
    /// an iterate is not numerically positive definite.
    #[inline(always)]
    pub(super) fn scaling_hkm(&mut self, stack: &mut MemStack) -> bool {
        for blk in &mut self.blocks {
            let n = blk.n;
            if !blk.psd {
                if !scale_diag(blk) {
                    return false;
                }
                continue;
            }
            blk.k.copy_from_slice(&blk.x);
            if !dense::cholesky(&mut blk.k, n, stack) {
                return false;
            }
            dense::invert_lower(&blk.k, &mut blk.l1, n);
            blk.k.copy_from_slice(&blk.y);
            if !dense::cholesky(&mut blk.k, n, stack) {
                return false;
            }
            dense::invert_lower(&blk.k, &mut blk.l2, n);
            dense::mul(&mut blk.xinv, n, view(&blk.l1, n).transpose(), view(&blk.l1, n));
            dense::symmetrize(&mut blk.xinv, n);
            dense::mul(&mut blk.k, n, view(&blk.rz, n), view(&blk.xinv, n));
            dense::mul(&mut blk.drd, n, view(&blk.y, n), view(&blk.k, n));
            dense::symmetrize(&mut blk.drd, n);
            if !blk.xinv.iter().chain(&blk.l2).all(|v| v.is_finite()) {
                return false;
            }
        }
        true
    }

    /// HKM Schur matrix `M̂ᵢⱼ = tr(Fᵢ Y Fⱼ X⁻¹)` for `0 ≤ j ≤ i ≤ m` (symmetric in `i, j`), from
    /// the groups of the entries: every `Fᵢ` is a sum over its groups `e_c wᵀ + w e_cᵀ`, and with
    /// `ξ_g = X⁻¹ w_g`, `η_g = Y w_g`, a pair of groups `h ∈ i`, `g ∈ j` adds
    /// `ξ_g[c_h] η_h[c_g] + ξ_h[c_g] η_g[c_h] + (w_hᵀξ_g) Y[c_h, c_g] + (w_hᵀη_g) X⁻¹[c_h, c_g]`.
    #[inline(always)]
    pub(super) fn assemble_schur_hkm(&mut self) {
        let mp = self.m + 1;
        self.mhat.fill(0.0);
        for blk in &mut self.blocks {
            let n = blk.n;
            if !blk.psd {
                assemble_diag(blk, &mut self.mhat, &mut self.fbuf, mp);
                continue;
            }
            if blk.grouped {
                assemble_grouped_hkm(blk, &mut self.mhat, mp);
                continue;
            }
            let (y, xi) = (&blk.y, &blk.xinv);
            for g in 0..blk.grp_row.len() {
                let xg = &mut blk.gy[g * n..g * n + n];
                let yg = &mut blk.gy2[g * n..g * n + n];
                xg.fill(0.0);
                yg.fill(0.0);
                for e in blk.grp_ent_start[g]..blk.grp_ent_start[g + 1] {
                    let (o, v) = (blk.gw_idx[e], blk.gw_val[e]);
                    for ((a, b), (xx, yy)) in
                        xg.iter_mut().zip(yg.iter_mut()).zip(xi[o * n..o * n + n].iter().zip(&y[o * n..o * n + n]))
                    {
                        *a += v * xx;
                        *b += v * yy;
                    }
                }
            }
            let (gx, gy) = (&blk.gy, &blk.gy2);
            for j in 0..mp {
                if matches!(blk.kind[j], SchurKind::Dense | SchurKind::RankUpdate) {
                    // Many groups (a dense Fⱼ): Y Fⱼ X⁻¹ by two products, then the traces.
                    let f = &mut self.fbuf[..n * n];
                    f.fill(0.0);
                    for k in blk.range(j) {
                        let Ent { row, col } = blk.ents[k];
                        f[row + col * n] = blk.val[k];
                        f[col + row * n] = blk.val[k];
                    }
                    dense::mul(&mut blk.tmp, n, view(f, n), view(xi, n));
                    dense::mul(&mut blk.tmp2, n, view(y, n), view(&blk.tmp, n));
                    let g = &blk.tmp2;
                    for i in j..mp {
                        let mut s = 0.0;
                        for k in blk.range(i) {
                            let Ent { row, col } = blk.ents[k];
                            s += blk.val[k]
                                * if row == col { g[row + row * n] } else { g[row + col * n] + g[col + row * n] };
                        }
                        self.mhat[i + j * mp] += s;
                    }
                    continue;
                }
                for g in blk.grp_start[j]..blk.grp_start[j + 1] {
                    let cg = blk.grp_row[g];
                    let (xg, yg) = (&gx[g * n..g * n + n], &gy[g * n..g * n + n]);
                    let (ycg, xcg) = (&y[cg * n..cg * n + n], &xi[cg * n..cg * n + n]);
                    for i in j..mp {
                        let mut s = 0.0;
                        for h in blk.grp_start[i]..blk.grp_start[i + 1] {
                            let ch = blk.grp_row[h];
                            let mut t = 0.0;
                            let mut u = 0.0;
                            for e in blk.grp_ent_start[h]..blk.grp_ent_start[h + 1] {
                                let (o, v) = (blk.gw_idx[e], blk.gw_val[e]);
                                t += v * xg[o];
                                u += v * yg[o];
                            }
                            s += xg[ch] * gy[h * n + cg] + gx[h * n + cg] * yg[ch] + t * ycg[ch] + u * xcg[ch];
                        }
                        self.mhat[i + j * mp] += s;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::problem::{Block, SdpProblem};

    /// The HKM Schur matrix (group by group, and with the whole-block grouping) against the
    /// definition `tr(Fᵢ Y Fⱼ X⁻¹)` summed over dense matrices.
    #[test]
    fn hkm_schur_matches_definition() {
        let n = 9;
        let m = 5;
        let mut rnd = crate::ipm::engine::test_data::lcg(11);
        let entries = crate::ipm::engine::test_data::sparse_entries(n, m, 3, &mut rnd);
        let p = SdpProblem::new(vec![Block::Psd(n)], vec![1.0; m], entries.clone()).unwrap();
        let mut ws = Workspace::new(&p, u128::MAX).unwrap();
        let unit = crate::scaling::Equilibration::IDENTITY;
        ws.load_values(&p, &unit);
        // Symmetric Y and X⁻¹ (definiteness does not matter for the identity).
        let mut sym = |shift: f64| {
            let mut a = vec![0.0; n * n];
            for j in 0..n {
                for i in 0..=j {
                    let v = rnd() + if i == j { shift } else { 0.0 };
                    a[i + j * n] = v;
                    a[j + i * n] = v;
                }
            }
            a
        };
        let (y, xi) = (sym(3.0), sym(2.0));
        let dense_f = |mat: usize| {
            let mut f = vec![0.0; n * n];
            for e in entries.iter().filter(|e| e.mat == mat) {
                f[e.row + e.col * n] = e.value;
                f[e.col + e.row * n] = e.value;
            }
            f
        };
        let mul = |a: &[f64], b: &[f64]| {
            let mut c = vec![0.0; n * n];
            for j in 0..n {
                for k in 0..n {
                    for i in 0..n {
                        c[i + j * n] += a[i + k * n] * b[k + j * n];
                    }
                }
            }
            c
        };
        let mp = m + 1;
        let mut reference = vec![0.0; mp * mp];
        for j in 0..mp {
            let g = mul(&mul(&y, &dense_f(j)), &xi);
            for i in j..mp {
                let fi = dense_f(i);
                reference[i + j * mp] = (0..n * n).map(|k| fi[k] * g[(k % n) * n + k / n]).sum();
            }
        }
        for (grouped, dense_columns) in [(false, false), (false, true), (true, false)] {
            let blk = &mut ws.blocks[0];
            blk.y.copy_from_slice(&y);
            blk.xinv.copy_from_slice(&xi);
            for j in 0..=m {
                if blk.kind[j] != SchurKind::Empty {
                    blk.kind[j] = if dense_columns { SchurKind::Dense } else { SchurKind::Pairwise };
                }
            }
            if grouped {
                let ng = blk.grp_row.len();
                blk.grouped = true;
                blk.gmat =
                    (0..=m).flat_map(|j| std::iter::repeat_n(j, blk.grp_start[j + 1] - blk.grp_start[j])).collect();
                blk.yt = vec![0.0; ng * n];
                blk.yt2 = vec![0.0; ng * n];
                blk.zg = vec![0.0; ng * ng];
                blk.zg2 = vec![0.0; ng * ng];
                blk.ag_row = Vec::with_capacity(ng);
                blk.ag_mat = Vec::with_capacity(ng);
                blk.ag_ent = Vec::with_capacity(ng + 1);
                blk.ag_idx = Vec::with_capacity(blk.grp_ents.len());
                blk.ag_val = Vec::with_capacity(blk.grp_ents.len());
                ws.load_values(&p, &unit);
            } else {
                blk.grouped = false;
            }
            ws.assemble_schur_hkm();
            for j in 0..mp {
                for i in j..mp {
                    let (a, b) = (ws.mhat[i + j * mp], reference[i + j * mp]);
                    assert!(
                        (a - b).abs() < 1e-12 * (1.0 + b.abs()),
                        "grouped {grouped} dense {dense_columns} ({i}, {j}): {a} vs {b}"
                    );
                }
            }
        }
    }
}
