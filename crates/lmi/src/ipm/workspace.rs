//! Everything a solve needs, allocated once in [`Workspace::new`] (called by `setup`).

use faer::dyn_stack::StackReq;

use crate::problem::{Block, SdpProblem};
use crate::scaling::Equilibration;

use super::dense;

/// Bytes [`Workspace::new`] allocates for `problem`, except what depends on the grouping of the
/// entries (checked by `Workspace::new` itself before it allocates it), the QR coefficients and
/// faer's scratch (both bounded by [`workspace_tail_bytes`] once this is known to be moderate).
/// Computed in `u128` from the sizes alone, in `O(blocks)`: it allocates nothing.
///
/// Per block: five index vectors of length `m + 2`, one row `m + 1` of the entry counts and
/// about 28 dense matrices of its order (`n²`, or `n` for a diagonal block); per entry about
/// 120 bytes of analysis (positions, values, groups); globally the `(m+1)²` Schur matrix, its
/// `m²` factor, the `ls_rows × m` matrix of precision mode, the dense scatter buffer and the
/// copy of the problem.
pub(crate) fn base_bytes(problem: &SdpProblem) -> u128 {
    let m = problem.num_vars() as u128;
    let nb = problem.blocks().len() as u128;
    let ne = problem.entries().len() as u128;
    let mut dense_blocks: u128 = 0;
    let mut nmax: u128 = 0;
    for b in problem.blocks() {
        let n = b.size() as u128;
        nmax = nmax.max(n);
        let len = if matches!(b, Block::Psd(_)) { n * n } else { n };
        dense_blocks += 8 * (28 * len + 5 * n);
    }
    let rows = (ls_rows(problem) as u128).max(m);
    let per_block_index = nb * (8 * (5 * (m + 2)) + (m + 1) + 8);
    let per_entry = 120 * ne;
    let analysis = 48 * (m + 1);
    let global = 8 * ((m + 1) * (m + 1) + m * m + 13 * (m + 1) + nmax * nmax + rows * m);
    let structure = 40 * ne + 8 * m + 16 * nb;
    dense_blocks + per_block_index + per_entry + analysis + global + structure
}

/// Bytes of the QR coefficients and of faer's scratch; call only once [`base_bytes`] is within
/// the limit (the sizes are then moderate).
pub(crate) fn workspace_tail_bytes(problem: &SdpProblem) -> u128 {
    let m = problem.num_vars().max(1);
    let rows = ls_rows(problem).max(m);
    let qcoef = 8 * (dense::qr_block_size(rows, m) as u128) * (m as u128);
    // `usize::MAX` if faer's computation overflowed.
    qcoef + scratch(problem).unaligned_bytes_required() as u128
}

/// faer scratch for a problem of this structure (Cholesky of the Schur matrix and of the blocks).
pub(crate) fn scratch(problem: &SdpProblem) -> StackReq {
    let nmax = problem.blocks().iter().map(|b| b.size()).max().unwrap_or(0);
    let m = problem.num_vars().max(1);
    let rows = ls_rows(problem).max(m);
    StackReq::any_of(&[
        dense::cholesky_scratch(m),
        dense::cholesky_scratch(nmax.max(1)),
        dense::qr_scratch(rows, m, dense::qr_block_size(rows, m)),
    ])
}

/// Rows of the scaled constraint matrix `[svec(TᵀFᵢT)]ᵢ`: `n(n+1)/2` per dense block, `n` per
/// nonnegative block.
pub(crate) fn ls_rows(problem: &SdpProblem) -> usize {
    problem.blocks().iter().map(|b| b.num_entries()).sum()
}

/// One nonzero of some `Fᵢ` inside one block (upper triangle, `row ≤ col`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Ent {
    pub row: usize,
    pub col: usize,
}

