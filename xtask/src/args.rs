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
                let v = it.next().ok_or_else(|| format!("--{name} needs a value"))?;
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
    #[allow(dead_code)]
    pub fn flag(&self, name: &str) -> bool {
        self.pairs.iter().any(|(n, v)| n == name && v.is_none())
    }
}
