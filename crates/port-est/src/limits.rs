//! The limits that keep one file or one setting from taking the machine's memory or time: each is
//! checked before anything is allocated for it, refused with a message naming the limit and how
//! to change it. `crates/port-est/README.md` lists them all.
//!
//! | limit | default | change with |
//! |---|---|---|
//! | size of a model, settings or rule file (read whole) | [`DEFAULT_MAX_FILE_BYTES`] | `--max-file-size SIZE` |
//! | memory of a moving-horizon estimator (`[mhe]` horizon and blocks) | [`DEFAULT_MHE_MEMORY_BYTES`] | `--mhe-memory-limit SIZE` |
//! | missing steps bridged at one gap (`--gaps bridge`) | [`DEFAULT_MAX_GAP`] | `--max-gap N` |
//! | sweeps or Newton iterations of a window (`[mhe] max_sweeps`) | [`MAX_MHE_SWEEPS`] | fixed |
//! | length of one data line | [`crate::data::MAX_RECORD_BYTES`] | fixed |

use std::io::Read as _;
use std::path::Path;

use crate::error::{Error, Location};

/// The largest model, settings or rule file read (each is read whole): 16 MiB, room for a model
/// of about a thousand states.
pub const DEFAULT_MAX_FILE_BYTES: u64 = 16 << 20;

/// The most memory a moving-horizon estimator built from an `[mhe]` table may take, by
/// [`crate::mhe_table::memory_estimate`]: 256 MiB. A window with `z` unknowns also costs about
/// `z³/3` operations per inner iteration, so this bounds the time of a step too (seconds at the
/// limit).
pub const DEFAULT_MHE_MEMORY_BYTES: u64 = estimators::registry::DEFAULT_MEMORY_LIMIT;

/// The most missing steps `--gaps bridge` fills at one gap (one predicted output row each).
pub const DEFAULT_MAX_GAP: u64 = 10_000;

/// The most sweeps (coordinate rotation) or Newton iterations (exact saddle) per window an
/// `[mhe]` table may ask for.
pub const MAX_MHE_SWEEPS: usize = estimators::registry::MAX_WINDOW_ITERATIONS;

/// The limits of one run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Largest model, settings or rule file, in bytes.
    pub file_bytes: u64,
    /// Largest memory estimate of a moving-horizon estimator, in bytes.
    pub mhe_memory_bytes: u64,
    /// Most missing steps bridged at one gap.
    pub max_gap: u64,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            file_bytes: DEFAULT_MAX_FILE_BYTES,
            mhe_memory_bytes: DEFAULT_MHE_MEMORY_BYTES,
            max_gap: DEFAULT_MAX_GAP,
        }
    }
}

pub use estimators::registry::show_bytes;

/// Parses a size: a whole number of bytes, optionally followed by `K`/`KiB`, `M`/`MiB`,
/// `G`/`GiB` or `T`/`TiB` (powers of 1024; case-insensitive): `4096`, `64MiB`, `2G`.
///
/// # Errors
/// A message for anything else, or a size beyond `u64`.
pub fn parse_size(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let digits = t.find(|c: char| !c.is_ascii_digit()).unwrap_or(t.len());
    let (number, unit) = t.split_at(digits);
    let shift = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 0,
        "k" | "kib" => 10,
        "m" | "mib" => 20,
        "g" | "gib" => 30,
        "t" | "tib" => 40,
        _ => {
            return Err(format!(
                "{text:?} is not a size (a number of bytes, or with K, M, G or T for KiB, MiB, GiB, TiB)"
            ));
        }
    };
    let n: u64 = number.parse().map_err(|_| format!("{text:?} is not a size (a whole number, say 64MiB)"))?;
    n.checked_mul(1 << shift).ok_or_else(|| format!("{text:?} is larger than 2^64 bytes"))
}

/// Reads a text file whole: at most `limit` bytes of it (an endless file such as `/dev/zero` is
/// refused after that much), UTF-8 (the first bad byte is located), a leading byte-order mark
/// dropped. `what` names the file's role in the message (`model file`, `settings file`, …).
///
/// # Errors
/// [`Error::Io`], [`Error::TooLarge`], [`Error::At`] for bytes that are not UTF-8.
pub(crate) fn read_text(path: &Path, what: &'static str, limit: u64) -> Result<String, Error> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut bytes = Vec::new();
    file.take(limit.saturating_add(1)).read_to_end(&mut bytes).map_err(|e| Error::io(path, e))?;
    if bytes.len() as u64 > limit {
        return Err(Error::TooLarge { path: path.to_owned(), what, limit });
    }
    let text = String::from_utf8(bytes).map_err(|e| {
        let good = e.utf8_error().valid_up_to();
        let prefix = String::from_utf8_lossy(&e.as_bytes()[..good]);
        let prefix = prefix.strip_prefix('\u{feff}').unwrap_or(&prefix);
        let (line, column) = crate::error::line_col(prefix, prefix.len());
        Error::at(Location::new(path, line, column), format!("not valid UTF-8 (the {what} must be UTF-8 TOML)"))
    })?;
    Ok(match text.strip_prefix('\u{feff}') {
        Some(rest) => rest.to_owned(),
        None => text,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_and_show() {
        assert_eq!(parse_size("4096"), Ok(4096));
        assert_eq!(parse_size("64MiB"), Ok(64 << 20));
        assert_eq!(parse_size(" 2g "), Ok(2 << 30));
        assert_eq!(parse_size("1 KiB"), Ok(1024));
        assert!(parse_size("1.5G").is_err());
        assert!(parse_size("-1").is_err());
        assert!(parse_size("lots").is_err());
        assert!(parse_size("99999999999T").is_err());
        assert_eq!(show_bytes(512), "512 B");
        assert_eq!(show_bytes(16 << 20), "16 MiB");
        assert_eq!(show_bytes(3 << 29), "1.5 GiB");
        assert!(show_bytes(u128::MAX).ends_with("EiB"), "{}", show_bytes(u128::MAX));
    }

    #[cfg(unix)]
    #[test]
    fn an_endless_file_is_refused_at_the_limit() {
        let e = read_text(Path::new("/dev/zero"), "model file", 1 << 20).unwrap_err().to_string();
        assert_eq!(e, "/dev/zero: larger than 1 MiB, the limit for a model file (raise it with --max-file-size)");
    }
}
