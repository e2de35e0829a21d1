//! The mean-value extension of a model over a box (docs/constrained-zonotopes.md (C1)–(C3)) and
//! the interval observer that runs beside the set (C5).
//!
//! For `x` in a box `X` with midpoint `p`, every entry of `φ(x)` (`φ = f(·, u)` or `h(·, u)`)
//! satisfies `φ(x) ∈ φ(p) + J(X)(x − p)` (mean-value theorem, `J(X)` an interval enclosure of
//! the Jacobian over the box). With `M = mid J(X)`:
//! `φ(x) ∈ M x + E`, `E = φ(p) − M p + (J(X) − M)(X − p)` (C1), an interval vector evaluated in
//! outward-rounded arithmetic, so `φ(Z) ⊆ M Z ⊕ E` for every set `Z ⊆ X`.

use intervals::Interval;
use nalgebra::{DMatrix, DVector};

use models::{SecondOrderModel, TaylorEnclosure};

/// Which function of the model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Function {
    /// `f(x, u)`.
    Dynamics,
    /// `h(x, u)`.
    Measurement,
}

impl Function {
    fn name(self) -> &'static str {
        match self {
            Function::Dynamics => "f",
            Function::Measurement => "h",
        }
    }
}

/// `φ(x) ∈ M x + E` for every `x` in the box.
#[derive(Debug, Clone)]
pub(crate) struct MeanValue {
    /// `M`, the midpoint of the Jacobian enclosure.
    pub(crate) m: DMatrix<f64>,
    /// `E` (C1).
    pub(crate) e: Vec<Interval>,
    /// The Jacobian enclosure over the box (for the interval observer's contraction).
    pub(crate) jacobian: Vec<Interval>,
    /// `φ(p)` enclosed.
    pub(crate) value: Vec<Interval>,
    /// The box's midpoint `p`.
    pub(crate) p: Vec<f64>,
}

impl MeanValue {
    /// The extension of the outputs `rows` only (a partial measurement).
    pub(crate) fn select(&self, rows: &[usize]) -> Self {
        let n = self.p.len();
        Self {
            m: DMatrix::from_fn(rows.len(), n, |a, j| self.m[(rows[a], j)]),
            e: rows.iter().map(|&i| self.e[i]).collect(),
            jacobian: rows.iter().flat_map(|&i| self.jacobian[i * n..(i + 1) * n].iter().copied()).collect(),
            value: rows.iter().map(|&i| self.value[i]).collect(),
            p: self.p.clone(),
        }
    }
}

/// Why an extension could not be formed (the caller turns it into `GuaranteeLost`).
pub(crate) type Unbounded = String;

/// The mean-value extension (C1) of `f` or `h` over the box `x`.
pub(crate) fn mean_value<M: SecondOrderModel + ?Sized>(
    model: &M,
    which: Function,
    x: &[Interval],
    u: &DVector<f64>,
    enclosure: &mut TaylorEnclosure,
) -> Result<Result<MeanValue, Unbounded>, models::ModelError> {
    let n = x.len();
    let p: Vec<f64> = x.iter().map(|v| v.mid_rad().0).collect();
    let point: Vec<Interval> = p.iter().map(|v| Interval::point(*v)).collect();
    match which {
        Function::Dynamics => model.f_value_enclosure(&point, u, enclosure)?,
        Function::Measurement => model.h_value_enclosure(&point, u, enclosure)?,
    }
    let rows = enclosure.dims().0;
    let (centre, mut plain) = (DVector::from_column_slice(&p), DVector::zeros(rows));
    let evaluated = match which {
        Function::Dynamics => model.f(&centre, u, &mut plain),
        Function::Measurement => model.h(&centre, u, &mut plain),
    };
    if let Err(reason) = crate::checks::defined_at(which.name(), "the set's centre", evaluated, &plain) {
        return Ok(Err(reason));
    }
    let value: Vec<Interval> = (0..rows).map(|i| enclosure.value(i)).collect();
    if let Some(i) = value.iter().position(|v| !v.is_bounded()) {
        return Ok(Err(format!("{}[{i}] is undefined or unbounded at the set's centre", which.name())));
    }
    match which {
        Function::Dynamics => model.f_enclosure(x, u, enclosure)?,
        Function::Measurement => model.h_enclosure(x, u, enclosure)?,
    }
    let mut jacobian = Vec::with_capacity(rows * n);
    for i in 0..rows {
        for j in 0..n {
            let v = enclosure.jacobian(i, j);
            if !v.is_bounded() {
                return Ok(Err(format!(
                    "the Jacobian entry ({i}, {j}) of {} is unbounded over the set's box (the function is undefined \
                     or not differentiable somewhere in it)",
                    which.name()
                )));
            }
            jacobian.push(v);
        }
    }
    let mut m = DMatrix::zeros(rows, n);
    let mut e = Vec::with_capacity(rows);
    for i in 0..rows {
        let mut s = value[i];
        for j in 0..n {
            let jij = jacobian[i * n + j];
            let mij = jij.mid_rad().0;
            m[(i, j)] = mij;
            s = s - Interval::point(mij) * p[j];
            s = s + (jij - Interval::point(mij)) * (x[j] - Interval::point(p[j]));
        }
        if !s.is_bounded() {
            return Ok(Err(format!("the mean-value remainder of {}[{i}] overflowed", which.name())));
        }
        e.push(s);
    }
    Ok(Ok(MeanValue { m, e, jacobian, value, p }))
}

