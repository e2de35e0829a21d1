//! The functions and operators a model file may use, with their values and derivatives (below
//! the graph and the interval rules, which both apply them).

/// A function of one argument.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Fun {
    Abs,
    Signum,
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Sinh,
    Cosh,
    Tanh,
    Asinh,
    Acosh,
    Atanh,
    Floor,
    Round,
    Ceil,
    Trunc,
    Fract,
    Exp,
    Sqrt,
    Cbrt,
    Ln,
    Log2,
    Log10,
}

impl Fun {
    /// The function of that name (`log` is the natural logarithm).
    pub(crate) fn of_name(name: &str) -> Option<Self> {
        Some(match name {
            "abs" => Self::Abs,
            "signum" => Self::Signum,
            "sin" => Self::Sin,
            "cos" => Self::Cos,
            "tan" => Self::Tan,
            "asin" => Self::Asin,
            "acos" => Self::Acos,
            "atan" => Self::Atan,
            "sinh" => Self::Sinh,
            "cosh" => Self::Cosh,
            "tanh" => Self::Tanh,
            "asinh" => Self::Asinh,
            "acosh" => Self::Acosh,
            "atanh" => Self::Atanh,
            "floor" => Self::Floor,
            "round" => Self::Round,
            "ceil" => Self::Ceil,
            "trunc" => Self::Trunc,
            "fract" => Self::Fract,
            "exp" => Self::Exp,
            "sqrt" => Self::Sqrt,
            "cbrt" => Self::Cbrt,
            "ln" | "log" => Self::Ln,
            "log2" => Self::Log2,
            "log10" => Self::Log10,
            _ => return None,
        })
    }

    pub(crate) fn apply(self, a: f64) -> f64 {
        match self {
            Self::Abs => a.abs(),
            Self::Signum => a.signum(),
            Self::Sin => a.sin(),
            Self::Cos => a.cos(),
            Self::Tan => a.tan(),
            Self::Asin => a.asin(),
            Self::Acos => a.acos(),
            Self::Atan => a.atan(),
            Self::Sinh => a.sinh(),
            Self::Cosh => a.cosh(),
            Self::Tanh => a.tanh(),
            Self::Asinh => a.asinh(),
            Self::Acosh => a.acosh(),
            Self::Atanh => a.atanh(),
            Self::Floor => a.floor(),
            Self::Round => a.round(),
            Self::Ceil => a.ceil(),
            Self::Trunc => a.trunc(),
            Self::Fract => a.fract(),
            Self::Exp => a.exp(),
            Self::Sqrt => a.sqrt(),
            Self::Cbrt => a.cbrt(),
            Self::Ln => a.ln(),
            Self::Log2 => a.log2(),
            Self::Log10 => a.log10(),
        }
    }

    /// The derivative at `a`, given the value `v = self(a)`. `abs` has derivative 0 at 0; the
    /// step functions (`signum floor ceil round trunc`) 0 and `fract` 1, their derivatives
    /// wherever they exist (everywhere but at their jumps).
    pub(crate) fn derivative(self, a: f64, v: f64) -> f64 {
        match self {
            Self::Abs => {
                if a > 0.0 {
                    1.0
                } else if a < 0.0 {
                    -1.0
                } else {
                    0.0
                }
            }
            Self::Signum | Self::Floor | Self::Round | Self::Ceil | Self::Trunc => 0.0,
            Self::Fract => 1.0,
            Self::Sin => a.cos(),
            Self::Cos => -a.sin(),
            Self::Tan => 1.0 + v * v,
            Self::Asin => 1.0 / (1.0 - a * a).sqrt(),
            Self::Acos => -1.0 / (1.0 - a * a).sqrt(),
            Self::Atan => 1.0 / (1.0 + a * a),
            Self::Sinh => a.cosh(),
            Self::Cosh => a.sinh(),
            Self::Tanh => 1.0 - v * v,
            Self::Asinh => 1.0 / (a * a + 1.0).sqrt(),
            Self::Acosh => 1.0 / (a * a - 1.0).sqrt(),
            Self::Atanh => 1.0 / (1.0 - a * a),
            Self::Exp => v,
            Self::Sqrt => 0.5 / v,
            Self::Cbrt => 1.0 / (3.0 * v * v),
            Self::Ln => 1.0 / a,
            Self::Log2 => 1.0 / (a * std::f64::consts::LN_2),
            Self::Log10 => 1.0 / (a * std::f64::consts::LN_10),
        }
    }
}

/// A function or operator of two arguments.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Bin {
    Add,
    Sub,
    Mul,
    Div,
    Pow,
    Atan2,
    Min,
    Max,
}

impl Bin {
    pub(crate) fn apply(self, a: f64, b: f64) -> f64 {
        match self {
            Self::Add => a + b,
            Self::Sub => a - b,
            Self::Mul => a * b,
            Self::Div => a / b,
            Self::Pow => a.powf(b),
            Self::Atan2 => a.atan2(b),
            Self::Min => a.min(b),
            Self::Max => a.max(b),
        }
    }

    /// `(∂/∂a, ∂/∂b)` at `(a, b)` with value `v`; `need_a`, `need_b` say which are used (the
    /// other may be anything). Ties of `min`/`max` take the first argument's derivative.
    pub(crate) fn partials(self, a: f64, b: f64, v: f64, need_a: bool, need_b: bool) -> (f64, f64) {
        match self {
            Self::Add => (1.0, 1.0),
            Self::Sub => (1.0, -1.0),
            Self::Mul => (b, a),
            Self::Div => (1.0 / b, -v / b),
            Self::Pow => {
                let da = if need_a { b * a.powf(b - 1.0) } else { 0.0 };
                let db = if need_b { v * a.ln() } else { 0.0 };
                (da, db)
            }
            Self::Atan2 => {
                let r = a * a + b * b;
                (b / r, -a / r)
            }
            Self::Min => {
                if a <= b || b.is_nan() {
                    (1.0, 0.0)
                } else {
                    (0.0, 1.0)
                }
            }
            Self::Max => {
                if a >= b || b.is_nan() {
                    (1.0, 0.0)
                } else {
                    (0.0, 1.0)
                }
            }
        }
    }
}
