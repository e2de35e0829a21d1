//! Interrupted runs: the process's uncommitted temporary files and directories are removed on
//! SIGINT, SIGTERM and SIGHUP; those a killed process left behind are found by their names.

use std::ffi::{OsStr, OsString};
use std::fs;
use std::io;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard, PoisonError};

/// This process's uncommitted temporary files and directories.
static PENDING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn pending() -> MutexGuard<'static, Vec<PathBuf>> {
    PENDING.lock().unwrap_or_else(PoisonError::into_inner)
}

/// A temporary path known to the signal handler until this value drops.
#[derive(Debug)]
pub(crate) struct Pending(PathBuf);

impl Pending {
    pub(crate) fn register(path: &Path) -> Self {
        pending().push(path.to_owned());
        Self(path.to_owned())
    }
}

impl Drop for Pending {
    fn drop(&mut self) {
        let mut all = pending();
        if let Some(i) = all.iter().rposition(|p| *p == self.0) {
            all.swap_remove(i);
        }
    }
}

/// `.NAME.PID.`: the start of the name of a temporary file or directory for the target `NAME`.
pub(crate) fn temporary_prefix(name: &OsStr) -> OsString {
    let mut prefix = OsString::from(".");
    prefix.push(name);
    prefix.push(format!(".{}.", std::process::id()));
    prefix
}

/// The directory the temporaries of `target` go in (its parent; `.` for a bare name) and a
/// builder of their names, `.NAME.PID.*.tmp`; `kind` says what `target` must name ("a file").
///
/// # Errors
/// [`io::ErrorKind::InvalidInput`] if `target` names nothing (empty, or ending in `..`).
pub(crate) fn temporary_place<'a>(target: &'a Path, kind: &str) -> io::Result<(&'a Path, OsString)> {
    let name = target.file_name().ok_or_else(|| {
        io::Error::new(io::ErrorKind::InvalidInput, format!("{}: does not name {kind}", target.display()))
    })?;
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    Ok((dir, temporary_prefix(name)))
}

/// Removes a file or a directory tree, ignoring what is already gone.
fn remove(path: &Path) {
    match fs::symlink_metadata(path) {
        Ok(m) if m.is_dir() => {
            let _ = fs::remove_dir_all(path);
        }
        Ok(_) => {
            let _ = fs::remove_file(path);
        }
        Err(_) => {}
    }
}

/// Installs, once per process, a handler of SIGINT, SIGTERM and SIGHUP that removes every
/// uncommitted temporary file of [`crate::AtomicFile`] and directory of [`crate::AtomicDir`],
/// then exits with status 128 + the signal's number (130 for SIGINT, 143 for SIGTERM). A thread
/// waits for the signals, so the removal runs as ordinary code. Does nothing on other platforms
/// than Unix. A SIGKILL cannot be caught: [`stale_temporaries`] finds what it leaves.
///
/// # Errors
/// When the handler cannot be installed.
pub fn remove_temporaries_on_signals() -> io::Result<()> {
    #[cfg(unix)]
    {
        use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};

        static INSTALLED: Mutex<bool> = Mutex::new(false);
        let mut installed = INSTALLED.lock().unwrap_or_else(PoisonError::into_inner);
        if *installed {
            return Ok(());
        }
        let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP])?;
        std::thread::Builder::new().name("atomic-output-signals".into()).spawn(move || {
            if let Some(signal) = signals.forever().next() {
                // Held to the exit: no temporary file is registered after the sweep.
                let all = pending();
                for path in all.iter() {
                    remove(path);
                }
                std::process::exit(128 + signal);
            }
        })?;
        *installed = true;
    }
    Ok(())
}

/// A temporary file or directory left beside a target by a run that did not finish.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StaleTemporary {
    /// Its path.
    pub path: PathBuf,
    /// The process that wrote it, when its name tells (names written before the process id was
    /// part of them do not).
    pub pid: Option<u32>,
}

/// Whether it can be told that process `pid` runs (`None`: it cannot be told here).
fn running(pid: u32) -> Option<bool> {
    let proc = Path::new("/proc");
    if !proc.join("self").exists() {
        return None;
    }
    Some(proc.join(pid.to_string()).exists())
}

/// The temporary files and directories beside `target` (`.NAME.PID.XXXXXX.tmp`, or the older
/// `.NAME.XXXXXX.tmp`) that no running process is writing: left by a run that was killed
/// (SIGKILL, an abort) before it could remove them. Those of this process and of a process that
/// runs (another run writing the same target) are not listed; where it cannot be told whether a
/// process runs (no `/proc`), they are.
///
/// # Errors
/// When `target`'s directory cannot be read (a missing directory is not an error: nothing is
/// listed).
pub fn stale_temporaries(target: &Path) -> io::Result<Vec<StaleTemporary>> {
    let Some(name) = target.file_name() else {
        return Ok(Vec::new());
    };
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let entries = match fs::read_dir(dir) {
        Ok(e) => e,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(e),
    };
    let start = format!(".{}.", name.to_string_lossy());
    let mut stale = Vec::new();
    for entry in entries {
        let entry = entry?;
        let file_name = entry.file_name();
        let file_name = file_name.to_string_lossy();
        let Some(middle) = file_name.strip_prefix(&start).and_then(|rest| rest.strip_suffix(".tmp")) else {
            continue;
        };
        // `PID.XXXXXX` (six random characters), or the older `XXXXXX`.
        let pid = middle.split_once('.').and_then(|(pid, _)| pid.parse::<u32>().ok());
        let live = match pid {
            Some(p) if p == std::process::id() => true,
            Some(p) => running(p).unwrap_or(false),
            None => false,
        };
        if !live {
            stale.push(StaleTemporary { path: entry.path(), pid });
        }
    }
    stale.sort_by(|a, b| a.path.cmp(&b.path));
    Ok(stale)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stale_names_are_found_and_live_ones_are_not() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out.csv");
        assert!(stale_temporaries(&target).unwrap().is_empty());
        // A process id that is certainly not running (above Linux's pid_max), an old-style name,
        // this process's own file, and unrelated names.
        let dead = dir.path().join(".out.csv.4294967295.ab12cd.tmp");
        let old = dir.path().join(".out.csv.Xy3k9Q.tmp");
        let own = dir.path().join(format!(".out.csv.{}.zz99zz.tmp", std::process::id()));
        for p in [&dead, &old, &own] {
            fs::write(p, "x").unwrap();
        }
        for other in [".other.csv.1.ab12cd.tmp", "out.csv", ".out.csv.1.ab12cd.txt"] {
            fs::write(dir.path().join(other), "x").unwrap();
        }
        let found = stale_temporaries(&target).unwrap();
        let paths: Vec<&Path> = found.iter().map(|s| s.path.as_path()).collect();
        assert_eq!(paths, [dead.as_path(), old.as_path()]);
        assert_eq!(found[0].pid, Some(u32::MAX));
        assert_eq!(found[1].pid, None);
        // A missing directory lists nothing.
        assert!(stale_temporaries(&dir.path().join("missing").join("out.csv")).unwrap().is_empty());
    }

    #[test]
    fn pending_paths_are_registered_until_dropped() {
        let path = PathBuf::from("/nonexistent/.x.1.abcdef.tmp");
        let p = Pending::register(&path);
        assert!(pending().contains(&path));
        drop(p);
        assert!(!pending().contains(&path));
    }
}
