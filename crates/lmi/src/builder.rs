//! A small builder for LMIs whose blocks are affine in named decision variables.
//!
//! Variables are declared with a name and a shape (scalar, symmetric matrix, full matrix); an
//! [`AffineMatrix`] is a matrix whose entries are affine in the scalar unknowns. Blocks are
//! stated as `F(x) ⪰ 0` (or a scalar `≥ 0`) and the objective as an affine expression to
//! minimise; [`LmiBuilder::build`] returns the SDPA-form [`SdpProblem`] and a [`VariableMap`]
//! that reads the named variables back from a solution vector.
//!
//! ```
//! use lmi::builder::{AffineMatrix, LmiBuilder};
//! use nalgebra::DMatrix;
//! // minimise t subject to [[t, 2], [2, 1]] ⪰ 0   (optimum t = 4)
//! let mut b = LmiBuilder::new();
//! let t = b.scalar("t").unwrap();
//! let t_expr = b.expr(t).unwrap();
//! let two = DMatrix::from_row_slice(2, 2, &[0.0, 2.0, 2.0, 1.0]);
//! let lmi = AffineMatrix::constant(&two)
//!     .add(&AffineMatrix::constant_times(&DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 0.0]), &t_expr))
//!     .unwrap();
//! b.psd(lmi).unwrap();
//! b.minimize(t_expr);
//! let (problem, map) = b.build().unwrap();
//! assert_eq!(problem.num_vars(), 1);
//! assert_eq!(map.scalar(&[4.0], t).unwrap(), 4.0);
//! ```

use nalgebra::DMatrix;

use crate::error::LmiError;
use crate::problem::{Block, Entry, SdpProblem};

/// Shape of a named decision variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum VarShape {
    /// One scalar.
    Scalar,
    /// A symmetric `n × n` matrix (`n(n+1)/2` scalars, upper triangle column by column).
    Symmetric(usize),
    /// A full `rows × cols` matrix (column-major scalars).
    Matrix(usize, usize),
}

impl VarShape {
    fn num_scalars(self) -> usize {
        match self {
            VarShape::Scalar => 1,
            VarShape::Symmetric(n) => n * (n + 1) / 2,
            VarShape::Matrix(r, c) => r * c,
        }
    }
}

/// Handle of a named variable declared in an [`LmiBuilder`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Var {
    id: usize,
    shape: VarShape,
    offset: usize,
}

impl Var {
    /// The variable's shape.
    pub fn shape(&self) -> VarShape {
        self.shape
    }

    /// Index in the decision vector `x` of entry `(i, j)` (`(0, 0)` for a scalar).
    pub fn scalar_index(&self, i: usize, j: usize) -> Option<usize> {
        match self.shape {
            VarShape::Scalar => (i == 0 && j == 0).then_some(self.offset),
            VarShape::Symmetric(n) => {
                if i >= n || j >= n {
                    return None;
                }
                let (r, c) = if i <= j { (i, j) } else { (j, i) };
                Some(self.offset + c * (c + 1) / 2 + r)
            }
            VarShape::Matrix(rows, cols) => (i < rows && j < cols).then_some(self.offset + j * rows + i),
        }
    }
}

/// An affine expression `constant + Σ coefᵢ xᵢ` in the scalar unknowns.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Affine {
    /// The constant term.
    pub constant: f64,
    /// `(index into x, coefficient)` pairs; an index may appear more than once (summed).
    pub terms: Vec<(usize, f64)>,
}

impl Affine {
    /// A constant expression.
    pub fn constant(value: f64) -> Self {
        Self { constant: value, terms: Vec::new() }
    }

    /// The scalar unknown `x[index]`.
    pub fn unknown(index: usize) -> Self {
        Self { constant: 0.0, terms: vec![(index, 1.0)] }
    }

    /// `self + other`.
    pub fn add(&self, other: &Affine) -> Affine {
        let mut terms = self.terms.clone();
        terms.extend_from_slice(&other.terms);
        Affine { constant: self.constant + other.constant, terms }
    }

    /// `self − other`.
    pub fn sub(&self, other: &Affine) -> Affine {
        self.add(&other.scale(-1.0))
    }

    /// `k · self`.
    pub fn scale(&self, k: f64) -> Affine {
        Affine { constant: k * self.constant, terms: self.terms.iter().map(|&(i, c)| (i, k * c)).collect() }
    }

