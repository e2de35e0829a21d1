//! Atomic file output: the content goes to a temporary file in the target's directory, which is
//! renamed over the target only once everything is written and synced. A reader of the target
//! sees the old file or the whole new one, never a half-written file, and a failed or abandoned
//! write leaves the target untouched and no temporary file behind.
//!
//! - [`AtomicFile`] streams the content ([`std::io::Write`], buffered) and publishes it on
//!   [`AtomicFile::commit`]; dropped without a commit, it removes its temporary file.
//! - [`write_atomic`] writes a whole buffer in one call.
//!
//! The temporary file is made by the [`tempfile`] crate (`.NAME.PID.XXXXXX.tmp` beside the target,
//! `PID` the writing process, created exclusively under an unpredictable name) and published by its
//! `persist` (a rename, which replaces an existing target). A new file gets the permissions
//! [`std::fs::File::create`] would give it; a replaced regular file keeps its permissions. No
//! directory is created.
//!
//! Interruptions: [`remove_temporaries_on_signals`] (called once by a program's `main`) removes the
//! process's uncommitted temporary files on SIGINT, SIGTERM or SIGHUP before it exits;
//! [`stale_temporaries`] finds those a killed process (SIGKILL, an abort, a power cut) left beside
//! a target, so that the next run can name them. [`AtomicDir`] builds a whole directory beside its
//! target and renames it into place.
//!
//! ```
//! use std::io::Write as _;
//!
//! let dir = tempfile::tempdir()?;
//! let path = dir.path().join("rows.csv");
//! let mut out = atomic_output::AtomicFile::create(&path)?;
//! writeln!(out, "k,x")?;
//! writeln!(out, "0,1.5")?;
//! assert!(!path.exists(), "nothing is published before the commit");
//! out.commit()?;
//! assert_eq!(std::fs::read_to_string(&path)?, "k,x\n0,1.5\n");
//!
//! atomic_output::write_atomic(&path, b"replaced\n")?;
//! assert_eq!(std::fs::read_to_string(&path)?, "replaced\n");
//! # Ok::<(), std::io::Error>(())
//! ```

use std::fs;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use tempfile::NamedTempFile;

mod cleanup;
mod dir;

pub use cleanup::{StaleTemporary, remove_temporaries_on_signals, stale_temporaries};
pub use dir::AtomicDir;

/// A file being written atomically: [`AtomicFile::commit`] renames it over the target; dropping
/// it without a commit (or a failed commit) removes the temporary file and leaves the target as
/// it was.
#[derive(Debug)]
pub struct AtomicFile {
    /// The buffered temporary file; `None` once committed or dropped.
    writer: Option<BufWriter<NamedTempFile>>,
    target: PathBuf,
    /// Known to the signal handler until this value drops.
    _pending: cleanup::Pending,
}

impl AtomicFile {
    /// Creates the temporary file for `target` in `target`'s directory (`.` for a bare file name).
    ///
    /// # Errors
    /// [`io::ErrorKind::InvalidInput`] if `target` names no file (empty, or ending in `..`); the
    /// error of creating the temporary file (e.g. the directory does not exist or is not
    /// writable).
    pub fn create(target: impl AsRef<Path>) -> io::Result<Self> {
        let target = target.as_ref();
        let (dir, prefix) = cleanup::temporary_place(target, "a file")?;
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".tmp");
        let kept = fs::metadata(target).ok().filter(fs::Metadata::is_file).map(|m| m.permissions());
        #[cfg(unix)]
        let default = {
            use std::os::unix::fs::PermissionsExt as _;
            // What `File::create` asks for; the process umask applies to both.
            Some(fs::Permissions::from_mode(0o666))
        };
        #[cfg(not(unix))]
        let default = None;
        if let Some(permissions) = kept.clone().or(default) {
            builder.permissions(permissions);
        }
        let file = builder.tempfile_in(dir)?;
        let pending = cleanup::Pending::register(file.path());
        if let Some(permissions) = kept {
            // A mode given at creation is reduced by the umask: the replaced file's mode exactly.
            file.as_file().set_permissions(permissions)?;
        }
        Ok(Self { writer: Some(BufWriter::new(file)), target: target.to_owned(), _pending: pending })
    }

    /// The path the content is published at.
    #[must_use]
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Writes the buffered content, syncs the temporary file to disk and renames it over the
    /// target.
    ///
    /// # Errors
    /// The error of writing, syncing or renaming; the temporary file is removed then and the
    /// target left as it was.
    pub fn commit(self) -> io::Result<()> {
        let target = self.target.clone();
        self.commit_as(&target)
    }

    /// As [`AtomicFile::commit`], but publishes the content at `path` instead of the target
    /// (`path` must be in the target's directory for the rename to be atomic; a partial result
    /// kept under another name, say).
    ///
    /// # Errors
    /// As [`AtomicFile::commit`].
    pub fn commit_as(mut self, path: &Path) -> io::Result<()> {
        let Some(writer) = self.writer.take() else {
            return Err(io::Error::other("already committed"));
        };
        let file = writer.into_inner().map_err(io::IntoInnerError::into_error)?;
        file.as_file().sync_all()?;
        file.persist(path).map_err(|e| e.error)?;
        Ok(())
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        match &mut self.writer {
            Some(w) => w.write(buf),
            None => Err(io::Error::other("output already committed")),
        }
    }

    fn write_all(&mut self, buf: &[u8]) -> io::Result<()> {
        match &mut self.writer {
            Some(w) => w.write_all(buf),
            None => Err(io::Error::other("output already committed")),
        }
    }

    fn flush(&mut self) -> io::Result<()> {
        match &mut self.writer {
            Some(w) => w.flush(),
            None => Ok(()),
        }
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if let Some(writer) = self.writer.take() {
            // Without writing out the buffer: the temporary file is removed when it drops.
            let (file, _unwritten) = writer.into_parts();
            drop(file);
        }
    }
}

