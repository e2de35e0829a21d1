//! Minimal `--flag value` parsing for the xtask commands.

/// Options given as `--name value` pairs, plus boolean `--name` switches.
pub struct Args {
    pairs: Vec<(String, Option<String>)>,
}

impl Args {
    /// Parses `args`; `switches` lists the options that take no value.
    pub fn parse(args: &[String], valued: &[&str], switches: &[&str]) -> Result<Self, String> {
        let mut pairs = Vec::new();
        let mut it = args.iter();
        while let Some(a) = it.next() {
            let name = a.strip_prefix("--").ok_or_else(|| format!("unexpected argument {a:?}"))?;
            if switches.contains(&name) {
                pairs.push((name.to_owned(), None));
            } else if valued.contains(&name) {
                let v = it.next().filter(|v| !v.starts_with("--")).ok_or_else(|| format!("--{name} needs a value"))?;
                pairs.push((name.to_owned(), Some(v.clone())));
            } else {
                return Err(format!("unknown option --{name}"));
            }
        }
        Ok(Self { pairs })
    }

    /// The value of `--name`, if given (the last one wins).
    pub fn value(&self, name: &str) -> Option<&str> {
        self.pairs.iter().rev().find(|(n, _)| n == name).and_then(|(_, v)| v.as_deref())
    }

    /// Whether the switch `--name` was given.
    pub fn flag(&self, name: &str) -> bool {
        self.pairs.iter().any(|(n, v)| n == name && v.is_none())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_and_switches() {
        let a = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let p = Args::parse(&a(&["--out", "x", "--quick"]), &["out"], &["quick"]).unwrap();
        assert_eq!(p.value("out"), Some("x"));
        assert!(p.flag("quick"));
        assert!(
            Args::parse(&a(&["--out", "--quick"]), &["out"], &["quick"]).err().unwrap().contains("--out needs a value")
        );
        assert!(Args::parse(&a(&["--nope"]), &["out"], &[]).err().unwrap().contains("unknown option --nope"));
        assert!(Args::parse(&a(&["stray"]), &["out"], &[]).err().unwrap().contains("unexpected argument"));
    }
}