/// How the contribution of one `Fⱼ` to the Schur matrix is computed in one dense block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum SchurKind {
    /// `Fⱼ` has no entry in this block.
    Empty,
    /// Pairwise sums over the entries of `Fᵢ` and `Fⱼ`: `Σ vₖ wₗ (D_bc D_ad + D_bd D_ac)`.
    Pairwise,
    /// `G = D Fⱼ D` formed densely (matrix products), then `⟨Fᵢ, G⟩` for every `i ≥ j`.
    Dense,
    /// `G = D Fⱼ D` formed by rank-two updates `v (d_c d_dᵀ + d_d d_cᵀ)` with the columns of `D`
    /// (for sparse `Fⱼ`: vectorises well), then `⟨Fᵢ, G⟩` for every `i ≥ j`.
    RankUpdate,
    /// Every `Fᵢ` is written as a sum over its groups `e_c wᵀ + w e_cᵀ` (see `grp_*`); with
    /// `y = D w` per group, `tr(Fᵢ D Fⱼ D) = 2 Σ_g Σ_h (y_g[d_h] y_h[c_g] + (w_g·y_h) D_{c_g d_h})`
    /// (sparse `Fᵢ` with few groups, such as a variable filling part of one row).
    LowRank,
}

/// Buffers of one block. For a nonnegative block every "matrix" is its diagonal (length `n`).
#[derive(Debug)]
pub(crate) struct BlockWs {
    pub psd: bool,
    pub n: usize,
    /// Entries of this block, sorted by matrix index; `start[i]..start[i + 1]` are those of `Fᵢ`.
    pub ents: Vec<Ent>,
    pub start: Vec<usize>,
    /// Position of each entry in `SdpProblem::entries()`.
    pub src: Vec<usize>,
    /// Entry values, and values scaled by `√2` (off-diagonal) or `1/√2` (diagonal).
    pub val: Vec<f64>,
    pub sval: Vec<f64>,
    /// The entries with a nonzero value (found by `load_values`, per solve): positions `p1`,
    /// `p2` in the dense block (`row + col·n` and `col + row·n`; the index on the diagonal of a
    /// nonnegative block; `p1 = p2` on the diagonal) and the value. Those of `Fᵢ` are
    /// `nz_start[i]..nz_start[i + 1]`. Capacity for all entries is reserved at setup.
    pub nz_p1: Vec<usize>,
    pub nz_p2: Vec<usize>,
    pub nz_v: Vec<f64>,
    pub nz_start: Vec<usize>,
    /// Schur strategy per matrix index `j = 0..=m`.
    pub kind: Vec<SchurKind>,
    /// Rank-update groups: the entries of `Fⱼ` sharing one index `c` (so that their sum is
    /// `d_c wᵀ + w d_cᵀ` with `w = Σ v d_other`). Groups of `Fⱼ` are
    /// `grp_start[j]..grp_start[j + 1]`; group `g` has index `grp_row[g]` and entries
    /// `grp_ents[grp_ent_start[g]..grp_ent_start[g + 1]]` (positions in `ents`).
    pub grp_start: Vec<usize>,
    pub grp_row: Vec<usize>,
    pub grp_ent_start: Vec<usize>,
    pub grp_ents: Vec<usize>,
    /// Scratch vector `w` of a group.
    pub wv: Vec<f64>,
    /// Per group entry (parallel to `grp_ents`): the index other than the group's, and the
    /// coefficient in `w` (the value, halved on the diagonal).
    pub gw_idx: Vec<usize>,
    pub gw_val: Vec<f64>,
    /// `y_g = D w_g` per group (`n` each), for the low-rank strategy (HKM: `X⁻¹ w_g`).
    pub gy: Vec<f64>,
    /// HKM only: `Y w_g` per group (`n` each).
    pub gy2: Vec<f64>,
    /// First matrix index whose Schur column uses the low-rank strategy (`m + 1` if none).
    pub lr_first: usize,
    /// Whole-block low-rank assembly: all pairs of groups at once (see `assemble_schur`),
    /// instead of the per-column strategies in `kind`.
    pub grouped: bool,
    /// Matrix index of each group.
    pub gmat: Vec<usize>,
    /// Groups with a nonzero entry (found by `load_values`, per solve; capacity reserved at
    /// setup): `ag_row` their shared index, `ag_mat` their matrix, `ag_start[j]..ag_start[j + 1]`
    /// those of `Fⱼ`, and their nonzero entries `ag_idx`/`ag_val` (other index, coefficient in
    /// `w`) in `ag_ent[a]..ag_ent[a + 1]`.
    pub ag_row: Vec<usize>,
    pub ag_mat: Vec<usize>,
    pub ag_start: Vec<usize>,
    pub ag_ent: Vec<usize>,
    pub ag_idx: Vec<usize>,
    pub ag_val: Vec<f64>,
    /// `Yᵀ` (`n × G`, row `o` holds `y_h[o]` for every group `h`) and `Z = Wᵀ D W` (`G × G`).
    pub yt: Vec<f64>,
    pub zg: Vec<f64>,
    /// HKM only, like `yt` and `zg` for `η_h = Y w_h` (`yt`, `zg`, `gy` then hold those of
    /// `ξ_h = X⁻¹ w_h`).
    pub yt2: Vec<f64>,
    pub zg2: Vec<f64>,
    // Iterates and residual.
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    pub rz: Vec<f64>,
    /// Best iterate so far (restored when the method stops early).
    pub best_x: Vec<f64>,
    pub best_y: Vec<f64>,
    /// Warm start: the last solved `X/τ`, `Y/τ` of this block.
    pub warm_x: Vec<f64>,
    pub warm_y: Vec<f64>,
    // Scaling: Y = T Λ Tᵀ, X = T⁻ᵀ Λ T⁻¹, D = T Tᵀ (D X D = Y).
    pub l1: Vec<f64>,
    pub l2: Vec<f64>,
    pub k: Vec<f64>,
    pub t: Vec<f64>,
    pub d: Vec<f64>,
    pub lam: Vec<f64>,
    /// `λ^{-1/2}`.
    pub lis: Vec<f64>,
    /// `D r_z D` (HKM: `sym(Y r_z X⁻¹)`).
    pub drd: Vec<f64>,
    /// HKM direction only: `X⁻¹` (with `l1 ← L₁⁻¹`, `l2 ← L₂⁻¹`, the inverse Cholesky factors
    /// of `X` and `Y`).
    pub xinv: Vec<f64>,
    // Directions (scaled `Δx̃`, `Δỹ`; unscaled `ΔX = E`, `ΔY`), predictor copies, rhs `w_s`.
    pub e: Vec<f64>,
    pub dxs: Vec<f64>,
    pub dys: Vec<f64>,
    pub dxs_a: Vec<f64>,
    pub dys_a: Vec<f64>,
    pub ws: Vec<f64>,
    pub g: Vec<f64>,
    pub dy: Vec<f64>,
    // First solution while a refinement step is computed.
    pub e2: Vec<f64>,
    pub dxs2: Vec<f64>,
    pub dys2: Vec<f64>,
    pub dy2: Vec<f64>,
    // Scratch.
    pub tmp: Vec<f64>,
    pub tmp2: Vec<f64>,
    pub ev: Vec<f64>,
    pub ee: Vec<f64>,
}

