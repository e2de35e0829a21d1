//! Reading an expression: tokens, names resolved, then a small recursive-descent parser that
//! appends the expression's operations to the [`Graph`].
//!
//! Grammar (as the expression library `exmex` of earlier versions read it): `+ -` then `* /`
//! then `^`, all left-associative (`2^3^2` is `(2^3)^2`); a leading `-` or `+` binds tighter
//! than `^` (`-x^2` is `(-x)^2`); functions take their arguments in parentheses.

use crate::graph::{Graph, Op};
use crate::limits::{MAX_DEPTH, MAX_EXPRESSION_BYTES, MAX_OPERATORS};
use crate::ops::{Bin, Fun};

/// The functions of the expression language (one argument, and the two-argument `atan2`,
/// `min`, `max`).
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
pub(crate) enum Meaning {
    /// A state, input or definition: its node.
    Node(u32),
    /// A parameter's value.
    Value(f64),
}

/// Why an expression was refused.
#[derive(Debug)]
pub(crate) enum ParseError {
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

#[derive(Debug, Clone, Copy, PartialEq)]
enum Tok {
    Num(f64),
    Node(u32),
    Unary(Fun),
    Binary(Bin),
    Op(u8),
}

/// Splits `text` into tokens, resolving names with `lookup`; checks the limits of length,
/// operators and nesting. Returns the tokens and the number of operators.
fn tokens(text: &str, lookup: &impl Fn(&str) -> Option<Meaning>) -> Result<(Vec<Tok>, usize), ParseError> {
    if text.len() > MAX_EXPRESSION_BYTES {
        return Err(ParseError::Limit { what: "the length (bytes)", size: text.len(), limit: MAX_EXPRESSION_BYTES });
    }
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(text.len() / 2 + 1);
    let (mut i, mut operators, mut depth, mut deepest) = (0, 0usize, 0usize, 0usize);
    while i < bytes.len() {
        let c = bytes[i];
        if c.is_ascii_whitespace() {
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
            let v: f64 = literal.parse().map_err(|_| ParseError::Syntax(format!("`{literal}` is not a number")))?;
            if !v.is_finite() {
                return Err(ParseError::Syntax(format!("the number `{literal}` is out of range")));
            }
            out.push(Tok::Num(v));
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
                operators += 1;
                out.push(match name {
                    "atan2" => Tok::Binary(Bin::Atan2),
                    "min" => Tok::Binary(Bin::Min),
                    "max" => Tok::Binary(Bin::Max),
                    _ => Tok::Unary(Fun::of_name(name).ok_or_else(|| ParseError::UnknownFunction(name.to_owned()))?),
                });
            } else if let Some((_, v)) = CONSTANTS.iter().find(|(c, _)| *c == name) {
                out.push(Tok::Num(*v));
            } else {
                out.push(match lookup(name) {
                    Some(Meaning::Node(n)) => Tok::Node(n),
                    Some(Meaning::Value(v)) => Tok::Num(v),
                    None => return Err(ParseError::UnknownSymbol(name.to_owned())),
                });
            }
        } else if b"+-*/^(),".contains(&c) {
            match c {
                b'(' => {
                    depth += 1;
                    deepest = deepest.max(depth);
                }
                b')' => {
                    depth = depth.checked_sub(1).ok_or_else(|| ParseError::Syntax("unbalanced `)`".to_owned()))?;
                }
                _ => operators += 1,
            }
            out.push(Tok::Op(c));
            i += 1;
        } else {
            let ch = text[i..].chars().next().unwrap_or('?');
            return Err(ParseError::Syntax(format!("unexpected character `{ch}`")));
        }
        if operators > MAX_OPERATORS {
            return Err(ParseError::Limit { what: "the number of operators", size: operators, limit: MAX_OPERATORS });
        }
        if deepest > MAX_DEPTH {
            return Err(ParseError::Limit {
                what: "the nesting depth of parentheses",
                size: deepest,
                limit: MAX_DEPTH,
            });
        }
    }
    if depth != 0 {
        return Err(ParseError::Syntax("unbalanced `(`".to_owned()));
    }
    if out.is_empty() {
        return Err(ParseError::Syntax("the expression is empty".to_owned()));
    }
    Ok((out, operators))
}

struct Parser<'a> {
    toks: &'a [Tok],
    at: usize,
    graph: &'a mut Graph,
}

fn syntax<T>(message: &str) -> Result<T, ParseError> {
    Err(ParseError::Syntax(message.to_owned()))
}

