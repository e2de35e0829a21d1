//! Reading an expression: tokens, names resolved, definitions and parameters substituted.
//!
//! The text handed to the expression library uses only numbers (written in plain decimal
//! notation, which it parses), the operators, the known functions and the internal variable
//! names `v0000`, `v0001`, ... (states first, then inputs). Fixed-width names make the library's
//! alphabetical variable order the order of the slots.

use crate::limits::{MAX_DEPTH, MAX_EXPRESSION_BYTES, MAX_OPERATORS};

/// The functions of the expression language (those of the expression library's default
/// operators that take one argument, and the two-argument `atan2`, `min`, `max`).
pub const FUNCTIONS: &[&str] = &[
    "abs", "signum", "sin", "cos", "tan", "asin", "acos", "atan", "sinh", "cosh", "tanh", "asinh", "acosh", "atanh",
    "floor", "round", "ceil", "trunc", "fract", "exp", "sqrt", "cbrt", "ln", "log2", "log10", "log", "atan2", "min",
    "max",
];

/// The named constants of the expression language.
pub const CONSTANTS: &[(&str, f64)] = &[
    ("PI", std::f64::consts::PI),
    ("pi", std::f64::consts::PI),
    ("TAU", std::f64::consts::TAU),
    ("tau", std::f64::consts::TAU),
    ("E", std::f64::consts::E),
];

/// What a name stands for.
pub(crate) enum Meaning<'a> {
    /// A state or input: its slot.
    Slot(usize),
    /// A parameter's value.
    Value(f64),
    /// A definition's already substituted text.
    Text(&'a str),
}

/// Why an expression was refused.
#[derive(Debug)]
pub(crate) enum ExpandError {
    UnknownSymbol(String),
    UnknownFunction(String),
    Syntax(String),
    Limit { what: &'static str, size: usize, limit: usize },
}

/// Whether `name` is an identifier of the expression language.
pub(crate) fn is_identifier(name: &str) -> bool {
    let mut chars = name.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// Whether `name` is a function or constant of the expression language.
pub(crate) fn is_reserved(name: &str) -> bool {
    FUNCTIONS.contains(&name) || CONSTANTS.iter().any(|(c, _)| *c == name) || name == "e"
}

/// The internal name of slot `slot`.
pub(crate) fn slot_name(slot: usize) -> String {
    format!("v{slot:04}")
}

/// A number as the expression library parses it: plain decimal, negative ones in parentheses.
pub(crate) fn push_number(out: &mut String, v: f64) {
    if v < 0.0 || (v == 0.0 && v.is_sign_negative()) {
        out.push_str(&format!("(-{})", -v));
    } else {
        out.push_str(&format!("{v}"));
    }
}

fn check_len(out: &str) -> Result<(), ExpandError> {
    if out.len() > MAX_EXPRESSION_BYTES {
        return Err(ExpandError::Limit {
            what: "the length after substitution (bytes)",
            size: out.len(),
            limit: MAX_EXPRESSION_BYTES,
        });
    }
    Ok(())
}

/// Rewrites `text` for the expression library, resolving names with `lookup`; checks the
/// limits of length, depth and operator count.
pub(crate) fn expand<'a>(text: &str, lookup: impl Fn(&str) -> Option<Meaning<'a>>) -> Result<String, ExpandError> {
    check_len(text)?;
    let bytes = text.as_bytes();
    let mut out = String::with_capacity(text.len() + 16);
    let mut i = 0;
    let mut operators = 0usize;
    while i < bytes.len() {
        let c = bytes[i];
        if c.is_ascii_whitespace() {
            // Kept (one space) so that tokens never merge.
            if !out.ends_with(' ') {
                out.push(' ');
            }
            i += 1;
        } else if c.is_ascii_digit() || (c == b'.' && bytes.get(i + 1).is_some_and(u8::is_ascii_digit)) {
            let start = i;
            while i < bytes.len() && (bytes[i].is_ascii_digit() || bytes[i] == b'.') {
                i += 1;
            }
            if i < bytes.len() && (bytes[i] == b'e' || bytes[i] == b'E') {
                let mut j = i + 1;
                if j < bytes.len() && (bytes[j] == b'+' || bytes[j] == b'-') {
                    j += 1;
                }
                if j < bytes.len() && bytes[j].is_ascii_digit() {
                    while j < bytes.len() && bytes[j].is_ascii_digit() {
                        j += 1;
                    }
                    i = j;
                }
            }
            let literal = &text[start..i];
            let v: f64 = literal.parse().map_err(|_| ExpandError::Syntax(format!("`{literal}` is not a number")))?;
            if !v.is_finite() {
                return Err(ExpandError::Syntax(format!("the number `{literal}` is out of range")));
            }
            push_number(&mut out, v);
        } else if c.is_ascii_alphabetic() || c == b'_' {
            let start = i;
            while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_') {
                i += 1;
            }
            let name = &text[start..i];
            let mut j = i;
            while j < bytes.len() && bytes[j].is_ascii_whitespace() {
                j += 1;
            }
            if bytes.get(j) == Some(&b'(') {
                if !FUNCTIONS.contains(&name) {
                    return Err(ExpandError::UnknownFunction(name.to_owned()));
                }
                operators += 1;
                out.push_str(name);
            } else if let Some((_, v)) = CONSTANTS.iter().find(|(c, _)| *c == name) {
                push_number(&mut out, *v);
            } else {
                match lookup(name) {
                    Some(Meaning::Slot(s)) => out.push_str(&slot_name(s)),
                    Some(Meaning::Value(v)) => push_number(&mut out, v),
                    Some(Meaning::Text(t)) => {
                        out.push('(');
                        out.push_str(t);
                        out.push(')');
                        operators += t.bytes().filter(|b| b"+-*/^,".contains(b)).count();
                    }
                    None => return Err(ExpandError::UnknownSymbol(name.to_owned())),
                }
            }
        } else if b"+-*/^(),".contains(&c) {
            if b"+-*/^,".contains(&c) {
                operators += 1;
            }
            out.push(c as char);
            i += 1;
        } else {
            let ch = text[i..].chars().next().unwrap_or('?');
            return Err(ExpandError::Syntax(format!("unexpected character `{ch}`")));
        }
        check_len(&out)?;
        if operators > MAX_OPERATORS {
            return Err(ExpandError::Limit { what: "the number of operators", size: operators, limit: MAX_OPERATORS });
        }
    }
    if out.trim().is_empty() {
        return Err(ExpandError::Syntax("the expression is empty".to_owned()));
    }
    check_depth(&out)?;
    Ok(out)
}

