//! No lost work, no litter: `--on-error keep-partial` keeps the steps before an error in
//! `OUT.partial.csv` (for `filter`, `truck` and `bds-ins`), SIGINT and SIGTERM remove the
//! temporary output, and one left by a killed run is named by the next run.

mod common;

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use port_est::bds_ins::{BdsInsOptions, bds_ins};
use port_est::truck::{TruckOptions, truck};
use port_est::{Error, FilterOptions, OnError, StatusPolicy, filter};

const MODEL: &str = include_str!("../../../examples/filter/model.toml");
const DATA: &str = include_str!("../../../examples/filter/data.csv");

fn dir(name: &str) -> PathBuf {
    common::fresh_dir("port-est-partial", name)
}

fn names(d: &Path) -> Vec<String> {
    let mut n: Vec<String> =
        std::fs::read_dir(d).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    n.sort();
    n
}

/// The example log with the measurement of data line `line` replaced by an outlier the
/// set-membership filter proves inconsistent.
fn with_outlier(line: usize) -> String {
    let mut lines: Vec<String> = DATA.lines().map(str::to_owned).collect();
    let cells: Vec<&str> = lines[line - 1].split(',').collect();
    lines[line - 1] = format!("{},{},1000", cells[0], cells[1]);
    lines.join("\n") + "\n"
}

fn filter_options(d: &Path, on_error: OnError, status: StatusPolicy) -> FilterOptions {
    FilterOptions { status, on_error, ..FilterOptions::new(d.join("m.toml"), d.join("d.csv"), d.join("out.csv")) }
}

#[test]
fn filter_keeps_the_steps_before_an_error_only_when_asked() {
    let d = dir("filter");
    std::fs::write(d.join("m.toml"), MODEL).unwrap();
    std::fs::write(d.join("d.csv"), with_outlier(20)).unwrap();
    let e = filter(&filter_options(&d, OnError::Discard, StatusPolicy::Warn)).unwrap_err();
    assert!(!matches!(e, Error::Stopped { .. }), "{e}");
    assert_eq!(names(&d), ["d.csv", "m.toml"], "nothing written, nothing left");

    let e = filter(&filter_options(&d, OnError::KeepPartial, StatusPolicy::Warn)).unwrap_err();
    assert!(matches!(e, Error::Stopped { .. }), "{e}");
    assert_eq!(e.location().map(|l| l.line), Some(20), "where it stopped: {e}");
    let partial = d.join("out.partial.csv");
    let msg = e.to_string();
    assert!(msg.contains("d.csv:20:1: step k = 18: data inconsistent"), "why it stopped: {msg}");
    assert!(
        msg.ends_with(&format!(
            "(the 18 steps before it are kept in {}; the output was not written)",
            partial.display()
        )),
        "{msg}"
    );
    assert_eq!(names(&d), ["d.csv", "m.toml", "out.partial.csv"]);
    let kept = std::fs::read_to_string(&partial).unwrap();
    assert_eq!(kept.lines().count(), 19, "header and 18 steps");
    assert!(kept.lines().last().unwrap().starts_with("18,"), "{kept}");
    // The same rows as a complete run's first 18.
    std::fs::write(d.join("d.csv"), DATA).unwrap();
    filter(&filter_options(&d, OnError::KeepPartial, StatusPolicy::Warn)).unwrap();
    let full = std::fs::read_to_string(d.join("out.csv")).unwrap();
    assert!(full.starts_with(&kept));
}

#[test]
fn a_partial_file_never_replaces_an_input() {
    let d = dir("strict");
    std::fs::write(d.join("m.toml"), MODEL).unwrap();
    // A partial file named like an input is not written over it.
    let mut options = filter_options(&d, OnError::KeepPartial, StatusPolicy::Warn);
    options.input = d.join("out.partial.csv");
    std::fs::write(&options.input, with_outlier(10)).unwrap();
    let e = filter(&options).unwrap_err().to_string();
    assert!(e.contains("nothing kept: ") && e.contains("is the input file"), "{e}");
    assert_eq!(std::fs::read_to_string(&options.input).unwrap(), with_outlier(10));
}

/// A slalom of the truth model in the layout of `port-est truck`, with the vehicle reversing
/// (negative speed measured) from step `reverse_at` on.
fn truck_log(seconds: f64, reverse_at: usize) -> String {
    use truck_dynamics::{Slalom, TruckParams, TruthConfig, simulate_truth};
    let params = TruckParams::digest_preset();
    let config = TruthConfig { duration: seconds, ..TruthConfig::digest() };
    let slalom = Slalom::digest();
    let truth = simulate_truth(&params, &config, |t| slalom.angle(t)).unwrap();
    let reversed = port_est::truck::truth_rows(&truth).enumerate().map(|(k, (mut u, mut y))| {
        if k >= reverse_at {
            u.omega = u.omega.map(|w| -w);
            y[0] = -y[0];
        }
        (u, y)
    });
    let mut text = Vec::new();
    port_est::truck::write_log(&mut text, reversed).unwrap();
    String::from_utf8(text).unwrap()
}

