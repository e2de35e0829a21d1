//! Bounded fuzzing (proptest, a few dozen cases each) of the surfaces beyond the model and data
//! readers: the `[mhe]` table, the truck and BDS/INS settings files, rule files through
//! `bds-ins`, and the truck and BDS/INS logs. No input panics or aborts; what is accepted stays
//! within the limits (the `[mhe]` memory estimate under its limit), and every error says where.

mod common;

use std::path::Path;

use common::OSCILLATOR_WITH_NOISE_BOXES as MODEL;
use port_est::bds_ins::{self, RtkCoding};
use port_est::data::DataReader;
use port_est::mhe_table::memory_estimate;
use port_est::{Error, Limits, StatusPolicy, parse_model_with, truck};
use proptest::prelude::*;
use text_fuzz::replace_char as mutate;

const TRUCK_SETTINGS: &str = "ts = 0.001
x0 = [10.0, 0.0, 0.0]
p0 = [[0.01, 0.0, 0.0], [0.0, 0.01, 0.0], [0.0, 0.0, 1e-4]]
q = [[1e-7, 0.0, 0.0], [0.0, 1e-7, 0.0], [0.0, 0.0, 1e-9]]
r = [[0.0025, 0.0, 0.0], [0.0, 0.0025, 0.0], [0.0, 0.0, 4e-6]]
";

const BDS_SETTINGS: &str = "ts = 0.5\nlatitude_deg = 45.0\nflat = false\nsigma0 = 0.05\nheading_sigma_deg = 0.3\n\
accel_white = 1e-3\ngyro_white = 1e-5\np0_sigma = [1, 1, 0.1, 0.1, 0.01, 0.01, 0.01, 1e-4, 1e-4, 1e-5, 1e-5, 1e-5, 1e-5]\n";

const RULES: &str = include_str!("../../fuzzy-inference/systems/bds_ins.toml");

/// Replacements that reach the interesting corners: huge, tiny and fractional numbers, ill-typed
/// values, broken syntax (with `text_fuzz`'s non-finite and signed ones).
fn pieces() -> impl Strategy<Value = String> {
    text_fuzz::pieces(&[
        "1e-320",
        "9223372036854775807",
        "18446744073709551615",
        "1000000000",
        "\"x\"",
        "[",
        "]",
        "=",
        ",",
        "\n",
        "[[1, 2], [3]]",
        "true",
        "#",
        "\u{feff}",
    ])
}

/// Every error names a place: a `file:line:column`, or at least the file.
fn located(e: &Error, file: &str) {
    let text = e.to_string();
    assert!(
        e.location().is_some() || text.contains(file) || text.starts_with("--fis") || text.contains("fuzzy"),
        "{text}"
    );
}

#[global_allocator]
static GLOBAL: counting_allocator::Counting = counting_allocator::Counting;

/// Runs one fuzzed case and checks its memory stayed bounded: no single allocation beyond 256 MiB
/// (the largest default limit, `--mhe-memory-limit`).
fn watchdog<T>(f: impl FnOnce() -> T) -> T {
    let (out, usage) = counting_allocator::measure(f);
    assert!(usage.largest <= 256 << 20, "a case allocated {} bytes at once", usage.largest);
    out
}

/// A truck log of `rows` steps of the truth model, in the layout of `port-est truck`.
fn truck_log(rows: usize) -> String {
    use truck_dynamics::{Slalom, TruckParams, TruthConfig, simulate_truth};
    let config = TruthConfig { duration: rows as f64 * 1e-3, ..TruthConfig::digest() };
    let slalom = Slalom::digest();
    let truth = simulate_truth(&TruckParams::digest_preset(), &config, |t| slalom.angle(t)).unwrap();
    let mut text = Vec::new();
    port_est::truck::write_log(&mut text, port_est::truck::truth_rows(&truth)).unwrap();
    String::from_utf8(text).unwrap()
}