    /// Value at `x`; an index beyond `x` is an error.
    pub fn eval(&self, x: &[f64]) -> Result<f64, LmiError> {
        let mut v = self.constant;
        for &(i, c) in &self.terms {
            let xi = x.get(i).ok_or_else(|| LmiError::UnknownVariable(format!("x[{i}] of {} unknowns", x.len())))?;
            v += c * xi;
        }
        Ok(v)
    }

    /// Terms sorted by index with repeated indices summed (coefficients that cancel to zero are
    /// kept, so that the structure does not depend on the data).
    fn merged_terms(&self) -> Vec<(usize, f64)> {
        let mut t = self.terms.clone();
        t.sort_by_key(|&(i, _)| i);
        let mut out: Vec<(usize, f64)> = Vec::with_capacity(t.len());
        for (i, c) in t {
            match out.last_mut() {
                Some(last) if last.0 == i => last.1 += c,
                _ => out.push((i, c)),
            }
        }
        out
    }
}

/// A matrix whose entries are [`Affine`] expressions (column-major storage).
#[derive(Debug, Clone, PartialEq)]
pub struct AffineMatrix {
    rows: usize,
    cols: usize,
    data: Vec<Affine>,
}

impl AffineMatrix {
    /// The `rows × cols` zero matrix.
    pub fn zeros(rows: usize, cols: usize) -> Self {
        Self { rows, cols, data: vec![Affine::default(); rows * cols] }
    }

    /// A constant matrix.
    pub fn constant(m: &DMatrix<f64>) -> Self {
        let mut out = Self::zeros(m.nrows(), m.ncols());
        for j in 0..m.ncols() {
            for i in 0..m.nrows() {
                out.data[j * m.nrows() + i].constant = m[(i, j)];
            }
        }
        out
    }

    /// The constant matrix `m` times the scalar expression `s` (for example `τ₂ Q⁻¹`).
    pub fn constant_times(m: &DMatrix<f64>, s: &Affine) -> Self {
        let mut out = Self::zeros(m.nrows(), m.ncols());
        for j in 0..m.ncols() {
            for i in 0..m.nrows() {
                out.data[j * m.nrows() + i] = s.scale(m[(i, j)]);
            }
        }
        out
    }

    /// Number of rows.
    pub fn nrows(&self) -> usize {
        self.rows
    }

    /// Number of columns.
    pub fn ncols(&self) -> usize {
        self.cols
    }

    /// Entry `(i, j)`.
    pub fn get(&self, i: usize, j: usize) -> Option<&Affine> {
        (i < self.rows && j < self.cols).then(|| &self.data[j * self.rows + i])
    }

    fn at(&self, i: usize, j: usize) -> &Affine {
        &self.data[j * self.rows + i]
    }

    fn same_shape(&self, other: &AffineMatrix, op: &'static str) -> Result<(), LmiError> {
        if self.rows != other.rows || self.cols != other.cols {
            return Err(LmiError::InvalidProblem(format!(
                "{op} of a {}x{} and a {}x{} matrix",
                self.rows, self.cols, other.rows, other.cols
            )));
        }
        Ok(())
    }

    /// `self + other`.
    pub fn add(&self, other: &AffineMatrix) -> Result<AffineMatrix, LmiError> {
        self.same_shape(other, "sum")?;
        let data = self.data.iter().zip(&other.data).map(|(a, b)| a.add(b)).collect();
        Ok(AffineMatrix { rows: self.rows, cols: self.cols, data })
    }

    /// `self − other`.
    pub fn sub(&self, other: &AffineMatrix) -> Result<AffineMatrix, LmiError> {
        self.same_shape(other, "difference")?;
        let data = self.data.iter().zip(&other.data).map(|(a, b)| a.sub(b)).collect();
        Ok(AffineMatrix { rows: self.rows, cols: self.cols, data })
    }

    /// `k · self`.
    pub fn scale(&self, k: f64) -> AffineMatrix {
        AffineMatrix { rows: self.rows, cols: self.cols, data: self.data.iter().map(|a| a.scale(k)).collect() }
    }

    /// The transpose.
    pub fn transpose(&self) -> AffineMatrix {
        let mut out = Self::zeros(self.cols, self.rows);
        for j in 0..self.cols {
            for i in 0..self.rows {
                out.data[i * self.cols + j] = self.at(i, j).clone();
            }
        }
        out
    }

