//! A directory built beside its target and renamed into place when complete.

use std::fs;
use std::io;
use std::path::{Path, PathBuf};

use tempfile::TempDir;

use crate::cleanup::{self, Pending};

/// A directory being built: its content goes into a hidden temporary directory beside the target
/// (`.NAME.PID.XXXXXX.tmp`), which [`AtomicDir::commit`] renames over the target. Until then the
/// target keeps its old content, whole; dropped without a commit, the temporary directory is
/// removed (on SIGINT/SIGTERM too, with [`crate::remove_temporaries_on_signals`]), and one left
/// by a killed process is found by [`crate::stale_temporaries`].
#[derive(Debug)]
pub struct AtomicDir {
    /// `None` once committed.
    tmp: Option<TempDir>,
    target: PathBuf,
    _pending: Pending,
}

impl AtomicDir {
    /// Creates the temporary directory for `target` in `target`'s parent (which must exist).
    ///
    /// # Errors
    /// [`io::ErrorKind::InvalidInput`] if `target` names no directory; the error of creating the
    /// temporary directory.
    pub fn create(target: impl AsRef<Path>) -> io::Result<Self> {
        let target = target.as_ref();
        let (parent, prefix) = cleanup::temporary_place(target, "a directory")?;
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".tmp");
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt as _;
            // What `create_dir` asks for (reduced by the umask), not tempfile's 0700.
            builder.permissions(fs::Permissions::from_mode(0o777));
        }
        let tmp = builder.tempdir_in(parent)?;
        let pending = Pending::register(tmp.path());
        Ok(Self { tmp: Some(tmp), target: target.to_owned(), _pending: pending })
    }

    /// Where to write the content now.
    #[must_use]
    pub fn path(&self) -> &Path {
        self.tmp.as_ref().map_or(self.target.as_path(), TempDir::path)
    }

    /// The path the directory is published at.
    #[must_use]
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Renames the built directory over the target: an existing target is first moved aside
    /// (`.NAME.PID.old.tmp`), then removed once the new directory is in place (put back if the
    /// rename fails).
    ///
    /// # Errors
    /// The error of a rename or of removing the old directory.
    pub fn commit(mut self) -> io::Result<()> {
        let Some(tmp) = self.tmp.take() else {
            return Err(io::Error::other("already committed"));
        };
        let built = tmp.keep();
        let result = self.publish(&built);
        if result.is_err() {
            let _ = fs::remove_dir_all(&built);
        }
        result
    }

    fn publish(&self, built: &Path) -> io::Result<()> {
        let exists = fs::symlink_metadata(&self.target).is_ok();
        if !exists {
            return fs::rename(built, &self.target);
        }
        let name = self.target.file_name().unwrap_or_default();
        let mut old_name = cleanup::temporary_prefix(name);
        old_name.push("old.tmp");
        let old = self.target.with_file_name(old_name);
        if fs::symlink_metadata(&old).is_ok() {
            fs::remove_dir_all(&old)?;
        }
        fs::rename(&self.target, &old)?;
        let _old_pending = Pending::register(&old);
        if let Err(e) = fs::rename(built, &self.target) {
            let _ = fs::rename(&old, &self.target);
            return Err(e);
        }
        fs::remove_dir_all(&old)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(dir: &Path) -> Vec<String> {
        let mut n: Vec<String> =
            fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        n.sort();
        n
    }

    #[test]
    fn a_directory_is_replaced_whole_or_not_at_all() {
        let root = tempfile::tempdir().unwrap();
        let target = root.path().join("paper");
        fs::create_dir(&target).unwrap();
        fs::write(target.join("old.txt"), "old").unwrap();
        let building = AtomicDir::create(&target).unwrap();
        fs::write(building.path().join("new.txt"), "new").unwrap();
        assert_eq!(names(&target), ["old.txt"], "the old content stays until the commit");
        building.commit().unwrap();
        assert_eq!(names(&target), ["new.txt"]);
        assert_eq!(names(root.path()), ["paper"], "nothing left beside it");
        // Dropped without a commit: the target is untouched and nothing is left.
        let abandoned = AtomicDir::create(&target).unwrap();
        fs::write(abandoned.path().join("half.txt"), "half").unwrap();
        drop(abandoned);
        assert_eq!(names(&target), ["new.txt"]);
        assert_eq!(names(root.path()), ["paper"]);
        // A new target.
        let fresh = AtomicDir::create(root.path().join("fresh")).unwrap();
        fresh.commit().unwrap();
        assert!(root.path().join("fresh").is_dir());
        assert!(AtomicDir::create(root.path().join("missing").join("x")).is_err());
    }
}
