//! `--output`, written safely: never one of the input files, the directory checked before any
//! computation, rows streamed into a temporary file beside the target and renamed over it only
//! on success, so that a failed run leaves no half-written output (and an older output intact).
//! The temporary file and the rename are [`atomic_output`]'s; the checks are this module's.

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use atomic_output::AtomicFile;

use crate::error::{Error, Kept};
use crate::run::OnError;

/// An output file being written. [`OutputFile::commit`] publishes it; dropping it without
/// committing removes the temporary file.
#[derive(Debug)]
pub struct OutputFile {
    /// `None` once committed.
    sink: Option<Sink>,
    /// The path as the user gave it (for messages).
    shown: PathBuf,
    /// The canonical target.
    target: PathBuf,
}

/// `OUT.partial.csv` for `OUT.csv` (`OUT.partial` without an extension): where
/// `--on-error keep-partial` keeps the steps before an error.
#[must_use]
pub fn partial_path(output: &Path) -> PathBuf {
    let stem = output.file_stem().unwrap_or_default();
    let mut name = stem.to_owned();
    name.push(".partial");
    if let Some(ext) = output.extension() {
        name.push(".");
        name.push(ext);
    }
    output.with_file_name(name)
}

/// Where the rows go.
#[derive(Debug)]
enum Sink {
    /// A temporary file beside the (canonical) target, renamed over it on commit.
    Atomic(AtomicFile),
    /// An existing non-regular file (a device, a pipe), written in place.
    InPlace(BufWriter<File>),
}

/// The canonical form of `path`, `None` if it cannot be resolved (it does not exist).
fn canonical(path: &Path) -> Option<PathBuf> {
    fs::canonicalize(path).ok()
}

/// Whether two existing paths are the same file (same canonical path, or on Unix the same
/// device and inode: a hard link).
pub(crate) fn same_file(a: &Path, b: &Path) -> bool {
    if canonical(a).is_some_and(|ca| canonical(b).is_some_and(|cb| ca == cb)) {
        return true;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(ma), Ok(mb)) = (fs::metadata(a), fs::metadata(b)) {
            return ma.dev() == mb.dev() && ma.ino() == mb.ino();
        }
    }
    false
}