    /// `self · m` for a constant matrix `m` (all products are kept, even with zero factors, so
    /// the sparsity structure depends only on the shapes).
    pub fn mul_right(&self, m: &DMatrix<f64>) -> Result<AffineMatrix, LmiError> {
        if self.cols != m.nrows() {
            return Err(LmiError::InvalidProblem(format!(
                "product of a {}x{} affine matrix and a {}x{} matrix",
                self.rows,
                self.cols,
                m.nrows(),
                m.ncols()
            )));
        }
        let mut out = Self::zeros(self.rows, m.ncols());
        for j in 0..m.ncols() {
            for i in 0..self.rows {
                let mut acc = Affine::default();
                for k in 0..self.cols {
                    acc = acc.add(&self.at(i, k).scale(m[(k, j)]));
                }
                out.data[j * self.rows + i] = acc;
            }
        }
        Ok(out)
    }

    /// `m · self` for a constant matrix `m`.
    pub fn mul_left(&self, m: &DMatrix<f64>) -> Result<AffineMatrix, LmiError> {
        Ok(self.transpose().mul_right(&m.transpose())?.transpose())
    }

    /// Assembles a block matrix from rows of blocks; blocks in a row share their row count and
    /// blocks in a column share their column count.
    pub fn block(rows: &[&[&AffineMatrix]]) -> Result<AffineMatrix, LmiError> {
        let Some(first_row) = rows.first().filter(|r| !r.is_empty()) else {
            return Err(LmiError::InvalidProblem("empty block matrix".into()));
        };
        let col_widths: Vec<usize> = first_row.iter().map(|b| b.cols).collect();
        let total_cols: usize = col_widths.iter().sum();
        let mut total_rows = 0;
        for (r, row) in rows.iter().enumerate() {
            if row.len() != col_widths.len() {
                return Err(LmiError::InvalidProblem(format!(
                    "block row {r} has {} blocks, expected {}",
                    row.len(),
                    col_widths.len()
                )));
            }
            let h = row[0].rows;
            for (c, b) in row.iter().enumerate() {
                if b.rows != h || b.cols != col_widths[c] {
                    return Err(LmiError::InvalidProblem(format!(
                        "block ({r}, {c}) is {}x{}, expected {h}x{}",
                        b.rows, b.cols, col_widths[c]
                    )));
                }
            }
            total_rows += h;
        }
        let mut out = Self::zeros(total_rows, total_cols);
        let mut r0 = 0;
        for row in rows {
            let mut c0 = 0;
            for b in row.iter() {
                for j in 0..b.cols {
                    for i in 0..b.rows {
                        out.data[(c0 + j) * total_rows + r0 + i] = b.at(i, j).clone();
                    }
                }
                c0 += b.cols;
            }
            r0 += row[0].rows;
        }
        Ok(out)
    }

    /// A block-diagonal matrix of the given square or rectangular blocks (zeros elsewhere).
    pub fn diag(blocks: &[&AffineMatrix]) -> AffineMatrix {
        let rows = blocks.iter().map(|b| b.rows).sum();
        let cols = blocks.iter().map(|b| b.cols).sum();
        let mut out = Self::zeros(rows, cols);
        let (mut r0, mut c0) = (0, 0);
        for b in blocks {
            for j in 0..b.cols {
                for i in 0..b.rows {
                    out.data[(c0 + j) * rows + r0 + i] = b.at(i, j).clone();
                }
            }
            r0 += b.rows;
            c0 += b.cols;
        }
        out
    }

    /// The trace (an affine scalar).
    pub fn trace(&self) -> Affine {
        let mut acc = Affine::default();
        for i in 0..self.rows.min(self.cols) {
            acc = acc.add(self.at(i, i));
        }
        acc
    }

    /// Value at `x`; an index beyond `x` is an error.
    pub fn eval(&self, x: &[f64]) -> Result<DMatrix<f64>, LmiError> {
        let mut out = DMatrix::zeros(self.rows, self.cols);
        for j in 0..self.cols {
            for i in 0..self.rows {
                out[(i, j)] = self.at(i, j).eval(x)?;
            }
        }
        Ok(out)
    }
}

#[derive(Debug, Clone)]
struct VarInfo {
    name: String,
    var: Var,
}

