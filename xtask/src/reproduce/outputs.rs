//! What every paper's reproduction writes alike: file-name slugs, per-run CSV files, atomic
//! writes (a temporary file in the target directory renamed into place, so that no half-written
//! output is ever left behind), the run's record in `summary.json` ([`RunInfo`]), the claims and
//! their verdicts ([`Claim`]), and the numbers and cells of the Markdown reports ([`sig3`],
//! [`cell`]).

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use nalgebra::DVector;
use serde::Serialize;
use svg_plot::{BarChart, Chart, Grid};

use super::runner::Run;

/// `v` with three significant digits (`–` when not finite).
#[must_use]
pub fn sig3(v: f64) -> String {
    if !v.is_finite() {
        return "–".into();
    }
    if v == 0.0 {
        return "0".into();
    }
    let decimals = (2 - v.abs().log10().floor() as i32).max(0) as usize;
    format!("{v:.decimals$}")
}

/// Text for a Markdown table cell (a `|` would end the cell).
#[must_use]
pub fn cell(text: &str) -> String {
    text.replace('|', "\\|")
}

/// One of a paper's claims (or one of a campaign's targets), the verdict of this reproduction
/// (`reproduced`, `partly reproduced (…)`, `not reproduced`, `not testable as published`; `met`,
/// `not met`) and the numbers behind it.
#[derive(Debug, Clone, Serialize)]
pub struct Claim {
    /// The claim, as the paper makes it, or the target.
    pub claim: String,
    /// The verdict.
    pub verdict: String,
    /// The numbers behind the verdict.
    pub evidence: String,
}

/// Where and how a reproduction ran, in its `summary.json` (never in a snapshot): read at the
/// start of the run, the wall-clock total at its end.
#[derive(Debug, Clone, Serialize)]
pub struct RunInfo {
    /// CPU model and core count.
    pub machine: String,
    /// `release`, or `debug` when built with debug assertions (timings then not representative).
    pub build: String,
    /// `/proc/loadavg` when the run started (other processes share the machine).
    pub load_average: String,
    /// Total wall-clock seconds of the reproduction.
    pub total_seconds: f64,
    /// When the run started.
    #[serde(skip)]
    started: Instant,
}

impl RunInfo {
    /// The machine, the build and the load now, and the clock started.
    #[must_use]
    pub fn start() -> Self {
        Self {
            machine: machine(),
            build: if cfg!(debug_assertions) { "debug" } else { "release" }.to_owned(),
            load_average: std::fs::read_to_string("/proc/loadavg")
                .map_or_else(|_| "unknown".into(), |s| s.trim().into()),
            total_seconds: 0.0,
            started: Instant::now(),
        }
    }

    /// The same, with the seconds since [`RunInfo::start`].
    #[must_use]
    pub fn finished(mut self) -> Self {
        self.total_seconds = self.started.elapsed().as_secs_f64();
        self
    }
}

/// A short description of the machine (CPU model and core count).
#[must_use]
pub fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines().find(|l| l.starts_with("model name")).map(|l| l.split(':').nth(1).unwrap_or("").trim().to_owned())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    format!("{cpu}, {cores} cores")
}

/// Writes `bytes` to `path` atomically with [`atomic_output::write_atomic`]: to a temporary file
/// in the same directory, synced, then renamed over `path`. On error the temporary file is removed
/// and `path` is untouched.
///
/// # Errors
/// The temporary file cannot be created, written or renamed over `path`.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    atomic_output::write_atomic(path, bytes)
}

/// Writing a figure of [`svg_plot`] (which renders SVG documents but writes no files):
/// `figure.write(path)` writes its SVG document to `path` with [`write_atomic`], creating missing
/// parent directories.
pub trait WriteFigure {
    /// The figure as a standalone SVG document.
    fn svg(&self) -> String;

    /// Writes [`WriteFigure::svg`] to `path`, creating missing parent directories; the document
    /// goes to a temporary file in the same directory first and is then renamed, so that no
    /// half-written figure is ever left at `path`.
    ///
    /// # Errors
    /// The directory cannot be created or the file cannot be written.
    fn write(&self, path: &Path) -> std::io::Result<()> {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)?;
        }
        write_atomic(path, self.svg().as_bytes())
    }
}

impl WriteFigure for Chart {
    fn svg(&self) -> String {
        self.to_svg()
    }
}

impl WriteFigure for BarChart {
    fn svg(&self) -> String {
        self.to_svg()
    }
}

impl WriteFigure for Grid {
    fn svg(&self) -> String {
        self.to_svg()
    }
}

/// A file-name-safe identifier of an estimator label.
pub fn slug(label: &str) -> String {
    let mut s: String =
        label.chars().map(|c| if c.is_ascii_alphanumeric() { c.to_ascii_lowercase() } else { '_' }).collect();
    while s.contains("__") {
        s = s.replace("__", "_");
    }
    s.trim_matches('_').to_owned()
}

