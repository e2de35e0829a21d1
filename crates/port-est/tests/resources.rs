//! Bounded resources for every setting and file: absurd `[mhe]` horizons and blocks, a `k` that
//! jumps by billions under `--gaps bridge`, endless model, settings and rule files, and an absurd
//! defuzzification resolution are refused quickly, at their place, naming the limit.

mod common;

use std::path::{Path, PathBuf};

use common::OSCILLATOR_WITH_NOISE_BOXES as MODEL;
use port_est::bds_ins::{BdsInsOptions, bds_ins};
use port_est::truck::{TruckOptions, truck};
use port_est::{Error, FilterOptions, GapPolicy, Limits, filter, parse_model_with};

fn dir(name: &str) -> PathBuf {
    common::fresh_dir("port-est-resources", name)
}

#[global_allocator]
static GLOBAL: counting_allocator::Counting = counting_allocator::Counting;

/// The largest single allocation an input beyond a limit may cause: the limits are checked before
/// anything is allocated for what they bound (the default file limit is 16 MiB; a file is read
/// up to one byte beyond it).
const REFUSED_WITHIN: usize = 32 << 20;

/// Runs `f` (an input beyond a limit) and checks that no allocation larger than
/// [`REFUSED_WITHIN`] was made for it.
fn quickly<T>(what: &str, f: impl FnOnce() -> T) -> T {
    let (out, usage) = counting_allocator::measure(f);
    assert!(usage.largest <= REFUSED_WITHIN, "{what}: an allocation of {} bytes", usage.largest);
    out
}

fn model_error(extra: &str, limits: &Limits) -> String {
    let text = format!("{MODEL}{extra}\n");
    quickly(extra, || parse_model_with(Path::new("m.toml"), &text, limits)).unwrap_err().to_string()
}

#[test]
fn absurd_horizons_are_refused_at_their_key_with_the_estimate_and_the_limit() {
    let limits = Limits::default();
    for horizon in ["100000", "1000000000", "9223372036854775807"] {
        for preset in ["", "preset = \"rmhe\"", "preset = \"rmhe-op\"", "preset = \"rmhe-of\""] {
            let e = model_error(&format!("horizon = {horizon}\n{preset}"), &limits);
            assert!(e.starts_with("m.toml:13:11: `mhe.horizon`: a horizon of N = "), "{horizon} {preset}: {e}");
            assert!(e.contains("more than the limit of 256 MiB") && e.contains("--mhe-memory-limit"), "{e}");
            assert!(e.contains("needs about ") || e.contains("more than 2^128 bytes"), "{e}");
        }
    }
    // Blocks that make the window large, without a horizon: at `blocks`.
    let many = vec!["1"; 200_000].join(", ");
    let e = model_error(&format!("blocks = [{many}]"), &limits);
    assert!(e.starts_with("m.toml:13:10: `mhe.blocks`: a horizon of N = 6 in 200000 blocks"), "{e}");
    // Negative, non-integer or beyond TOML's integers: type errors at the value, never a panic.
    for bad in ["-1", "1e9", "-9223372036854775808", "18446744073709551615"] {
        let e = model_error(&format!("horizon = {bad}"), &limits);
        assert!(e.starts_with("m.toml:13:11: "), "{bad}: {e}");
    }
}

#[test]
fn the_memory_limit_is_the_users_to_raise() {
    let e = model_error("horizon = 2000", &Limits::default());
    assert!(e.contains("needs about 672.9 MiB"), "{e}");
    let raised = Limits { mhe_memory_bytes: 4 << 30, ..Limits::default() };
    let text = format!("{MODEL}horizon = 2000\n");
    let model = parse_model_with(Path::new("m.toml"), &text, &raised).unwrap();
    assert_eq!(model.mhe.unwrap().horizon, 2000);
    // The paper's horizons are far below the default.
    assert!(parse_model_with(Path::new("m.toml"), &format!("{MODEL}horizon = 60\n"), &Limits::default()).is_ok());
}

#[test]
fn sums_and_sweeps_of_user_numbers_are_checked() {
    let limits = Limits::default();
    let e = model_error("blocks = [9223372036854775807, 9223372036854775807, 2]", &limits);
    assert!(e.starts_with("m.toml:13:10: `mhe.blocks`: the block lengths overflow when summed"), "{e}");
    let e = model_error("max_sweeps = 1000000000000", &limits);
    assert!(e.starts_with("m.toml:13:14: `mhe.max_sweeps`: at most 10000 sweeps"), "{e}");
    assert!(e.contains("per window, got 1000000000000"), "{e}");
    let e = model_error("solver = \"exact-saddle\"\nmax_sweeps = 9223372036854775807", &limits);
    assert!(e.contains("`mhe.max_sweeps`"), "{e}");
}

fn filter_options(d: &Path, model: &Path, input: &Path, gaps: GapPolicy, limits: Limits) -> FilterOptions {
    FilterOptions { gaps, limits, ..FilterOptions::new(model.to_owned(), input.to_owned(), d.join("out.csv")) }
}