impl BlockWs {
    fn new(block: Block, m: usize) -> Self {
        let (psd, n) = match block {
            Block::Psd(n) => (true, n),
            Block::Nonneg(n) => (false, n),
        };
        let len = if psd { n * n } else { n };
        let z = || vec![0.0; len];
        Self {
            psd,
            n,
            ents: Vec::new(),
            start: vec![0; m + 2],
            src: Vec::new(),
            val: Vec::new(),
            sval: Vec::new(),
            kind: vec![SchurKind::Empty; m + 1],
            nz_p1: Vec::new(),
            nz_p2: Vec::new(),
            nz_v: Vec::new(),
            nz_start: vec![0; m + 2],
            grp_start: vec![0; m + 2],
            grp_row: Vec::new(),
            grp_ent_start: vec![0],
            grp_ents: Vec::new(),
            wv: vec![0.0; n],
            gw_idx: Vec::new(),
            gw_val: Vec::new(),
            gy: Vec::new(),
            gy2: Vec::new(),
            lr_first: m + 1,
            grouped: false,
            gmat: Vec::new(),
            ag_row: Vec::new(),
            ag_mat: Vec::new(),
            ag_start: vec![0; m + 2],
            ag_ent: Vec::new(),
            ag_idx: Vec::new(),
            ag_val: Vec::new(),
            yt: Vec::new(),
            zg: Vec::new(),
            yt2: Vec::new(),
            zg2: Vec::new(),
            x: z(),
            y: z(),
            rz: z(),
            best_x: z(),
            best_y: z(),
            warm_x: z(),
            warm_y: z(),
            l1: z(),
            l2: z(),
            k: z(),
            t: z(),
            d: z(),
            lam: vec![0.0; n],
            lis: vec![0.0; n],
            drd: z(),
            xinv: z(),
            e: z(),
            dxs: z(),
            dys: z(),
            dxs_a: z(),
            dys_a: z(),
            ws: z(),
            g: z(),
            dy: z(),
            e2: z(),
            dxs2: z(),
            dys2: z(),
            dy2: z(),
            tmp: z(),
            tmp2: z(),
            ev: vec![0.0; n],
            ee: vec![0.0; n],
        }
    }

