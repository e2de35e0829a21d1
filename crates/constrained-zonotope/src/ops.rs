//! The set operations (Z1)–(Z3), each with its rounding errors enclosed (crate documentation).

use nalgebra::{DMatrix, DVector};

use crate::enclose::{add_up, dot_error, product, row_sums_up};
use crate::{ConstrainedZonotope, MAX_CONSTRAINTS, MAX_GENERATORS, SetError, check_size};

fn dimension(what: &'static str, expected: String, found: String) -> SetError {
    SetError::Dimension { what, expected, found }
}

impl ConstrainedZonotope {
    /// Grows the set by the box of `radius` (exactly, `Z ⊕ □(0, r)`): a positive `radius[i]` is
    /// added to an existing generator `ρ eᵢ` with a zero column of `A` (`|ρ| + rᵢ`, rounded up:
    /// collinear segments add), else appended as a new one.
    pub(crate) fn push_box(&mut self, radius: &[f64]) -> Result<(), SetError> {
        self.push_diagonal(radius, true, "box enlargement")
    }

    /// Relaxes every constraint row `i` with `slack[i] > 0` to `|aᵢ ξ − bᵢ| ≤ slackᵢ` (which every
    /// `ξ` within the row's rounding error satisfies): the slack is added to an existing slack
    /// factor of that row (a column `σ eᵢ` of `A`, zero in `G`), else a new factor with column
    /// `slack[i] eᵢ` in `A` and a zero column in `G` is appended.
    pub(crate) fn push_slack(&mut self, slack: &[f64]) -> Result<(), SetError> {
        self.push_diagonal(slack, false, "constraint slack")
    }

    /// The column `j` that is `v eᵢ` in `G` (`generators`) or in `A` and zero in the other.
    fn axis_column(&self, i: usize, generators: bool) -> Option<usize> {
        let (target, other) = if generators { (&self.g, &self.a) } else { (&self.a, &self.g) };
        // From the end: the rounding boxes and slacks of earlier operations were appended there.
        (0..self.generators()).rev().find(|&j| {
            target[(i, j)] != 0.0
                && other.column(j).iter().all(|v| *v == 0.0)
                && target.column(j).iter().enumerate().all(|(r, v)| r == i || *v == 0.0)
        })
    }

    /// [`Self::push_box`] (`generators`) or [`Self::push_slack`].
    fn push_diagonal(&mut self, d: &[f64], generators: bool, what: &'static str) -> Result<(), SetError> {
        if d.iter().any(|r| !r.is_finite()) {
            return Err(SetError::Overflow(what));
        }
        let mut new = Vec::new();
        for (i, &di) in d.iter().enumerate().filter(|(_, di)| **di > 0.0) {
            match self.axis_column(i, generators) {
                Some(j) => {
                    let target = if generators { &mut self.g } else { &mut self.a };
                    let v = target[(i, j)];
                    let grown = add_up(v.abs(), di);
                    if !grown.is_finite() {
                        return Err(SetError::Overflow(what));
                    }
                    target[(i, j)] = grown.copysign(v);
                }
                None => new.push(i),
            }
        }
        if new.is_empty() {
            return Ok(());
        }
        let ng = self.generators();
        check_size("generators", ng + new.len(), MAX_GENERATORS)?;
        let g = std::mem::replace(&mut self.g, DMatrix::zeros(0, 0)).resize_horizontally(ng + new.len(), 0.0);
        let a = std::mem::replace(&mut self.a, DMatrix::zeros(0, 0)).resize_horizontally(ng + new.len(), 0.0);
        let (mut g, mut a) = (g, a);
        let target = if generators { &mut g } else { &mut a };
        for (k, &i) in new.iter().enumerate() {
            target[(i, ng + k)] = d[i];
        }
        self.g = g;
        self.a = a;
        Ok(())
    }

    /// `M Z + d` (Z1): `⟨M c + d, M G, A, b⟩`, enlarged by a box that covers the rounding of
    /// `M c + d` and of `M G`.
    ///
    /// # Errors
    /// Sizes that do not fit, non-finite entries, or a result over the size limits.
    pub fn affine_map(&self, m: &DMatrix<f64>, d: Option<&DVector<f64>>) -> Result<Self, SetError> {
        let n = self.dim();
        if m.ncols() != n {
            return Err(dimension("map", format!("{n} columns"), format!("{} columns", m.ncols())));
        }
        crate::check_size("dimension", m.nrows(), crate::MAX_DIMENSION)?;
        crate::check_finite("map", m)?;
        if let Some(d) = d {
            if d.len() != m.nrows() {
                return Err(dimension("offset", format!("length {}", m.nrows()), format!("length {}", d.len())));
            }
            crate::check_finite_vec("offset", d)?;
        }
        let (g, eg) = product(m, &self.g);
        let mut err = row_sums_up(&eg);
        let mut c = DVector::zeros(m.nrows());
        for i in 0..m.nrows() {
            let d = d.map_or(0.0, |d| d[i]);
            let (mut s, mut abs) = (d, d.abs());
            for k in 0..n {
                let t = m[(i, k)] * self.c[k];
                s += t;
                abs += t.abs();
            }
            c[i] = s;
            err[i] = add_up(err[i], dot_error(abs, n + 1));
        }
        let mut out = Self { c, g, a: self.a.clone(), b: self.b.clone() };
        if out.c.iter().chain(out.g.iter()).any(|v| !v.is_finite()) {
            return Err(SetError::Overflow("affine map"));
        }
        out.push_box(&err)?;
        Ok(out)
    }

