//! The `port-est` binary as a user runs it: clap's help, the registry listing, exit codes and
//! `error: file:line:column: …` on stderr.

use std::path::Path;
use std::process::{Command, Output};

fn port_est(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_port-est")).args(args).output().unwrap()
}

/// `port-est filter -m model -i input -o output -e kf`.
fn filter_kf(model: &Path, input: &str, output: &str) -> Output {
    port_est(&["filter", "-m", model.to_str().unwrap(), "-i", input, "-o", output, "-e", "kf"])
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8(bytes.to_vec()).unwrap()
}

#[test]
fn help_of_the_binary_and_of_filter() {
    let out = port_est(&["--help"]);
    assert!(out.status.success());
    let help = text(&out.stdout);
    // `[OPTIONS]`: the global `--max-file-size`.
    assert!(
        help.contains("Usage: port-est [OPTIONS] <COMMAND>") && help.contains("filter") && help.contains("estimators")
    );
    assert!(help.contains("--max-file-size <SIZE>"), "{help}");

    let out = port_est(&["filter", "--help"]);
    assert!(out.status.success());
    let help = text(&out.stdout);
    for s in ["--model <MODEL.toml>", "--input <DATA.csv>", "--output <OUT.csv>", "--estimator <NAME>", "yang-li"] {
        assert!(help.contains(s), "{s} in\n{help}");
    }
    assert!(port_est(&["help", "filter"]).status.success());
    assert!(port_est(&["--version"]).status.success());
}

#[test]
fn estimators_lists_the_registry_and_the_solvers() {
    let out = port_est(&["estimators"]);
    assert!(out.status.success());
    let list = text(&out.stdout);
    for e in estimators::registry::ESTIMATORS {
        assert!(list.contains(e.name) && list.contains(e.summary), "{}", e.name);
        for d in e.details {
            assert!(list.contains(&format!("column {}: {}", d.name, d.meaning)), "{}: {}", e.name, d.name);
        }
        for k in e.settings.keywords() {
            assert!(list.contains(&format!("setting {}: {}", k.name, k.meaning)), "{}: {}", e.name, k.name);
        }
    }
    for s in estimators::registry::SmfSolver::names() {
        assert!(list.contains(s), "{s}");
    }
}