/// Declares named variables, collects LMI blocks and an objective, and emits an [`SdpProblem`].
#[derive(Debug, Clone, Default)]
pub struct LmiBuilder {
    vars: Vec<VarInfo>,
    num_scalars: usize,
    psd_blocks: Vec<AffineMatrix>,
    nonneg: Vec<Affine>,
    objective: Affine,
    keep_zeros: bool,
}

impl LmiBuilder {
    /// An empty builder.
    pub fn new() -> Self {
        Self::default()
    }

    /// Keep entries whose value is zero (every upper-triangle position of every PSD block in
    /// `F₀`, and every variable term that appears symbolically). Use this when the same problem
    /// is rebuilt with new numbers and its structure must not depend on them.
    pub fn keep_structural_zeros(mut self, keep: bool) -> Self {
        self.keep_zeros = keep;
        self
    }

    fn declare(&mut self, name: &str, shape: VarShape) -> Result<Var, LmiError> {
        if self.vars.iter().any(|v| v.name == name) {
            return Err(LmiError::InvalidProblem(format!("variable {name:?} declared twice")));
        }
        if shape.num_scalars() == 0 {
            return Err(LmiError::InvalidProblem(format!("variable {name:?} has no entries")));
        }
        let var = Var { id: self.vars.len(), shape, offset: self.num_scalars };
        self.num_scalars += shape.num_scalars();
        self.vars.push(VarInfo { name: name.to_owned(), var });
        Ok(var)
    }

    /// Declares a scalar variable.
    pub fn scalar(&mut self, name: &str) -> Result<Var, LmiError> {
        self.declare(name, VarShape::Scalar)
    }

    /// Declares a symmetric `n × n` matrix variable.
    pub fn symmetric(&mut self, name: &str, n: usize) -> Result<Var, LmiError> {
        self.declare(name, VarShape::Symmetric(n))
    }

    /// Declares a full `rows × cols` matrix variable.
    pub fn matrix(&mut self, name: &str, rows: usize, cols: usize) -> Result<Var, LmiError> {
        self.declare(name, VarShape::Matrix(rows, cols))
    }

    fn check_var(&self, var: Var) -> Result<(), LmiError> {
        match self.vars.get(var.id) {
            Some(v) if v.var == var => Ok(()),
            _ => Err(LmiError::UnknownVariable(format!("handle {var:?} is not from this builder"))),
        }
    }

    /// A scalar variable as an affine expression.
    pub fn expr(&self, var: Var) -> Result<Affine, LmiError> {
        self.check_var(var)?;
        match var.shape {
            VarShape::Scalar => Ok(Affine::unknown(var.offset)),
            _ => Err(LmiError::InvalidProblem(format!(
                "variable {:?} is not a scalar; use `matrix_expr`",
                self.vars[var.id].name
            ))),
        }
    }

    /// A variable as an affine matrix (a scalar as `1 × 1`).
    pub fn matrix_expr(&self, var: Var) -> Result<AffineMatrix, LmiError> {
        self.check_var(var)?;
        let (rows, cols) = match var.shape {
            VarShape::Scalar => (1, 1),
            VarShape::Symmetric(n) => (n, n),
            VarShape::Matrix(r, c) => (r, c),
        };
        let mut out = AffineMatrix::zeros(rows, cols);
        for j in 0..cols {
            for i in 0..rows {
                // tidy: invariant — (i, j) ranges over the variable's own shape.
                let idx = var.scalar_index(i, j).expect("index inside the variable's shape");
                out.data[j * rows + i] = Affine::unknown(idx);
            }
        }
        Ok(out)
    }

    fn check_indices(&self, a: &Affine) -> Result<(), LmiError> {
        if !a.constant.is_finite() {
            return Err(LmiError::InvalidProblem(format!("constant {} is not finite", a.constant)));
        }
        for &(i, c) in &a.terms {
            if i >= self.num_scalars {
                return Err(LmiError::UnknownVariable(format!("scalar index {i} of {}", self.num_scalars)));
            }
            if !c.is_finite() {
                return Err(LmiError::InvalidProblem(format!("coefficient {c} of x[{i}] is not finite")));
            }
        }
        Ok(())
    }