    /// `Z ⊕ W` (Z2): `⟨c + c_w, [G G_w], blkdiag(A, A_w), [b; b_w]⟩`, the centre's rounding
    /// covered by a box.
    ///
    /// # Errors
    /// Different dimensions, or a result over the size limits.
    pub fn minkowski_sum(&self, other: &Self) -> Result<Self, SetError> {
        let n = self.dim();
        if other.dim() != n {
            return Err(dimension("summand", format!("dimension {n}"), format!("dimension {}", other.dim())));
        }
        let (ng1, ng2) = (self.generators(), other.generators());
        let (nc1, nc2) = (self.constraints(), other.constraints());
        check_size("generators", ng1 + ng2, MAX_GENERATORS)?;
        check_size("constraints", nc1 + nc2, MAX_CONSTRAINTS)?;
        let mut c = DVector::zeros(n);
        let mut err = vec![0.0; n];
        for i in 0..n {
            c[i] = self.c[i] + other.c[i];
            err[i] = intervals::up(f64::EPSILON * c[i].abs());
        }
        let mut g = DMatrix::zeros(n, ng1 + ng2);
        g.columns_mut(0, ng1).copy_from(&self.g);
        g.columns_mut(ng1, ng2).copy_from(&other.g);
        let mut a = DMatrix::zeros(nc1 + nc2, ng1 + ng2);
        a.view_mut((0, 0), (nc1, ng1)).copy_from(&self.a);
        a.view_mut((nc1, ng1), (nc2, ng2)).copy_from(&other.a);
        let mut b = DVector::zeros(nc1 + nc2);
        b.rows_mut(0, nc1).copy_from(&self.b);
        b.rows_mut(nc1, nc2).copy_from(&other.b);
        if c.iter().any(|v| !v.is_finite()) {
            return Err(SetError::Overflow("Minkowski sum"));
        }
        let mut out = Self { c, g, a, b };
        out.push_box(&err)?;
        Ok(out)
    }

    /// `Z ⊕ □(0, r)`: the sum with the box of radii `r` (non-negative).
    ///
    /// # Errors
    /// A radius of the wrong length, negative or not finite.
    pub fn add_box(&self, radius: &DVector<f64>) -> Result<Self, SetError> {
        if radius.len() != self.dim() {
            return Err(dimension("box radius", format!("length {}", self.dim()), format!("length {}", radius.len())));
        }
        crate::check_finite_vec("box radius", radius)?;
        if let Some(i) = radius.iter().position(|r| *r < 0.0) {
            return Err(SetError::NegativeRadius { what: "box radius", index: i, value: radius[i] });
        }
        let mut out = self.clone();
        out.push_box(radius.as_slice())?;
        Ok(out)
    }

    /// The generalised intersection `Z ∩_R Y = {x ∈ Z : R x ∈ Y}` (Z3):
    /// `⟨c, [G 0], [[A 0]; [0 A_y]; [R G  −G_y]], [b; b_y; c_y − R c]⟩`, every new row with a
    /// slack factor covering its rounding. With `Y = y ⊕ (−V)` it is the measurement update
    /// `{x ∈ Z : y − R x ∈ V}`.
    ///
    /// # Errors
    /// Sizes that do not fit, non-finite entries, or a result over the size limits.
    pub fn intersect(&self, r: &DMatrix<f64>, y: &Self) -> Result<Self, SetError> {
        let n = self.dim();
        let m = y.dim();
        if r.ncols() != n || r.nrows() != m {
            return Err(dimension(
                "R",
                format!("{m} × {n} (the dimensions of Y and Z)"),
                format!("{} × {}", r.nrows(), r.ncols()),
            ));
        }
        crate::check_finite("R", r)?;
        let (ng1, ng2) = (self.generators(), y.generators());
        let (nc1, nc2) = (self.constraints(), y.constraints());
        check_size("generators", ng1 + ng2, MAX_GENERATORS)?;
        check_size("constraints", nc1 + nc2 + m, MAX_CONSTRAINTS)?;
        let (rg, erg) = product(r, &self.g);
        // c_y − R c, one dot product of length n + 1 per row.
        let mut slack = row_sums_up(&erg);
        let mut rhs = DVector::zeros(m);
        for i in 0..m {
            let (mut s, mut abs) = (y.c[i], y.c[i].abs());
            for k in 0..n {
                let t = r[(i, k)] * self.c[k];
                s -= t;
                abs += t.abs();
            }
            rhs[i] = s;
            slack[i] = add_up(slack[i], dot_error(abs, n + 1));
        }
        let ng = ng1 + ng2;
        let nc = nc1 + nc2 + m;
        let mut g = DMatrix::zeros(n, ng);
        g.columns_mut(0, ng1).copy_from(&self.g);
        let mut a = DMatrix::zeros(nc, ng);
        a.view_mut((0, 0), (nc1, ng1)).copy_from(&self.a);
        a.view_mut((nc1, ng1), (nc2, ng2)).copy_from(&y.a);
        a.view_mut((nc1 + nc2, 0), (m, ng1)).copy_from(&rg);
        a.view_mut((nc1 + nc2, ng1), (m, ng2)).copy_from(&(-&y.g));
        let mut b = DVector::zeros(nc);
        b.rows_mut(0, nc1).copy_from(&self.b);
        b.rows_mut(nc1, nc2).copy_from(&y.b);
        b.rows_mut(nc1 + nc2, m).copy_from(&rhs);
        if a.iter().chain(b.iter()).any(|v| !v.is_finite()) {
            return Err(SetError::Overflow("intersection"));
        }
        let mut out = Self { c: self.c.clone(), g, a, b };
        let mut all = vec![0.0; nc];
        all[nc1 + nc2..].copy_from_slice(&slack);
        out.push_slack(&all)?;
        Ok(out)
    }
}
