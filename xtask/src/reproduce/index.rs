//! `DIR/index.md` and the record each paper's directory keeps of its run (`run.json`), so that
//! the index lists every paper present in `DIR` — those of this run and those of earlier runs
//! (`--paper NAME` into a directory holding all papers keeps the others' rows), each with the
//! seed and sizes it ran with.

use std::path::Path;

use serde::{Deserialize, Serialize};

/// What one paper's run was, kept in its directory as `run.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunRecord {
    /// Short name (the directory's).
    pub name: String,
    /// Title.
    pub title: String,
    /// Claims judged.
    pub claims: usize,
    /// Claims reproduced (fully or with a stated condition), or benchmark targets met.
    pub reproduced: usize,
    /// Base seed.
    pub seed: u64,
    /// `--quick` sizes.
    pub quick: bool,
    /// `--runs`, if given.
    pub runs: Option<usize>,
    /// Wall time in seconds.
    pub seconds: f64,
}

/// The record's file name in a paper's directory.
pub const RECORD: &str = "run.json";

/// The record of the paper in `dir`, if it has a readable one.
#[must_use]
pub fn read_record(dir: &Path) -> Option<RunRecord> {
    let text = std::fs::read_to_string(dir.join(RECORD)).ok()?;
    serde_json::from_str(&text).ok()
}

/// The index row of an earlier run of `name` in an older `index.md` (written before the
/// records), if the index has one.
fn old_row<'a>(old_index: &'a str, name: &str) -> Option<&'a str> {
    let link = format!("[{name}/report.md]({name}/report.md)");
    old_index.lines().find(|l| l.starts_with('|') && l.contains(&link))
}

/// The index of `out`: one row per paper of `order` (names) whose directory holds a report, from
/// its record, or from the row of `old_index` for a directory written before the records.
#[must_use]
pub fn index(out: &Path, order: &[&str], old_index: &str) -> String {
    let mut s = String::from("# Reproductions\n\n");
    s.push_str(
        "Each row is one paper's latest run, with the seed and sizes it ran with (`quick`: `--quick` sizes, not \
         the full experiment). Each report says which numbers are the paper's and which are reconstructed.\n\n",
    );
    s.push_str("| paper | report | claims | reproduced (fully or with a stated condition) or target met | seed | wall time |\n");
    s.push_str("|---|---|---:|---:|---|---:|\n");
    for name in order {
        let dir = out.join(name);
        if !dir.join("report.md").is_file() {
            continue;
        }
        match read_record(&dir) {
            Some(r) => {
                let mut seed = r.seed.to_string();
                if r.quick {
                    seed.push_str(", quick");
                }
                if let Some(runs) = r.runs {
                    seed.push_str(&format!(", {runs} runs"));
                }
                s.push_str(&format!(
                    "| {} | [{name}/report.md]({name}/report.md) | {} | {} | {seed} | {:.1} s |\n",
                    r.title, r.claims, r.reproduced, r.seconds
                ));
            }
            None => {
                if let Some(row) = old_row(old_index, name) {
                    s.push_str(row);
                    s.push('\n');
                }
            }
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_index_lists_every_paper_present_with_its_own_seed() {
        let out = std::env::temp_dir().join(format!("xtask-index-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&out);
        std::fs::create_dir_all(&out).unwrap();
        let record = |name: &str, seed: u64, quick: bool| RunRecord {
            name: name.into(),
            title: format!("The {name} paper"),
            claims: 4,
            reproduced: 3,
            seed,
            quick,
            runs: None,
            seconds: 1.25,
        };
        for (name, r) in [("a", Some(record("a", 7, false))), ("b", None), ("c", Some(record("c", 9, true)))] {
            let dir = out.as_path().join(name);
            std::fs::create_dir(&dir).unwrap();
            std::fs::write(dir.join("report.md"), "# report").unwrap();
            if let Some(r) = r {
                std::fs::write(dir.join(RECORD), serde_json::to_string(&r).unwrap()).unwrap();
            }
        }
        // "d" has no directory; "b" was written before the records: its old row is kept.
        let old = "| The b paper | [b/report.md](b/report.md) | 2 | 2 | 1.0 s |\n| gone | [d/report.md](d/report.md) | 1 | 1 | 1 s |\n";
        let text = index(out.as_path(), &["a", "b", "c", "d"], old);
        let rows: Vec<&str> = text.lines().filter(|l| l.starts_with("| The")).collect();
        assert_eq!(rows.len(), 3, "{text}");
        assert!(rows[0].contains("[a/report.md]") && rows[0].contains("| 7 |"), "{text}");
        assert_eq!(rows[1], "| The b paper | [b/report.md](b/report.md) | 2 | 2 | 1.0 s |");
        assert!(rows[2].contains("| 9, quick |"), "{text}");
        assert!(!text.contains("[d/report.md]"));
        std::fs::remove_dir_all(&out).unwrap();
    }
}
