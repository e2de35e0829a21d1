//! Data-only description of a block-diagonal SDP in SDPA standard form.
//!
//! ```text
//! (P)  minimise  cᵀx              subject to  X = Σᵢ xᵢ Fᵢ − F₀ ⪰ 0
//! (D)  maximise  tr(F₀ Y)         subject to  tr(Fᵢ Y) = cᵢ (i = 1..m),  Y ⪰ 0
//! ```
//!
//! Throughout this crate, **primal** means (P), the problem in the decision vector `x`, and
//! **dual** means (D), the problem in the block matrix `Y`. This is SDPA's naming. CSDP (and the
//! SDPLIB paper) call (D) the primal; Clarabel's primal is (P) written as `Ax + s = b`, `s ∈ K`.
//! A *primal infeasible* outcome therefore means that no `x` makes `X ⪰ 0`; it is certified by a
//! `Y ⪰ 0` with `tr(Fᵢ Y) = 0` and `tr(F₀ Y) > 0`. *Dual infeasible* means that no `Y` satisfies
//! the equalities; it is certified by an `x` with `Σ xᵢ Fᵢ ⪰ 0` and `cᵀx < 0` (then (P) is
//! unbounded if it is feasible).
//!
//! All `Fᵢ` share one block-diagonal structure; a block is either a dense symmetric block
//! ([`Block::Psd`]) or a diagonal block of nonnegative scalars ([`Block::Nonneg`]).

use crate::error::LmiError;

/// One diagonal block of the block-diagonal structure.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Block {
    /// A dense symmetric block of the given order that must be positive semidefinite.
    Psd(usize),
    /// A diagonal block of the given size: that many nonnegative scalars (an LP cone).
    Nonneg(usize),
}

impl Block {
    /// Order of the block (the number of rows of the square block).
    pub fn size(&self) -> usize {
        match *self {
            Block::Psd(n) | Block::Nonneg(n) => n,
        }
    }

    /// Number of independent entries: `n(n+1)/2` for a PSD block, `n` for a nonnegative block.
    pub fn num_entries(&self) -> usize {
        match *self {
            Block::Psd(n) => n * (n + 1) / 2,
            Block::Nonneg(n) => n,
        }
    }
}

/// One nonzero entry of one of the matrices `F₀ … F_m`, upper triangle (`row ≤ col`), 0-based.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Entry {
    /// Which matrix: `0` for `F₀`, `i` for `Fᵢ` (the coefficient of `xᵢ`, 1-based as in SDPA).
    pub mat: usize,
    /// Which block (0-based).
    pub block: usize,
    /// Row inside the block (0-based), `row ≤ col`.
    pub row: usize,
    /// Column inside the block (0-based).
    pub col: usize,
    /// The value; the symmetric entry `(col, row)` has the same value.
    pub value: f64,
}

impl Entry {
    fn key(&self) -> (usize, usize, usize, usize) {
        (self.mat, self.block, self.col, self.row)
    }
}

/// A block-diagonal SDP in SDPA standard form (see the module documentation).
///
/// Entries are kept sorted by `(mat, block, col, row)` without duplicates, so two problems with
/// the same sparsity pattern list their entries in the same order: a backend can analyse the
/// pattern once ([`crate::SdpBackend::setup`]) and then read only the values.
#[derive(Debug, Clone, PartialEq)]
pub struct SdpProblem {
    num_vars: usize,
    blocks: Vec<Block>,
    c: Vec<f64>,
    entries: Vec<Entry>,
}

impl SdpProblem {
    /// Validates and builds a problem with `c.len()` variables.
    ///
    /// Entries may come in any order; duplicates are an error. Entries of a
    /// [`Block::Nonneg`] block must be on the diagonal. Errors name the offending entry.
    pub fn new(blocks: Vec<Block>, c: Vec<f64>, mut entries: Vec<Entry>) -> Result<Self, LmiError> {
        let num_vars = c.len();
        if blocks.is_empty() {
            return Err(LmiError::InvalidProblem("the problem has no blocks".into()));
        }
        for (b, blk) in blocks.iter().enumerate() {
            if blk.size() == 0 {
                return Err(LmiError::InvalidProblem(format!("block {b} has size 0")));
            }
        }
        if let Some(i) = c.iter().position(|v| !v.is_finite()) {
            return Err(LmiError::InvalidProblem(format!("objective coefficient c[{i}] is not finite ({})", c[i])));
        }
        for e in &entries {
            check_entry(e, num_vars, &blocks)?;
        }
        entries.sort_by_key(Entry::key);
        for w in entries.windows(2) {
            if w[0].key() == w[1].key() {
                let e = w[1];
                return Err(LmiError::InvalidProblem(format!(
                    "duplicate entry: matrix {}, block {}, ({}, {})",
                    e.mat, e.block, e.row, e.col
                )));
            }
        }
        Ok(Self { num_vars, blocks, c, entries })
    }

