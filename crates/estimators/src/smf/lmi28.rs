//! The ellipsoidal filter update as an SDP: LMI (28) and problem (29) of the straddle-carrier
//! set-membership filter, for any linear system (nothing here is vehicle-specific).
//!
//! Given `x_{k+1} = A x_k + B u_k + w_k`, `y_{k+1} = C x_{k+1} + v_{k+1}`, `w ∈ 𝓔(0, Q)`,
//! `v ∈ 𝓔(0, R)` and the current set `𝓔(x̂_k, P_k)` with `P_k = E Eᵀ`, the estimation error of
//! the filter `x̂_{k+1} = G x̂_k + (I − LC) B u_k + L y_{k+1}` (13) is `Π η` with
//! `η = [1, z, w, v]`, `‖z‖ ≤ 1` and (19)
//!
//! ```text
//! Π = [ g,  (I − LC) A E,  (I − LC),  −L ],      g = (I − LC) A x̂_k − G x̂_k  (free)
//! ```
//!
//! (the paper prints `A − A L C`; the product that follows from (15) is `(I − LC) A`). The
//! S-procedure with multipliers `τ₁, τ₂, τ₃ ≥ 0` gives (28) in the equivalent form used here:
//!
//! ```text
//! [ P    Π   ]
//! [ Πᵀ   Θ(τ)] ⪰ 0,   Θ(τ) = diag(1 − τ₁ − τ₂ − τ₃,  τ₁ Iₙ,  τ₂ Q⁻¹,  τ₃ R⁻¹)     (26), (28)
//! ```
//!
//! and (29) minimises `tr P` over `P`, `L`, `g`, `τ`. The block has order `n + 1 + 2n + m`; the
//! decision vector holds `P` (`n(n+1)/2`), `L` (`n·m`), `g` (`n`) and `τ` (3), in that order.
//! The LMI implies `τ ≥ 0` through the diagonal blocks of `Θ`, so no separate cone is added.
//!
//! The structure depends only on `(n, m)`: [`FilterSdp::update`] rewrites the numbers of the
//! same problem, so a backend set up once can solve it at every step.
//!
//! # Whitened statement (the default)
//!
//! With `Q = E_Q E_Qᵀ` and `R = E_R E_Rᵀ` (Cholesky factors) and the diagonal
//! `D = diag(sᵢ)`, `sᵢ = 0.3 / √(A P_k Aᵀ + Q)ᵢᵢ` (the predicted spread of state `i`), the
//! congruence `S = diag(D, 1, Iₙ, E_Q, E_R)` turns the block into the equivalent
//!
//! ```text
//! Sᵀ [ P  Π ; Πᵀ  Θ(τ) ] S = [ D P D   D Π_w ; Π_wᵀ D   diag(1 − τ₁ − τ₂ − τ₃, τ₁ Iₙ, τ₂ Iₙ, τ₃ Iₘ) ],
//! Π_w = [ g,  (I − LC) A E,  (I − LC) E_Q,  −L E_R ]
//! ```
//!
//! (`E_Qᵀ Q⁻¹ E_Q = I`): the same unknowns, the same feasible set and optimum, but no `Q⁻¹`,
//! `R⁻¹` in the data and rows of `P` of comparable size. The vehicles' noise shapes span many
//! decades (the carrier's `Q` from `4·10⁻¹⁰` to `10⁻⁶`): with `Q⁻¹` in the block the
//! interior-point method needed 28–30 iterations on the carrier reproduction's steps, 15–16 with
//! the whitening alone and 11–15 with `D` as well (`0.3` was chosen among 0.1–0.5 on those steps
//! and the benchmark cases; see `docs/sdp.md`). [`Formulation::AsStated`] keeps the literal form
//! (for comparisons).

use nalgebra::{DMatrix, DVector};

use lmi::LmiError;
use lmi::SdpProblem;

/// The data of one filter step.
#[derive(Debug, Clone, Copy)]
pub struct FilterSdpData<'a> {
    /// State transition `A_p` (`n × n`).
    pub a: &'a DMatrix<f64>,
    /// Output matrix `C` (`m × n`).
    pub c: &'a DMatrix<f64>,
    /// Process-noise shape `Q` (`n × n`, symmetric positive definite).
    pub q: &'a DMatrix<f64>,
    /// Measurement-noise shape `R` (`m × m`, symmetric positive definite).
    pub r: &'a DMatrix<f64>,
    /// Current shape `P_k` (`n × n`, symmetric positive definite).
    pub p: &'a DMatrix<f64>,
    /// Current centre `x̂_k` (`n`).
    pub x_hat: &'a DVector<f64>,
}

