//! The `xtask` binary as a user runs it: `--help` for every command, and arguments that are not
//! UTF-8 answered with an error, never a panic.

use std::process::{Command, Output};

fn xtask(args: &[std::ffi::OsString]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_xtask")).args(args).output().unwrap()
}

fn os(v: &[&str]) -> Vec<std::ffi::OsString> {
    v.iter().map(Into::into).collect()
}

#[test]
fn every_command_answers_help() {
    for args in [&["--help"][..], &["help"], &["reproduce", "--help"], &["sdplib", "--help"], &["sdplib", "-h"]] {
        let out = xtask(&os(args));
        assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(text.starts_with("cargo xtask"), "{args:?}: {text}");
    }
    let out = xtask(&os(&["help", "reproduce"]));
    assert!(String::from_utf8_lossy(&out.stdout).contains("--runs R"));
}

#[cfg(unix)]
#[test]
fn arguments_that_are_not_utf8_do_not_panic() {
    use std::os::unix::ffi::OsStringExt;
    let bad = std::ffi::OsString::from_vec(b"re\xffproduce".to_vec());
    for args in [
        vec![bad.clone()],
        vec!["reproduce".into(), bad.clone()],
        vec!["reproduce".into(), "--seed".into(), bad.clone()],
        vec!["sdplib".into(), "--backend".into(), bad.clone()],
    ] {
        let out = xtask(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(stderr.starts_with("error: ") && !stderr.contains("panicked"), "{args:?}: {stderr}");
    }
}