/// The interval observer's prediction (C5): per row, the best of the natural interval extension
/// of `f` over the box, the mean-value form `f(p) + J(X)(X − p)` and, where every Jacobian entry
/// of the row has one sign over the box (`f_i` monotone in each state), the exact range
/// `[f_i(x̲ⁱ), f_i(x̄ⁱ)]` at the row's two corners, each enclosed (not for a row affine over the
/// box, whose mean-value form is already its range); then the process-noise box.
/// `None` when unbounded.
pub(crate) fn predict_box<M: SecondOrderModel + ?Sized>(
    model: &M,
    x: &[Interval],
    u: &DVector<f64>,
    mv: &MeanValue,
    w_radius: &[f64],
    enclosure: &mut TaylorEnclosure,
) -> Result<Option<Vec<Interval>>, models::ModelError> {
    let n = x.len();
    model.f_value_enclosure(x, u, enclosure)?;
    let mut out: Vec<Interval> = (0..n).map(|i| enclosure.value(i)).collect();
    let mut corner = vec![Interval::ZERO; n];
    let mut evaluated: Vec<(Vec<Interval>, Vec<Interval>)> = Vec::new();
    for i in 0..n {
        let mut form = mv.value[i];
        for j in 0..n {
            form = form + mv.jacobian[i * n + j] * (x[j] - Interval::point(mv.p[j]));
        }
        if let Some(v) = out[i].meet(form) {
            out[i] = v;
        }
        let row = &mv.jacobian[i * n..(i + 1) * n];
        let definite = |j: usize| row[j].lo() >= 0.0 || row[j].hi() <= 0.0;
        // A row affine over the box (its Jacobian enclosure a point) has the mean-value form as
        // its exact range up to rounding: its corners would add no more than a few ulps.
        if !(0..n).any(definite) || row.iter().all(|d| d.lo() == d.hi()) {
            continue;
        }
        // Monotone in each definite state: its ends give the range over the sub-box where the
        // other states sit at p; their share is the mean-value term J_ij (X_j − p_j).
        let mut rest = Interval::ZERO;
        for j in (0..n).filter(|&j| !definite(j)) {
            rest = rest + row[j] * (x[j] - Interval::point(mv.p[j]));
        }
        let end = |j: usize, upper: bool| {
            if !definite(j) {
                Interval::point(mv.p[j])
            } else if (row[j].lo() >= 0.0) == upper {
                Interval::point(x[j].hi())
            } else {
                Interval::point(x[j].lo())
            }
        };
        let mut value_at = |upper: bool| -> Result<Interval, models::ModelError> {
            for j in 0..n {
                corner[j] = end(j, upper);
            }
            // Rows that are monotone the same way share their corners (every tank of a cascade).
            if let Some((_, values)) = evaluated.iter().find(|(c, _)| *c == corner) {
                return Ok(values[i]);
            }
            model.f_value_enclosure(&corner, u, enclosure)?;
            let values: Vec<Interval> = (0..n).map(|r| enclosure.value(r)).collect();
            let v = values[i];
            evaluated.push((corner.clone(), values));
            Ok(v)
        };
        let lo = value_at(false)?.lo();
        let hi = value_at(true)?.hi();
        if lo <= hi {
            if let Some(v) = out[i].meet(Interval::new(lo, hi) + rest) {
                out[i] = v;
            }
        }
    }
    for (o, r) in out.iter_mut().zip(w_radius) {
        *o = *o + Interval::new(-r, *r);
    }
    Ok(out.iter().all(|v| v.is_bounded()).then_some(out))
}

/// The interval observer's update (C5): `x_j` contracted by each measurement row
/// `yᵢ − vᵢ ∈ φᵢ(p) + Σ_k J_ik (x_k − p_k)` where `J_ij` excludes 0; `None` when a range becomes
/// empty (the data contradict the box and the noise bounds: certified).
pub(crate) fn contract_box(x: &mut [Interval], mv: &MeanValue, y: &DVector<f64>, v_radius: &[f64]) -> Option<()> {
    let n = x.len();
    for _ in 0..2 {
        for i in 0..y.len() {
            // yᵢ − vᵢ − φᵢ(p) = Σ_k J_ik (x_k − p_k).
            let target = Interval::point(y[i]) - Interval::new(-v_radius[i], v_radius[i]) - mv.value[i];
            let terms: Vec<Interval> =
                (0..n).map(|k| mv.jacobian[i * n + k] * (x[k] - Interval::point(mv.p[k]))).collect();
            for j in 0..n {
                let jij = mv.jacobian[i * n + j];
                if jij.lo() <= 0.0 && jij.hi() >= 0.0 {
                    continue;
                }
                let mut rest = Interval::ZERO;
                for (k, t) in terms.iter().enumerate() {
                    if k != j {
                        rest = rest + *t;
                    }
                }
                let implied = (target - rest) / jij + Interval::point(mv.p[j]);
                if implied.is_bounded() {
                    x[j] = x[j].meet(implied)?;
                }
            }
        }
    }
    Some(())
}

/// The box `[lo, hi]` as intervals.
pub(crate) fn boxed(lo: &DVector<f64>, hi: &DVector<f64>) -> Vec<Interval> {
    lo.iter().zip(hi.iter()).map(|(l, h)| Interval::new(*l, *h)).collect()
}