/// What a solution of (29) says, read back from the decision vector.
#[derive(Debug, Clone, PartialEq)]
pub struct FilterSdpSolution {
    /// `P_{k+1}` as returned by the solver (not certified: see the estimators crate).
    pub p_next: DMatrix<f64>,
    /// The gain `L_k` (`n × m`).
    pub l: DMatrix<f64>,
    /// The free first column `g` of `Π` (zero at the optimum, since the noise sets are symmetric).
    pub g: DVector<f64>,
    /// `G_k x̂_k = (I − L C) A x̂_k − g`, the part of (13) that the LMI determines.
    pub g_x_hat: DVector<f64>,
    /// The S-procedure multipliers `(τ₁, τ₂, τ₃)`.
    pub tau: [f64; 3],
}

/// How (28) is written as an SDP (same unknowns, same optimum).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Formulation {
    /// The congruence with `diag(D, 1, I, E_Q, E_R)`: `Θ = diag(1 − Στ, τ₁I, τ₂I, τ₃I)` and the
    /// rows of `P` scaled by `D` (see the [module documentation](self)); the default.
    #[default]
    Whitened,
    /// (28) literally, with `τ₂ Q⁻¹` and `τ₃ R⁻¹` in the block (the earlier form).
    AsStated,
}

/// LMI (28) with a fixed structure for given dimensions; the numbers change per step.
#[derive(Debug, Clone)]
pub struct FilterSdp {
    n: usize,
    m: usize,
    form: Formulation,
    problem: SdpProblem,
    ws: Workspace,
}

/// Buffers of [`FilterSdp::update`], allocated once so that an update does not allocate.
#[derive(Debug, Clone)]
struct Workspace {
    /// Cholesky factor `E` of `P_k` (lower).
    e: DMatrix<f64>,
    /// `A E`.
    ae: DMatrix<f64>,
    /// `C A E`.
    cae: DMatrix<f64>,
    /// `Q⁻¹`, `R⁻¹` and a factor buffer for each.
    q_inv: DMatrix<f64>,
    r_inv: DMatrix<f64>,
    q_fac: DMatrix<f64>,
    r_fac: DMatrix<f64>,
    /// `C E_Q` and the row scales `sᵢ` (whitened statement).
    ceq: DMatrix<f64>,
    rows: Vec<f64>,
    /// The new entry values and objective.
    values: Vec<f64>,
    c: Vec<f64>,
}

impl Workspace {
    fn new(n: usize, m: usize, entries: usize, vars: usize) -> Self {
        Self {
            e: DMatrix::zeros(n, n),
            ae: DMatrix::zeros(n, n),
            cae: DMatrix::zeros(m, n),
            q_inv: DMatrix::zeros(n, n),
            r_inv: DMatrix::zeros(m, m),
            q_fac: DMatrix::zeros(n, n),
            r_fac: DMatrix::zeros(m, m),
            ceq: DMatrix::zeros(m, n),
            rows: vec![1.0; n],
            values: vec![0.0; entries],
            c: vec![0.0; vars],
        }
    }
}

/// Symmetry within [`dense_kernels::SYMMETRY_TOLERANCE`], then the lower Cholesky factor of the
/// symmetric part of `src` written into `l` (upper part zeroed) at the workspace's pivot rule.
/// No allocation.
fn factor_spd(src: &DMatrix<f64>, l: &mut DMatrix<f64>, name: &'static str) -> Result<(), LmiError> {
    if dense_kernels::max_asymmetry(src, dense_kernels::SYMMETRY_TOLERANCE).is_some() {
        return Err(LmiError::NotPositiveDefinite(name));
    }
    l.copy_from(src);
    dense_kernels::symmetrize(l);
    dense_kernels::cholesky_in_place(l).map_err(|_| LmiError::NotPositiveDefinite(name))
}

fn check_dims(d: &FilterSdpData<'_>) -> Result<(usize, usize), LmiError> {
    let n = d.a.nrows();
    let m = d.c.nrows();
    let dim = |what, expected, found| {
        if expected == found { Ok(()) } else { Err(LmiError::DimensionMismatch { what, expected, found }) }
    };
    if n == 0 || m == 0 {
        return Err(LmiError::InvalidProblem("the system needs at least one state and one output".into()));
    }
    dim("columns of A", n, d.a.ncols())?;
    dim("columns of C", n, d.c.ncols())?;
    dim("rows of Q", n, d.q.nrows())?;
    dim("columns of Q", n, d.q.ncols())?;
    dim("rows of R", m, d.r.nrows())?;
    dim("columns of R", m, d.r.ncols())?;
    dim("rows of P", n, d.p.nrows())?;
    dim("columns of P", n, d.p.ncols())?;
    dim("length of x_hat", n, d.x_hat.len())?;
    for (name, mat) in [("A", d.a), ("C", d.c), ("Q", d.q), ("R", d.r), ("P", d.p)] {
        if mat.iter().any(|v| !v.is_finite()) {
            return Err(LmiError::InvalidProblem(format!("{name} has a non-finite entry")));
        }
    }
    if d.x_hat.iter().any(|v| !v.is_finite()) {
        return Err(LmiError::InvalidProblem("x_hat has a non-finite entry".into()));
    }
    Ok((n, m))
}