    /// Adds the constraint `m ⪰ 0`; `m` must be square and symmetric (entry `(i, j)` and
    /// `(j, i)` equal as affine expressions, within `1e-12` relative per coefficient).
    pub fn psd(&mut self, m: AffineMatrix) -> Result<(), LmiError> {
        if m.rows != m.cols || m.rows == 0 {
            return Err(LmiError::InvalidProblem(format!("a PSD block must be square, got {}x{}", m.rows, m.cols)));
        }
        for j in 0..m.cols {
            for i in 0..=j {
                let (a, b) = (m.at(i, j), m.at(j, i));
                self.check_indices(a)?;
                self.check_indices(b)?;
                let close = |x: f64, y: f64| (x - y).abs() <= 1e-12 * (1.0 + x.abs().max(y.abs()));
                let (ta, tb) = (a.merged_terms(), b.merged_terms());
                let same = close(a.constant, b.constant) && merged_close(&ta, &tb, &close);
                if !same {
                    return Err(LmiError::InvalidProblem(format!("PSD block is not symmetric at ({i}, {j})")));
                }
            }
        }
        self.psd_blocks.push(m);
        Ok(())
    }

    /// Adds the constraint `a ≥ 0` (collected into one nonnegative block).
    pub fn nonnegative(&mut self, a: Affine) -> Result<(), LmiError> {
        self.check_indices(&a)?;
        self.nonneg.push(a);
        Ok(())
    }

    /// Sets the objective to minimise (a constant part is kept in the [`VariableMap`]).
    pub fn minimize(&mut self, objective: Affine) {
        self.objective = objective;
    }

    /// Emits the SDPA-form problem: each block `F(x) = F′₀ + Σ xᵢ F′ᵢ ⪰ 0` becomes
    /// `X = Σ xᵢ Fᵢ − F₀` with `F₀ = −F′₀`, `Fᵢ = F′ᵢ`.
    pub fn build(&self) -> Result<(SdpProblem, VariableMap), LmiError> {
        if self.num_scalars == 0 {
            return Err(LmiError::InvalidProblem("no variables declared".into()));
        }
        self.check_indices(&self.objective)?;
        let mut c = vec![0.0; self.num_scalars];
        for &(i, k) in &self.objective.terms {
            c[i] += k;
        }
        let mut blocks = Vec::new();
        let mut entries = Vec::new();
        let push = |entries: &mut Vec<Entry>, block: usize, row: usize, col: usize, a: &Affine, zeros: bool| {
            if zeros || a.constant != 0.0 {
                entries.push(Entry { mat: 0, block, row, col, value: -a.constant });
            }
            for (i, k) in a.merged_terms() {
                if zeros || k != 0.0 {
                    entries.push(Entry { mat: i + 1, block, row, col, value: k });
                }
            }
        };
        for m in &self.psd_blocks {
            let b = blocks.len();
            blocks.push(Block::Psd(m.rows));
            for j in 0..m.cols {
                for i in 0..=j {
                    push(&mut entries, b, i, j, m.at(i, j), self.keep_zeros);
                }
            }
        }
        if !self.nonneg.is_empty() {
            let b = blocks.len();
            blocks.push(Block::Nonneg(self.nonneg.len()));
            for (i, a) in self.nonneg.iter().enumerate() {
                push(&mut entries, b, i, i, a, self.keep_zeros);
            }
        }
        if blocks.is_empty() {
            return Err(LmiError::InvalidProblem("no constraints: add a PSD or nonnegative block".into()));
        }
        let problem = SdpProblem::new(blocks, c, entries)?;
        let map = VariableMap {
            vars: self.vars.clone(),
            num_scalars: self.num_scalars,
            objective_constant: self.objective.constant,
        };
        Ok((problem, map))
    }
}

fn merged_close(a: &[(usize, f64)], b: &[(usize, f64)], close: &impl Fn(f64, f64) -> bool) -> bool {
    // Compare two sorted term lists, treating absent terms as zero.
    let (mut p, mut q) = (0, 0);
    while p < a.len() || q < b.len() {
        let (ia, ib) = (a.get(p).map(|t| t.0), b.get(q).map(|t| t.0));
        let (x, y) = match (ia, ib) {
            (Some(i), Some(j)) if i == j => {
                p += 1;
                q += 1;
                (a[p - 1].1, b[q - 1].1)
            }
            (Some(i), Some(j)) if i < j => {
                p += 1;
                (a[p - 1].1, 0.0)
            }
            (Some(_), None) => {
                p += 1;
                (a[p - 1].1, 0.0)
            }
            _ => {
                q += 1;
                (0.0, b[q - 1].1)
            }
        };
        if !close(x, y) {
            return false;
        }
    }
    true
}