#[test]
fn bridged_gaps_are_capped_at_the_row_with_the_gap_size() {
    let d = dir("gaps");
    let model = d.join("m.toml");
    std::fs::write(&model, MODEL).unwrap();
    let input = d.join("d.csv");
    for (jump, max_gap, ok) in [(1_000_000_001_u64, None, false), (6, Some(3), false), (6, Some(4), true)] {
        std::fs::write(&input, format!("k,u1,y1\n0,0.1,0.0\n1,0.1,0.0\n{jump},0.1,0.0\n")).unwrap();
        let limits = Limits { max_gap: max_gap.unwrap_or(Limits::default().max_gap), ..Limits::default() };
        let r = quickly("a gap", || filter(&filter_options(&d, &model, &input, GapPolicy::Bridge, limits)));
        if ok {
            assert_eq!(r.unwrap().tally.steps, jump + 1);
            continue;
        }
        let e = r.unwrap_err().to_string();
        let missing = jump - 2;
        let limit = max_gap.unwrap_or(10_000);
        assert!(e.contains("d.csv:4:1: k jumps from 1 to"), "{e}");
        assert!(e.contains(&format!("a gap of {missing} missing steps, more than --max-gap {limit}")), "{e}");
        assert!(!d.join("out.csv").exists());
    }
}

#[cfg(unix)]
#[test]
fn endless_model_settings_and_rule_files_are_refused_at_the_size_limit() {
    let d = dir("endless");
    let zero = Path::new("/dev/zero");
    let data = d.join("d.csv");
    std::fs::write(&data, "k,u1,y1\n0,0,0\n").unwrap();
    let e = quickly("model", || filter(&filter_options(&d, zero, &data, GapPolicy::Error, Limits::default())));
    let e = e.unwrap_err();
    assert!(matches!(e, Error::TooLarge { .. }), "{e}");
    assert_eq!(
        e.to_string(),
        "/dev/zero: larger than 16 MiB, the limit for a model file (raise it with --max-file-size)"
    );
    let truck_options = TruckOptions { config: Some(zero.to_owned()), ..TruckOptions::new(&data, d.join("t.csv")) };
    let e = quickly("truck settings", || truck(&truck_options)).unwrap_err().to_string();
    assert!(e.contains("the limit for a settings file (raise it with --max-file-size)"), "{e}");
    let bds = |config: Option<&Path>, fis: Option<&Path>| BdsInsOptions {
        config: config.map(Path::to_owned),
        fis: fis.map(Path::to_owned),
        limits: Limits { file_bytes: 1 << 20, ..Limits::default() },
        ..BdsInsOptions::new(&data, d.join("b.csv"))
    };
    let e = quickly("bds settings", || bds_ins(&bds(Some(zero), None))).unwrap_err().to_string();
    assert!(e.contains("larger than 1 MiB, the limit for a settings file"), "{e}");
    let e = quickly("rule file", || bds_ins(&bds(None, Some(zero)))).unwrap_err().to_string();
    assert!(e.contains("larger than 1 MiB, the limit for a rule file"), "{e}");
    // A regular file just over a (small) limit, and one within it.
    let model = d.join("m.toml");
    std::fs::write(&model, MODEL).unwrap();
    let small = Limits { file_bytes: MODEL.len() as u64 - 1, ..Limits::default() };
    let e = filter(&filter_options(&d, &model, &data, GapPolicy::Error, small)).unwrap_err();
    assert!(matches!(e, Error::TooLarge { .. }), "{e}");
    let fits = Limits { file_bytes: MODEL.len() as u64, ..Limits::default() };
    assert!(filter(&filter_options(&d, &model, &data, GapPolicy::Error, fits)).is_ok());
}

#[test]
fn a_rule_file_asking_for_an_absurd_resolution_is_refused_at_its_line() {
    let d = dir("resolution");
    let shipped = include_str!("../../fuzzy-inference/systems/bds_ins.toml");
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/bds-ins/data.csv");
    for setting in ["{ sampled = 10000000000 }", "{ sampled = 1e10 }", "{ grid = 1000000 }"] {
        let fis = d.join("fis.toml");
        std::fs::write(&fis, shipped.replace("defuzzifier = \"exact\"", &format!("defuzzifier = {setting}"))).unwrap();
        let options = BdsInsOptions { fis: Some(fis.clone()), ..BdsInsOptions::new(&data, d.join("out.csv")) };
        let e = quickly(setting, || bds_ins(&options)).unwrap_err().to_string();
        assert!(e.starts_with(&format!("--fis: {}:8:", fis.display())), "{setting}: {e}");
    }
}

/// The memory check above can fail: reading a large file to its end allocates its size.
#[test]
fn the_memory_check_sees_a_large_allocation() {
    let d = dir("large-allocation");
    let big = d.join("big.bin");
    std::fs::write(&big, vec![b' '; 40 << 20]).unwrap();
    let (_, usage) = counting_allocator::measure(|| std::fs::read(&big).unwrap().len());
    assert!(usage.largest > REFUSED_WITHIN, "{usage:?}");
    let _ = std::fs::remove_file(big);
}