impl FilterSdp {
    /// Builds (28)/(29) for the given data. Errors name a wrong dimension, a non-finite entry or
    /// a `Q`, `R`, `P` that is not symmetric positive definite.
    pub fn new(data: &FilterSdpData<'_>) -> Result<Self, LmiError> {
        Self::with_formulation(data, Formulation::default())
    }

    /// Like [`FilterSdp::new`], with the given statement of (28).
    pub fn with_formulation(data: &FilterSdpData<'_>, form: Formulation) -> Result<Self, LmiError> {
        let (n, m) = check_dims(data)?;
        let layout = Layout { n, m, form };
        let problem = layout.structure()?;
        let ws = Workspace::new(n, m, problem.entries().len(), problem.num_vars());
        let mut sdp = Self { n, m, form, problem, ws };
        sdp.update(data)?;
        Ok(sdp)
    }

    /// The statement of (28) in use.
    pub fn formulation(&self) -> Formulation {
        self.form
    }

    /// Number of states `n`.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Number of outputs `m`.
    pub fn m(&self) -> usize {
        self.m
    }

    /// The SDP in SDPA form.
    pub fn problem(&self) -> &SdpProblem {
        &self.problem
    }

    /// Rewrites the numbers for new data of the same dimensions (the structure is unchanged, so a
    /// backend set up on [`FilterSdp::problem`] can solve the result). On error, unchanged.
    pub fn update(&mut self, data: &FilterSdpData<'_>) -> Result<(), LmiError> {
        if data.a.nrows() != self.n || data.c.nrows() != self.m {
            return Err(LmiError::StructureMismatch(format!(
                "filter SDP built for n = {}, m = {}; got n = {}, m = {}",
                self.n,
                self.m,
                data.a.nrows(),
                data.c.nrows()
            )));
        }
        check_dims(data)?;
        let ws = &mut self.ws;
        factor_spd(data.p, &mut ws.e, "P")?;
        factor_spd(data.q, &mut ws.q_fac, "Q")?;
        factor_spd(data.r, &mut ws.r_fac, "R")?;
        if self.form == Formulation::AsStated {
            dense_kernels::cholesky_inverse(ws.q_fac.as_slice(), self.n, ws.q_inv.as_mut_slice());
            dense_kernels::cholesky_inverse(ws.r_fac.as_slice(), self.m, ws.r_inv.as_mut_slice());
        }
        ws.ae.gemm(1.0, data.a, &ws.e, 0.0);
        ws.cae.gemm(1.0, data.c, &ws.ae, 0.0);
        ws.ceq.gemm(1.0, data.c, &ws.q_fac, 0.0);
        for (i, s) in ws.rows.iter_mut().enumerate() {
            // (A P_k Aᵀ + Q)ᵢᵢ = ‖row i of A E‖² + ‖row i of E_Q‖² > 0 (Q is positive definite).
            let spread: f64 = ws.ae.row(i).norm_squared() + ws.q_fac.row(i).norm_squared();
            *s = if self.form == Formulation::Whitened { ROW_SCALE / spread.sqrt() } else { 1.0 };
        }
        let layout = Layout { n: self.n, m: self.m, form: self.form };
        let src = Sources {
            ae: &ws.ae,
            cae: &ws.cae,
            c: data.c,
            q_inv: &ws.q_inv,
            r_inv: &ws.r_inv,
            eq: &ws.q_fac,
            er: &ws.r_fac,
            ceq: &ws.ceq,
            rows: &ws.rows,
        };
        for (v, e) in ws.values.iter_mut().zip(self.problem.entries()) {
            *v = layout.value(e.mat, e.row, e.col, &src);
        }
        // Objective tr P: coefficient 1 on the diagonal entries of P.
        for (k, c) in ws.c.iter_mut().enumerate() {
            *c = match layout.var(k) {
                Var28::P(i, j) if i == j => 1.0,
                _ => 0.0,
            };
        }
        self.problem.set_values(&ws.c, &ws.values)
    }