/// Writes `bytes` to `path` atomically: to a temporary file in the same directory, synced, then
/// renamed over `path`. On error the temporary file is removed and `path` is untouched.
///
/// # Errors
/// As [`AtomicFile::create`] and [`AtomicFile::commit`].
pub fn write_atomic(path: impl AsRef<Path>, bytes: &[u8]) -> io::Result<()> {
    let mut file = AtomicFile::create(path)?;
    file.write_all(bytes)?;
    file.commit()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The names in `dir`, sorted.
    fn names(dir: &Path) -> Vec<String> {
        let mut n: Vec<String> =
            fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        n.sort();
        n
    }

    #[test]
    fn commit_publishes_and_replaces() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.txt");
        let mut f = AtomicFile::create(&path).unwrap();
        assert_eq!(f.target(), path);
        f.write_all(b"first").unwrap();
        f.flush().unwrap();
        assert!(!path.exists(), "not published before the commit");
        let temporaries = names(dir.path());
        assert_eq!(temporaries.len(), 1);
        assert!(temporaries[0].starts_with(".out.txt.") && temporaries[0].ends_with(".tmp"), "{temporaries:?}");
        f.commit().unwrap();
        assert_eq!(fs::read_to_string(&path).unwrap(), "first");
        write_atomic(&path, b"second").unwrap();
        assert_eq!(fs::read_to_string(&path).unwrap(), "second");
        assert_eq!(names(dir.path()), ["out.txt"]);
    }

    #[test]
    fn a_dropped_writer_leaves_nothing_and_the_target_untouched() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.txt");
        fs::write(&path, "old").unwrap();
        let mut f = AtomicFile::create(&path).unwrap();
        // More than the buffer holds, so that some of it reached the temporary file.
        f.write_all(&vec![b'x'; 100_000]).unwrap();
        assert_eq!(names(dir.path()).len(), 2);
        drop(f);
        assert_eq!(fs::read_to_string(&path).unwrap(), "old");
        assert_eq!(names(dir.path()), ["out.txt"]);
        // Never created: nothing appears.
        drop(AtomicFile::create(dir.path().join("new.txt")).unwrap());
        assert_eq!(names(dir.path()), ["out.txt"]);
    }

    #[test]
    fn a_failed_commit_leaves_nothing_and_the_target_untouched() {
        let dir = tempfile::tempdir().unwrap();
        // A non-empty directory in the way: the rename fails.
        let blocked = dir.path().join("sub");
        fs::create_dir(&blocked).unwrap();
        fs::write(blocked.join("inside"), "kept").unwrap();
        let mut f = AtomicFile::create(&blocked).unwrap();
        f.write_all(b"x").unwrap();
        assert!(f.commit().is_err());
        assert!(write_atomic(&blocked, b"x").is_err());
        assert!(blocked.is_dir());
        assert_eq!(fs::read_to_string(blocked.join("inside")).unwrap(), "kept");
        assert_eq!(names(dir.path()), ["sub"]);
    }

    #[test]
    fn paths_without_a_file_or_a_directory_are_errors() {
        let dir = tempfile::tempdir().unwrap();
        let e = AtomicFile::create("").unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
        assert!(AtomicFile::create(dir.path().join("..")).is_err());
        assert!(write_atomic(dir.path().join("missing").join("out.txt"), b"x").is_err());
        // A file where the directory should be.
        fs::write(dir.path().join("file"), "f").unwrap();
        assert!(write_atomic(dir.path().join("file").join("out.txt"), b"x").is_err());
        assert_eq!(names(dir.path()), ["file"]);
    }

    #[cfg(unix)]
    #[test]
    fn permissions_are_those_of_a_new_file_or_the_replaced_one() {
        use std::os::unix::fs::PermissionsExt as _;
        let dir = tempfile::tempdir().unwrap();
        let (fresh, created) = (dir.path().join("fresh"), dir.path().join("created"));
        write_atomic(&fresh, b"x").unwrap();
        fs::File::create(&created).unwrap();
        let mode = |p: &Path| fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&fresh), mode(&created), "as File::create (not tempfile's 0600)");
        fs::set_permissions(&fresh, fs::Permissions::from_mode(0o640)).unwrap();
        write_atomic(&fresh, b"y").unwrap();
        assert_eq!(mode(&fresh), 0o640);
    }
}
