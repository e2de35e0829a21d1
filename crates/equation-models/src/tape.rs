//! A section's schedule compiled once, when the model is read, into straight-line instructions
//! for the evaluations the filters make at every step: the values of `f` or `h`, or the values
//! with their derivatives with respect to the states.
//!
//! [`Graph::run`] decides at every node whether it carries derivatives, which of its operands
//! do, and which operation it is, and writes every constant again; here those decisions are
//! taken once: constants are written in one loop, a node without derivatives is a value
//! instruction, a node with them names which operands carry derivatives, and the four
//! arithmetic operators have instructions of their own. The row loops are instantiated for the
//! common numbers of states, so that they unroll. Every value and derivative is computed by the
//! same expression as in [`Graph::run`], in the same order: the results are bit for bit the same
//! (tested against it).

use crate::graph::{Graph, Op};
use crate::ops::{Bin, Fun};

/// Which operands of a binary node carry derivatives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Carries {
    A,
    B,
    Both,
}

/// One instruction; operands and results are node numbers.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Instr {
    Neg {
        a: u32,
        out: u32,
    },
    Unary {
        f: Fun,
        a: u32,
        out: u32,
    },
    Add {
        a: u32,
        b: u32,
        out: u32,
    },
    Sub {
        a: u32,
        b: u32,
        out: u32,
    },
    Mul {
        a: u32,
        b: u32,
        out: u32,
    },
    Div {
        a: u32,
        b: u32,
        out: u32,
    },
    Binary {
        g: Bin,
        a: u32,
        b: u32,
        out: u32,
    },
    /// With derivatives (the node varies with the states).
    NegD {
        a: u32,
        out: u32,
    },
    UnaryD {
        f: Fun,
        a: u32,
        out: u32,
    },
    BinaryD {
        g: Bin,
        a: u32,
        b: u32,
        out: u32,
        carries: Carries,
    },
    /// The four operators with derivatives, by which operands carry them.
    ArithD {
        op: Arith,
        a: u32,
        b: u32,
        out: u32,
    },
}

/// An arithmetic operator and which of its operands carry derivatives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Arith {
    AddA,
    AddB,
    AddBoth,
    SubA,
    SubB,
    SubBoth,
    MulA,
    MulB,
    MulBoth,
    DivA,
    DivB,
    DivBoth,
}

impl Arith {
    fn of(g: Bin, carries: Carries) -> Option<Self> {
        use Carries::{A, B, Both};
        Some(match (g, carries) {
            (Bin::Add, A) => Self::AddA,
            (Bin::Add, B) => Self::AddB,
            (Bin::Add, Both) => Self::AddBoth,
            (Bin::Sub, A) => Self::SubA,
            (Bin::Sub, B) => Self::SubB,
            (Bin::Sub, Both) => Self::SubBoth,
            (Bin::Mul, A) => Self::MulA,
            (Bin::Mul, B) => Self::MulB,
            (Bin::Mul, Both) => Self::MulBoth,
            (Bin::Div, A) => Self::DivA,
            (Bin::Div, B) => Self::DivB,
            (Bin::Div, Both) => Self::DivBoth,
            _ => return None,
        })
    }
}

/// The compiled schedule of one section.
#[derive(Debug, Clone)]
pub(crate) struct Tape {
    constants: Vec<(u32, f64)>,
    /// Values only.
    values: Vec<Instr>,
    /// Values, and derivatives where the node varies with the states.
    derivatives: Vec<Instr>,
}

fn value_instr(op: Op, out: u32) -> Option<Instr> {
    Some(match op {
        Op::Slot | Op::Const(_) => return None,
        Op::Neg(a) => Instr::Neg { a, out },
        Op::Unary(f, a) => Instr::Unary { f, a, out },
        Op::Binary(Bin::Add, a, b) => Instr::Add { a, b, out },
        Op::Binary(Bin::Sub, a, b) => Instr::Sub { a, b, out },
        Op::Binary(Bin::Mul, a, b) => Instr::Mul { a, b, out },
        Op::Binary(Bin::Div, a, b) => Instr::Div { a, b, out },
        Op::Binary(g, a, b) => Instr::Binary { g, a, b, out },
    })
}