    /// Reads only the gain `L` (into `l`, `n × m`) and `τ` from a decision vector `x`, without
    /// allocating: what a filter needs to certify its own `P_{k+1}`.
    pub fn read_gain(&self, x: &[f64], l: &mut DMatrix<f64>) -> Result<[f64; 3], LmiError> {
        if x.len() != self.problem.num_vars() {
            return Err(LmiError::DimensionMismatch {
                what: "decision vector x",
                expected: self.problem.num_vars(),
                found: x.len(),
            });
        }
        if l.nrows() != self.n {
            return Err(LmiError::DimensionMismatch { what: "rows of the gain L", expected: self.n, found: l.nrows() });
        }
        if l.ncols() != self.m {
            return Err(LmiError::DimensionMismatch {
                what: "columns of the gain L",
                expected: self.m,
                found: l.ncols(),
            });
        }
        let layout = Layout { n: self.n, m: self.m, form: self.form };
        for j in 0..self.m {
            for i in 0..self.n {
                l[(i, j)] = x[layout.index(Var28::L(i, j))];
            }
        }
        let t = |k: usize| x[layout.index(Var28::Tau(k))];
        Ok([t(0), t(1), t(2)])
    }

    /// Reads `P_{k+1}`, `L`, `g`, `G x̂` and `τ` from a decision vector `x` (allocates).
    pub fn read(&self, x: &[f64], data: &FilterSdpData<'_>) -> Result<FilterSdpSolution, LmiError> {
        check_dims(data)?;
        let mut l = DMatrix::zeros(self.n, self.m);
        let tau = self.read_gain(x, &mut l)?;
        let layout = Layout { n: self.n, m: self.m, form: self.form };
        let p_next = DMatrix::from_fn(self.n, self.n, |i, j| x[layout.index(Var28::P(i.min(j), i.max(j)))]);
        let g = DVector::from_fn(self.n, |i, _| x[layout.index(Var28::G(i))]);
        let k = DMatrix::identity(self.n, self.n) - &l * data.c;
        let g_x_hat = &k * (data.a * data.x_hat) - &g;
        Ok(FilterSdpSolution { p_next, l, g, g_x_hat, tau })
    }
}

/// The scalar unknowns of (28) in the builder's order: `P` (packed upper triangle, column by
/// column), `L` (column-major), `g`, `τ₁, τ₂, τ₃`.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Var28 {
    P(usize, usize),
    L(usize, usize),
    G(usize),
    Tau(usize),
}

/// The data matrices the entries of (28) are made of.
struct Sources<'a> {
    ae: &'a DMatrix<f64>,
    cae: &'a DMatrix<f64>,
    c: &'a DMatrix<f64>,
    q_inv: &'a DMatrix<f64>,
    r_inv: &'a DMatrix<f64>,
    /// Whitened statement: the lower Cholesky factors `E_Q`, `E_R`, `C E_Q` and the scales of
    /// the rows of `P`.
    eq: &'a DMatrix<f64>,
    er: &'a DMatrix<f64>,
    ceq: &'a DMatrix<f64>,
    rows: &'a [f64],
}

/// The factor `0.3` of the row scales `sᵢ = 0.3/√(A P_k Aᵀ + Q)ᵢᵢ` of the whitened statement.
const ROW_SCALE: f64 = 0.3;

/// Where things sit in the block `[[P, Π], [Πᵀ, Θ]]` of order `n + 1 + 2n + m`.
#[derive(Debug, Clone, Copy)]
struct Layout {
    n: usize,
    m: usize,
    form: Formulation,
}

impl Layout {
    /// Scalar unknowns: `P` (packed upper triangle), `L`, `g`, `τ`.
    fn num_vars(&self) -> usize {
        self.n * (self.n + 1) / 2 + self.n * self.m + self.n + 3
    }

    /// Order of the block `[[P, Π], [Πᵀ, Θ]]`.
    fn order(&self) -> usize {
        3 * self.n + 1 + self.m
    }

    /// The index of an unknown (the inverse of [`Layout::var`]).
    fn index(&self, v: Var28) -> usize {
        let np = self.n * (self.n + 1) / 2;
        let nl = self.n * self.m;
        match v {
            Var28::P(i, j) => j * (j + 1) / 2 + i,
            Var28::L(i, j) => np + j * self.n + i,
            Var28::G(i) => np + nl + i,
            Var28::Tau(t) => np + nl + self.n + t,
        }
    }

    /// The structure of (28)/(29) for `(n, m)`: every entry that can be non-zero for some data
    /// (found by evaluating [`Layout::value`] with all data entries 1, so no cancellation hides
    /// one), values to be set by [`FilterSdp::update`].
    fn structure(&self) -> Result<SdpProblem, LmiError> {
        let (n, m) = (self.n, self.m);
        let ones = |r: usize, c: usize| DMatrix::from_element(r, c, 1.0);
        let (ae, cae, c, q_inv, r_inv) = (ones(n, n), ones(m, n), ones(m, n), ones(n, n), ones(m, m));
        // The factors are lower triangular: their upper parts are structural zeros.
        let lower = |k: usize| DMatrix::from_fn(k, k, |i, j| if i >= j { 1.0 } else { 0.0 });
        let (eq, er, ceq, rows) = (lower(n), lower(m), ones(m, n), vec![1.0; n]);
        let src = Sources {
            ae: &ae,
            cae: &cae,
            c: &c,
            q_inv: &q_inv,
            r_inv: &r_inv,
            eq: &eq,
            er: &er,
            ceq: &ceq,
            rows: &rows,
        };
        let mut entries = Vec::new();
        for mat in 0..=self.num_vars() {
            for col in 0..self.order() {
                for row in 0..=col {
                    let value = self.value(mat, row, col, &src);
                    if value != 0.0 {
                        entries.push(lmi::Entry { mat, block: 0, row, col, value });
                    }
                }
            }
        }
        SdpProblem::new(vec![lmi::Block::Psd(self.order())], vec![0.0; self.num_vars()], entries)
    }