/// One CSV per run: `k,t,x1..xn,xhat1..xhatn,lo1..lon,hi1..hin,trace,tau1,tau2,tau3,fallback`.
pub fn write_csv(path: &Path, run: &Run, truth: &[DVector<f64>], ts: f64) -> std::io::Result<()> {
    let n = truth[0].len();
    let mut out = String::new();
    let cols = |p: &str| (1..=n).map(|i| format!("{p}{i}")).collect::<Vec<_>>().join(",");
    let _ =
        writeln!(out, "k,t,{},{},{},{},trace,tau1,tau2,tau3,fallback", cols("x"), cols("xhat"), cols("lo"), cols("hi"));
    for (k, s) in run.snapshots.iter().enumerate() {
        let mut line = format!("{k},{}", k as f64 * ts);
        for v in truth[k].iter().chain(s.centre.iter()) {
            let _ = write!(line, ",{v:e}");
        }
        for sign in [-1.0, 1.0] {
            for i in 0..n {
                let _ = write!(line, ",{:e}", s.centre[i] + sign * s.shape[(i, i)].max(0.0).sqrt());
            }
        }
        let _ = write!(line, ",{:e}", s.shape.trace());
        match s.tau {
            Some(t) => {
                let _ = write!(line, ",{:e},{:e},{:e}", t[0], t[1], t[2]);
            }
            None => line.push_str(",,,"),
        }
        let _ = writeln!(line, ",{}", u8::from(s.fallback));
        out.push_str(&line);
    }
    write_atomic(path, out.as_bytes())
}

/// Writes `summary.json` (pretty JSON of `summary`) and `report.md` into `out`, each atomically.
///
/// # Errors
/// A message naming the file that could not be written.
pub fn write_summary_and_report<S: serde::Serialize>(out: &Path, summary: &S, report: &str) -> Result<(), String> {
    let json = serde_json::to_string_pretty(summary).map_err(|e| e.to_string())?;
    write_atomic(&out.join("summary.json"), json.as_bytes()).map_err(|e| format!("summary.json: {e}"))?;
    write_atomic(&out.join("report.md"), report.as_bytes()).map_err(|e| format!("report.md: {e}"))
}

/// `v` rounded to five significant digits as JSON (0 as `0.0`, non-finite as `null`): the
/// numbers of the snapshot tests' deterministic views.
#[must_use]
pub fn five_digits(v: f64) -> serde_json::Value {
    if v.is_finite() && v != 0.0 {
        let e = v.abs().log10().floor() as i32;
        let f = 10f64.powi(4 - e);
        serde_json::json!((v * f).round() / f)
    } else if v.is_finite() {
        serde_json::json!(0.0)
    } else {
        serde_json::Value::Null
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atomic_write_replaces_whole_files_and_leaves_no_temporary() {
        let dir = std::env::temp_dir().join(format!("xtask-atomic-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("a.txt");
        write_atomic(&p, b"first").unwrap();
        write_atomic(&p, b"second").unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "second");
        // A directory in the way: an error, the directory untouched, no temporary left.
        let blocked = dir.join("sub");
        std::fs::create_dir_all(&blocked).unwrap();
        assert!(write_atomic(&blocked, b"x").is_err());
        assert!(blocked.is_dir());
        let names: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names.len(), 2, "{names:?}");
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(slug("[17] without input"), "17_without_input");
    }

    #[test]
    fn figures_are_written_whole() {
        let dir = std::env::temp_dir().join(format!("xtask-figures-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let path = dir.join("nested").join("fig.svg");
        let mut chart = Chart::new("a chart", "t [s]", "y");
        chart.add(svg_plot::Series::line("y", vec![0.0, 1.0, 2.0], vec![1.0, 0.0, 1.0], svg_plot::PALETTE[1]));
        chart.write(&path).expect("write");
        chart.write(&path).expect("overwrite");
        assert_eq!(std::fs::read_to_string(&path).expect("read"), chart.to_svg());
        let names: Vec<_> =
            std::fs::read_dir(path.parent().unwrap()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names, ["fig.svg"], "no temporary file is left");
        let bars = BarChart::new("", "", "", ["a"]);
        bars.write(&dir.join("bars.svg")).expect("bars");
        assert_eq!(std::fs::read_to_string(dir.join("bars.svg")).expect("read"), bars.to_svg());
        Grid::new(2).write(&dir.join("grid.svg")).expect("grid");
        // A parent that is a file, and a path without a file name: errors, not panics.
        assert!(chart.write(&path.join("below-a-file.svg")).is_err());
        assert!(chart.write(Path::new("")).is_err());
        std::fs::remove_dir_all(&dir).expect("clean up");
    }
}
