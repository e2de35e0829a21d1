//! Mutations of valid text files for the workspace's bounded fuzzing of its readers: one
//! character of a file replaced by a piece chosen to reach a reader's corners (huge, negative,
//! non-finite and ill-typed numbers, broken syntax). Readers must never panic on the result, and
//! must say where an error is.

use proptest::prelude::*;

/// Number spellings every reader of numbers must survive, in every piece list of [`pieces`].
pub const NUMBER_CORNERS: [&str; 8] = ["0", "-1", "0.5", "1e308", "-1e308", "nan", "inf", "-inf"];

/// `text` with its character at `at` (modulo its length in characters) replaced by `with`;
/// `text` itself when it is empty.
#[must_use]
pub fn replace_char(text: &str, at: usize, with: &str) -> String {
    let count = text.chars().count();
    if count == 0 {
        return text.to_owned();
    }
    let i = at % count;
    let mut out = String::with_capacity(text.len() + with.len());
    for (k, c) in text.chars().enumerate() {
        if k == i {
            out.push_str(with);
        } else {
            out.push(c);
        }
    }
    out
}

/// Pieces to put in a file: [`NUMBER_CORNERS`], the reader's own `extra` pieces (syntax and
/// names of its format), any integer and any double in exponent notation.
pub fn pieces(extra: &[&'static str]) -> impl Strategy<Value = String> + use<> {
    let listed: Vec<&'static str> = NUMBER_CORNERS.iter().chain(extra).copied().collect();
    prop_oneof![
        prop::sample::select(listed).prop_map(str::to_owned),
        any::<i64>().prop_map(|v| v.to_string()),
        any::<f64>().prop_map(|v| format!("{v:e}")),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replaces_one_character_counted_in_characters() {
        assert_eq!(replace_char("aéc", 1, "xy"), "axyc");
        assert_eq!(replace_char("aéc", 5, "!"), "aé!");
        assert_eq!(replace_char("", 3, "x"), "");
    }
}