    /// Number of decision variables `m` (the length of `x`).
    pub fn num_vars(&self) -> usize {
        self.num_vars
    }

    /// The block structure.
    pub fn blocks(&self) -> &[Block] {
        &self.blocks
    }

    /// The objective vector `c`.
    pub fn c(&self) -> &[f64] {
        &self.c
    }

    /// All nonzero entries, sorted by `(mat, block, col, row)`.
    pub fn entries(&self) -> &[Entry] {
        &self.entries
    }

    /// Whether `other` has the same sizes, blocks and entry positions (values may differ).
    pub fn same_structure(&self, other: &SdpProblem) -> bool {
        self.num_vars == other.num_vars
            && self.blocks == other.blocks
            && self.entries.len() == other.entries.len()
            && self.entries.iter().zip(&other.entries).all(|(a, b)| a.key() == b.key())
    }

    /// Replaces the values of the objective and of the entries, keeping the structure.
    ///
    /// `values[k]` is the new value of `entries()[k]`. Does not allocate. On error the problem
    /// is unchanged.
    pub fn set_values(&mut self, c: &[f64], values: &[f64]) -> Result<(), LmiError> {
        if c.len() != self.num_vars {
            return Err(LmiError::DimensionMismatch {
                what: "objective vector c",
                expected: self.num_vars,
                found: c.len(),
            });
        }
        if values.len() != self.entries.len() {
            return Err(LmiError::DimensionMismatch {
                what: "entry values",
                expected: self.entries.len(),
                found: values.len(),
            });
        }
        if let Some(i) = c.iter().position(|v| !v.is_finite()) {
            return Err(LmiError::InvalidProblem(format!("objective coefficient c[{i}] is not finite")));
        }
        if let Some(k) = values.iter().position(|v| !v.is_finite()) {
            let e = self.entries[k];
            return Err(LmiError::InvalidProblem(format!(
                "value of matrix {}, block {}, ({}, {}) is not finite",
                e.mat, e.block, e.row, e.col
            )));
        }
        self.c.copy_from_slice(c);
        for (e, v) in self.entries.iter_mut().zip(values) {
            e.value = *v;
        }
        Ok(())
    }

    /// Value of `X = Σ xᵢ Fᵢ − F₀` for the given `x`, as dense blocks (nonnegative blocks as
    /// diagonal matrices). Allocates; meant for checks and tests.
    pub fn slack(&self, x: &[f64]) -> Result<Vec<nalgebra::DMatrix<f64>>, LmiError> {
        if x.len() != self.num_vars {
            return Err(LmiError::DimensionMismatch {
                what: "decision vector x",
                expected: self.num_vars,
                found: x.len(),
            });
        }
        let mut out: Vec<_> = self.blocks.iter().map(|b| nalgebra::DMatrix::zeros(b.size(), b.size())).collect();
        for e in &self.entries {
            let coef = if e.mat == 0 { -1.0 } else { x[e.mat - 1] };
            let blk = &mut out[e.block];
            blk[(e.row, e.col)] += coef * e.value;
            if e.row != e.col {
                blk[(e.col, e.row)] += coef * e.value;
            }
        }
        Ok(out)
    }

    /// `tr(Fᵢ Y)` for `i = 0..=m`, for a dense block-diagonal `Y` (one matrix per block).
    /// Allocates; meant for checks and tests.
    pub fn traces(&self, y: &[nalgebra::DMatrix<f64>]) -> Result<Vec<f64>, LmiError> {
        if y.len() != self.blocks.len() {
            return Err(LmiError::DimensionMismatch {
                what: "number of blocks of Y",
                expected: self.blocks.len(),
                found: y.len(),
            });
        }
        for (b, (blk, yb)) in self.blocks.iter().zip(y).enumerate() {
            if yb.nrows() != blk.size() || yb.ncols() != blk.size() {
                return Err(LmiError::InvalidProblem(format!(
                    "block {b} of Y is {}x{}, expected {}x{}",
                    yb.nrows(),
                    yb.ncols(),
                    blk.size(),
                    blk.size()
                )));
            }
        }
        let mut t = vec![0.0; self.num_vars + 1];
        for e in &self.entries {
            let yb = &y[e.block];
            let v = if e.row == e.col {
                e.value * yb[(e.row, e.row)]
            } else {
                e.value * (yb[(e.row, e.col)] + yb[(e.col, e.row)])
            };
            t[e.mat] += v;
        }
        Ok(t)
    }
}