/// Reads named variables back from a decision vector produced for the built problem.
#[derive(Debug, Clone)]
pub struct VariableMap {
    vars: Vec<VarInfo>,
    num_scalars: usize,
    objective_constant: f64,
}

impl VariableMap {
    /// Length of the decision vector.
    pub fn num_scalars(&self) -> usize {
        self.num_scalars
    }

    /// Constant part of the objective (not represented in the SDPA problem).
    pub fn objective_constant(&self) -> f64 {
        self.objective_constant
    }

    /// The handle of the variable called `name`.
    pub fn var(&self, name: &str) -> Result<Var, LmiError> {
        self.vars
            .iter()
            .find(|v| v.name == name)
            .map(|v| v.var)
            .ok_or_else(|| LmiError::UnknownVariable(name.to_owned()))
    }

    fn check(&self, x: &[f64], var: Var) -> Result<(), LmiError> {
        if x.len() != self.num_scalars {
            return Err(LmiError::DimensionMismatch {
                what: "decision vector x",
                expected: self.num_scalars,
                found: x.len(),
            });
        }
        match self.vars.get(var.id) {
            Some(v) if v.var == var => Ok(()),
            _ => Err(LmiError::UnknownVariable(format!("handle {var:?} is not in this map"))),
        }
    }

    /// Value of a scalar variable.
    pub fn scalar(&self, x: &[f64], var: Var) -> Result<f64, LmiError> {
        self.check(x, var)?;
        match var.shape {
            VarShape::Scalar => Ok(x[var.offset]),
            _ => Err(LmiError::InvalidProblem(format!("variable {:?} is not a scalar", self.vars[var.id].name))),
        }
    }

