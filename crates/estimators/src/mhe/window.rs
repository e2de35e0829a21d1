//! The condensed problem of one window (docs/robust-mhe.md §2.5): the states of the window are an
//! affine function `x_j = M_j z + c_j` of the unknowns `z = (x_s, ω_1, …, ω_S)` (blocked
//! disturbances, §2.4), so every cost of §2.1 for fixed measurement-noise targets is a
//! box-constrained least-squares problem in `z`. All buffers are sized at construction for the
//! largest window; building and evaluating allocate nothing.

/// How one scalar measurement enters the minimisation: with weight `weight` on `(e − offset)²`,
/// `e = y − C x` the output residual.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Target {
    pub weight: f64,
    pub offset: f64,
}

/// One window's data (borrowed from the estimator's rings by the caller through closures) turned
/// into the condensed quantities.
#[derive(Debug, Clone)]
pub(crate) struct WindowProblem {
    n: usize,
    m: usize,
    /// Samples in the window (`L = T − s + 1`).
    pub len: usize,
    /// Number of blocks `S`.
    pub blocks: usize,
    /// Unknowns `n (1 + S)`.
    pub nz: usize,
    /// `M_j`, `j < len`, each `n × nz` column-major, at `j n nz_cap`.
    maps: Vec<f64>,
    /// `c_j`, each `n`.
    offsets: Vec<f64>,
    /// Measurement rows `a_{j,i} = (C_j M_j)_i`, each `nz`, at `(j m + i) nz_cap`.
    rows: Vec<f64>,
    /// `ỹ_{j,i} = y_{j,i} − (C_j c_j)_i`.
    pub y_tilde: Vec<f64>,
    /// Whether sample `j` has a measurement.
    pub measured: Vec<bool>,
    /// Base Hessian (prior and process terms), `nz × nz` column-major (lower triangle valid).
    h_base: Vec<f64>,
    /// Base linear term (prior).
    b_base: Vec<f64>,
    /// Process weights `κ_b Q⁻¹` per block are applied through `q_inv` and `kappa`.
    kappa: Vec<f64>,
    /// Lower / upper bounds of `z`.
    pub lo: Vec<f64>,
    /// Upper bounds of `z`.
    pub hi: Vec<f64>,
    /// Assembled Hessian for the current targets.
    pub h: Vec<f64>,
    /// Assembled linear term for the current targets.
    pub b: Vec<f64>,
    /// Prior `x̄_s` and `P_s⁻¹` (`n`, `n × n`).
    prior_mean: Vec<f64>,
    prior_inv: Vec<f64>,
    q_inv: Vec<f64>,
    nz_cap: usize,
    tmp: Vec<f64>,
}

impl WindowProblem {
    /// Buffers for windows of up to `max_len` samples and `max_blocks` blocks.
    pub fn new(n: usize, m: usize, max_len: usize, max_blocks: usize) -> Self {
        let nz_cap = n * (1 + max_blocks);
        Self {
            n,
            m,
            len: 0,
            blocks: 0,
            nz: n,
            maps: vec![0.0; max_len * n * nz_cap],
            offsets: vec![0.0; max_len * n],
            rows: vec![0.0; max_len * m * nz_cap],
            y_tilde: vec![0.0; max_len * m],
            measured: vec![false; max_len],
            h_base: vec![0.0; nz_cap * nz_cap],
            b_base: vec![0.0; nz_cap],
            kappa: vec![0.0; max_blocks.max(1)],
            lo: vec![0.0; nz_cap],
            hi: vec![0.0; nz_cap],
            h: vec![0.0; nz_cap * nz_cap],
            b: vec![0.0; nz_cap],
            prior_mean: vec![0.0; n],
            prior_inv: vec![0.0; n * n],
            q_inv: vec![0.0; n * n],
            nz_cap,
            tmp: vec![0.0; n * nz_cap],
        }
    }

