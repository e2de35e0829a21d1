//! Minimal `--flag value` parsing for the xtask commands, over the operating system's arguments
//! as they are (`OsString`): a path may be any bytes, an option name or a number that is not
//! UTF-8 is an error naming it, never a panic. `--help` / `-h` anywhere asks for the command's
//! help.

use std::ffi::{OsStr, OsString};
use std::path::PathBuf;

/// Options given as `--name value` pairs, plus boolean `--name` switches.
#[derive(Debug)]
pub struct Args {
    pairs: Vec<(String, Option<OsString>)>,
}

/// What the command line asks for.
#[derive(Debug)]
pub enum Parsed {
    /// Run with these options.
    Run(Args),
    /// Print the command's help (`--help` or `-h` was given).
    Help,
}

/// An argument in messages: as text, with any bytes that are not UTF-8 shown as `\xNN`-like
/// replacement characters.
fn shown(a: &OsStr) -> String {
    format!("{:?}", a.to_string_lossy())
}

impl Args {
    /// Parses `args`; `valued` lists the options that take a value, `switches` those that take
    /// none.
    ///
    /// # Errors
    /// An argument that is not an option, an unknown option, a missing value.
    pub fn parse(args: &[OsString], valued: &[&str], switches: &[&str]) -> Result<Parsed, String> {
        if args.iter().any(|a| a == "--help" || a == "-h") {
            return Ok(Parsed::Help);
        }
        let mut pairs = Vec::new();
        let mut it = args.iter();
        while let Some(a) = it.next() {
            let name = a
                .to_str()
                .and_then(|s| s.strip_prefix("--"))
                .ok_or_else(|| format!("unexpected argument {} (see --help)", shown(a)))?;
            if switches.contains(&name) {
                pairs.push((name.to_owned(), None));
            } else if valued.contains(&name) {
                let v = it
                    .next()
                    .filter(|v| !v.to_str().is_some_and(|s| s.starts_with("--")))
                    .ok_or_else(|| format!("--{name} needs a value"))?;
                pairs.push((name.to_owned(), Some(v.clone())));
            } else {
                return Err(format!("unknown option --{name} (see --help)"));
            }
        }
        Ok(Parsed::Run(Self { pairs }))
    }

    fn raw(&self, name: &str) -> Option<&OsString> {
        self.pairs.iter().rev().find(|(n, _)| n == name).and_then(|(_, v)| v.as_ref())
    }

    /// The value of `--name` as text, if given (the last one wins).
    ///
    /// # Errors
    /// A value that is not UTF-8.
    pub fn value(&self, name: &str) -> Result<Option<&str>, String> {
        match self.raw(name) {
            None => Ok(None),
            Some(v) => v.to_str().map(Some).ok_or_else(|| format!("--{name}: {} is not valid UTF-8", shown(v))),
        }
    }

    /// The value of `--name` as a path (any bytes), if given.
    #[must_use]
    pub fn path(&self, name: &str) -> Option<PathBuf> {
        self.raw(name).map(PathBuf::from)
    }

    /// Whether the switch `--name` was given.
    #[must_use]
    pub fn flag(&self, name: &str) -> bool {
        self.pairs.iter().any(|(n, v)| n == name && v.is_none())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn a(v: &[&str]) -> Vec<OsString> {
        v.iter().map(OsString::from).collect()
    }

    fn run(p: Result<Parsed, String>) -> Args {
        match p {
            Ok(Parsed::Run(args)) => args,
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn values_and_switches() {
        let p = run(Args::parse(&a(&["--out", "x", "--quick"]), &["out"], &["quick"]));
        assert_eq!(p.value("out"), Ok(Some("x")));
        assert!(p.flag("quick"));
        assert!(
            Args::parse(&a(&["--out", "--quick"]), &["out"], &["quick"]).err().unwrap().contains("--out needs a value")
        );
        assert!(Args::parse(&a(&["--nope"]), &["out"], &[]).err().unwrap().contains("unknown option --nope"));
        assert!(Args::parse(&a(&["stray"]), &["out"], &[]).err().unwrap().contains("unexpected argument"));
        assert!(matches!(Args::parse(&a(&["--out", "x", "--help"]), &["out"], &[]), Ok(Parsed::Help)));
        assert!(matches!(Args::parse(&a(&["-h"]), &[], &[]), Ok(Parsed::Help)));
    }

    #[cfg(unix)]
    #[test]
    fn arguments_that_are_not_utf8_are_errors_or_paths_never_panics() {
        use std::os::unix::ffi::OsStringExt;
        let bad = OsString::from_vec(b"d\xff".to_vec());
        let p = run(Args::parse(&[OsString::from("--out"), bad.clone()], &["out", "seed"], &[]));
        assert_eq!(p.path("out"), Some(PathBuf::from(&bad)));
        assert!(p.value("out").unwrap_err().contains("is not valid UTF-8"));
        let e = Args::parse(std::slice::from_ref(&bad), &["out"], &[]).unwrap_err();
        assert!(e.starts_with("unexpected argument \"d\u{fffd}\""), "{e}");
        let mut option = b"--".to_vec();
        option.extend_from_slice(b"\xffout");
        assert!(Args::parse(&[OsString::from_vec(option)], &["out"], &[]).is_err());
    }
}