    /// Position of diagonal entry `i` in this block's dense (`n × n`) or diagonal storage.
    #[inline]
    pub fn diag(&self, i: usize) -> usize {
        if self.psd { i + i * self.n } else { i }
    }

    /// Sum of the diagonal of `v`, stored as this block's matrices are.
    #[inline]
    pub fn trace(&self, v: &[f64]) -> f64 {
        (0..self.n).map(|i| v[self.diag(i)]).sum()
    }

    /// Entry range of `Fᵢ` in this block.
    #[inline]
    pub fn range(&self, i: usize) -> std::ops::Range<usize> {
        self.start[i]..self.start[i + 1]
    }
}

/// All solve-time storage.
#[derive(Debug)]
pub(crate) struct Workspace {
    /// Copy of the problem given to `setup` (its structure is compared on every solve).
    pub structure: SdpProblem,
    pub m: usize,
    /// Barrier degree `ν = Σ block orders`.
    pub nu: f64,
    pub blocks: Vec<BlockWs>,
    /// Schur matrix including the `F₀` row/column: `(m+1) × (m+1)`, lower triangle, column-major.
    pub mhat: Vec<f64>,
    /// Cholesky factor of the `m × m` Schur matrix.
    pub lfac: Vec<f64>,
    pub c: Vec<f64>,
    pub x: Vec<f64>,
    pub best_x: Vec<f64>,
    /// Warm start: the last solved `x/τ` (the blocks' `warm_x`, `warm_y` hold `X/τ`, `Y/τ`),
    /// whether one is stored, and whether this solve should start from it.
    pub warm_xv: Vec<f64>,
    pub has_warm: bool,
    pub warm_wanted: bool,
    /// `(τ, κ)` of the best iterate.
    pub best_tk: (f64, f64),
    pub dx: Vec<f64>,
    pub dx2: Vec<f64>,
    /// Right-hand side `d_x` of the Newton system.
    pub rhs: Vec<f64>,
    pub p: Vec<f64>,
    pub q: Vec<f64>,
    pub rx: Vec<f64>,
    pub cb: Vec<f64>,
    /// Traces `tr(Fᵢ G)`, `i = 0..=m`.
    pub tr: Vec<f64>,
    /// Coefficients for `Σ coefᵢ Fᵢ`, `i = 0..=m`.
    pub coef: Vec<f64>,
    /// Precision mode: the Schur factor comes from a QR factorisation of the scaled constraint
    /// matrix `[svec(TᵀFᵢT)]ᵢ` (`ls`, `ls_rows × m`) instead of a Cholesky of `M`.
    pub precise: bool,
    pub ls_rows: usize,
    pub ls: Vec<f64>,
    pub qcoef: Vec<f64>,
    pub qr_bs: usize,
    /// `‖e₁‖² / ‖d_x‖²` of the last corrector before refinement (loss of accuracy indicator).
    pub loss: f64,
    /// Dense scatter buffer for one `Fⱼ` (order of the largest block, squared).
    pub fbuf: Vec<f64>,
    /// The HKM direction is selected ([`FaerIpm::set_direction`](super::FaerIpm::set_direction)).
    pub hkm: bool,
    /// The HKM direction is in use in this solve (cleared when the solve falls back to NT).
    pub hkm_on: bool,
}

