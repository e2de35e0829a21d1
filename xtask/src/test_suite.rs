//! `cargo xtask test`: every test of the repository in one command — the Rust tests
//! (`cargo test --workspace`, with any extra arguments passed through), then the Python package's
//! tests in a virtual environment under the target directory:
//!
//! 1. `python3 -m venv target/python-venv` (once; `$PYTHON` overrides the interpreter);
//! 2. `pip install -r crates/port-estimation-py/requirements-test.txt` (pinned; again only when the
//!    file changed);
//! 3. `pip install crates/port-estimation-py` (maturin builds the extension, optimised, sharing the
//!    release build of the workspace crates with `cargo xtask` itself);
//! 4. `python -m pytest crates/port-estimation-py/tests`.
//!
//! `--rust-only` and `--python-only` run one half. A missing interpreter, `venv` module or `pip`
//! is reported with what to install.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The Python package's directory, relative to the workspace root.
pub const PACKAGE_DIR: &str = "crates/port-estimation-py";

/// `cargo xtask test --help`.
pub const HELP: &str = "\
cargo xtask test [--rust-only | --python-only] [CARGO TEST ARGS...] [-- TEST BINARY ARGS...]

Every test: `cargo test --workspace ARGS`, then the Python package's tests (a virtual environment
in target/python-venv with the pinned requirements of crates/port-estimation-py, the package built
by maturin, pytest). $PYTHON names the interpreter (default python3).

  --rust-only      only the Rust tests
  --python-only    only the Python tests
  -h, --help       this text
";

/// What `cargo xtask test` was asked to run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TestPlan {
    /// Run `cargo test --workspace`.
    pub rust: bool,
    /// Run the Python tests.
    pub python: bool,
    /// Extra arguments of `cargo test` (`--features …`, `-- --nocapture`).
    pub cargo_args: Vec<OsString>,
    /// Only print the command's help.
    pub help: bool,
}

impl TestPlan {
    /// Splits the command line: `--rust-only` and `--python-only` are this command's, everything
    /// else goes to `cargo test` (after a `--`, everything goes to the test binaries).
    ///
    /// # Errors
    /// Both `--rust-only` and `--python-only`.
    pub fn parse(args: &[OsString]) -> Result<Self, String> {
        let (mut rust, mut python, mut cargo_args) = (true, true, Vec::new());
        let (mut passthrough, mut help) = (false, false);
        for a in args {
            match a.to_str() {
                Some("--") if !passthrough => {
                    passthrough = true;
                    cargo_args.push(a.clone());
                }
                Some("--rust-only") if !passthrough => python = false,
                Some("--python-only") if !passthrough => rust = false,
                Some("--help" | "-h") if !passthrough => help = true,
                _ => cargo_args.push(a.clone()),
            }
        }
        if !rust && !python {
            return Err("--rust-only and --python-only exclude each other".into());
        }
        Ok(Self { rust, python, cargo_args, help })
    }
}

/// The workspace root (the parent of this crate).
fn root() -> PathBuf {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    here.parent().map_or_else(|| here.join(".."), Path::to_path_buf)
}

/// The target directory: `$CARGO_TARGET_DIR` or `target/` of the workspace.
fn target_dir(root: &Path) -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| root.join("target"), PathBuf::from)
}

/// The interpreter of a virtual environment.
pub fn venv_python(venv: &Path) -> PathBuf {
    if cfg!(windows) { venv.join("Scripts").join("python.exe") } else { venv.join("bin").join("python") }
}

/// Runs `cmd`, echoing it; `Err(what)` when it cannot start or fails.
fn run(cmd: &mut Command, what: &str) -> Result<(), String> {
    let shown = std::iter::once(cmd.get_program())
        .chain(cmd.get_args())
        .map(|a| a.to_string_lossy().into_owned())
        .collect::<Vec<_>>()
        .join(" ");
    eprintln!("==> {shown}");
    match cmd.status() {
        Ok(s) if s.success() => Ok(()),
        Ok(s) => Err(format!("{what} ({shown} exited with {s})")),
        Err(e) => Err(format!("{what}: cannot run {shown}: {e}")),
    }
}

/// Whether `cmd` runs and succeeds, quietly.
fn succeeds(cmd: &mut Command) -> bool {
    cmd.stdout(std::process::Stdio::null()).stderr(std::process::Stdio::null()).status().is_ok_and(|s| s.success())
}

/// Runs the plan from the command line (`cargo xtask test …`).
///
/// # Errors
/// The first part that failed, with what to do about it.
pub fn run_tests(args: &[OsString]) -> Result<(), String> {
    let plan = TestPlan::parse(args)?;
    if plan.help {
        print!("{HELP}");
        return Ok(());
    }
    let root = root();
    let mut failures = Vec::new();
    if plan.rust {
        let cargo = std::env::var_os("CARGO").unwrap_or_else(|| OsString::from("cargo"));
        let rust = run(
            Command::new(cargo).current_dir(&root).args(["test", "--workspace"]).args(&plan.cargo_args),
            "the Rust tests failed",
        );
        failures.extend(rust.err());
    }
    // The Python half runs even when the Rust half failed: one run reports both.
    if plan.python {
        failures.extend(python_tests(&root).err());
    }
    if failures.is_empty() { Ok(()) } else { Err(failures.join("\n")) }
}