/// Checks that the parentheses of `text` balance and nest at most [`MAX_DEPTH`] deep.
fn check_depth(text: &str) -> Result<(), ExpandError> {
    let (mut depth, mut deepest) = (0usize, 0usize);
    for c in text.bytes() {
        match c {
            b'(' => {
                depth += 1;
                deepest = deepest.max(depth);
            }
            b')' => {
                depth = depth.checked_sub(1).ok_or_else(|| ExpandError::Syntax("unbalanced `)`".to_owned()))?;
            }
            _ => {}
        }
    }
    if depth != 0 {
        return Err(ExpandError::Syntax("unbalanced `(`".to_owned()));
    }
    if deepest > MAX_DEPTH {
        return Err(ExpandError::Limit { what: "the nesting depth of parentheses", size: deepest, limit: MAX_DEPTH });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lookup(name: &str) -> Option<Meaning<'static>> {
        match name {
            "x" => Some(Meaning::Slot(0)),
            "u" => Some(Meaning::Slot(3)),
            "k" => Some(Meaning::Value(-1e-3)),
            "d" => Some(Meaning::Text("v0000*2")),
            _ => None,
        }
    }

    #[test]
    fn names_numbers_and_definitions_are_rewritten() {
        let s = expand("sin(x) + k*u^2.5e1 - d / pi", lookup).unwrap();
        assert_eq!(s, format!("sin(v0000) + (-0.001)*v0003^25 - (v0000*2) / {}", std::f64::consts::PI));
        assert!(matches!(expand("y + 1", lookup), Err(ExpandError::UnknownSymbol(n)) if n == "y"));
        assert!(matches!(expand("foo(x)", lookup), Err(ExpandError::UnknownFunction(n)) if n == "foo"));
        assert!(matches!(expand("x $ 1", lookup), Err(ExpandError::Syntax(_))));
        assert!(matches!(expand("(x", lookup), Err(ExpandError::Syntax(_))));
        assert!(matches!(expand("1e400", lookup), Err(ExpandError::Syntax(_))));
    }
}