    /// Builds the window: `len` samples, transition `j → j+1` with `(A_j, B_j u_j)` given by
    /// `transition(j, a_out (n×n col-major), bu_out (n))`, measurement of sample `j` by
    /// `measurement(j, c_out (m×n col-major), y_out (m)) -> bool` (false: no measurement);
    /// `block_of(j)` the block of transition `j`, `kappa(b)` its process weight; prior
    /// `(x̄_s, P_s⁻¹)`, `Q⁻¹`; the box `W` of each block.
    #[allow(clippy::too_many_arguments)]
    pub fn build(
        &mut self,
        len: usize,
        blocks: usize,
        mut transition: impl FnMut(usize, &mut [f64], &mut [f64]),
        mut measurement: impl FnMut(usize, &mut [f64], &mut [f64]) -> bool,
        block_of: impl Fn(usize) -> usize,
        kappa: impl Fn(usize) -> f64,
        prior_mean: &[f64],
        prior_inv: &[f64],
        q_inv: &[f64],
        w_lo: &[f64],
        w_hi: &[f64],
        a_buf: &mut [f64],
        bu_buf: &mut [f64],
        c_buf: &mut [f64],
        y_buf: &mut [f64],
    ) {
        let (n, m) = (self.n, self.m);
        self.len = len;
        self.blocks = blocks;
        let nz = n * (1 + blocks);
        self.nz = nz;
        let cap = self.nz_cap;
        self.prior_mean.copy_from_slice(prior_mean);
        self.prior_inv.copy_from_slice(prior_inv);
        self.q_inv.copy_from_slice(q_inv);
        for b in 0..blocks {
            self.kappa[b] = kappa(b);
        }
        // M_0 = [I 0], c_0 = 0.
        let map0 = &mut self.maps[..n * nz];
        map0.fill(0.0);
        for i in 0..n {
            map0[i * n + i] = 1.0;
        }
        self.offsets[..n].fill(0.0);
        for j in 0..len {
            // Measurement rows of sample j.
            let has = measurement(j, c_buf, y_buf);
            self.measured[j] = has;
            if has {
                let map = &self.maps[j * n * cap..j * n * cap + n * nz];
                let off = &self.offsets[j * n..(j + 1) * n];
                for i in 0..m {
                    let row = &mut self.rows[(j * m + i) * cap..(j * m + i) * cap + nz];
                    for (col, r) in row.iter_mut().enumerate() {
                        let mut s = 0.0;
                        for k in 0..n {
                            s += c_buf[k * m + i] * map[col * n + k];
                        }
                        *r = s;
                    }
                    let mut cc = 0.0;
                    for k in 0..n {
                        cc += c_buf[k * m + i] * off[k];
                    }
                    self.y_tilde[j * m + i] = y_buf[i] - cc;
                }
            }
            if j + 1 == len {
                break;
            }
            // M_{j+1} = A_j M_j + E_{b(j)},  c_{j+1} = A_j c_j + B_j u_j.
            transition(j, a_buf, bu_buf);
            let blk = block_of(j);
            let (head, tail) = self.maps.split_at_mut((j + 1) * n * cap);
            let cur = &head[j * n * cap..j * n * cap + n * nz];
            let next = &mut tail[..n * nz];
            dense_kernels::mul_slices(n, n, nz, &a_buf[..n * n], cur, next);
            for r in 0..n {
                next[(n * (1 + blk) + r) * n + r] += 1.0;
            }
            let (oh, ot) = self.offsets.split_at_mut((j + 1) * n);
            let oc = &oh[j * n..];
            for r in 0..n {
                let mut s = bu_buf[r];
                for k in 0..n {
                    s += a_buf[k * n + r] * oc[k];
                }
                ot[r] = s;
            }
        }
        // Base Hessian: P_s⁻¹ on x_s, κ_b Q⁻¹ on ω_b; base linear term P_s⁻¹ x̄_s.
        self.h_base[..nz * nz].fill(0.0);
        self.b_base[..nz].fill(0.0);
        for c in 0..n {
            for r in 0..n {
                self.h_base[c * nz + r] = self.prior_inv[c * n + r];
            }
        }
        for r in 0..n {
            let mut s = 0.0;
            for c in 0..n {
                s += self.prior_inv[c * n + r] * self.prior_mean[c];
            }
            self.b_base[r] = s;
        }
        for b in 0..blocks {
            let o = n * (1 + b);
            for c in 0..n {
                for r in 0..n {
                    self.h_base[(o + c) * nz + o + r] = self.kappa[b] * self.q_inv[c * n + r];
                }
            }
        }
        for i in 0..n {
            self.lo[i] = f64::NEG_INFINITY;
            self.hi[i] = f64::INFINITY;
        }
        for b in 0..blocks {
            for i in 0..n {
                self.lo[n * (1 + b) + i] = w_lo[i];
                self.hi[n * (1 + b) + i] = w_hi[i];
            }
        }
    }