/// Steps 1–4 of the module documentation.
fn python_tests(root: &Path) -> Result<(), String> {
    let python = std::env::var_os("PYTHON").unwrap_or_else(|| OsString::from("python3"));
    let shown = PathBuf::from(&python).display().to_string();
    if !succeeds(Command::new(&python).arg("--version")) {
        return Err(format!(
            "{shown} not found: the Python tests need CPython 3.11 or newer with venv and pip (Debian/Ubuntu: apt-get \
             install python3 python3-venv python3-pip), or PYTHON=/path/to/python3; `cargo xtask test --rust-only` \
             skips them"
        ));
    }
    let venv = target_dir(root).join("python-venv");
    let py = venv_python(&venv);
    if !py.exists() {
        run(
            Command::new(&python).arg("-m").arg("venv").arg(&venv),
            &format!(
                "could not create the virtual environment {} (is the venv module installed? Debian/Ubuntu: apt-get \
                 install python3-venv)",
                venv.display()
            ),
        )?;
    }
    if !succeeds(Command::new(&py).args(["-m", "pip", "--version"])) {
        return Err(format!(
            "pip is missing in {} (Debian/Ubuntu: apt-get install python3-pip python3-venv; then remove that directory)",
            venv.display()
        ));
    }
    let package = root.join(PACKAGE_DIR);
    let requirements = package.join("requirements-test.txt");
    let wanted = std::fs::read_to_string(&requirements).map_err(|e| format!("{}: {e}", requirements.display()))?;
    let stamp = venv.join("requirements-test.installed");
    if std::fs::read_to_string(&stamp).ok().as_deref() != Some(wanted.as_str()) {
        run(
            Command::new(&py).args(["-m", "pip", "install", "--disable-pip-version-check", "-r"]).arg(&requirements),
            "pip could not install the test requirements (is PyPI reachable?)",
        )?;
        std::fs::write(&stamp, &wanted).map_err(|e| format!("{}: {e}", stamp.display()))?;
    }
    // The venv's maturin builds the extension (no isolated build environment to download).
    let path = std::env::join_paths(
        std::iter::once(py.parent().map(Path::to_path_buf).unwrap_or_default())
            .chain(std::env::var_os("PATH").map(|p| std::env::split_paths(&p).collect::<Vec<_>>()).unwrap_or_default()),
    )
    .map_err(|e| format!("PATH: {e}"))?;
    eprintln!("==> building the extension with maturin (optimised; a few minutes the first time)");
    run(
        Command::new(&py)
            .current_dir(root)
            .env("PATH", &path)
            .args(["-m", "pip", "install", "--disable-pip-version-check", "--no-build-isolation", "--no-deps"])
            .args(["--force-reinstall", PACKAGE_DIR]),
        "building or installing the Python package failed",
    )?;
    // (No .pytest_cache in the source tree.)
    run(
        Command::new(&py)
            .current_dir(root)
            .args(["-m", "pytest", "-q", "-p", "no:cacheprovider"])
            .arg(package.join("tests")),
        "the Python tests failed",
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(v: &[&str]) -> Vec<OsString> {
        v.iter().map(OsString::from).collect()
    }

    #[test]
    fn cargo_arguments_pass_through_and_the_switches_stay_here() {
        let p = TestPlan::parse(&args(&["--features", "estimators/clarabel"])).unwrap();
        assert_eq!(
            p,
            TestPlan {
                rust: true,
                python: true,
                cargo_args: args(&["--features", "estimators/clarabel"]),
                help: false
            }
        );
        assert!(TestPlan::parse(&args(&["--help"])).unwrap().help);
        let p = TestPlan::parse(&args(&["--rust-only", "-p", "models", "--", "--python-only"])).unwrap();
        assert!(p.rust && !p.python);
        assert_eq!(p.cargo_args, args(&["-p", "models", "--", "--python-only"]));
        assert!(TestPlan::parse(&args(&["--python-only"])).unwrap().python);
        assert!(TestPlan::parse(&args(&["--rust-only", "--python-only"])).is_err());
    }

    #[test]
    fn the_package_and_its_requirements_are_where_the_command_looks() {
        let package = root().join(PACKAGE_DIR);
        assert!(package.join("pyproject.toml").is_file());
        let req = std::fs::read_to_string(package.join("requirements-test.txt")).unwrap();
        for name in ["maturin==", "numpy==", "filterpy==", "pytest==", "dask[distributed]==", "pyarrow=="] {
            assert!(req.lines().any(|l| l.starts_with(name)), "{name} is not pinned");
        }
        assert!(venv_python(Path::new("v")).starts_with("v"));
    }
}