fn check_entry(e: &Entry, num_vars: usize, blocks: &[Block]) -> Result<(), LmiError> {
    let loc = || format!("matrix {}, block {}, ({}, {})", e.mat, e.block, e.row, e.col);
    if e.mat > num_vars {
        return Err(LmiError::InvalidProblem(format!(
            "entry {}: matrix index exceeds the number of variables {num_vars}",
            loc()
        )));
    }
    let Some(blk) = blocks.get(e.block) else {
        return Err(LmiError::InvalidProblem(format!(
            "entry {}: block index exceeds the number of blocks {}",
            loc(),
            blocks.len()
        )));
    };
    if e.row >= blk.size() || e.col >= blk.size() {
        return Err(LmiError::InvalidProblem(format!("entry {}: index outside a block of size {}", loc(), blk.size())));
    }
    if e.row > e.col {
        return Err(LmiError::InvalidProblem(format!(
            "entry {}: lower-triangle entry (give the upper triangle, row <= col)",
            loc()
        )));
    }
    if matches!(blk, Block::Nonneg(_)) && e.row != e.col {
        return Err(LmiError::InvalidProblem(format!(
            "entry {}: off-diagonal entry in a diagonal (nonnegative) block",
            loc()
        )));
    }
    if !e.value.is_finite() {
        return Err(LmiError::InvalidProblem(format!("entry {}: value is not finite", loc())));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn e(mat: usize, block: usize, row: usize, col: usize, value: f64) -> Entry {
        Entry { mat, block, row, col, value }
    }

    #[test]
    fn entries_are_sorted_and_structure_compares() {
        let p = SdpProblem::new(
            vec![Block::Psd(2), Block::Nonneg(1)],
            vec![1.0],
            vec![e(1, 0, 0, 1, 2.0), e(0, 1, 0, 0, 1.0), e(1, 0, 0, 0, 1.0)],
        )
        .unwrap();
        let keys: Vec<_> = p.entries().iter().map(|e| (e.mat, e.block, e.row, e.col)).collect();
        assert_eq!(keys, vec![(0, 1, 0, 0), (1, 0, 0, 0), (1, 0, 0, 1)]);
        let mut q = p.clone();
        q.set_values(&[3.0], &[5.0, 6.0, 7.0]).unwrap();
        assert!(p.same_structure(&q));
        assert_eq!(q.entries()[2].value, 7.0);
        let s = q.slack(&[2.0]).unwrap();
        assert_eq!(s[0][(0, 1)], 14.0);
        assert_eq!(s[0][(1, 0)], 14.0);
        assert_eq!(s[1][(0, 0)], -5.0);
    }

    #[test]
    fn invalid_entries_are_named() {
        let cases = [
            (e(2, 0, 0, 0, 1.0), "matrix index exceeds"),
            (e(1, 3, 0, 0, 1.0), "block index exceeds"),
            (e(1, 0, 0, 2, 1.0), "outside a block of size 2"),
            (e(1, 0, 1, 0, 1.0), "lower-triangle"),
            (e(1, 1, 0, 0, f64::NAN), "not finite"),
        ];
        for (entry, msg) in cases {
            let err =
                SdpProblem::new(vec![Block::Psd(2), Block::Nonneg(2)], vec![1.0], vec![entry]).unwrap_err().to_string();
            assert!(err.contains(msg), "{err}");
        }
        let err = SdpProblem::new(vec![Block::Nonneg(2)], vec![1.0], vec![e(1, 0, 0, 1, 1.0)]).unwrap_err().to_string();
        assert!(err.contains("off-diagonal entry in a diagonal"), "{err}");
        let err = SdpProblem::new(vec![Block::Psd(2)], vec![1.0], vec![e(1, 0, 0, 1, 1.0), e(1, 0, 0, 1, 2.0)])
            .unwrap_err()
            .to_string();
        assert!(err.contains("duplicate entry"), "{err}");
        let err = SdpProblem::new(vec![Block::Psd(2)], vec![f64::INFINITY], vec![]).unwrap_err().to_string();
        assert!(err.contains("c[0] is not finite"), "{err}");
        let err = SdpProblem::new(vec![], vec![], vec![]).unwrap_err().to_string();
        assert!(err.contains("no blocks"), "{err}");
    }

    #[test]
    fn set_values_checks_and_leaves_problem_unchanged() {
        let mut p = SdpProblem::new(vec![Block::Psd(1)], vec![1.0], vec![e(1, 0, 0, 0, 1.0)]).unwrap();
        let before = p.clone();
        assert!(p.set_values(&[1.0, 2.0], &[1.0]).unwrap_err().to_string().contains("objective vector c"));
        assert!(p.set_values(&[1.0], &[f64::NAN]).unwrap_err().to_string().contains("not finite"));
        assert_eq!(p, before);
    }
}