    /// Value of a matrix variable (symmetric or full; a scalar as `1 × 1`).
    pub fn matrix(&self, x: &[f64], var: Var) -> Result<DMatrix<f64>, LmiError> {
        self.check(x, var)?;
        let (rows, cols) = match var.shape {
            VarShape::Scalar => (1, 1),
            VarShape::Symmetric(n) => (n, n),
            VarShape::Matrix(r, c) => (r, c),
        };
        // tidy: invariant — (i, j) ranges over the variable's own shape (checked above).
        Ok(DMatrix::from_fn(rows, cols, |i, j| x[var.scalar_index(i, j).expect("inside shape")]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn symmetric_variable_packs_upper_triangle() {
        let mut b = LmiBuilder::new();
        let s = b.scalar("s").unwrap();
        let p = b.symmetric("P", 3).unwrap();
        let l = b.matrix("L", 3, 2).unwrap();
        assert_eq!(s.scalar_index(0, 0), Some(0));
        assert_eq!(p.scalar_index(0, 0), Some(1));
        assert_eq!(p.scalar_index(0, 1), Some(2));
        assert_eq!(p.scalar_index(1, 0), Some(2));
        assert_eq!(p.scalar_index(2, 2), Some(6));
        assert_eq!(l.scalar_index(2, 1), Some(7 + 5));
        assert_eq!(l.scalar_index(3, 0), None);
        let pm = b.matrix_expr(p).unwrap();
        b.psd(pm.clone()).unwrap();
        b.minimize(pm.trace());
        let (prob, map) = b.build().unwrap();
        assert_eq!(prob.num_vars(), 13);
        assert_eq!(prob.c()[1], 1.0);
        assert_eq!(prob.c()[3], 1.0);
        assert_eq!(prob.c()[6], 1.0);
        let x: Vec<f64> = (0..13).map(f64::from).collect();
        let pv = map.matrix(&x, p).unwrap();
        assert_eq!(pv[(1, 2)], 5.0);
        assert_eq!(pv[(2, 1)], 5.0);
        assert_eq!(map.matrix(&x, l).unwrap()[(1, 1)], 11.0);
        assert_eq!(map.var("L").unwrap(), l);
        // The SDPA slack X(x) equals the affine matrix evaluated at x.
        let xs = prob.slack(&x).unwrap();
        assert_eq!(xs[0], pm.eval(&x).unwrap());
        assert!(pm.eval(&x[..3]).unwrap_err().to_string().contains("of 3 unknowns"));
    }

    #[test]
    fn block_products_and_transposes_evaluate_like_dense_algebra() {
        let mut b = LmiBuilder::new();
        let l = b.matrix("L", 2, 3).unwrap();
        let lm = b.matrix_expr(l).unwrap();
        let c = DMatrix::from_row_slice(3, 2, &[1.0, 2.0, -1.0, 0.5, 3.0, 0.0]);
        let a = DMatrix::from_row_slice(2, 2, &[0.5, 1.0, -2.0, 4.0]);
        let x: Vec<f64> = (0..6).map(|i| 0.3 * i as f64 - 0.7).collect();
        let lv = DMatrix::from_column_slice(2, 3, &x);
        assert_eq!(lm.eval(&x).unwrap(), lv);
        let prod = lm.mul_right(&c).unwrap();
        assert!((prod.eval(&x).unwrap() - &lv * &c).abs().max() < 1e-14);
        let left = lm.mul_left(&a).unwrap();
        assert!((left.eval(&x).unwrap() - &a * &lv).abs().max() < 1e-14);
        let blk =
            AffineMatrix::block(&[&[&AffineMatrix::constant(&a), &lm], &[&lm.transpose(), &AffineMatrix::zeros(3, 3)]])
                .unwrap();
        let v = blk.eval(&x).unwrap();
        assert_eq!(v.nrows(), 5);
        assert_eq!(v[(0, 3)], lv[(0, 1)]);
        assert_eq!(v[(3, 0)], lv[(0, 1)]);
        assert!(AffineMatrix::block(&[&[&lm], &[&AffineMatrix::zeros(2, 2)]]).is_err());
        assert!(AffineMatrix::block(&[&[]]).unwrap_err().to_string().contains("empty block matrix"));
        assert!(AffineMatrix::block(&[]).is_err());
    }

    #[test]
    fn errors_name_the_problem() {
        let mut b = LmiBuilder::new();
        let t = b.scalar("t").unwrap();
        assert!(b.scalar("t").unwrap_err().to_string().contains("declared twice"));
        assert!(b.symmetric("Z", 0).unwrap_err().to_string().contains("no entries"));
        let mut other = LmiBuilder::new();
        other.scalar("a").unwrap();
        let a2 = other.scalar("b").unwrap();
        assert!(b.expr(a2).unwrap_err().to_string().contains("not from this builder"));
        let ns =
            AffineMatrix::block(&[&[&AffineMatrix::constant(&DMatrix::from_row_slice(1, 2, &[1.0, 2.0]))]]).unwrap();
        assert!(b.psd(ns).unwrap_err().to_string().contains("square"));
        let te = b.expr(t).unwrap();
        let asym = AffineMatrix::block(&[
            &[&AffineMatrix::constant_times(&DMatrix::from_element(1, 1, 1.0), &te), &AffineMatrix::zeros(1, 1)],
            &[&AffineMatrix::constant(&DMatrix::from_element(1, 1, 1.0)), &AffineMatrix::zeros(1, 1)],
        ])
        .unwrap();
        assert!(b.psd(asym).unwrap_err().to_string().contains("not symmetric at (0, 1)"));
        assert!(b.nonnegative(Affine::constant(f64::NAN)).unwrap_err().to_string().contains("not finite"));
        assert!(b.build().unwrap_err().to_string().contains("no constraints"));
        b.nonnegative(te).unwrap();
        let (_, map) = b.build().unwrap();
        assert!(map.scalar(&[1.0, 2.0], t).unwrap_err().to_string().contains("decision vector"));
        assert!(map.var("nope").unwrap_err().to_string().contains("nope"));
    }

    #[test]
    fn structural_zeros_make_the_structure_data_independent() {
        let build = |v: f64| {
            let mut b = LmiBuilder::new().keep_structural_zeros(true);
            let t = b.scalar("t").unwrap();
            let te = b.expr(t).unwrap();
            let m = DMatrix::from_row_slice(2, 2, &[v, 0.0, 0.0, 1.0]);
            b.psd(AffineMatrix::constant_times(&m, &te).add(&AffineMatrix::constant(&m)).unwrap()).unwrap();
            b.minimize(te);
            b.build().unwrap().0
        };
        assert!(build(0.0).same_structure(&build(2.0)));
    }
}