    /// Measurement row `a_{j,i}` (`nz` entries).
    pub fn row(&self, j: usize, i: usize) -> &[f64] {
        let o = (j * self.m + i) * self.nz_cap;
        &self.rows[o..o + self.nz]
    }

    /// Assembles `H`, `b` of `min zᵀ H z − 2 bᵀ z` for per-measurement targets
    /// (`targets[j m + i]`).
    pub fn assemble(&mut self, targets: &[Target]) {
        self.assemble_h(targets);
        self.assemble_b(targets);
    }

    /// Assembles `H` only (it depends on the weights, not on the offsets).
    pub fn assemble_h(&mut self, targets: &[Target]) {
        let nz = self.nz;
        self.h[..nz * nz].copy_from_slice(&self.h_base[..nz * nz]);
        for j in 0..self.len {
            if !self.measured[j] {
                continue;
            }
            for i in 0..self.m {
                let weight = targets[j * self.m + i].weight;
                let o = (j * self.m + i) * self.nz_cap;
                let row = &self.rows[o..o + nz];
                for c in 0..nz {
                    let wc = weight * row[c];
                    if wc == 0.0 {
                        continue;
                    }
                    for r in c..nz {
                        self.h[c * nz + r] += wc * row[r];
                    }
                }
            }
        }
    }

    /// Assembles `b` only.
    pub fn assemble_b(&mut self, targets: &[Target]) {
        let nz = self.nz;
        self.b[..nz].copy_from_slice(&self.b_base[..nz]);
        for j in 0..self.len {
            if !self.measured[j] {
                continue;
            }
            for i in 0..self.m {
                let t = targets[j * self.m + i];
                let o = (j * self.m + i) * self.nz_cap;
                let rhs = t.weight * (self.y_tilde[j * self.m + i] - t.offset);
                for (bc, a) in self.b[..nz].iter_mut().zip(&self.rows[o..o + nz]) {
                    *bc += rhs * a;
                }
            }
        }
    }

    /// Output residuals `e_{j,i} = ỹ_{j,i} − a_{j,i} z` into `e` (zero where unmeasured).
    pub fn residuals(&self, z: &[f64], e: &mut [f64]) {
        for j in 0..self.len {
            for i in 0..self.m {
                e[j * self.m + i] = if self.measured[j] {
                    let row = self.row(j, i);
                    self.y_tilde[j * self.m + i] - row.iter().zip(z).map(|(a, z)| a * z).sum::<f64>()
                } else {
                    0.0
                };
            }
        }
    }

    /// Prior plus process terms `‖x_s − x̄_s‖²_{P_s⁻¹} + Σ κ_b ‖ω_b‖²_{Q⁻¹}` at `z`.
    pub fn prior_and_process(&mut self, z: &[f64]) -> f64 {
        let n = self.n;
        for i in 0..n {
            self.tmp[i] = z[i] - self.prior_mean[i];
        }
        let mut total = quad(&self.prior_inv, &self.tmp[..n], n);
        for b in 0..self.blocks {
            let o = n * (1 + b);
            total += self.kappa[b] * quad(&self.q_inv, &z[o..o + n], n);
        }
        total
    }

    /// State `x_j = M_j z + c_j` into `out`.
    pub fn state(&self, j: usize, z: &[f64], out: &mut [f64]) {
        let (n, nz) = (self.n, self.nz);
        let map = &self.maps[j * n * self.nz_cap..j * n * self.nz_cap + n * nz];
        for r in 0..n {
            let mut s = self.offsets[j * n + r];
            for c in 0..nz {
                s += map[c * n + r] * z[c];
            }
            out[r] = s;
        }
    }
}

fn quad(a: &[f64], x: &[f64], n: usize) -> f64 {
    let mut s = 0.0;
    for c in 0..n {
        for r in 0..n {
            s += x[r] * a[c * n + r] * x[c];
        }
    }
    s
}
