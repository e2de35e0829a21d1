//! The scaled upper-triangular, column-wise vectorisation of symmetric matrices.
//!
//! `svec(X) = [X₀₀, √2 X₀₁, X₁₁, √2 X₀₂, √2 X₁₂, X₂₂, …]`: upper triangle column by column,
//! off-diagonal entries scaled by √2 so that `svec(X)·svec(Y) = tr(X Y)`. This is the layout of
//! Clarabel's (and SCS's) PSD triangle cone.

use nalgebra::DMatrix;

use crate::error::LmiError;

fn check(n: usize, len: usize, what: &'static str) -> Result<(), LmiError> {
    if len == svec_len(n) {
        Ok(())
    } else {
        Err(LmiError::DimensionMismatch { what, expected: svec_len(n), found: len })
    }
}

/// Length of `svec` of an `n × n` matrix: `n(n+1)/2`.
pub fn svec_len(n: usize) -> usize {
    n * (n + 1) / 2
}

/// Position of entry `(i, j)` (either triangle) in `svec`.
pub fn svec_index(i: usize, j: usize) -> usize {
    let (r, c) = if i <= j { (i, j) } else { (j, i) };
    c * (c + 1) / 2 + r
}

/// The factor applied to entry `(i, j)`: `1` on the diagonal, `√2` off it.
pub fn svec_scale(i: usize, j: usize) -> f64 {
    if i == j { 1.0 } else { std::f64::consts::SQRT_2 }
}

/// `svec(x)` written into `out` (length `n(n+1)/2`); reads the upper triangle of the square `x`.
pub fn svec_into(x: &DMatrix<f64>, out: &mut [f64]) -> Result<(), LmiError> {
    let n = x.nrows();
    if x.ncols() != n {
        return Err(LmiError::DimensionMismatch { what: "columns of a square matrix", expected: n, found: x.ncols() });
    }
    check(n, out.len(), "length of svec")?;
    for j in 0..n {
        for i in 0..=j {
            out[svec_index(i, j)] = svec_scale(i, j) * x[(i, j)];
        }
    }
    Ok(())
}

/// The symmetric matrix whose `svec` is `v`, written into the square `out` (both triangles).
pub fn smat_into(v: &[f64], out: &mut DMatrix<f64>) -> Result<(), LmiError> {
    let n = out.nrows();
    if out.ncols() != n {
        return Err(LmiError::DimensionMismatch {
            what: "columns of a square matrix",
            expected: n,
            found: out.ncols(),
        });
    }
    check(n, v.len(), "length of svec")?;
    for j in 0..n {
        for i in 0..=j {
            let x = v[svec_index(i, j)] / svec_scale(i, j);
            out[(i, j)] = x;
            out[(j, i)] = x;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_inner_product() {
        let n = 4;
        let a = DMatrix::from_fn(n, n, |i, j| ((i + 1) * (j + 2)) as f64 + 0.5 * (i + j) as f64);
        let a = &a + a.transpose();
        let b = DMatrix::from_fn(n, n, |i, j| (i as f64 - j as f64).powi(2) - 1.0);
        let mut va = vec![0.0; svec_len(n)];
        let mut vb = vec![0.0; svec_len(n)];
        svec_into(&a, &mut va).unwrap();
        svec_into(&b, &mut vb).unwrap();
        let dot: f64 = va.iter().zip(&vb).map(|(x, y)| x * y).sum();
        assert!((dot - (&a * &b).trace()).abs() < 1e-12 * dot.abs().max(1.0));
        let mut back = DMatrix::zeros(n, n);
        smat_into(&va, &mut back).unwrap();
        assert!(smat_into(&va[1..], &mut back).unwrap_err().to_string().contains("length of svec"));
        assert!(svec_into(&a, &mut [0.0; 3]).is_err());
        assert!((back - &a).abs().max() < 1e-13);
        // Layout: (0,0), (0,1), (1,1), (0,2), …
        assert_eq!(svec_index(0, 1), 1);
        assert_eq!(svec_index(1, 1), 2);
        assert_eq!(svec_index(2, 0), 3);
        assert_eq!(va[1], std::f64::consts::SQRT_2 * a[(0, 1)]);
    }
}
