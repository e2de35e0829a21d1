//! The optional settings files of `port-est truck` and `port-est bds-ins` (`--config`): read
//! whole within the size limit, parsed with `serde` keeping each value's span, so that every
//! complaint — a wrong type, a value out of range, a matrix the filter refuses, a matrix derived
//! from several settings — is reported at the `file:line:column` of the key it is about.

use std::ops::Range;
use std::path::{Path, PathBuf};

use nalgebra::DMatrix;
use serde::de::DeserializeOwned;
use toml::Spanned;

use crate::error::{Error, Location, line_col};

/// A settings file as read: its name and text (both empty without a file: the defaults).
#[derive(Debug, Clone, Default)]
pub(crate) struct SettingsFile {
    path: Option<PathBuf>,
    text: String,
}

impl SettingsFile {
    /// Reads and parses `path` into `T` (`T::default()` without a file); a syntax or type error
    /// is reported at its `file:line:column`.
    ///
    /// # Errors
    /// [`Error::Io`], [`Error::TooLarge`] beyond `limit` bytes, [`Error::At`] for text that is
    /// not UTF-8 or what TOML or the settings' types refuse.
    pub(crate) fn read<T: DeserializeOwned + Default>(path: Option<&Path>, limit: u64) -> Result<(T, Self), Error> {
        let Some(p) = path else {
            return Ok((T::default(), Self::default()));
        };
        let text = crate::limits::read_text(p, "settings file", limit)?;
        let file = Self { path: Some(p.to_owned()), text };
        let parsed = file.parse()?;
        Ok((parsed, file))
    }

    /// Parses `text` as if read from `path` (tests and fuzzing).
    pub(crate) fn from_text<T: DeserializeOwned>(path: &Path, text: &str) -> Result<(T, Self), Error> {
        let file = Self { path: Some(path.to_owned()), text: text.strip_prefix('\u{feff}').unwrap_or(text).to_owned() };
        let parsed = file.parse()?;
        Ok((parsed, file))
    }

    fn parse<T: DeserializeOwned>(&self) -> Result<T, Error> {
        toml::from_str(&self.text).map_err(|e| {
            let message = e.message().trim_end().to_owned();
            match e.span() {
                Some(span) => Error::At { at: self.at(span), message },
                None => Error::File { path: self.shown().to_owned(), message },
            }
        })
    }

    /// The file's name, or `<defaults>` without a file.
    pub(crate) fn shown(&self) -> &Path {
        self.path.as_deref().unwrap_or(Path::new("<defaults>"))
    }

    /// The location of a value's span.
    pub(crate) fn at(&self, span: Range<usize>) -> Location {
        let (line, column) = line_col(&self.text, span.start);
        Location::new(self.shown(), line, column)
    }

    /// An error about the key `key` whose value is `value`: at its location.
    pub(crate) fn error<T>(&self, key: &str, value: &Spanned<T>, message: impl std::fmt::Display) -> Error {
        Error::At { at: self.at(value.span()), message: format!("`{key}`: {message}") }
    }

    /// An error about a quantity derived from settings: at the first of `keys` that was given
    /// (`given`: each key's span if it was), or about the file (the defaults) when none was.
    pub(crate) fn derived_error(&self, given: &[(&str, Option<Range<usize>>)], message: String) -> Error {
        match given.iter().find_map(|(k, s)| s.clone().map(|s| (k, s))) {
            Some((key, span)) => Error::At { at: self.at(span), message: format!("`{key}`: {message}") },
            None => Error::File { path: self.shown().to_owned(), message: format!("{message} (from the defaults)") },
        }
    }
}

/// A number that must be positive and finite.
/// The positive finite value of an optional `key`, or `default` when it is absent.
pub(crate) fn positive_or(
    file: &SettingsFile,
    key: &str,
    v: &Option<Spanned<f64>>,
    default: f64,
) -> Result<f64, Error> {
    match v {
        Some(v) => positive(file, key, v),
        None => Ok(default),
    }
}

pub(crate) fn positive(file: &SettingsFile, key: &str, v: &Spanned<f64>) -> Result<f64, Error> {
    let x = *v.get_ref();
    if x.is_finite() && x > 0.0 {
        Ok(x)
    } else {
        Err(file.error(key, v, format!("must be positive and finite, got {x}")))
    }
}

/// A number that must be finite and non-negative.
pub(crate) fn non_negative(file: &SettingsFile, key: &str, v: &Spanned<f64>) -> Result<f64, Error> {
    let x = *v.get_ref();
    if x.is_finite() && x >= 0.0 {
        Ok(x)
    } else {
        Err(file.error(key, v, format!("must be finite and non-negative, got {x}")))
    }
}

/// A vector of `len` finite numbers.
pub(crate) fn vector(file: &SettingsFile, key: &str, v: &Spanned<Vec<f64>>, len: usize) -> Result<Vec<f64>, Error> {
    let x = v.get_ref();
    if x.len() != len {
        return Err(file.error(key, v, format!("expected {len} entries, found {}", x.len())));
    }
    if let Some(i) = x.iter().position(|e| !e.is_finite()) {
        return Err(file.error(key, v, format!("entry {} = {} is not finite", i + 1, x[i])));
    }
    Ok(x.clone())
}

/// A `size × size` matrix (arrays of rows) of finite numbers that is symmetric and positive
/// definite (a covariance).
pub(crate) fn covariance(
    file: &SettingsFile,
    key: &str,
    v: &Spanned<Vec<Vec<f64>>>,
    size: usize,
) -> Result<DMatrix<f64>, Error> {
    let rows = v.get_ref();
    if rows.len() != size || rows.iter().any(|r| r.len() != size) {
        return Err(file.error(key, v, format!("must be {size} rows of {size} numbers")));
    }
    let m = DMatrix::from_fn(size, size, |i, j| rows[i][j]);
    check_covariance(&m).map_err(|why| file.error(key, v, why))?;
    Ok(m)
}

/// Why `m` is not a covariance (finite, symmetric, positive definite), if it is not.
pub(crate) fn check_covariance(m: &DMatrix<f64>) -> Result<(), String> {
    if let Some(i) = m.iter().position(|x| !x.is_finite()) {
        let (r, c) = (i % m.nrows(), i / m.nrows());
        return Err(format!("entry ({}, {}) = {} is not finite", r + 1, c + 1, m[(r, c)]));
    }
    if dense_kernels::max_asymmetry(m, dense_kernels::SYMMETRY_TOLERANCE).is_some() {
        return Err("is not symmetric".into());
    }
    if dense_kernels::cholesky_checked(m, dense_kernels::PD_RELATIVE_TOLERANCE).is_err() {
        return Err("is not positive definite (a covariance needs positive variances it can tell apart from 0)".into());
    }
    Ok(())
}
