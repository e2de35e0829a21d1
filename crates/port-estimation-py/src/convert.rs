//! NumPy in, NumPy out: array-likes (arrays of any real dtype, lists, scalars) checked for their
//! shape and for NaN/∞ with a `ValueError` naming the argument, and read-only NumPy arrays out.

use nalgebra::{DMatrix, DVector};
use numpy::ndarray::Array2;
use numpy::{AllowTypeChange, PyArray1, PyArray2, PyArrayLikeDyn, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::value_error;

/// The array-like `obj` as an aligned float64 array of any dimension. Arrays that NumPy marks
/// unaligned (as unpickled from out-of-band buffers, say) are copied first: a view of them would
/// not be sound.
fn array<'py>(obj: &Bound<'py, PyAny>, what: &str) -> PyResult<PyArrayLikeDyn<'py, f64, AllowTypeChange>> {
    // Real numbers only: complex values (their imaginary part would be dropped), booleans, strings
    // and objects are refused, and a masked array's hidden values are never read silently.
    let py = obj.py();
    if py.import("numpy.ma")?.call_method1("isMaskedArray", (obj,))?.extract::<bool>()? {
        return Err(value_error(format!(
            "{what} is a masked array: only a measurement (y, ys) may be masked (its masked entries not measured)"
        )));
    }
    let kind: String =
        py.import("numpy")?.call_method1("asarray", (obj,))?.getattr("dtype")?.getattr("kind")?.extract()?;
    if !matches!(kind.as_str(), "i" | "u" | "f") {
        let what_kind = match kind.as_str() {
            "c" => "complex numbers",
            "b" => "booleans",
            "U" | "S" => "strings",
            _ => "objects that are not real numbers",
        };
        return Err(value_error(format!("{what} must be an array of real numbers, got {what_kind}")));
    }
    let extract = |o: &Bound<'py, PyAny>| {
        o.extract::<PyArrayLikeDyn<'py, f64, AllowTypeChange>>()
            .map_err(|e| value_error(format!("{what} must be an array of real numbers: {e}")))
    };
    let a = extract(obj)?;
    if a.is_aligned() {
        return Ok(a);
    }
    let copy = a.as_any().call_method0("copy")?;
    let a = extract(&copy)?;
    if a.is_aligned() { Ok(a) } else { Err(value_error(format!("{what}: could not make an aligned copy"))) }
}

fn shape_text(shape: &[usize]) -> String {
    let dims: Vec<String> = shape.iter().map(ToString::to_string).collect();
    format!("({})", dims.join(", "))
}

fn check_finite(what: &str, values: &[f64]) -> PyResult<()> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(value_error(format!("{what} has a non-finite entry (NaN or infinity) at flat index {i}"))),
        None => Ok(()),
    }
}