impl Tape {
    /// Compiles `schedule`; `varies` marks the nodes that depend on a state.
    pub(crate) fn new(graph: &Graph, schedule: &[u32], varies: &[bool]) -> Self {
        let mut tape = Self { constants: Vec::new(), values: Vec::new(), derivatives: Vec::new() };
        for &i in schedule {
            let op = graph.op(i);
            if let Op::Const(c) = op {
                tape.constants.push((i, c));
                continue;
            }
            let Some(plain) = value_instr(op, i) else { continue };
            tape.values.push(plain);
            let with = if varies[i as usize] {
                match op {
                    Op::Neg(a) => Instr::NegD { a, out: i },
                    Op::Unary(f, a) => Instr::UnaryD { f, a, out: i },
                    Op::Binary(g, a, b) => {
                        let carries = match (varies[a as usize], varies[b as usize]) {
                            (true, true) => Carries::Both,
                            (true, false) => Carries::A,
                            _ => Carries::B,
                        };
                        match Arith::of(g, carries) {
                            Some(op) => Instr::ArithD { op, a, b, out: i },
                            None => Instr::BinaryD { g, a, b, out: i, carries },
                        }
                    }
                    Op::Slot | Op::Const(_) => continue,
                }
            } else {
                plain
            };
            tape.derivatives.push(with);
        }
        tape
    }

    fn constants(&self, values: &mut [f64]) {
        for &(i, c) in &self.constants {
            values[i as usize] = c;
        }
    }

    /// The values of the scheduled nodes (the states and inputs already in `values`).
    pub(crate) fn run_values(&self, values: &mut [f64]) {
        self.constants(values);
        for &instr in &self.values {
            value(instr, values);
        }
    }

    /// The values and, in `grads` (`n` per node, the first `n` rows the states' seeds), the
    /// derivatives with respect to the `n` states.
    pub(crate) fn run_derivatives(&self, n: usize, values: &mut [f64], grads: &mut [f64]) {
        self.constants(values);
        match n {
            1 => self.derivatives_of_width(1, values, grads),
            2 => self.derivatives_of_width(2, values, grads),
            3 => self.derivatives_of_width(3, values, grads),
            4 => self.derivatives_of_width(4, values, grads),
            5 => self.derivatives_of_width(5, values, grads),
            6 => self.derivatives_of_width(6, values, grads),
            7 => self.derivatives_of_width(7, values, grads),
            8 => self.derivatives_of_width(8, values, grads),
            _ => self.derivatives_of_width(n, values, grads),
        }
    }