#[test]
fn usage_errors_exit_2_and_run_errors_exit_1() {
    let out = port_est(&[]);
    assert_eq!(out.status.code(), Some(2));
    let out = port_est(&["filter", "--model", "m.toml"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("--input <DATA.csv>"));
    let out = port_est(&["filter", "-m", "m", "-i", "d", "-o", "o", "--estimator", "nope"]);
    assert_eq!(out.status.code(), Some(2));

    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/filter");
    let (model, data) = (examples.join("model.toml"), examples.join("data.csv"));
    let (model, data) = (model.to_str().unwrap(), data.to_str().unwrap());
    let out = port_est(&["filter", "--model", model, "--input", data, "--output", data]);
    assert_eq!(out.status.code(), Some(1));
    let err = text(&out.stderr);
    assert!(err.starts_with("error: refusing to overwrite the input file"), "{err}");

    // A model file given as the data: the header is wrong at line 1.
    let out_file = Path::new(env!("CARGO_TARGET_TMPDIR")).join("port-est-cli-out.csv");
    let out = port_est(&["filter", "-m", model, "-i", model, "-o", out_file.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let err = text(&out.stderr);
    assert!(err.starts_with(&format!("error: {model}:1:1: the header has no column \"k\"")), "{err}");
    assert!(!out_file.exists());
}

#[test]
fn the_example_runs_through_the_binary() {
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/filter");
    let out_file = Path::new(env!("CARGO_TARGET_TMPDIR")).join("port-est-cli-example.csv");
    let out = Command::new(env!("CARGO_BIN_EXE_port-est"))
        .arg("filter")
        .arg("--model")
        .arg(examples.join("model.toml"))
        .arg("--input")
        .arg(examples.join("data.csv"))
        .arg("--output")
        .arg(&out_file)
        .args(["--estimator", "kf"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stderr).starts_with("40 steps of kf written to "));
    assert_eq!(std::fs::read_to_string(&out_file).unwrap().lines().count(), 41);
}

#[cfg(unix)]
#[test]
fn the_data_may_come_from_a_pipe() {
    use std::io::Write;
    use std::process::Stdio;
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/filter");
    let out_file = Path::new(env!("CARGO_TARGET_TMPDIR")).join("port-est-cli-pipe.csv");
    let run = |data: &str| {
        let mut child = Command::new(env!("CARGO_BIN_EXE_port-est"))
            .arg("filter")
            .arg("--model")
            .arg(examples.join("model.toml"))
            .args(["--input", "/dev/stdin", "--output"])
            .arg(&out_file)
            .stdin(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        child.stdin.take().unwrap().write_all(data.as_bytes()).unwrap();
        child.wait_with_output().unwrap()
    };
    let out = run("k,u1,y1\n0,0.1,0.3\n1,0.2,0.29\n");
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(std::fs::read_to_string(&out_file).unwrap().lines().count(), 3);
    let out = run("k,u1,y1\n0,0.1,0.3\n1,0.2, bad\n");
    assert_eq!(out.status.code(), Some(1));
    let err = text(&out.stderr);
    assert!(err.starts_with("error: /dev/stdin:3:8: y1 = \"bad\" is not a number"), "{err}");
}

/// A robust MHE whose coordinate rotation cannot converge (`lambda_v` near 1, one sweep): every
/// row says so in its status, stderr warns with the count, `--strict` refuses the run at the
/// first such row and writes nothing; the point estimates have no bound columns.
#[test]
fn non_converged_windows_are_reported_and_can_be_refused() {
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/filter");
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("port-est-cli-rmhe");
    std::fs::create_dir_all(&dir).unwrap();
    let model = std::fs::read_to_string(examples.join("model.toml"))
        .unwrap()
        .replace("lambda_v = 10.0", "lambda_v = 1.2\nmax_sweeps = 1");
    let model_path = dir.join("model.toml");
    std::fs::write(&model_path, model).unwrap();
    let out_file = dir.join("out.csv");
    let run = |strict: bool| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_port-est"));
        c.arg("filter").arg("--model").arg(&model_path).arg("--input").arg(examples.join("data.csv"));
        c.arg("--output").arg(&out_file).args(["--estimator", "rmhe"]);
        if strict {
            c.arg("--strict");
        }
        c.output().unwrap()
    };
    let out = run(false);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let err = text(&out.stderr);
    let csv = std::fs::read_to_string(&out_file).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], "k,xhat1,xhat2,iterations,status", "no bounds for a point estimate");
    let not_converged = lines[1..].iter().filter(|l| l.ends_with(",not-converged")).count();
    assert!(not_converged > 0, "{csv}");
    assert!(err.contains(&format!("warning: {not_converged} of 40 steps did not converge")), "{err}");
    std::fs::remove_file(&out_file).unwrap();
    let out = run(true);
    assert_eq!(out.status.code(), Some(1));
    let err = text(&out.stderr);
    assert!(err.contains("ended not-converged and --strict refuses"), "{err}");
    assert!(!out_file.exists(), "nothing is written when a step is refused");
}

#[test]
fn the_limits_are_options_of_the_command_line() {
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/filter");
    let (model, data) = (examples.join("model.toml"), examples.join("data.csv"));
    let (model, data) = (model.to_str().unwrap(), data.to_str().unwrap());
    let out_dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("port-est-cli-limits");
    std::fs::create_dir_all(&out_dir).unwrap();
    let out = out_dir.join("out.csv");
    let out = out.to_str().unwrap();
    let run = |extra: &[&str]| {
        let mut args = vec!["filter", "-m", model, "-i", data, "-o", out];
        args.extend_from_slice(extra);
        let o = port_est(&args);
        (o.status.code(), text(&o.stderr))
    };
    // Global, before or after the subcommand.
    let (code, err) = run(&["--max-file-size", "100"]);
    assert_eq!(code, Some(1));
    assert!(err.contains("larger than 100 B, the limit for a model file (raise it with --max-file-size)"), "{err}");
    let o = port_est(&["--max-file-size", "1K", "filter", "-m", model, "-i", data, "-o", out]);
    assert!(text(&o.stderr).contains("larger than 1 KiB"), "{}", text(&o.stderr));
    let (code, err) = run(&["-e", "rmhe", "--mhe-memory-limit", "1K"]);
    assert_eq!(code, Some(1));
    assert!(err.contains("`mhe.horizon`: a horizon of N = 6") && err.contains("more than the limit of 1 KiB"), "{err}");
    let (code, _) = run(&["--max-file-size", "lots"]);
    assert_eq!(code, Some(2), "a bad size is a usage error");
    let (code, err) = run(&["--on-error", "keep-partial", "--max-gap", "3"]);
    assert_eq!((code, err.contains("40 steps")), (Some(0), true), "{err}");
}

#[test]
fn dash_reads_standard_input_and_writes_standard_output() {
    use std::io::Write;
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let model = root.join("examples/filter/model.toml");
    let data = std::fs::read_to_string(root.join("examples/filter/data.csv")).unwrap();
    let file_out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("port-est-cli-pipe.csv");
    let by_file = filter_kf(&model, "-", file_out.to_str().unwrap());
    // Without stdin attached the run sees an empty file.
    assert_eq!(by_file.status.code(), Some(1));
    assert!(text(&by_file.stderr).contains("<stdin>:1:1: empty file"), "{}", text(&by_file.stderr));
    let mut child = Command::new(env!("CARGO_BIN_EXE_port-est"))
        .args(["filter", "-m", model.to_str().unwrap(), "-i", "-", "-o", "-", "-e", "kf"])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    child.stdin.take().unwrap().write_all(data.as_bytes()).unwrap();
    let piped = child.wait_with_output().unwrap();
    assert!(piped.status.success(), "{}", text(&piped.stderr));
    assert!(text(&piped.stderr).contains("written to standard output"), "{}", text(&piped.stderr));
    // The same rows as a run between files.
    let input = root.join("examples/filter/data.csv");
    let ok = filter_kf(&model, input.to_str().unwrap(), file_out.to_str().unwrap());
    assert!(ok.status.success());
    assert_eq!(text(&piped.stdout), std::fs::read_to_string(&file_out).unwrap());
    // `/dev/stdout` on a pipe (it resolves to `/proc/self/fd/1`, `pipe:[…]`, which names no file).
    if Path::new("/dev/stdout").exists() {
        let out = filter_kf(&model, input.to_str().unwrap(), "/dev/stdout");
        assert!(out.status.success(), "{}", text(&out.stderr));
        assert_eq!(text(&out.stdout), text(&piped.stdout));
    }
}