/// Blocks below this order keep the classic Schur strategies (pairwise, rank update, dense).
const SMALL_BLOCK: usize = 8;

/// Estimated cost of a Schur column with the given strategy (`costs`: pairwise, rank update,
/// dense, low rank).
fn column_cost(kind: SchurKind, costs: &[f64; 4]) -> f64 {
    match kind {
        SchurKind::Empty => 0.0,
        SchurKind::Pairwise => costs[0],
        SchurKind::RankUpdate => costs[1],
        SchurKind::Dense => costs[2],
        SchurKind::LowRank => costs[3],
    }
}

/// Groups entries by a shared index, greedily taking for each entry the endpoint that occurs
/// most often; returns `(index, positions)` pairs.
fn group_entries(ents: &[Ent], n: usize) -> Vec<(usize, Vec<usize>)> {
    let mut count = vec![0usize; n];
    for e in ents {
        count[e.row] += 1;
        if e.col != e.row {
            count[e.col] += 1;
        }
    }
    let mut groups: Vec<(usize, Vec<usize>)> = Vec::new();
    for (k, e) in ents.iter().enumerate() {
        let key = if count[e.col] > count[e.row] { e.col } else { e.row };
        match groups.iter_mut().find(|(r, _)| *r == key) {
            Some((_, v)) => v.push(k),
            None => groups.push((key, vec![k])),
        }
    }
    groups
}