impl OutputFile {
    /// Prepares `output`: refuses it if it is one of `inputs` (`(role, path)`, compared by
    /// canonical path), a directory, a read-only file or in a directory that does not exist,
    /// and creates the temporary file beside it (which checks that the directory is writable).
    /// An existing non-regular file (`/dev/null`, a named pipe) is written in place.
    ///
    /// # Errors
    /// [`Error::SameFile`], [`Error::Output`].
    pub fn create(output: &Path, inputs: &[(&'static str, &Path)]) -> Result<Self, Error> {
        let refuse = |message: String| Error::Output { path: output.to_owned(), message };
        if output.as_os_str().is_empty() {
            return Err(refuse("empty path".into()));
        }
        if output.as_os_str() == "-" {
            return Err(refuse(
                "`-` is not read as standard output (the output is written atomically to a file): give a file \
                 path, or /dev/stdout to stream it"
                    .into(),
            ));
        }
        let existing = match fs::metadata(output) {
            Ok(meta) => Some(meta),
            Err(e) if e.kind() == io::ErrorKind::NotFound => {
                if fs::symlink_metadata(output).is_ok() {
                    return Err(refuse("is a symbolic link to a file that does not exist".into()));
                }
                None
            }
            Err(e) => return Err(refuse(e.to_string())),
        };
        let target = match &existing {
            Some(meta) if meta.is_dir() => return Err(refuse("is a directory".into())),
            Some(meta) if meta.is_file() && meta.permissions().readonly() => {
                return Err(refuse("is read-only".into()));
            }
            // A device or a pipe may have no canonical name (`/dev/stdout` on a pipe resolves to
            // `/proc/self/fd/1` → `pipe:[…]`): then the name given.
            Some(meta) if !meta.is_file() => fs::canonicalize(output).unwrap_or_else(|_| output.to_owned()),
            Some(_) => fs::canonicalize(output).map_err(|e| refuse(e.to_string()))?,
            None => {
                let Some(name) = output.file_name() else {
                    return Err(refuse("does not name a file".into()));
                };
                let parent = match output.parent() {
                    Some(p) if !p.as_os_str().is_empty() => p,
                    _ => Path::new("."),
                };
                let dir = fs::canonicalize(parent)
                    .map_err(|e| refuse(format!("cannot use directory {}: {e}", parent.display())))?;
                dir.join(name)
            }
        };
        for (role, path) in inputs {
            let same =
                if existing.is_some() { same_file(output, path) } else { canonical(path) == Some(target.clone()) };
            if same {
                return Err(Error::SameFile { role, output: output.to_owned(), other: path.to_path_buf() });
            }
        }
        let sink = match existing {
            Some(meta) if !meta.is_file() => {
                // A device or a pipe: nothing to replace, nothing half-written to clean up.
                // Opened by the name given: `/dev/stdout` resolves to `/proc/self/fd/1`, whose
                // canonical form (`pipe:[…]`) names no file.
                let file =
                    OpenOptions::new().write(true).truncate(true).open(output).map_err(|e| refuse(e.to_string()))?;
                Sink::InPlace(BufWriter::new(file))
            }
            // The temporary file beside the target (keeping a replaced file's permissions).
            _ => Sink::Atomic(AtomicFile::create(&target).map_err(|e| {
                let dir = target.parent().unwrap_or(Path::new("."));
                refuse(format!("cannot write in directory {}: {e}", dir.display()))
            })?),
        };
        Ok(Self { sink: Some(sink), shown: output.to_owned(), target })
    }

    /// The error `e` that stopped a run after `steps` rows, with what `policy` did with them:
    /// with [`OnError::KeepPartial`] the rows are published as `OUT.partial.csv` (never over one
    /// of `inputs`), a streamed output keeps what it was sent; otherwise `e` as it is (the
    /// temporary file is removed).
    #[must_use]
    pub fn fail(self, e: Error, steps: u64, policy: OnError, inputs: &[(&'static str, &Path)]) -> Error {
        if policy != OnError::KeepPartial {
            return e;
        }
        let kept = self.keep_partial(steps, inputs);
        Error::Stopped { source: Box::new(e), kept }
    }

    fn keep_partial(mut self, steps: u64, inputs: &[(&'static str, &Path)]) -> Kept {
        match self.sink.take() {
            Some(Sink::InPlace(w)) => {
                let _ = w.into_inner();
                Kept::Streamed { path: self.shown.clone(), steps }
            }
            Some(Sink::Atomic(_)) if steps == 0 => Kept::Nothing { reason: "no step had succeeded".into() },
            Some(Sink::Atomic(file)) => {
                let partial = partial_path(&self.target);
                if let Some((role, _)) = inputs.iter().find(|(_, p)| canonical(p).is_some_and(|c| c == partial)) {
                    let reason = format!("{} is the {role} file", partial.display());
                    return Kept::Nothing { reason };
                }
                // Named as the user named the output, unless that is a link to elsewhere.
                let linked = fs::symlink_metadata(&self.shown).is_ok_and(|m| m.file_type().is_symlink());
                let shown = if linked { partial.clone() } else { partial_path(&self.shown) };
                match file.commit_as(&partial) {
                    Ok(()) => Kept::Partial { path: shown, steps },
                    Err(e) => Kept::Nothing { reason: format!("writing {}: {e}", partial.display()) },
                }
            }
            None => Kept::Nothing { reason: "the output was already written".into() },
        }
    }

    /// The path as given.
    #[must_use]
    pub fn path(&self) -> &Path {
        &self.shown
    }

    /// Flushes the content to disk and renames the temporary file over the target.
    ///
    /// # Errors
    /// [`Error::Io`] if writing, syncing or renaming fails (the temporary file is removed).
    pub fn commit(mut self) -> Result<(), Error> {
        let io = |e| Error::io(&self.shown, e);
        match self.sink.take() {
            Some(Sink::Atomic(file)) => file.commit().map_err(io),
            Some(Sink::InPlace(w)) => w.into_inner().map(drop).map_err(|e| io(e.into_error())),
            None => Ok(()),
        }
    }
}

impl Write for OutputFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        match &mut self.sink {
            Some(Sink::Atomic(f)) => f.write(buf),
            Some(Sink::InPlace(w)) => w.write(buf),
            None => Err(io::Error::other("output already committed")),
        }
    }

    fn flush(&mut self) -> io::Result<()> {
        match &mut self.sink {
            Some(Sink::Atomic(f)) => f.flush(),
            Some(Sink::InPlace(w)) => w.flush(),
            None => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("port-est-output-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn commit_replaces_and_drop_leaves_nothing() {
        let d = dir("commit");
        let out = d.join("out.csv");
        fs::write(&out, "old\n").unwrap();
        let mut f = OutputFile::create(&out, &[]).unwrap();
        writeln!(f, "new").unwrap();
        assert_eq!(fs::read_to_string(&out).unwrap(), "old\n", "untouched until committed");
        drop(f);
        assert_eq!(fs::read_to_string(&out).unwrap(), "old\n");
        assert_eq!(fs::read_dir(&d).unwrap().count(), 1, "temporary file removed");
        let mut f = OutputFile::create(&out, &[]).unwrap();
        writeln!(f, "new").unwrap();
        f.commit().unwrap();
        assert_eq!(fs::read_to_string(&out).unwrap(), "new\n");
        assert_eq!(fs::read_dir(&d).unwrap().count(), 1);
        fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn refuses_inputs_directories_and_missing_directories() {
        let d = dir("refuse");
        let input = d.join("in.csv");
        fs::write(&input, "x").unwrap();
        let other = d.join("sub").join("..").join("in.csv");
        fs::create_dir(d.join("sub")).unwrap();
        let e = OutputFile::create(&other, &[("input", &input)]).unwrap_err();
        assert!(matches!(e, Error::SameFile { role: "input", .. }), "{e}");
        let e = OutputFile::create(&d, &[]).unwrap_err().to_string();
        assert!(e.ends_with("is a directory"), "{e}");
        let e = OutputFile::create(&d.join("nope").join("out.csv"), &[]).unwrap_err().to_string();
        assert!(e.contains("cannot use directory"), "{e}");
        assert_eq!(fs::read_to_string(&input).unwrap(), "x");
        fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_dash_is_not_a_file_name() {
        let e = OutputFile::create(Path::new("-"), &[]).unwrap_err().to_string();
        assert!(e.starts_with("--output -: `-` is not read as standard output"), "{e}");
        assert!(!Path::new("-").exists());
    }
}
