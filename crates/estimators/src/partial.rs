//! Partial measurements: a step that carries only some outputs (sensors at their own rates,
//! dropouts). The update uses the measured rows of `h` (or `C`) and the sub-block `R_SS` of the
//! measurement covariance — for an ellipsoid `V = 𝓔(0, R)` that is its projection onto the
//! measured coordinates, for a zonotope the measured rows of its generators. Unmeasured entries
//! of `y` are ignored (they may be NaN). The workspaces of the filters' smaller updates are made
//! the first time a step measures that many outputs, and reused after.

use nalgebra::{DMatrix, DVector};

use crate::checks::{DataChecks, InnovationGate};
use crate::error::EstimatorError;
use crate::gaussian_update::GaussianUpdate;

/// The indices of the measured outputs of `measured` (length `m`) into `rows` (its capacity is
/// `m`, so this does not allocate); their count.
///
/// # Errors
/// [`EstimatorError::DimensionMismatch`] for a mask of another length.
pub(crate) fn measured_rows(measured: &[bool], m: usize, rows: &mut Vec<usize>) -> Result<usize, EstimatorError> {
    if measured.len() != m {
        return Err(EstimatorError::DimensionMismatch { what: "measured", expected: m, found: measured.len() });
    }
    rows.clear();
    rows.extend(measured.iter().enumerate().filter_map(|(i, &b)| b.then_some(i)));
    Ok(rows.len())
}

/// What a step with a mask measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Measured {
    /// Every output: the ordinary step (which checks its data itself).
    All,
    /// None: a prediction (`y`'s length checked).
    Nothing,
    /// `k` of them, their indices in `rows`; `u` and the measured entries of `y` checked.
    Some(usize),
}

/// Classifies `measured` (its measured indices into `rows`, capacity `m`) and checks the data a
/// partial step uses: `u` (length `p`, finite) and `y`'s measured entries.
///
/// # Errors
/// A mask or `y` of another length than `m`, `u` of another length than `p`, non-finite data.
pub(crate) fn classify(
    measured: &[bool],
    u: &DVector<f64>,
    y: &DVector<f64>,
    (m, p): (usize, usize),
    rows: &mut Vec<usize>,
) -> Result<Measured, EstimatorError> {
    let k = measured_rows(measured, m, rows)?;
    if k == m {
        return Ok(Measured::All);
    }
    if k == 0 {
        check_measured(y, m, &[])?;
        return Ok(Measured::Nothing);
    }
    crate::validate::check_vec("u", u, p)?;
    check_measured(y, m, rows)?;
    Ok(Measured::Some(k))
}

/// `y`'s length, and its measured entries finite.
///
/// # Errors
/// [`EstimatorError::DimensionMismatch`] or [`EstimatorError::NonFinite`] naming `y`.
pub(crate) fn check_measured(y: &DVector<f64>, m: usize, rows: &[usize]) -> Result<(), EstimatorError> {
    if y.len() != m {
        return Err(EstimatorError::DimensionMismatch { what: "y", expected: m, found: y.len() });
    }
    match rows.iter().find(|&&i| !y[i].is_finite()) {
        Some(&index) => Err(EstimatorError::NonFinite { what: "y", index }),
        None => Ok(()),
    }
}

/// Workspaces by measured count `k` (1 ..= m − 1), made on first use; `rows` the last step's
/// measured outputs.
#[derive(Debug, Clone)]
pub(crate) struct Subsets<T> {
    pub(crate) rows: Vec<usize>,
    by_count: Vec<Option<T>>,
}

impl<T> Subsets<T> {
    pub(crate) fn new(m: usize) -> Self {
        Self { rows: Vec::with_capacity(m), by_count: (0..m).map(|_| None).collect() }
    }

    /// Drops every workspace (after a change of settings they are made again).
    pub(crate) fn clear(&mut self) {
        self.by_count.iter_mut().for_each(|w| *w = None);
    }

    /// Moves the workspace for `k` out (to be [`Subsets::put`] back).
    pub(crate) fn take(&mut self, k: usize) -> Option<T> {
        self.by_count[k].take()
    }