impl Workspace {
    /// Analyses `problem` and allocates every buffer. The buffers whose size depends on the
    /// grouping of the entries (the low-rank Schur strategy: `G·n` per block, `G²` for whole-block
    /// assembly) are counted once the groups are known and, if they exceed `budget` bytes, not
    /// allocated: `Err` then holds the bytes they would need.
    pub fn new(problem: &SdpProblem, budget: u128) -> Result<Self, u128> {
        let m = problem.num_vars();
        let mut blocks: Vec<BlockWs> = problem.blocks().iter().map(|b| BlockWs::new(*b, m)).collect();
        // Entries are sorted by (mat, block, col, row): per block they come out sorted by mat.
        let mut count = vec![vec![0usize; m + 1]; blocks.len()];
        for (k, e) in problem.entries().iter().enumerate() {
            let b = &mut blocks[e.block];
            b.ents.push(Ent { row: e.row, col: e.col });
            b.src.push(k);
            count[e.block][e.mat] += 1;
        }
        for (b, blk) in blocks.iter_mut().enumerate() {
            for i in 0..=m {
                blk.start[i + 1] = blk.start[i] + count[b][i];
            }
            blk.val = vec![0.0; blk.ents.len()];
            blk.sval = vec![0.0; blk.ents.len()];
            blk.nz_p1 = Vec::with_capacity(blk.ents.len());
            blk.nz_p2 = Vec::with_capacity(blk.ents.len());
            blk.nz_v = Vec::with_capacity(blk.ents.len());
            if blk.psd {
                let n = blk.n as f64;
                let nnz: Vec<f64> = (0..=m).map(|i| blk.range(i).len() as f64).collect();
                let ngroups: Vec<f64> = (0..=m)
                    .map(|i| group_entries(&blk.ents[blk.start[i]..blk.start[i + 1]], blk.n).len() as f64)
                    .collect();
                let mut costs = vec![[0.0; 4]; m + 1];
                let mut tail = 0.0; // Σ_{i ≥ j} nnzᵢ
                let mut gtail = 0.0; // Σ_{i ≥ j} groupsᵢ
                for j in (0..=m).rev() {
                    tail += nnz[j];
                    gtail += ngroups[j];
                    // Rough cycle counts: the pairwise sums are scalar code, the products vectorise.
                    let pairwise = 12.0 * nnz[j] * tail;
                    let groups = ngroups[j];
                    let rank = groups * n * n + 2.0 * nnz[j] * n + 4.0 * tail;
                    let dense = n * n * n + n * n + 4.0 * tail;
                    // Per pair of groups: a sparse dot product of w_g with y_h and four loads;
                    // plus y_h = D w_h for this column's groups.
                    // (Only for blocks of order 8 and more: below, every strategy is cheap, and
                    // the nearly ill-posed SDPLIB `hinf` problems, whose blocks have order 4–6,
                    // are sensitive to the rounding of the Schur matrix.)
                    let low_rank =
                        if blk.n >= SMALL_BLOCK { groups * (tail + 4.0 * gtail) + nnz[j] * n } else { f64::INFINITY };
                    costs[j] = [pairwise, rank, dense, low_rank];
                    blk.kind[j] = if nnz[j] == 0.0 {
                        SchurKind::Empty
                    } else if low_rank <= pairwise && low_rank <= rank && low_rank <= dense {
                        SchurKind::LowRank
                    } else if pairwise <= rank && pairwise <= dense {
                        SchurKind::Pairwise
                    } else if rank <= dense {
                        SchurKind::RankUpdate
                    } else {
                        SchurKind::Dense
                    };
                }
                blk.lr_first = (0..=m).find(|&j| blk.kind[j] == SchurKind::LowRank).unwrap_or(m + 1);
                // Whole-block assembly: G² pairs (scalar), Z = WᵀDW and y = Dw (vectorised).
                let total: f64 = ngroups.iter().sum();
                let per_column: f64 = (0..=m).map(|j| column_cost(blk.kind[j], &costs[j])).sum();
                let grouped = 2.0 * total * total + tail * (total + n) / 4.0 + n * total;
                blk.grouped = blk.n >= SMALL_BLOCK && grouped < per_column;
            }
        }
        for blk in &mut blocks {
            for j in 0..=m {
                if blk.psd {
                    let base = blk.start[j];
                    for (row, ents) in group_entries(&blk.ents[blk.start[j]..blk.start[j + 1]], blk.n) {
                        blk.grp_row.push(row);
                        for k in ents {
                            let Ent { row: a, col: b } = blk.ents[base + k];
                            blk.grp_ents.push(base + k);
                            blk.gw_idx.push(if a == row { b } else { a });
                        }
                        blk.grp_ent_start.push(blk.grp_ents.len());
                    }
                }
                blk.grp_start[j + 1] = blk.grp_row.len();
            }
        }
        // What the groups need: checked against the budget before it is allocated.
        let grouped_bytes: u128 = blocks
            .iter()
            .map(|blk| {
                let (g, n, e) = (blk.grp_row.len() as u128, blk.n as u128, blk.grp_ents.len() as u128);
                let always = 8 * (e + 2 * g * n);
                let grouped = if blk.grouped { 8 * (g + 2 * g * n + 2 * g * g + 3 * g + 1 + 2 * e) } else { 0 };
                always + grouped
            })
            .sum();
        if grouped_bytes > budget {
            return Err(grouped_bytes);
        }
        for blk in &mut blocks {
            blk.gw_val = vec![0.0; blk.grp_ents.len()];
            blk.gy = vec![0.0; blk.grp_row.len() * blk.n];
            blk.gy2 = vec![0.0; blk.grp_row.len() * blk.n];
            if blk.grouped {
                let g = blk.grp_row.len();
                blk.gmat =
                    (0..=m).flat_map(|j| std::iter::repeat_n(j, blk.grp_start[j + 1] - blk.grp_start[j])).collect();
                blk.yt = vec![0.0; g * blk.n];
                blk.yt2 = vec![0.0; g * blk.n];
                blk.ag_row = Vec::with_capacity(g);
                blk.ag_mat = Vec::with_capacity(g);
                blk.ag_ent = Vec::with_capacity(g + 1);
                blk.ag_idx = Vec::with_capacity(blk.grp_ents.len());
                blk.ag_val = Vec::with_capacity(blk.grp_ents.len());
                blk.zg = vec![0.0; g * g];
                blk.zg2 = vec![0.0; g * g];
            }
        }
        let nmax = problem.blocks().iter().map(|b| b.size()).max().unwrap_or(0);
        let nu = problem.blocks().iter().map(|b| b.size() as f64).sum();
        let rows = ls_rows(problem).max(m);
        let qr_bs = dense::qr_block_size(rows, m.max(1));
        Ok(Self {
            structure: problem.clone(),
            m,
            nu,
            blocks,
            mhat: vec![0.0; (m + 1) * (m + 1)],
            lfac: vec![0.0; m * m],
            c: vec![0.0; m],
            x: vec![0.0; m],
            best_x: vec![0.0; m],
            warm_xv: vec![0.0; m],
            has_warm: false,
            warm_wanted: false,
            best_tk: (1.0, 1.0),
            dx: vec![0.0; m],
            dx2: vec![0.0; m],
            rhs: vec![0.0; m],
            p: vec![0.0; m],
            q: vec![0.0; m],
            rx: vec![0.0; m],
            cb: vec![0.0; m],
            tr: vec![0.0; m + 1],
            coef: vec![0.0; m + 1],
            fbuf: vec![0.0; nmax * nmax],
            precise: false,
            ls_rows: rows,
            ls: vec![0.0; rows * m],
            qcoef: vec![0.0; qr_bs * m],
            qr_bs,
            loss: 0.0,
            hkm: false,
            hkm_on: false,
        })
    }