    /// The body of [`Tape::run_derivatives`], inlined at each literal width so that its row
    /// loops are compiled for it.
    #[inline(always)]
    fn derivatives_of_width(&self, w: usize, values: &mut [f64], grads: &mut [f64]) {
        for s in 0..w {
            let row = &mut grads[s * w..(s + 1) * w];
            row.fill(0.0);
            row[s] = 1.0;
        }
        for &instr in &self.derivatives {
            let (a, out) = match instr {
                Instr::NegD { a, out } | Instr::UnaryD { a, out, .. } => (a, out),
                Instr::BinaryD { a, out, .. } | Instr::ArithD { a, out, .. } => (a, out),
                _ => {
                    value(instr, values);
                    continue;
                }
            };
            let out = out as usize;
            let (done, rest) = grads.split_at_mut(out * w);
            let row = &mut rest[..w];
            let ga = |a: u32| &done[a as usize * w..(a as usize + 1) * w];
            match instr {
                Instr::NegD { .. } => {
                    values[out] = -values[a as usize];
                    for (r, &d) in row.iter_mut().zip(ga(a)) {
                        *r = -d;
                    }
                }
                Instr::UnaryD { f, .. } => {
                    let x = values[a as usize];
                    let v = f.apply(x);
                    values[out] = v;
                    let d = f.derivative(x, v);
                    for (r, &g) in row.iter_mut().zip(ga(a)) {
                        *r = d * g;
                    }
                }
                Instr::BinaryD { g, b, carries, .. } => {
                    let (x, y) = (values[a as usize], values[b as usize]);
                    let v = g.apply(x, y);
                    values[out] = v;
                    let (da, db) = g.partials(x, y, v, carries != Carries::B, carries != Carries::A);
                    match carries {
                        Carries::Both => {
                            for ((r, &p), &q) in row.iter_mut().zip(ga(a)).zip(ga(b)) {
                                *r = da * p + db * q;
                            }
                        }
                        Carries::A => {
                            for (r, &p) in row.iter_mut().zip(ga(a)) {
                                *r = da * p;
                            }
                        }
                        Carries::B => {
                            for (r, &q) in row.iter_mut().zip(ga(b)) {
                                *r = db * q;
                            }
                        }
                    }
                }
                Instr::ArithD { op, b, .. } => {
                    // `Bin::apply` and `Bin::partials` written out per operator: (1, 1) for `+`,
                    // (1, −1) for `−`, (b, a) for `×`, (1/b, −v/b) for `/`; a product with ±1
                    // is exact, so `1 · p` is `p` bit for bit.
                    let (x, y) = (values[a as usize], values[b as usize]);
                    let (pa, pb) = (ga(a), ga(b));
                    values[out] = match op {
                        Arith::AddA => {
                            row.copy_from_slice(pa);
                            x + y
                        }
                        Arith::AddB => {
                            row.copy_from_slice(pb);
                            x + y
                        }
                        Arith::AddBoth => {
                            for ((r, &p), &q) in row.iter_mut().zip(pa).zip(pb) {
                                *r = p + q;
                            }
                            x + y
                        }
                        Arith::SubA => {
                            row.copy_from_slice(pa);
                            x - y
                        }
                        Arith::SubB => {
                            for (r, &q) in row.iter_mut().zip(pb) {
                                *r = -q;
                            }
                            x - y
                        }
                        Arith::SubBoth => {
                            for ((r, &p), &q) in row.iter_mut().zip(pa).zip(pb) {
                                *r = p + -q;
                            }
                            x - y
                        }
                        Arith::MulA => {
                            for (r, &p) in row.iter_mut().zip(pa) {
                                *r = y * p;
                            }
                            x * y
                        }
                        Arith::MulB => {
                            for (r, &q) in row.iter_mut().zip(pb) {
                                *r = x * q;
                            }
                            x * y
                        }
                        Arith::MulBoth => {
                            for ((r, &p), &q) in row.iter_mut().zip(pa).zip(pb) {
                                *r = y * p + x * q;
                            }
                            x * y
                        }
                        Arith::DivA => {
                            let da = 1.0 / y;
                            for (r, &p) in row.iter_mut().zip(pa) {
                                *r = da * p;
                            }
                            x / y
                        }
                        Arith::DivB => {
                            let v = x / y;
                            let db = -v / y;
                            for (r, &q) in row.iter_mut().zip(pb) {
                                *r = db * q;
                            }
                            v
                        }
                        Arith::DivBoth => {
                            let v = x / y;
                            let (da, db) = (1.0 / y, -v / y);
                            for ((r, &p), &q) in row.iter_mut().zip(pa).zip(pb) {
                                *r = da * p + db * q;
                            }
                            v
                        }
                    };
                }
                _ => {}
            }
        }
    }
}

/// A value instruction (as [`Graph::run`] computes it).
#[inline(always)]
fn value(instr: Instr, values: &mut [f64]) {
    let v = |i: u32| values[i as usize];
    let (out, r) = match instr {
        Instr::Neg { a, out } => (out, -v(a)),
        Instr::Unary { f, a, out } => (out, f.apply(v(a))),
        Instr::Add { a, b, out } => (out, v(a) + v(b)),
        Instr::Sub { a, b, out } => (out, v(a) - v(b)),
        Instr::Mul { a, b, out } => (out, v(a) * v(b)),
        Instr::Div { a, b, out } => (out, v(a) / v(b)),
        Instr::Binary { g, a, b, out } => (out, g.apply(v(a), v(b))),
        Instr::NegD { .. } | Instr::UnaryD { .. } | Instr::BinaryD { .. } | Instr::ArithD { .. } => return,
    };
    values[out as usize] = r;
}

#[cfg(test)]
mod tests {
    use crate::EquationModel;
    use crate::graph::Seeds;
    use crate::model::Rows;

