//! The Nesterov–Todd direction on the dense blocks: the scaling, the Schur matrix
//! `tr(Fᵢ D Fⱼ D)`, and the block formulas of the Newton step in the scaled space.

use faer::dyn_stack::MemStack;

use super::Ws;
use super::nonneg::{assemble_diag, scale_diag};
use crate::ipm::dense::{self, view};
use crate::ipm::eig::sym_eig;
use crate::ipm::workspace::{BlockWs, Ent, SchurKind, Workspace};

/// Schur contributions of one dense block from all pairs of groups at once: every `Fᵢ` is a sum
/// over its groups `e_c wᵀ + w e_cᵀ`, and with `y_h = D w_h`, `Z = Wᵀ D W`,
/// `tr(Fᵢ D Fⱼ D) = 2 Σ_{g ∈ i} Σ_{h ∈ j} (y_g[c_h] y_h[c_g] + Z_gh D_{c_g c_h})`. Only the groups
/// with a nonzero entry take part (`ag_*`).
#[inline(always)]
fn assemble_grouped(blk: &mut BlockWs, mhat: &mut [f64], mp: usize) {
    let n = blk.n;
    let na = blk.ag_row.len();
    let d = &blk.d;
    // y_a = D w_a (columns of gy), then Yᵀ (rows of yt, length na).
    for a in 0..na {
        let y = &mut blk.gy[a * n..a * n + n];
        y.fill(0.0);
        for e in blk.ag_ent[a]..blk.ag_ent[a + 1] {
            let (o, v) = (blk.ag_idx[e], blk.ag_val[e]);
            for (yy, dd) in y.iter_mut().zip(&d[o * n..o * n + n]) {
                *yy += v * dd;
            }
        }
        for o in 0..n {
            blk.yt[o * na + a] = y[o];
        }
    }
    // Row a of Z: Σ_{e ∈ a} v_e Yᵀ[o_e, :] (only the groups of matrices up to a's are used).
    for a in 0..na {
        let hend = blk.ag_start[blk.ag_mat[a] + 1];
        let z = &mut blk.zg[a * na..a * na + hend];
        z.fill(0.0);
        for e in blk.ag_ent[a]..blk.ag_ent[a + 1] {
            let (o, v) = (blk.ag_idx[e], blk.ag_val[e]);
            for (zz, yy) in z.iter_mut().zip(&blk.yt[o * na..o * na + hend]) {
                *zz += v * yy;
            }
        }
    }
    for a in 0..na {
        let i = blk.ag_mat[a];
        let c = blk.ag_row[a];
        let ya = &blk.gy[a * n..a * n + n];
        let dc = &d[c * n..c * n + n];
        let ytc = &blk.yt[c * na..c * na + na];
        let z = &blk.zg[a * na..a * na + na];
        let mut h0 = 0;
        while h0 < blk.ag_start[i + 1] {
            let j = blk.ag_mat[h0];
            let h1 = blk.ag_start[j + 1];
            let mut s = 0.0;
            for ((&ch, &y), &zz) in blk.ag_row[h0..h1].iter().zip(&ytc[h0..h1]).zip(&z[h0..h1]) {
                s += ya[ch] * y + zz * dc[ch];
            }
            mhat[i + j * mp] += 2.0 * s;
            h0 = h1;
        }
    }
}

/// Adds `‖TᵀHT‖²` to `den`, `H = F₀ − A(q)` in `tmp2`: the block's part of the `τ` row's
/// coefficient `⟨H, DHD⟩`.
#[inline(always)]
pub(super) fn add_tau_term(blk: &mut BlockWs, den: &mut f64) {
    let n = blk.n;
    dense::congruence(&mut blk.g, &mut blk.tmp, &blk.t, &blk.tmp2, n, true);
    *den += dense::norm2(&blk.g);
}