    /// Copies the numeric values of `problem` (same structure), equilibrated by `scale`, into the
    /// workspace.
    pub fn load_values(&mut self, problem: &SdpProblem, scale: &Equilibration) {
        let entries = problem.entries();
        for blk in &mut self.blocks {
            for (k, &s) in blk.src.iter().enumerate() {
                let v = scale.entry(&entries[s]);
                blk.val[k] = v;
                let ent = blk.ents[k];
                blk.sval[k] =
                    if ent.row == ent.col { v * std::f64::consts::FRAC_1_SQRT_2 } else { v * std::f64::consts::SQRT_2 };
            }
            // Nonzero entries (within the capacity reserved at setup: no allocation).
            blk.nz_p1.clear();
            blk.nz_p2.clear();
            blk.nz_v.clear();
            let n = blk.n;
            for i in 0..blk.start.len() - 1 {
                blk.nz_start[i] = blk.nz_v.len();
                for k in blk.start[i]..blk.start[i + 1] {
                    let v = blk.val[k];
                    if v == 0.0 {
                        continue;
                    }
                    let Ent { row, col } = blk.ents[k];
                    let (p1, p2) = if !blk.psd { (row, row) } else { (row + col * n, col + row * n) };
                    blk.nz_p1.push(p1);
                    blk.nz_p2.push(p2);
                    blk.nz_v.push(v);
                }
            }
            let last = blk.start.len() - 1;
            blk.nz_start[last] = blk.nz_v.len();
            for (e, &k) in blk.grp_ents.iter().enumerate() {
                let ent = blk.ents[k];
                blk.gw_val[e] = if ent.row == ent.col { 0.5 * blk.val[k] } else { blk.val[k] };
            }
            if blk.grouped {
                blk.ag_row.clear();
                blk.ag_mat.clear();
                blk.ag_ent.clear();
                blk.ag_idx.clear();
                blk.ag_val.clear();
                blk.ag_ent.push(0);
                for j in 0..blk.grp_start.len() - 1 {
                    blk.ag_start[j] = blk.ag_row.len();
                    for g in blk.grp_start[j]..blk.grp_start[j + 1] {
                        for e in blk.grp_ent_start[g]..blk.grp_ent_start[g + 1] {
                            if blk.gw_val[e] != 0.0 {
                                blk.ag_idx.push(blk.gw_idx[e]);
                                blk.ag_val.push(blk.gw_val[e]);
                            }
                        }
                        if blk.ag_idx.len() > *blk.ag_ent.last().unwrap_or(&0) {
                            blk.ag_row.push(blk.grp_row[g]);
                            blk.ag_mat.push(j);
                            blk.ag_ent.push(blk.ag_idx.len());
                        }
                    }
                }
                let last = blk.grp_start.len() - 1;
                blk.ag_start[last] = blk.ag_row.len();
            }
        }
        for (dst, &c) in self.c.iter_mut().zip(problem.c()) {
            *dst = scale.cost(c);
        }
    }
}