#[test]
fn truck_keeps_the_good_part_of_a_log_that_turns_bad() {
    let d = dir("truck");
    std::fs::write(d.join("t.csv"), truck_log(1.5, 1158)).unwrap();
    let options =
        TruckOptions { on_error: OnError::KeepPartial, ..TruckOptions::new(d.join("t.csv"), d.join("out.csv")) };
    let e = truck(&options).unwrap_err();
    let msg = e.to_string();
    let steps = std::fs::read_to_string(d.join("out.partial.csv")).unwrap().lines().count() - 1;
    assert!(steps >= 1158, "{steps} steps kept: {msg}");
    assert!(msg.contains(&format!("the {steps} steps before it are kept in")), "{msg}");
    assert!(!d.join("out.csv").exists());
}

#[test]
fn bds_ins_keeps_the_epochs_before_a_bad_status() {
    let d = dir("bds-ins");
    let log = include_str!("../../../examples/bds-ins/data.csv");
    let mut lines: Vec<String> = log.lines().map(str::to_owned).collect();
    let mut cells: Vec<String> = lines[101].split(',').map(str::to_owned).collect();
    cells[8] = "7".into();
    lines[101] = cells.join(",");
    std::fs::write(d.join("d.csv"), lines.join("\n") + "\n").unwrap();
    let options =
        BdsInsOptions { on_error: OnError::KeepPartial, ..BdsInsOptions::new(d.join("d.csv"), d.join("out.csv")) };
    let msg = bds_ins(&options).unwrap_err().to_string();
    assert!(msg.contains("d.csv:102:") && msg.contains("RTK status code 7"), "{msg}");
    assert!(msg.contains("the 100 steps before it are kept in"), "{msg}");
    assert_eq!(std::fs::read_to_string(d.join("out.partial.csv")).unwrap().lines().count(), 101);
}

fn port_est() -> Command {
    Command::new(env!("CARGO_BIN_EXE_port-est"))
}

#[test]
fn a_later_success_removes_the_partial_file_it_supersedes() {
    let d = dir("supersede");
    std::fs::write(d.join("m.toml"), MODEL).unwrap();
    std::fs::write(d.join("bad.csv"), with_outlier(20)).unwrap();
    std::fs::write(d.join("good.csv"), DATA).unwrap();
    let run = |input: &str| {
        port_est()
            .current_dir(&d)
            .args(["filter", "-m", "m.toml", "-i", input, "-o", "out.csv", "--on-error", "keep-partial"])
            .output()
            .unwrap()
    };
    let out = run("bad.csv");
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("kept in out.partial.csv"), "{stderr}");
    assert!(d.join("out.partial.csv").is_file());
    let out = run("good.csv");
    assert!(out.status.success());
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("removed out.partial.csv, the partial output of an earlier run")
    );
    assert_eq!(names(&d), ["bad.csv", "good.csv", "m.toml", "out.csv"]);
}

#[cfg(unix)]
#[test]
fn sigint_and_sigterm_remove_the_temporary_output() {
    for (signal, code) in [("INT", 130), ("TERM", 143)] {
        let d = dir(&format!("signal-{signal}"));
        std::fs::write(d.join("m.toml"), MODEL).unwrap();
        // The log comes through a pipe that stays open: the run waits for more rows.
        let mut child = port_est()
            .current_dir(&d)
            .args(["filter", "-m", "m.toml", "-i", "/dev/stdin", "-o", "out.csv"])
            .stdin(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut stdin = child.stdin.take().unwrap();
        stdin.write_all(DATA.as_bytes()).unwrap();
        stdin.flush().unwrap();
        let t0 = Instant::now();
        while !names(&d).iter().any(|n| n.starts_with(".out.csv.") && n.ends_with(".tmp")) {
            assert!(t0.elapsed() < Duration::from_secs(30), "no temporary file appeared: {:?}", names(&d));
            std::thread::sleep(Duration::from_millis(20));
        }
        std::thread::sleep(Duration::from_millis(200));
        let killed = Command::new("kill").args([format!("-{signal}"), child.id().to_string()]).status().unwrap();
        assert!(killed.success());
        let status = child.wait().unwrap();
        drop(stdin);
        assert_eq!(status.code(), Some(code), "SIG{signal}");
        assert_eq!(names(&d), ["m.toml"], "SIG{signal}: the temporary file is removed, nothing is published");
    }
}

#[test]
fn a_temporary_file_left_by_a_killed_run_is_named() {
    let d = dir("stale");
    std::fs::write(d.join("m.toml"), MODEL).unwrap();
    std::fs::write(d.join("d.csv"), DATA).unwrap();
    // The name a run of process 4294967295 (above any pid limit: not running) would have used.
    let stale = ".out.csv.4294967295.Ab3dEf.tmp";
    std::fs::write(d.join(stale), "k,xhat1\n1,0.5\n").unwrap();
    let out =
        port_est().current_dir(&d).args(["filter", "-m", "m.toml", "-i", "d.csv", "-o", "out.csv"]).output().unwrap();
    assert!(out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains(&format!("warning: ./{stale} is a temporary file of out.csv left by an interrupted run"))
            && stderr.contains("process 4294967295, no longer running"),
        "{stderr}"
    );
    assert!(d.join(stale).exists(), "named, not removed");
}