/// The predictor's scaled right-hand side `w_s = −Λ`.
#[inline(always)]
pub(super) fn affine_rhs(blk: &mut BlockWs) {
    let n = blk.n;
    blk.ws.fill(0.0);
    for i in 0..n {
        blk.ws[i + i * n] = -blk.lam[i];
    }
}

/// The corrector's scaled right-hand side: `λ ∘ w_s = −λ∘λ + σμI − Δx̃ₐ∘Δỹₐ`, solved entrywise
/// (`Λ` is diagonal); `smu = σμ`.
#[inline(always)]
pub(super) fn corrector_rhs(blk: &mut BlockWs, smu: f64) {
    let n = blk.n;
    dense::mul(&mut blk.tmp, n, view(&blk.dxs_a, n), view(&blk.dys_a, n));
    for j in 0..n {
        for i in 0..n {
            let mut r = -0.5 * (blk.tmp[i + j * n] + blk.tmp[j + i * n]);
            if i == j {
                r += smu - blk.lam[i] * blk.lam[i];
            }
            blk.ws[i + j * n] = 2.0 * r / (blk.lam[i] + blk.lam[j]);
        }
    }
}

/// From `ΔX` (`e`): `Δx̃ = TᵀΔXT`, `Δỹ = w_s − Δx̃` and, if `with_dy`, `ΔY = TΔỹTᵀ`.
#[inline(always)]
pub(super) fn recover_direction(blk: &mut BlockWs, ws: Ws, with_dy: bool) {
    let n = blk.n;
    dense::congruence(&mut blk.dxs, &mut blk.tmp, &blk.t, &blk.e, n, true);
    if ws == Ws::Zero {
        for (dy, dx) in blk.dys.iter_mut().zip(&blk.dxs) {
            *dy = -dx;
        }
    } else {
        for (dy, (w, dx)) in blk.dys.iter_mut().zip(blk.ws.iter().zip(&blk.dxs)) {
            *dy = w - dx;
        }
    }
    if with_dy {
        dense::congruence(&mut blk.dy, &mut blk.tmp, &blk.t, &blk.dys, n, false);
    }
}

impl Workspace {
    /// NT scaling of every block; `false` if an iterate is not numerically positive definite.
    #[inline(always)]
    pub(super) fn scaling(&mut self, stack: &mut MemStack) -> bool {
        for blk in &mut self.blocks {
            let n = blk.n;
            if !blk.psd {
                if !scale_diag(blk) {
                    return false;
                }
                continue;
            }
            blk.l1.copy_from_slice(&blk.x);
            if !dense::cholesky(&mut blk.l1, n, stack) {
                return false;
            }
            blk.l2.copy_from_slice(&blk.y);
            if !dense::cholesky(&mut blk.l2, n, stack) {
                return false;
            }
            // K = L₂ᵀ L₁, K Kᵀ = L₂ᵀ X L₂ = U Λ² Uᵀ.
            dense::mul(&mut blk.k, n, view(&blk.l2, n).transpose(), view(&blk.l1, n));
            dense::mul(&mut blk.tmp, n, view(&blk.k, n), view(&blk.k, n).transpose());
            if !sym_eig(&mut blk.tmp, n, &mut blk.ev, &mut blk.ee, true) {
                return false;
            }
            for i in 0..n {
                if blk.ev[i].is_nan() || blk.ev[i] <= 0.0 {
                    return false;
                }
                blk.lam[i] = blk.ev[i].sqrt();
                blk.lis[i] = 1.0 / blk.lam[i].sqrt();
            }
            // T = L₂ U Λ^{-1/2}, D = T Tᵀ.
            dense::mul(&mut blk.t, n, view(&blk.l2, n), view(&blk.tmp, n));
            for j in 0..n {
                let s = 1.0 / blk.lam[j].sqrt();
                blk.t[j * n..j * n + n].iter_mut().for_each(|v| *v *= s);
            }
            dense::mul(&mut blk.d, n, view(&blk.t, n), view(&blk.t, n).transpose());
            dense::symmetrize(&mut blk.d, n);
            dense::mul(&mut blk.tmp, n, view(&blk.rz, n), view(&blk.d, n));
            dense::mul(&mut blk.drd, n, view(&blk.d, n), view(&blk.tmp, n));
            dense::symmetrize(&mut blk.drd, n);
        }
        true
    }