    fn var(&self, k: usize) -> Var28 {
        let np = self.n * (self.n + 1) / 2;
        let nl = self.n * self.m;
        if k < np {
            let mut c = 0;
            while (c + 1) * (c + 2) / 2 <= k {
                c += 1;
            }
            Var28::P(k - c * (c + 1) / 2, c)
        } else if k < np + nl {
            let j = k - np;
            Var28::L(j % self.n, j / self.n)
        } else if k < np + nl + self.n {
            Var28::G(k - np - nl)
        } else {
            Var28::Tau(k - np - nl - self.n)
        }
    }

    /// The SDPA value of entry `(row, col)` (`row ≤ col`) of matrix `mat`: `−(constant)` for
    /// `F₀`, the coefficient of the unknown `mat − 1` otherwise. This is the one statement of
    /// (28) in the library: (19) `Π = [g, (I − LC) A E, (I − LC), −L]` and (26)
    /// `Θ(τ) = diag(1 − τ₁ − τ₂ − τ₃, τ₁ I, τ₂ Q⁻¹, τ₃ R⁻¹)` in `[[P, Π], [Πᵀ, Θ]] ⪰ 0`
    /// ([`Formulation::AsStated`]), or its congruence with `diag(D, 1, I, E_Q, E_R)`
    /// ([`Formulation::Whitened`]: `E_Q`, `C E_Q` and `E_R` replace `I`, `C` and `I` in `Π`,
    /// `Θ = diag(1 − Στ, τ₁I, τ₂I, τ₃I)`, and the rows of `P` are scaled by `D`); the tests check
    /// both against an independent statement with the `lmi` builder.
    fn value(&self, mat: usize, row: usize, col: usize, ws: &Sources<'_>) -> f64 {
        // Whitened: the rows (and columns) of P scaled by D; `row ≤ col`, so `col < n` means
        // both are rows of P. (All scales are 1 as stated.)
        let scale = if row < self.n { ws.rows[row] } else { 1.0 } * if col < self.n { ws.rows[col] } else { 1.0 };
        scale * self.value_unscaled(mat, row, col, ws)
    }