/// The numbers of an array-like of one dimension (a scalar, a row or a column too), in order;
/// `±inf` and NaN are returned as they are, for the caller to judge.
pub fn numbers(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<f64>> {
    let a = array(obj, what)?;
    let shape = a.shape().to_vec();
    let ok = match shape.as_slice() {
        [] | [_] => true,
        [r, c] => *r == 1 || *c == 1,
        _ => false,
    };
    if !ok {
        return Err(value_error(format!("{what} must be a vector (one dimension), got shape {}", shape_text(&shape))));
    }
    Ok(a.as_array().iter().copied().collect())
}

/// A vector of length `len`: shape `(len,)`, a column `(len, 1)` or a row `(1, len)` (filterpy's
/// column vectors), or a scalar when `len` is 1. Finite entries only.
pub fn vector(obj: &Bound<'_, PyAny>, what: &str, len: usize) -> PyResult<DVector<f64>> {
    vector_with(obj, what, len, false)
}

/// A measurement of `len` outputs that may be partial: a NumPy masked array (masked entries were
/// not measured), or `measured` (a boolean array-like of length `len`, True where measured), not
/// both. Returns `y` with its unmeasured entries set to 0 (their values, NaN included, are
/// ignored) and the mask, `None` when every output was measured and no mask was given.
pub fn measurement(
    obj: &Bound<'_, PyAny>,
    measured: Option<&Bound<'_, PyAny>>,
    len: usize,
) -> PyResult<(DVector<f64>, Option<Vec<bool>>)> {
    let py = obj.py();
    let ma = py.import("numpy.ma")?;
    let masked: bool = ma.call_method1("isMaskedArray", (obj,))?.extract()?;
    let mask = match (masked, measured) {
        (true, Some(_)) => return Err(value_error("y: give a masked array or measured=, not both")),
        (false, None) => return Ok((vector(obj, "y", len)?, None)),
        (true, None) => {
            let hidden: Vec<bool> =
                ma.call_method1("getmaskarray", (obj,))?.call_method0("ravel")?.call_method0("tolist")?.extract()?;
            hidden.into_iter().map(|h| !h).collect::<Vec<bool>>()
        }
        (false, Some(m)) => {
            let a = py.import("numpy")?.call_method1("asarray", (m,))?;
            let kind: String = a.getattr("dtype")?.getattr("kind")?.extract()?;
            if kind != "b" {
                return Err(value_error(format!("measured must be an array of booleans, got dtype kind {kind:?}")));
            }
            a.call_method0("ravel")?.call_method0("tolist")?.extract()?
        }
    };
    if mask.len() != len {
        return Err(value_error(format!("measured must have {len} entries (one per output), got {}", mask.len())));
    }
    let data = if masked { obj.call_method1("filled", (0.0,))? } else { obj.clone() };
    let a = array(&data, "y")?;
    let values: Vec<f64> = a.as_array().iter().copied().collect();
    if values.len() != len || a.shape().len() > 2 {
        return Err(value_error(format!(
            "y must have {len} entries (shape ({len},)), got shape {}",
            shape_text(a.shape())
        )));
    }
    let y: Vec<f64> = values.iter().zip(&mask).map(|(&v, &m)| if m { v } else { 0.0 }).collect();
    if let Some(i) = y.iter().position(|v| !v.is_finite()) {
        return Err(value_error(format!("y has a non-finite measured entry (NaN or infinity) at index {i}")));
    }
    Ok((DVector::from_vec(y), Some(mask)))
}

/// A log of measurements `(T, cols)` that may be partial, as [`measurement`] for one: a masked
/// array, or `measured` a boolean `(T, cols)` array. Returns `T`, the values row by row (0 where
/// not measured) and the mask row by row, `None` when neither was given.
pub fn measurement_table(
    obj: &Bound<'_, PyAny>,
    measured: Option<&Bound<'_, PyAny>>,
    cols: usize,
) -> PyResult<(usize, Vec<f64>, Option<Vec<bool>>)> {
    let py = obj.py();
    let np = py.import("numpy")?;
    let ma = py.import("numpy.ma")?;
    let masked: bool = ma.call_method1("isMaskedArray", (obj,))?.extract()?;
    let mask_array = match (masked, measured) {
        (true, Some(_)) => return Err(value_error("ys: give a masked array or measured=, not both")),
        (false, None) => {
            let (rows, values) = table(Some(obj), "ys", None, cols)?;
            return Ok((rows, values, None));
        }
        (true, None) => ma.call_method1("getmaskarray", (obj,))?.call_method0("__invert__")?,
        (false, Some(m)) => {
            let a = np.call_method1("asarray", (m,))?;
            let kind: String = a.getattr("dtype")?.getattr("kind")?.extract()?;
            if kind != "b" {
                return Err(value_error(format!("measured must be an array of booleans, got dtype kind {kind:?}")));
            }
            a
        }
    };
    let data = if masked { obj.call_method1("filled", (0.0,))? } else { obj.clone() };
    let data_shape: Vec<usize> = data.getattr("shape")?.extract()?;
    let mask_shape: Vec<usize> = mask_array.getattr("shape")?.extract()?;
    if data_shape != mask_shape {
        return Err(value_error(format!(
            "measured must have the shape of ys, {}, got {}",
            shape_text(&data_shape),
            shape_text(&mask_shape)
        )));
    }
    // Unmeasured entries are ignored: zeros, so that NaN may mark them.
    let zeroed = np.call_method1("where", (&mask_array, &data, 0.0))?;
    let (rows, values) = table(Some(&zeroed), "ys", None, cols)?;
    let mask: Vec<bool> = mask_array.call_method0("ravel")?.call_method0("tolist")?.extract()?;
    Ok((rows, values, Some(mask)))
}

/// A bound vector of length `len` (as [`vector`]; entries may be ±∞, not NaN).
pub fn bound_vector(obj: &Bound<'_, PyAny>, what: &str, len: usize) -> PyResult<DVector<f64>> {
    vector_with(obj, what, len, true)
}

fn vector_with(obj: &Bound<'_, PyAny>, what: &str, len: usize, allow_infinite: bool) -> PyResult<DVector<f64>> {
    let a = array(obj, what)?;
    let shape = a.shape().to_vec();
    let ok = match shape.as_slice() {
        [] => len == 1,
        [k] => *k == len,
        [r, c] => (*r == len && *c == 1) || (*r == 1 && *c == len),
        _ => false,
    };
    if !ok {
        return Err(value_error(format!(
            "{what} must have {len} entries (shape ({len},)), got shape {}",
            shape_text(&shape)
        )));
    }
    let values: Vec<f64> = a.as_array().iter().copied().collect();
    if allow_infinite {
        if let Some(i) = values.iter().position(|v| v.is_nan()) {
            return Err(value_error(format!("{what} has a NaN entry at index {i}")));
        }
    } else {
        check_finite(what, &values)?;
    }
    Ok(DVector::from_vec(values))
}

/// A `rows × cols` matrix (a 2-D array-like). Finite entries only.
pub fn matrix(obj: &Bound<'_, PyAny>, what: &str, rows: Option<usize>, cols: Option<usize>) -> PyResult<DMatrix<f64>> {
    let a = array(obj, what)?;
    let shape = a.shape().to_vec();
    let [r, c] = shape.as_slice() else {
        return Err(value_error(format!("{what} must be a 2-D array, got shape {}", shape_text(&shape))));
    };
    let (r, c) = (*r, *c);
    if rows.is_some_and(|want| want != r) || cols.is_some_and(|want| want != c) {
        let show = |d: Option<usize>| d.map_or_else(|| "any".to_owned(), |d| d.to_string());
        return Err(value_error(format!("{what} must have shape ({}, {}), got ({r}, {c})", show(rows), show(cols))));
    }
    let view = a.as_array();
    let m = DMatrix::from_fn(r, c, |i, j| view[[i, j]]);
    check_finite(what, m.as_slice())?;
    Ok(m)
}

/// An `n × n` matrix given as a matrix, as its diagonal (a vector of length `n`) or as a scalar
/// `s` meaning `s·I`. Finite entries only (symmetry and definiteness are the estimator's checks).
pub fn square(obj: &Bound<'_, PyAny>, what: &str, n: usize) -> PyResult<DMatrix<f64>> {
    let a = array(obj, what)?;
    match a.shape().len() {
        0 => {
            let s = a.as_array().iter().copied().next().unwrap_or(f64::NAN);
            check_finite(what, &[s])?;
            Ok(DMatrix::identity(n, n) * s)
        }
        1 => Ok(DMatrix::from_diagonal(&vector(obj, what, n)?)),
        _ => matrix(obj, what, Some(n), Some(n)),
    }
}

/// A `T × k` table (rows are steps) as a row-major vector, checked finite; `None` for `T × 0`
/// tables given as `None`.
pub fn table(
    obj: Option<&Bound<'_, PyAny>>,
    what: &str,
    rows: Option<usize>,
    cols: usize,
) -> PyResult<(usize, Vec<f64>)> {
    let Some(obj) = obj else {
        return match (rows, cols) {
            (Some(t), 0) => Ok((t, Vec::new())),
            _ => Err(value_error(format!("{what} is required (the model has {cols} of them per step)"))),
        };
    };
    let a = array(obj, what)?;
    let shape = a.shape().to_vec();
    let (t, c) = match shape.as_slice() {
        [t] if cols == 1 => (*t, 1),
        [t, c] => (*t, *c),
        _ => {
            return Err(value_error(format!(
                "{what} must be a 2-D array of shape (T, {cols}), got shape {}",
                shape_text(&shape)
            )));
        }
    };
    if c != cols {
        return Err(value_error(format!(
            "{what} must have {cols} columns (shape (T, {cols})), got shape {}",
            shape_text(&shape)
        )));
    }
    if let Some(want) = rows
        && want != t
    {
        return Err(value_error(format!("{what} has {t} rows, the other log {want}: give one row per step to both")));
    }
    let values: Vec<f64> = a.as_array().iter().copied().collect();
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        let (row, col) = (i / cols.max(1), i % cols.max(1));
        return Err(value_error(format!("{what}[{row}, {col}] is not finite (NaN or infinity)")));
    }
    Ok((t, values))
}