    /// `M̂ᵢⱼ = tr(Fᵢ D Fⱼ D)` for `0 ≤ j ≤ i ≤ m` (lower triangle, column-major `(m+1)²`).
    #[inline(always)]
    pub(super) fn assemble_schur(&mut self) {
        let mp = self.m + 1;
        self.mhat.fill(0.0);
        for blk in &mut self.blocks {
            let n = blk.n;
            if !blk.psd {
                assemble_diag(blk, &mut self.mhat, &mut self.fbuf, mp);
                continue;
            }
            let d = &blk.d;
            if blk.grouped {
                assemble_grouped(blk, &mut self.mhat, mp);
                continue;
            }
            if blk.lr_first < mp {
                // y_g = D w_g for every group of the matrices the low-rank columns meet.
                for g in blk.grp_start[blk.lr_first]..blk.grp_start[mp] {
                    let y = &mut blk.gy[g * n..g * n + n];
                    y.fill(0.0);
                    for e in blk.grp_ent_start[g]..blk.grp_ent_start[g + 1] {
                        let (o, v) = (blk.gw_idx[e], blk.gw_val[e]);
                        for (yy, dd) in y.iter_mut().zip(&d[o * n..o * n + n]) {
                            *yy += v * dd;
                        }
                    }
                }
            }
            for j in 0..mp {
                match blk.kind[j] {
                    SchurKind::Empty => {}
                    SchurKind::LowRank => {
                        let gj = blk.grp_start[j]..blk.grp_start[j + 1];
                        for i in j..mp {
                            let mut s = 0.0;
                            for g in blk.grp_start[i]..blk.grp_start[i + 1] {
                                let c = blk.grp_row[g];
                                let yg = &blk.gy[g * n..g * n + n];
                                let wi = &blk.gw_idx[blk.grp_ent_start[g]..blk.grp_ent_start[g + 1]];
                                let wv = &blk.gw_val[blk.grp_ent_start[g]..blk.grp_ent_start[g + 1]];
                                let dc = &d[c * n..c * n + n];
                                for h in gj.clone() {
                                    let dh = blk.grp_row[h];
                                    let yh = &blk.gy[h * n..h * n + n];
                                    let mut dot = 0.0;
                                    for (&o, &v) in wi.iter().zip(wv) {
                                        dot += v * yh[o];
                                    }
                                    s += yg[dh] * yh[c] + dot * dc[dh];
                                }
                            }
                            self.mhat[i + j * mp] += 2.0 * s;
                        }
                    }
                    SchurKind::Pairwise => {
                        let rj = blk.range(j);
                        for i in j..mp {
                            let mut s = 0.0;
                            for k in blk.range(i) {
                                let Ent { row: a, col: b } = blk.ents[k];
                                let da = &d[a * n..a * n + n];
                                let db = &d[b * n..b * n + n];
                                let mut t = 0.0;
                                for l in rj.clone() {
                                    let Ent { row: c, col: dd } = blk.ents[l];
                                    t += blk.sval[l] * (db[c] * da[dd] + db[dd] * da[c]);
                                }
                                s += blk.sval[k] * t;
                            }
                            self.mhat[i + j * mp] += s;
                        }
                    }
                    SchurKind::Dense | SchurKind::RankUpdate => {
                        if blk.kind[j] == SchurKind::Dense {
                            let f = &mut self.fbuf[..n * n];
                            f.fill(0.0);
                            for k in blk.range(j) {
                                let Ent { row, col } = blk.ents[k];
                                f[row + col * n] = blk.val[k];
                                f[col + row * n] = blk.val[k];
                            }
                            dense::mul(&mut blk.tmp, n, view(f, n), view(d, n));
                            dense::mul(&mut blk.tmp2, n, view(d, n), view(&blk.tmp, n));
                        } else {
                            // Σ over groups of d_c wᵀ + w d_cᵀ, upper triangle only (entries are
                            // stored with row ≤ col), then mirrored.
                            let g = &mut blk.tmp2[..n * n];
                            g.fill(0.0);
                            for grp in blk.grp_start[j]..blk.grp_start[j + 1] {
                                let c = blk.grp_row[grp];
                                let w = &mut blk.wv[..n];
                                w.fill(0.0);
                                for &k in &blk.grp_ents[blk.grp_ent_start[grp]..blk.grp_ent_start[grp + 1]] {
                                    let Ent { row: a, col: b } = blk.ents[k];
                                    let (other, v) = if a == b {
                                        (a, 0.5 * blk.val[k])
                                    } else {
                                        (if a == c { b } else { a }, blk.val[k])
                                    };
                                    for (x, y) in w.iter_mut().zip(&d[other * n..other * n + n]) {
                                        *x += v * y;
                                    }
                                }
                                let dc = &d[c * n..c * n + n];
                                for (q, gq) in g.chunks_exact_mut(n).enumerate() {
                                    let (u, z) = (w[q], dc[q]);
                                    for ((x, y), ww) in gq[..=q].iter_mut().zip(dc).zip(w.iter()) {
                                        *x += y * u + ww * z;
                                    }
                                }
                            }
                            for q in 0..n {
                                for r in q + 1..n {
                                    g[r + q * n] = g[q + r * n];
                                }
                            }
                        }
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

    /// All three Schur strategies give the same matrix.
    #[test]
    fn schur_strategies_agree() {
        let n = 6;
        let mut rnd = crate::ipm::engine::test_data::lcg(7);
        let m = 5;
        let entries = crate::ipm::engine::test_data::sparse_entries(n, m, 2, &mut rnd);
        let p = SdpProblem::new(vec![Block::Psd(n)], vec![1.0; m], entries).unwrap();
        let mut ws = Workspace::new(&p, u128::MAX).unwrap();
        let unit = crate::scaling::Equilibration::IDENTITY;
        ws.load_values(&p, &unit);
        // A symmetric positive definite D.
        let blk = &mut ws.blocks[0];
        for j in 0..n {
            for i in 0..=j {
                let v = rnd() + if i == j { 3.0 } else { 0.0 };
                blk.d[i + j * n] = v;
                blk.d[j + i * n] = v;
            }
        }
        let mut results = vec![];
        for kind in [SchurKind::Pairwise, SchurKind::RankUpdate, SchurKind::Dense, SchurKind::LowRank] {
            let blk = &mut ws.blocks[0];
            for j in 0..=m {
                if blk.kind[j] != SchurKind::Empty {
                    blk.kind[j] = kind;
                }
            }
            blk.lr_first = 0;
            ws.assemble_schur();
            results.push(ws.mhat.clone());
        }
        let blk = &mut ws.blocks[0];
        let ng = blk.grp_row.len();
        blk.grouped = true;
        blk.gmat = (0..=m).flat_map(|j| std::iter::repeat_n(j, blk.grp_start[j + 1] - blk.grp_start[j])).collect();
        blk.yt = vec![0.0; ng * n];
        blk.zg = vec![0.0; ng * ng];
        blk.ag_row = Vec::with_capacity(ng);
        blk.ag_mat = Vec::with_capacity(ng);
        blk.ag_ent = Vec::with_capacity(ng + 1);
        blk.ag_idx = Vec::with_capacity(blk.grp_ents.len());
        blk.ag_val = Vec::with_capacity(blk.grp_ents.len());
        ws.load_values(&p, &unit);
        ws.assemble_schur();
        results.push(ws.mhat.clone());
        for r in &results[1..] {
            for (a, b) in r.iter().zip(&results[0]) {
                assert!((a - b).abs() < 1e-10 * (1.0 + b.abs()), "{a} vs {b}");
            }
        }
    }
}