impl Parser<'_> {
    fn peek(&self) -> Option<Tok> {
        self.toks.get(self.at).copied()
    }

    fn eat(&mut self, op: u8) -> bool {
        if self.peek() == Some(Tok::Op(op)) {
            self.at += 1;
            true
        } else {
            false
        }
    }

    /// `term (('+' | '-') term)*`
    fn sum(&mut self) -> Result<u32, ParseError> {
        let mut left = self.product()?;
        loop {
            let g = if self.eat(b'+') {
                Bin::Add
            } else if self.eat(b'-') {
                Bin::Sub
            } else {
                return Ok(left);
            };
            let right = self.product()?;
            left = self.graph.push(Op::Binary(g, left, right));
        }
    }

    /// `power (('*' | '/') power)*`
    fn product(&mut self) -> Result<u32, ParseError> {
        let mut left = self.power()?;
        loop {
            let g = if self.eat(b'*') {
                Bin::Mul
            } else if self.eat(b'/') {
                Bin::Div
            } else {
                return Ok(left);
            };
            let right = self.power()?;
            left = self.graph.push(Op::Binary(g, left, right));
        }
    }

    /// `signed ('^' signed)*`
    fn power(&mut self) -> Result<u32, ParseError> {
        let mut left = self.signed()?;
        while self.eat(b'^') {
            let right = self.signed()?;
            left = self.graph.push(Op::Binary(Bin::Pow, left, right));
        }
        Ok(left)
    }

    /// `('-' | '+')* primary`
    fn signed(&mut self) -> Result<u32, ParseError> {
        let mut negate = false;
        loop {
            if self.eat(b'-') {
                negate = !negate;
            } else if !self.eat(b'+') {
                break;
            }
        }
        let value = self.primary()?;
        Ok(if negate { self.graph.push(Op::Neg(value)) } else { value })
    }

    /// A number, a name, `( sum )` or a function call.
    fn primary(&mut self) -> Result<u32, ParseError> {
        let Some(tok) = self.peek() else { return syntax("the expression ends early") };
        self.at += 1;
        match tok {
            Tok::Num(v) => Ok(self.graph.push(Op::Const(v))),
            Tok::Node(n) => Ok(n),
            Tok::Op(b'(') => {
                let inner = self.sum()?;
                if self.eat(b')') { Ok(inner) } else { syntax("expected `)`") }
            }
            Tok::Unary(f) => {
                self.eat(b'(');
                let a = self.sum()?;
                if !self.eat(b')') {
                    return syntax("a function of one argument takes one argument in parentheses");
                }
                Ok(self.graph.push(Op::Unary(f, a)))
            }
            Tok::Binary(g) => {
                self.eat(b'(');
                let a = self.sum()?;
                if !self.eat(b',') {
                    return syntax("atan2, min and max take two arguments");
                }
                let b = self.sum()?;
                if !self.eat(b')') {
                    return syntax("atan2, min and max take two arguments");
                }
                Ok(self.graph.push(Op::Binary(g, a, b)))
            }
            Tok::Op(c) => Err(ParseError::Syntax(format!("unexpected `{}`", c as char))),
        }
    }
}

/// Parses `text`, resolving names with `lookup`, appends its operations to `graph` and returns
/// the node of its value and its number of operators. On error the graph may hold unused
/// nodes (the model is refused anyway).
pub(crate) fn parse_into(
    text: &str,
    graph: &mut Graph,
    lookup: impl Fn(&str) -> Option<Meaning>,
) -> Result<(u32, usize), ParseError> {
    let (toks, operators) = tokens(text, &lookup)?;
    let mut parser = Parser { toks: &toks, at: 0, graph };
    let root = parser.sum()?;
    match parser.peek() {
        None => Ok((root, operators)),
        Some(Tok::Op(c)) => Err(ParseError::Syntax(format!("unexpected `{}`", c as char))),
        Some(_) => syntax("two operands without an operator between them"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lookup(name: &str) -> Option<Meaning> {
        match name {
            "x" => Some(Meaning::Node(0)),
            "u" => Some(Meaning::Node(1)),
            "k" => Some(Meaning::Value(-1e-3)),
            _ => None,
        }
    }

    fn value(text: &str) -> f64 {
        let mut g = Graph::new(2);
        let (root, _) = parse_into(text, &mut g, lookup).unwrap();
        let schedule = g.schedule(&[root]);
        let mut values = vec![0.0; g.len()];
        values[0] = 3.0;
        values[1] = 0.5;
        g.run(&schedule, &mut values, None);
        values[root as usize]
    }

    #[test]
    fn precedence_and_names() {
        assert_eq!(value("-x^2"), 9.0);
        assert_eq!(value("2^3^2"), 64.0);
        assert_eq!(value("1 + 2 * x ^ 2 / 3 - u"), 6.5);
        assert_eq!(value("--x + +u"), 3.5);
        assert_eq!(value("k * 1000 + max(x, u) - atan2(0, 1)"), 2.0);
        let mut g = Graph::new(2);
        assert!(matches!(parse_into("y + 1", &mut g, lookup), Err(ParseError::UnknownSymbol(n)) if n == "y"));
        assert!(matches!(parse_into("foo(x)", &mut g, lookup), Err(ParseError::UnknownFunction(n)) if n == "foo"));
        for bad in ["x $ 1", "(x", "x)", "1e400", "x x", "(x)(x)", "sin()", "min(x)", "atan2(x, u, x)", "x +", ","] {
            assert!(matches!(parse_into(bad, &mut g, lookup), Err(ParseError::Syntax(_))), "{bad}");
        }
    }
}