/// Marks a NumPy array read-only (writes raise instead of silently changing a copy).
fn read_only<'py, T>(a: Bound<'py, T>) -> PyResult<Bound<'py, T>> {
    let kwargs = PyDict::new(a.py());
    kwargs.set_item("write", false)?;
    a.as_any().call_method("setflags", (), Some(&kwargs))?;
    Ok(a)
}

/// A read-only copy of `v`.
pub fn vec_out<'py>(py: Python<'py>, v: &[f64]) -> PyResult<Bound<'py, PyArray1<f64>>> {
    read_only(PyArray1::from_slice(py, v))
}

/// A read-only copy of `m` (row-major, C order).
pub fn mat_out<'py>(py: Python<'py>, m: &DMatrix<f64>) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let a = Array2::from_shape_fn((m.nrows(), m.ncols()), |(i, j)| m[(i, j)]);
    read_only(PyArray2::from_owned_array(py, a))
}

/// A read-only `rows × cols` array that takes over `data` (row-major) without copying.
pub fn table_out<T: numpy::Element>(
    py: Python<'_>,
    data: Vec<T>,
    rows: usize,
    cols: usize,
) -> PyResult<Bound<'_, PyArray2<T>>> {
    let a = Array2::from_shape_vec((rows, cols), data)
        .map_err(|e| crate::errors::broken(format!("internal error: result table of the wrong size ({e})")))?;
    read_only(PyArray2::from_owned_array(py, a))
}

/// A read-only array that takes over `data` without copying.
pub fn column_out<T: numpy::Element>(py: Python<'_>, data: Vec<T>) -> PyResult<Bound<'_, PyArray1<T>>> {
    read_only(PyArray1::from_vec(py, data))
}