    /// Every function and operator, with states on either side of each binary operation.
    const EVERY_OPERATION: &str = r#"
[model]
states = ["a", "b", "c"]
inputs = ["u"]
outputs = ["y1", "y2", "y3"]

[parameters]
k = 0.5

[definitions]
s = "sin(a) + cos(b) * tan(c / 4) - asin(a / 9) + acos(b / 9) * atan(c)"
t = "sinh(a / 3) - cosh(b / 3) + tanh(c) + asinh(a) + acosh(2 + b^2) + atanh(c / 9)"
r = "abs(a) + signum(b) + floor(c) + round(a) + ceil(b) + trunc(c) + fract(a)"
ex = "exp(a / 4) + sqrt(2 + b^2) + cbrt(c) + ln(3 + a^2) + log2(4 + b^2) + log10(5 + c^2)"
p = "a^2 + 2^b + (1 + c^2)^a + k^u + u^2 * a"
m = "atan2(a, b) + atan2(1, c) + atan2(a, 2) + min(a, b) + max(b, 1) + min(2, c) + max(a, u)"

[f]
a = "s * t - r / (1 + ex^2) + p"
b = "-m + u * a / (2 + c^2) - 3 / (1 + a^2)"
c = "k * c + u"

[h]
y1 = "s + t * u"
y2 = "p - m"
y3 = "ex * r"
"#;

    /// Top-level keys that are not the model's (a file's noise description and settings).
    fn foreign(text: &str) -> Vec<String> {
        let table: toml::Table = text.parse().unwrap_or_default();
        let model = ["model", "parameters", "definitions", "f", "dxdt", "h"];
        table.keys().filter(|k| !model.contains(&k.as_str())).cloned().collect()
    }

    fn models() -> Vec<(String, EquationModel)> {
        let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples");
        let mut out = vec![("every operation".to_owned(), EquationModel::from_toml_str(EVERY_OPERATION, "t").unwrap())];
        let mut files: Vec<_> = std::fs::read_dir(format!("{root}/models"))
            .unwrap()
            .map(|e| e.unwrap().path())
            .chain(std::fs::read_dir(root).unwrap().map(|e| e.unwrap().path().join("model.toml")))
            .filter(|p| p.extension().is_some_and(|e| e == "toml") && p.exists())
            .collect();
        files.sort();
        for path in files {
            let text = std::fs::read_to_string(&path).unwrap();
            if !text.lines().any(|l| l.trim() == "[model]") {
                continue; // a linear model given as matrices
            }
            let keys = foreign(&text);
            let keys: Vec<&str> = keys.iter().map(String::as_str).collect();
            let name = path.display().to_string();
            let model = EquationModel::from_toml_str_with_foreign_keys(&text, &name, &keys).unwrap();
            out.push((name, model));
        }
        out
    }

    /// Deterministic points spread over a few units around zero.
    fn point(seed: usize, len: usize) -> Vec<f64> {
        (0..len).map(|i| 3.0 * ((seed * 31 + i * 17) as f64 * 0.7390851).sin() + 0.1 * (i as f64)).collect()
    }

    fn same(what: &str, x: &[f64], y: &[f64]) {
        for (k, (a, b)) in x.iter().zip(y).enumerate() {
            assert!(a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()), "{what}[{k}]: {a:e} vs {b:e}");
        }
    }

    #[test]
    fn the_tape_computes_the_graph_s_values_and_derivatives_bit_for_bit() {
        for (name, model) in models() {
            let n = model.states.len();
            let slots = n + model.inputs.len();
            let nodes = model.graph.len();
            let rows: [(&str, &Rows); 2] = [("f", &model.rhs), ("h", &model.out)];
            for (section, rows) in rows {
                for seed in 0..40 {
                    let x = point(seed, slots);
                    let (mut v1, mut v2) = (vec![0.0; nodes], vec![0.0; nodes]);
                    v1[..slots].copy_from_slice(&x);
                    v2[..slots].copy_from_slice(&x);
                    model.graph.run(&rows.schedule, &mut v1, None);
                    rows.tape.run_values(&mut v2);
                    same(&format!("{name} {section} values, point {seed}"), &v1, &v2);
                    let (mut g1, mut g2) = (vec![0.0; nodes * n], vec![0.0; nodes * n]);
                    let seeds = Seeds { lo: 0, width: n, varies: &model.varies };
                    v1[..slots].copy_from_slice(&x);
                    v2[..slots].copy_from_slice(&x);
                    model.graph.run(&rows.schedule, &mut v1, Some((&mut g1, &seeds)));
                    rows.tape.run_derivatives(n, &mut v2, &mut g2);
                    same(&format!("{name} {section} values with derivatives, point {seed}"), &v1, &v2);
                    for &i in rows.schedule.iter().filter(|&&i| model.varies[i as usize]) {
                        let r = i as usize * n..(i as usize + 1) * n;
                        same(
                            &format!("{name} {section} derivatives of node {i}, point {seed}"),
                            &g1[r.clone()],
                            &g2[r],
                        );
                    }
                }
            }
        }
    }
}
