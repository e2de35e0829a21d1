//! A table of the model file read by keyword ([`estimators::registry::KeywordSource`]): the
//! `[mhe]` and `[ukf]` tables and each `[estimator.NAME]` table are read by the registry's one
//! settings reader ([`estimators::registry::read_settings`]), the same that reads Python's
//! keyword arguments; this module only converts TOML values and says where each key is, so that
//! every complaint is at the `file:line:column` of the key's value.

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

use estimators::registry::KeywordSource;
use toml::{Spanned, Value};

use crate::error::{Error, Location, line_col};

/// A table as written: every key's value with its span.
pub(crate) type SpannedTable = BTreeMap<String, Spanned<Value>>;

/// A table of the model file with the location of every value.
#[derive(Debug, Clone)]
pub struct KeywordTable {
    /// Its name in messages (`mhe`, `estimator.czf`).
    name: String,
    /// The file it is in (a relative `path` value is read against the file's folder).
    path: PathBuf,
    /// Where the table starts (`None`: the file has no such table).
    at: Option<Location>,
    /// Each key, its value and where the value is.
    entries: Vec<(String, Value, Location)>,
}

impl KeywordTable {
    /// The table `name` of the file `path` (text `text`), spanning `span`.
    pub(crate) fn new(name: &str, path: &Path, text: &str, span: Range<usize>, table: &SpannedTable) -> Self {
        let at = |span: Range<usize>| {
            let (line, column) = line_col(text, span.start);
            Location::new(path, line, column)
        };
        Self {
            name: name.to_owned(),
            path: path.to_owned(),
            at: Some(at(span)),
            entries: table.iter().map(|(k, v)| (k.clone(), v.get_ref().clone(), at(v.span()))).collect(),
        }
    }

    /// No table: the defaults (errors are about the file `path`).
    pub(crate) fn absent(name: &str, path: &Path) -> Self {
        Self { name: name.to_owned(), path: path.to_owned(), at: None, entries: Vec::new() }
    }

    /// Its name in messages.
    #[must_use]
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Where the table starts (`None`: the file has no such table).
    pub(crate) fn at(&self) -> Option<&Location> {
        self.at.as_ref()
    }

    /// Each key (as `table.key`) and where its value is.
    pub(crate) fn locations(&self) -> impl Iterator<Item = (String, &Location)> {
        self.entries.iter().map(|(k, _, at)| (format!("{}.{k}", self.name), at))
    }

    /// Whether the key is given.
    #[must_use]
    pub fn has(&self, key: &str) -> bool {
        self.entries.iter().any(|(k, ..)| k == key)
    }

    /// The error about `key` saying `message`: at the key's value when the table gives it, at the
    /// table when it does not, about the file without a table.
    pub(crate) fn error(&self, key: &str, message: &str) -> Error {
        match self.entries.iter().find(|(k, ..)| k == key) {
            Some((_, _, at)) => Error::At { at: at.clone(), message: format!("`{}.{key}`: {message}", self.name) },
            None => match &self.at {
                Some(at) => Error::At { at: at.clone(), message: format!("`{}`: {message}", self.name) },
                None => Error::File { path: self.path.clone(), message: message.to_owned() },
            },
        }
    }

    /// A reader of the table, every key unread; `overrides` (the command line's `--solver`, say)
    /// are read before the table's own values.
    #[must_use]
    pub fn reader<'t>(&'t self, overrides: &'t [(&'static str, String)]) -> TableReader<'t> {
        TableReader { table: self, read: vec![false; self.entries.len()], overrides }
    }
}

/// A [`KeywordSource`] over a [`KeywordTable`].
#[derive(Debug)]
pub struct TableReader<'t> {
    table: &'t KeywordTable,
    read: Vec<bool>,
    overrides: &'t [(&'static str, String)],
}

impl TableReader<'_> {
    /// Marks `key` read and returns its value.
    fn take(&mut self, key: &str) -> Option<&Value> {
        let i = self.table.entries.iter().position(|(k, ..)| k == key)?;
        self.read[i] = true;
        Some(&self.table.entries[i].1)
    }

    /// The value of `key` converted by `convert` (`None`: the wrong type, described by `what`).
    fn get<T>(&mut self, key: &str, what: &str, convert: impl Fn(&Value) -> Option<T>) -> Result<Option<T>, Error> {
        let Some(value) = self.take(key) else {
            return Ok(None);
        };
        match convert(value) {
            Some(t) => Ok(Some(t)),
            None => {
                let shown = value.to_string();
                Err(self.table.error(key, &format!("must be {what}, got {shown}")))
            }
        }
    }
}

/// A TOML number as `f64` (an integer too).
fn number(v: &Value) -> Option<f64> {
    match v {
        Value::Float(x) => Some(*x),
        Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

/// A TOML integer as a count.
fn count(v: &Value) -> Option<usize> {
    v.as_integer().and_then(|i| usize::try_from(i).ok())
}

impl KeywordSource for TableReader<'_> {
    type Error = Error;

    fn number(&mut self, key: &'static str) -> Result<Option<f64>, Error> {
        self.get(key, "a number", number)
    }

    fn count(&mut self, key: &'static str) -> Result<Option<usize>, Error> {
        self.get(key, "a non-negative integer", count)
    }

    fn flag(&mut self, key: &'static str) -> Result<Option<bool>, Error> {
        self.get(key, "true or false", Value::as_bool)
    }

    fn text(&mut self, key: &'static str) -> Result<Option<String>, Error> {
        let from_file = self.get(key, "a string", |v| v.as_str().map(str::to_owned))?;
        Ok(self.overrides.iter().find(|(k, _)| *k == key).map(|(_, v)| v.clone()).or(from_file))
    }

    fn path(&mut self, key: &'static str) -> Result<Option<PathBuf>, Error> {
        let folder = self.table.path.parent().map(Path::to_owned).unwrap_or_default();
        Ok(self.get(key, "a path (a string)", |v| v.as_str().map(PathBuf::from))?.map(|p| folder.join(p)))
    }

    fn numbers(&mut self, key: &'static str) -> Result<Option<Vec<f64>>, Error> {
        self.get(key, "a list of numbers", |v| v.as_array()?.iter().map(number).collect())
    }

    fn counts(&mut self, key: &'static str) -> Result<Option<Vec<usize>>, Error> {
        self.get(key, "a list of non-negative integers", |v| v.as_array()?.iter().map(count).collect())
    }

    fn refuse(&self, key: &str, message: String) -> Error {
        self.table.error(key, &message)
    }

    fn unread(&self) -> Vec<String> {
        self.table.entries.iter().zip(&self.read).filter(|(_, read)| !**read).map(|((k, ..), _)| k.clone()).collect()
    }
}