    /// [`Layout::value`] before the scaling of the rows of `P`.
    fn value_unscaled(&self, mat: usize, row: usize, col: usize, ws: &Sources<'_>) -> f64 {
        let n = self.n;
        // Π's column blocks, relative to column n: g (0), z (1..=n), w (n+1..=2n), v (2n+1..).
        if mat == 0 {
            return -if col < n {
                0.0 // P block has no constant
            } else if row < n {
                match col - n {
                    0 => 0.0,
                    j if j <= n => ws.ae[(row, j - 1)],
                    j if j <= 2 * n => match self.form {
                        Formulation::Whitened => ws.eq[(row, j - 1 - n)],
                        Formulation::AsStated => f64::from(u8::from(row == j - 1 - n)),
                    },
                    _ => 0.0,
                }
            } else if row == n && col == n {
                1.0
            } else {
                0.0
            };
        }
        let (i, j) = (row, col);
        match self.var(mat - 1) {
            Var28::P(a, b) => f64::from(u8::from(a == i && b == j)),
            Var28::G(a) => f64::from(u8::from(i == a && j == n)),
            Var28::L(a, b) => {
                if i != a || j < n + 1 {
                    return 0.0;
                }
                let white = self.form == Formulation::Whitened;
                match j - n {
                    z if z <= n => -ws.cae[(b, z - 1)],
                    w if w <= 2 * n && white => -ws.ceq[(b, w - 1 - n)],
                    w if w <= 2 * n => -ws.c[(b, w - 1 - n)],
                    v if white => -ws.er[(b, v - 1 - 2 * n)],
                    v => -f64::from(u8::from(v - 1 - 2 * n == b)),
                }
            }
            Var28::Tau(t) => {
                if i < n {
                    return 0.0;
                }
                let (bi, bj) = (i - n, j - n);
                if bi == 0 && bj == 0 {
                    return -1.0; // 1 − τ₁ − τ₂ − τ₃
                }
                let region = |k: usize| match k {
                    0 => 0,
                    k if k <= n => 1,
                    k if k <= 2 * n => 2,
                    _ => 3,
                };
                if region(bi) != t + 1 || region(bj) != t + 1 {
                    return 0.0;
                }
                match (t, self.form) {
                    (0, _) | (_, Formulation::Whitened) => f64::from(u8::from(bi == bj)),
                    (1, _) => ws.q_inv[(bi - 1 - n, bj - 1 - n)],
                    _ => ws.r_inv[(bi - 1 - 2 * n, bj - 1 - 2 * n)],
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lmi::builder::{AffineMatrix, LmiBuilder};

    /// Cholesky factor of a symmetric positive definite matrix (symmetry within `1e-10` relative).
    fn spd_factor(m: &DMatrix<f64>, name: &'static str) -> Result<nalgebra::Cholesky<f64, nalgebra::Dyn>, LmiError> {
        let scale = m.amax().max(f64::MIN_POSITIVE);
        if (m - m.transpose()).amax() > 1e-10 * scale {
            return Err(LmiError::NotPositiveDefinite(name));
        }
        let sym = (m + m.transpose()) * 0.5;
        nalgebra::Cholesky::new(sym).ok_or(LmiError::NotPositiveDefinite(name))
    }

    /// The independent reference: (28)/(29) stated with the `lmi` builder, term by term as in the
    /// paper.
    fn build(d: &FilterSdpData<'_>) -> Result<SdpProblem, LmiError> {
        let (n, m) = check_dims(d)?;
        let e = spd_factor(d.p, "P")?.l();
        let q_inv = spd_factor(d.q, "Q")?.inverse();
        let r_inv = spd_factor(d.r, "R")?.inverse();
        let mut b = LmiBuilder::new().keep_structural_zeros(true);
        let p = b.symmetric("P", n)?;
        let l = b.matrix("L", n, m)?; // m outputs
        let g = b.matrix("g", n, 1)?;
        let tau = [b.scalar("tau1")?, b.scalar("tau2")?, b.scalar("tau3")?];
        let pm = b.matrix_expr(p)?;
        let lm = b.matrix_expr(l)?;
        let gm = b.matrix_expr(g)?;
        let t = [b.expr(tau[0])?, b.expr(tau[1])?, b.expr(tau[2])?];

        let ae = d.a * &e;
        // (19): Π = [g, (I − LC) A E, (I − LC), −L]
        let col_z = AffineMatrix::constant(&ae).sub(&lm.mul_right(&(d.c * &ae))?)?;
        let col_w = AffineMatrix::constant(&DMatrix::identity(n, n)).sub(&lm.mul_right(d.c)?)?;
        let col_v = lm.scale(-1.0);
        let pi = AffineMatrix::block(&[&[&gm, &col_z, &col_w, &col_v]])?;
        // (26): Θ(τ) = diag(1 − τ₁ − τ₂ − τ₃, τ₁ I, τ₂ Q⁻¹, τ₃ R⁻¹)
        let one = DMatrix::from_element(1, 1, 1.0);
        let theta0 =
            AffineMatrix::constant(&one).sub(&AffineMatrix::constant_times(&one, &t[0].add(&t[1]).add(&t[2])))?;
        let theta = AffineMatrix::diag(&[
            &theta0,
            &AffineMatrix::constant_times(&DMatrix::identity(n, n), &t[0]),
            &AffineMatrix::constant_times(&q_inv, &t[1]),
            &AffineMatrix::constant_times(&r_inv, &t[2]),
        ]);
        // (28) as [[P, Π], [Πᵀ, Θ]] ⪰ 0, (29): minimise tr P.
        b.psd(AffineMatrix::block(&[&[&pm, &pi], &[&pi.transpose(), &theta]])?)?;
        b.minimize(pm.trace());
        let (problem, _) = b.build()?;
        Ok(problem)
    }

    type Case = (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, DVector<f64>);

    fn data_case() -> Case {
        let a = DMatrix::from_row_slice(2, 2, &[0.9, 0.1, -0.2, 0.8]);
        let c = DMatrix::from_row_slice(1, 2, &[1.0, 0.0]);
        let q = DMatrix::identity(2, 2) * 0.1;
        let r = DMatrix::identity(1, 1) * 0.2;
        let p = DMatrix::identity(2, 2);
        let x = DVector::from_vec(vec![1.0, -1.0]);
        (a, c, q, r, p, x)
    }

    #[test]
    fn lmi_at_a_feasible_point_matches_the_schur_form() {
        // For L, τ on the simplex and P = (I−LC) A P Aᵀ (I−LC)ᵀ/τ₁ + (I−LC) Q (I−LC)ᵀ/τ₂ + L R Lᵀ/τ₃
        // (plus a margin), the LMI must be positive semidefinite.
        let (a, c, q, r, p, x) = data_case();
        let d = FilterSdpData { a: &a, c: &c, q: &q, r: &r, p: &p, x_hat: &x };
        let sdp = FilterSdp::new(&d).unwrap();
        assert_eq!(sdp.problem().blocks(), &[lmi::Block::Psd(2 + 1 + 2 + 2 + 1)]);
        assert_eq!(sdp.problem().num_vars(), 3 + 2 + 2 + 3);
        let l = DMatrix::from_row_slice(2, 1, &[0.5, 0.1]);
        let tau = [0.4, 0.3, 0.3];
        let k = DMatrix::identity(2, 2) - &l * &c;
        let pn = &k * &a * &p * a.transpose() * k.transpose() / tau[0]
            + &k * &q * k.transpose() / tau[1]
            + &l * &r * l.transpose() / tau[2]
            + DMatrix::identity(2, 2) * 1e-6;
        let mut xv = vec![0.0; 10];
        xv[0] = pn[(0, 0)];
        xv[1] = pn[(0, 1)];
        xv[2] = pn[(1, 1)];
        xv[3] = l[(0, 0)];
        xv[4] = l[(1, 0)];
        xv[7..10].copy_from_slice(&tau);
        let s = sdp.problem().slack(&xv).unwrap();
        let min_eig = s[0].clone().symmetric_eigenvalues().min();
        assert!(min_eig > -1e-12, "{min_eig}");
        // Slightly smaller P breaks it.
        xv[0] -= 1e-3;
        let s = sdp.problem().slack(&xv).unwrap();
        assert!(s[0].clone().symmetric_eigenvalues().min() < 0.0);
        let sol = sdp.read(&xv, &d).unwrap();
        assert_eq!(sol.tau, tau);
        assert_eq!(sol.l, l);
        assert!((sol.g_x_hat - &k * &a * &x).norm() < 1e-15);
    }

    #[test]
    fn closed_form_update_reproduces_the_builder() {
        // Pseudo-random data of several sizes: the values written by `update` equal those of a
        // fresh build with the builder, entry for entry.
        let mut g = dense_kernels::test_data::Lcg(7);
        let mut rnd = move || g.centred();
        for (n, m) in [(1, 1), (2, 1), (3, 2), (4, 3), (4, 4), (6, 2)] {
            let spd = |k: usize, rnd: &mut dyn FnMut() -> f64| {
                let b = DMatrix::from_fn(k, k, |_, _| rnd());
                &b * b.transpose() + DMatrix::identity(k, k) * 0.5
            };
            let a = DMatrix::from_fn(n, n, |_, _| rnd());
            let c = DMatrix::from_fn(m, n, |_, _| rnd());
            let (q, r, p) = (spd(n, &mut rnd), spd(m, &mut rnd), spd(n, &mut rnd));
            let x = DVector::from_fn(n, |_, _| rnd());
            let d = FilterSdpData { a: &a, c: &c, q: &q, r: &r, p: &p, x_hat: &x };
            let reference = build(&d).unwrap();
            // The whitened statement is the congruence Sᵀ(·)S, S = diag(D, 1, I, E_Q, E_R),
            // D = diag(0.3/√(A P Aᵀ + Q)ᵢᵢ).
            let order = 3 * n + 1 + m;
            let mut cong = DMatrix::identity(order, order);
            let spread = &a * &p * a.transpose() + &q;
            for i in 0..n {
                cong[(i, i)] = 0.3 / spread[(i, i)].sqrt();
            }
            cong.view_mut((2 * n + 1, 2 * n + 1), (n, n)).copy_from(&spd_factor(&q, "Q").unwrap().l());
            cong.view_mut((3 * n + 1, 3 * n + 1), (m, m)).copy_from(&spd_factor(&r, "R").unwrap().l());
            for form in [Formulation::AsStated, Formulation::Whitened] {
                // Build for other data first, then update to `d`.
                let a0 = DMatrix::identity(n, n);
                let mut sdp = FilterSdp::with_formulation(&FilterSdpData { a: &a0, ..d }, form).unwrap();
                sdp.update(&d).unwrap();
                assert_eq!(sdp.formulation(), form);
                assert_eq!(sdp.problem().c(), reference.c());
                assert_eq!(sdp.problem().blocks(), reference.blocks());
                // Same LMI: equal slack matrices F(x) = Σ xᵢFᵢ − F₀ at random points (which also
                // fixes every Fᵢ, i.e. the variable order), up to the congruence.
                for _ in 0..5 {
                    let x: Vec<f64> = (0..reference.num_vars()).map(|_| rnd()).collect();
                    let (s1, s2) = (sdp.problem().slack(&x).unwrap(), reference.slack(&x).unwrap());
                    let want =
                        if form == Formulation::Whitened { cong.transpose() * &s2[0] * &cong } else { s2[0].clone() };
                    let diff = (&s1[0] - &want).amax();
                    assert!(diff <= 1e-12 * (1.0 + want.amax()), "{form:?} n {n} m {m}: {diff:e}");
                }
            }
        }
    }

    #[test]
    fn update_keeps_the_structure_and_errors_are_named() {
        let (a, c, q, r, p, x) = data_case();
        let d = FilterSdpData { a: &a, c: &c, q: &q, r: &r, p: &p, x_hat: &x };
        let mut sdp = FilterSdp::new(&d).unwrap();
        let before = sdp.problem().clone();
        let a2 = DMatrix::zeros(2, 2);
        sdp.update(&FilterSdpData { a: &a2, ..d }).unwrap();
        assert!(sdp.problem().same_structure(&before));
        assert_ne!(sdp.problem(), &before);
        let bad_q = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        let snapshot = sdp.problem().clone();
        let err = sdp.update(&FilterSdpData { q: &bad_q, ..d }).unwrap_err();
        assert_eq!(err.to_string(), "Q is not symmetric positive definite");
        assert_eq!(sdp.problem(), &snapshot);
        let c3 = DMatrix::zeros(1, 3);
        let err = FilterSdp::new(&FilterSdpData { c: &c3, ..d }).unwrap_err();
        assert!(err.to_string().contains("columns of C"), "{err}");
        let nan = DMatrix::from_element(2, 2, f64::NAN);
        let err = FilterSdp::new(&FilterSdpData { a: &nan, ..d }).unwrap_err();
        assert!(err.to_string().contains("A has a non-finite entry"), "{err}");
    }

    #[test]
    fn both_statements_have_the_same_optimum() {
        // Random systems with well- and ill-conditioned noise shapes (eigenvalues over 4 decades):
        // the whitened, row-scaled statement and the literal one are congruent, so faer-ipm must
        // find the same objective (here within 1e-8 relative) and multipliers (to the accuracy the
        // tolerance 1e-9 allows).
        let mut g = dense_kernels::test_data::XorShift(0x2545f4914f6cdd1d);
        let mut rnd = move || g.centred();
        let settings = lmi::SolverSettings::builder().tolerance(1e-9).build().unwrap();
        for k in 0..6 {
            let (n, m) = (2 + k % 4, 1 + k % 2);
            let spd = |d: usize, decades: f64, rnd: &mut dyn FnMut() -> f64| {
                let u = DMatrix::from_fn(d, d, |_, _| rnd()).qr().q();
                let e = DVector::from_fn(d, |i, _| 10f64.powf(-decades * i as f64 / d.max(2) as f64));
                &u * DMatrix::from_diagonal(&e) * u.transpose()
            };
            let decades = if k % 2 == 0 { 4.0 } else { 0.5 };
            let a = DMatrix::from_fn(n, n, |i, j| if i == j { 0.9 } else { 0.3 * rnd() });
            let c = DMatrix::from_fn(m, n, |_, _| rnd());
            let (q, r, p) = (spd(n, decades, &mut rnd) * 0.01, spd(m, decades, &mut rnd) * 0.05, spd(n, 1.0, &mut rnd));
            let x = DVector::from_fn(n, |_, _| rnd());
            let d = FilterSdpData { a: &a, c: &c, q: &q, r: &r, p: &p, x_hat: &x };
            let mut out = vec![];
            for form in [Formulation::AsStated, Formulation::Whitened] {
                let sdp = FilterSdp::with_formulation(&d, form).unwrap();
                let mut ipm = lmi::FaerIpm::new(settings.clone()).unwrap();
                let sol = lmi::SdpBackend::setup_and_solve(&mut ipm, sdp.problem()).unwrap();
                // Measured: the literal form ends `AlmostSolved` in 2 of the 6 cases (11–17
                // iterations), the default one `Solved` in all (10–13).
                let want = if form == Formulation::Whitened {
                    sol.status == lmi::SolveStatus::Solved
                } else {
                    sol.status.is_optimal()
                };
                assert!(want, "case {k} {form:?}: {}", sol.status);
                out.push((sol.primal_objective, sdp.read(&sol.x, &d).unwrap().tau));
            }
            let rel = (out[0].0 - out[1].0).abs() / out[0].0.abs();
            assert!(rel < 1e-7, "case {k}: objectives {} and {} ({rel:e})", out[0].0, out[1].0);
            for (a, b) in out[0].1.iter().zip(&out[1].1) {
                assert!((a - b).abs() < 1e-3, "case {k}: tau {:?} vs {:?}", out[0].1, out[1].1);
            }
        }
    }
}