    /// Puts a workspace back.
    pub(crate) fn put(&mut self, k: usize, work: T) {
        self.by_count[k] = Some(work);
    }

    /// The workspace for `k` measured outputs and the rows, made by `make` the first time.
    ///
    /// # Errors
    /// Whatever `make` returns.
    pub(crate) fn get(
        &mut self,
        k: usize,
        make: impl FnOnce() -> Result<T, EstimatorError>,
    ) -> Result<(&mut T, &[usize]), EstimatorError> {
        let slot = &mut self.by_count[k];
        if slot.is_none() {
            *slot = Some(make()?);
        }
        match slot {
            Some(w) => Ok((w, &self.rows)),
            None => unreachable!("made above"),
        }
    }
}

/// The Kalman and extended Kalman update for `k` measured outputs.
#[derive(Debug, Clone)]
pub(crate) struct GaussianSubset {
    pub(crate) upd: GaussianUpdate,
    /// `H_S` (`k × n`), `R_SS`, `ν_S`.
    pub(crate) h: DMatrix<f64>,
    pub(crate) r: DMatrix<f64>,
    pub(crate) innov: DVector<f64>,
    /// The gate with `k` degrees of freedom.
    pub(crate) gate: InnovationGate,
}

impl GaussianSubset {
    pub(crate) fn new(n: usize, k: usize, checks: DataChecks) -> Result<Self, EstimatorError> {
        Ok(Self {
            upd: GaussianUpdate::new(n, k),
            h: DMatrix::zeros(k, n),
            r: DMatrix::zeros(k, k),
            innov: DVector::zeros(k),
            gate: InnovationGate::new(checks, k)?,
        })
    }

    /// The measured rows of `h`, `innov` and the sub-block of `r`. Allocation-free.
    pub(crate) fn gather(&mut self, rows: &[usize], h: &DMatrix<f64>, r: &DMatrix<f64>, innov: &DVector<f64>) {
        gather_rows(h, rows, &mut self.h);
        gather_block(r, rows, &mut self.r);
        for (a, &i) in rows.iter().enumerate() {
            self.innov[a] = innov[i];
        }
    }
}

/// `out = src[rows, :]`.
pub(crate) fn gather_rows(src: &DMatrix<f64>, rows: &[usize], out: &mut DMatrix<f64>) {
    for j in 0..src.ncols() {
        for (a, &i) in rows.iter().enumerate() {
            out[(a, j)] = src[(i, j)];
        }
    }
}

/// `out = src[rows, rows]`.
pub(crate) fn gather_block(src: &DMatrix<f64>, rows: &[usize], out: &mut DMatrix<f64>) {
    for (b, &j) in rows.iter().enumerate() {
        for (a, &i) in rows.iter().enumerate() {
            out[(a, b)] = src[(i, j)];
        }
    }
}

/// The positions within `rows` of the entries of `angles` (both sorted), into `out`.
pub(crate) fn angle_positions(rows: &[usize], angles: &[usize], out: &mut Vec<usize>) {
    out.clear();
    out.extend(rows.iter().enumerate().filter_map(|(a, i)| angles.binary_search(i).is_ok().then_some(a)));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_blocks_and_masks() {
        let mut rows = Vec::with_capacity(3);
        assert_eq!(measured_rows(&[true, false, true], 3, &mut rows).unwrap(), 2);
        assert_eq!(rows, [0, 2]);
        assert!(measured_rows(&[true], 3, &mut rows).is_err());
        let r = DMatrix::from_fn(3, 3, |i, j| (10 * i + j) as f64);
        let mut block = DMatrix::zeros(2, 2);
        gather_block(&r, &[0, 2], &mut block);
        assert_eq!(block, DMatrix::from_row_slice(2, 2, &[0.0, 2.0, 20.0, 22.0]));
        let mut pos = Vec::new();
        angle_positions(&[0, 2, 3], &[2, 5], &mut pos);
        assert_eq!(pos, [1]);
        let y = DVector::from_vec(vec![1.0, f64::NAN, 2.0]);
        assert!(check_measured(&y, 3, &[0, 2]).is_ok());
        assert!(check_measured(&y, 3, &[1]).is_err());
    }
}