fn bds_log(rows: usize) -> String {
    include_str!("../../../examples/bds-ins/data.csv").lines().take(rows + 1).collect::<Vec<_>>().join("\n") + "\n"
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn mhe_tables_never_panic_and_what_is_accepted_fits_the_limit(
        horizon in prop_oneof![Just(None), (0u64..u64::MAX).prop_map(Some), (0u64..5000).prop_map(Some)],
        blocks in prop::option::of(prop::collection::vec(prop_oneof![0usize..8, Just(usize::MAX)], 0..12)),
        preset in prop::option::of(prop::sample::select(vec!["rmhe", "rmhe-op", "rmhe-of", "none"])),
        sweeps in prop::option::of(0u64..u64::MAX),
        limit_mib in 1u64..1024,
    ) {
        let mut table = String::new();
        if let Some(h) = horizon { table.push_str(&format!("horizon = {}\n", h.min(i64::MAX as u64))); }
        if let Some(b) = &blocks {
            let cells: Vec<String> = b.iter().map(|v| v.min(&(i64::MAX as usize)).to_string()).collect();
            table.push_str(&format!("blocks = [{}]\n", cells.join(", ")));
        }
        if let Some(p) = preset { table.push_str(&format!("preset = \"{p}\"\n")); }
        if let Some(s) = sweeps { table.push_str(&format!("max_sweeps = {}\n", s.min(i64::MAX as u64))); }
        let limits = Limits { mhe_memory_bytes: limit_mib << 20, ..Limits::default() };
        let text = format!("{MODEL}{table}");
        match watchdog(|| parse_model_with(Path::new("m.toml"), &text, &limits)) {
            Ok(model) => {
                let s = model.mhe.unwrap();
                let estimate = memory_estimate(2, 1, 1, s.horizon, s.blocks.len(), false).unwrap();
                prop_assert!(estimate <= u128::from(limits.mhe_memory_bytes), "{table}");
            }
            Err(e) => prop_assert!(e.location().is_some(), "{e}"),
        }
    }

    #[test]
    fn mutated_mhe_tables_never_panic(at in 0usize..400, with in pieces()) {
        let text = format!("{MODEL}horizon = 6\nblocks = [5, 1]\nmax_sweeps = 10\n");
        let start = text.find("[mhe]").unwrap();
        let mutated = format!("{}{}", &text[..start], mutate(&text[start..], at, &with));
        if let Err(e) = watchdog(|| parse_model_with(Path::new("m.toml"), &mutated, &Limits::default())) {
            located(&e, "m.toml");
        }
    }

    #[test]
    fn mutated_truck_settings_never_panic(at in 0usize..400, with in pieces(), at2 in 0usize..400, with2 in pieces()) {
        let text = mutate(&mutate(TRUCK_SETTINGS, at, &with), at2, &with2);
        if let Err(e) = watchdog(|| truck::check_settings(Path::new("c.toml"), &text)) {
            located(&e, "c.toml");
        }
    }

    #[test]
    fn mutated_bds_ins_settings_never_panic(at in 0usize..400, with in pieces(), at2 in 0usize..400, with2 in pieces()) {
        let text = mutate(&mutate(BDS_SETTINGS, at, &with), at2, &with2);
        if let Err(e) = watchdog(|| bds_ins::check_settings(Path::new("c.toml"), &text)) {
            located(&e, "c.toml");
        }
    }

    #[test]
    fn arbitrary_settings_never_panic(text in "[ -~\n]{0,120}") {
        let _ = truck::check_settings(Path::new("c.toml"), &text);
        let _ = bds_ins::check_settings(Path::new("c.toml"), &text);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn mutated_truck_logs_never_panic(row in 1usize..40, column in 0usize..11, with in pieces()) {
        let log = truck_log(40);
        let mut lines: Vec<String> = log.lines().map(str::to_owned).collect();
        let mut cells: Vec<String> = lines[row].split(',').map(str::to_owned).collect();
        cells[column] = with;
        lines[row] = cells.join(",");
        let text = lines.join("\n") + "\n";
        let r = watchdog(|| {
            let mut data = DataReader::from_text(Path::new("t.csv"), &text, 7, 3)?;
            truck::run_log(None, &mut data, &mut Vec::new(), StatusPolicy::Warn)
        });
        if let Err(e) = r {
            located(&e, "t.csv");
        }
    }

    #[test]
    fn mutated_bds_ins_logs_and_rule_files_never_panic(
        row in 1usize..30,
        column in 0usize..9,
        with in pieces(),
        rule_at in 0usize..6000,
        rule_with in prop::option::of(pieces()),
    ) {
        let log = bds_log(30);
        let mut lines: Vec<String> = log.lines().map(str::to_owned).collect();
        let mut cells: Vec<String> = lines[row].split(',').map(str::to_owned).collect();
        cells[column] = with;
        lines[row] = cells.join(",");
        let text = lines.join("\n") + "\n";
        let rules = rule_with.map(|w| mutate(RULES, rule_at, &w));
        let r = watchdog(|| {
            let mut data = DataReader::from_text(Path::new("d.csv"), &text, 3, 5)?;
            let fis = rules.as_deref().map(|t| (Path::new("fis.toml"), t));
            bds_ins::run_log(None, fis, RtkCoding::Paper, &mut data, &mut Vec::new())
        });
        if let Err(e) = r {
            located(&e, "d.csv");
        }
    }
}

#[test]
fn the_seeds_are_valid() {
    assert!(parse_model_with(Path::new("m.toml"), MODEL, &Limits::default()).is_ok());
    truck::check_settings(Path::new("c.toml"), TRUCK_SETTINGS).unwrap();
    bds_ins::check_settings(Path::new("c.toml"), BDS_SETTINGS).unwrap();
    let log = truck_log(40);
    let mut data = DataReader::from_text(Path::new("t.csv"), &log, 7, 3).unwrap();
    assert_eq!(truck::run_log(None, &mut data, &mut Vec::new(), StatusPolicy::Warn).unwrap().steps, 40);
    let log = bds_log(30);
    let mut data = DataReader::from_text(Path::new("d.csv"), &log, 3, 5).unwrap();
    let fis = Some((Path::new("fis.toml"), RULES));
    assert_eq!(bds_ins::run_log(None, fis, RtkCoding::Paper, &mut data, &mut Vec::new()).unwrap().epochs, 30);
}
