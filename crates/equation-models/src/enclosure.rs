//! Interval enclosures of a model written as equations over a box of states
//! (`models::SecondOrderModel`), for the nonlinear set-membership filter: the graph evaluated in
//! outward-rounded interval arithmetic with the forward-mode Jacobian (module `interval_rules`),
//! then the integration scheme on intervals — Euler `x + ts·g`, RK4 through its stages with the
//! chain rule `D_s = J(x_s)(I + c_s D_{s−1})`, the exact zero-order hold `A_d x + B_d u`.
//!
//! Only first derivatives are enclosed: the Hessians are declared invalid, and the filter bounds
//! the linearisation remainder by the mean-value form, valid also across the kinks of `abs`,
//! `min`, `max`. A function undefined or discontinuous on the box gives unbounded enclosures,
//! which the filter reports instead of publishing a set. The intervals live in the thread's
//! scratch (module `scratch`): no allocation after a thread's first call.

use intervals::Interval;
use models::{DiscreteModel, ModelError, SecondOrderModel, TaylorEnclosure, check_enclosure_dims};
use nalgebra::DVector;

use crate::file::{Discretization, TimeModel};
use crate::model::{EquationModel, Rows};
use crate::scratch::with_interval_scratch;

/// Interval scratch of the graph: one value and `n` derivatives per node.
struct Work<'a> {
    values: &'a mut [Interval],
    grads: &'a mut [Interval],
}

impl EquationModel {
    fn check_box(
        &self,
        what: &str,
        rows: usize,
        x: &[Interval],
        u: &DVector<f64>,
        out: &TaylorEnclosure,
    ) -> Result<(), ModelError> {
        let d = self.dims();
        check_enclosure_dims(what, rows, d.states, x, out)?;
        models::error::check_dims("u", u, d.inputs, 1)?;
        models::error::check_finite("u", u)
    }

    /// `rows` over the box `x` (input `u`): values into `value`, Jacobian (row-major) into `jac`.
    fn enclose(
        &self,
        rows: &Rows,
        x: &[Interval],
        u: &[f64],
        work: &mut Work,
        value: &mut [Interval],
        jac: &mut [Interval],
    ) {
        let n = x.len();
        work.values[..n].copy_from_slice(x);
        for (v, &ui) in work.values[n..n + u.len()].iter_mut().zip(u) {
            *v = Interval::point(ui);
        }
        self.graph.run_enclosure(&rows.schedule, n, &self.varies, work.values, work.grads);
        for (k, &r) in rows.roots.iter().enumerate() {
            let r = r as usize;
            value[k] = work.values[r];
            let row = &mut jac[k * n..(k + 1) * n];
            if self.varies[r] {
                row.copy_from_slice(&work.grads[r * n..(r + 1) * n]);
            } else {
                row.fill(Interval::ZERO);
            }
        }
    }

    /// `rows` over the box `x` (input `u`), values only: into `value`, with `values` the graph's
    /// scratch (one interval per node).
    fn enclose_values(&self, rows: &Rows, x: &[Interval], u: &[f64], values: &mut [Interval], value: &mut [Interval]) {
        let n = x.len();
        values[..n].copy_from_slice(x);
        for (v, &ui) in values[n..n + u.len()].iter_mut().zip(u) {
            *v = Interval::point(ui);
        }
        self.graph.run_value_enclosure(&rows.schedule, values);
        for (k, &r) in rows.roots.iter().enumerate() {
            value[k] = values[r as usize];
        }
    }

    /// Runs `f` on the graph's value scratch (one interval per node) and `extra` more intervals.
    fn with_value_work<R>(&self, extra: usize, mut f: impl FnMut(&mut [Interval], &mut [Interval]) -> R) -> R {
        let nodes = self.graph.len();
        with_interval_scratch(nodes + extra, |buf| {
            let (values, rest) = buf.split_at_mut(nodes);
            f(values, rest)
        })
    }

    /// Runs `f` on the graph's interval scratch and `extra` more intervals.
    fn with_work<R>(&self, extra: usize, mut f: impl FnMut(Work<'_>, &mut [Interval]) -> R) -> R {
        let (nodes, n) = (self.graph.len(), self.dims().states);
        with_interval_scratch(nodes * (n + 1) + extra, |buf| {
            let (values, rest) = buf.split_at_mut(nodes);
            let (grads, rest) = rest.split_at_mut(nodes * n);
            f(Work { values, grads }, rest)
        })
    }
}

/// `out = I + c·d` (row-major `n × n`).
fn identity_plus(n: usize, c: Interval, d: &[Interval], out: &mut [Interval]) {
    for i in 0..n {
        for j in 0..n {
            let id = if i == j { Interval::point(1.0) } else { Interval::ZERO };
            out[i * n + j] = id + c * d[i * n + j];
        }
    }
}

/// RK4's weights of its four stages (their offsets are 0, ts/2, ts/2, ts).
const RK4_WEIGHTS: [f64; 4] = [1.0, 2.0, 2.0, 1.0];

/// A stage's slope `g` added to the sum, `acc += w·g`, and kept for the next stage, `k = g`.
fn accumulate(acc: &mut [Interval], g: &[Interval], w: f64, k: &mut [Interval]) {
    for (a, gi) in acc.iter_mut().zip(g) {
        *a = *a + *gi * w;
    }
    k.copy_from_slice(g);
}

/// `value = x + c·slope`: Euler's step (`c = ts`), an RK4 stage's point (`c = c_s`, the previous
/// stage's slope), RK4's last (`c = ts/6`, the weighted sum).
fn advance(x: &[Interval], c: Interval, slope: &[Interval], value: &mut [Interval]) {
    for ((v, xi), si) in value.iter_mut().zip(x).zip(slope) {
        *v = *xi + c * *si;
    }
}

/// `out`'s values, and its Jacobian (row-major, `value.len()` rows) when given.
fn write(out: &mut TaylorEnclosure, value: &[Interval], jac: Option<&[Interval]>) {
    let cols = jac.map_or(0, |j| j.len() / value.len().max(1));
    for (i, v) in value.iter().enumerate() {
        out.set_value(i, *v);
        if let Some(jac) = jac {
            for j in 0..cols {
                out.set_jacobian(i, j, jac[i * cols + j]);
            }
        }
    }
}

impl SecondOrderModel for EquationModel {
    fn f_enclosure(&self, x: &[Interval], u: &DVector<f64>, out: &mut TaylorEnclosure) -> Result<(), ModelError> {
        let n = self.dims().states;
        self.check_box("f enclosure", n, x, u, out)?;
        out.clear();
        out.set_hessian_invalid();
        if let TimeModel::Continuous { discretization: Discretization::Zoh, .. } = self.time {
            let (a, b) = self
                .zoh
                .as_ref()
                .ok_or_else(|| ModelError::Evaluation("zero-order hold without its matrices".to_owned()))?;
            for i in 0..n {
                let mut s = Interval::ZERO;
                for j in 0..n {
                    s = s + x[j] * a[(i, j)];
                    out.set_jacobian(i, j, Interval::point(a[(i, j)]));
                }
                for k in 0..u.len() {
                    s = s + Interval::point(b[(i, k)]) * u[k];
                }
                out.set_value(i, s);
            }
            return Ok(());
        }
        self.with_work(5 * n + 5 * n * n, |mut work, rest| {
            let (value, rest) = rest.split_at_mut(n);
            let (jac, rest) = rest.split_at_mut(n * n);
            let (g, rest) = rest.split_at_mut(n);
            let (jg, rest) = rest.split_at_mut(n * n);
            let (prev, rest) = rest.split_at_mut(n * n);
            let (tmp, rest) = rest.split_at_mut(n * n);
            let (sum, rest) = rest.split_at_mut(n * n);
            let (acc, rest) = rest.split_at_mut(n);
            let (k, xs) = rest.split_at_mut(n);
            match self.time {
                TimeModel::Continuous { ts, discretization } => {
                    let ts = Interval::point(ts);
                    self.enclose(&self.rhs, x, u.as_slice(), &mut work, g, jg);
                    if discretization == Discretization::Euler {
                        advance(x, ts, g, value);
                        identity_plus(n, ts, jg, jac);
                    } else {
                        // RK4: stages k_s, their points x_s = x + c_s k_{s−1}, the chain rule.
                        let offsets = [Interval::ZERO, ts * 0.5, ts * 0.5, ts];
                        prev.copy_from_slice(jg);
                        sum.copy_from_slice(jg);
                        acc.copy_from_slice(g);
                        k.copy_from_slice(g);
                        for s in 1..4 {
                            advance(x, offsets[s], k, xs);
                            self.enclose(&self.rhs, xs, u.as_slice(), &mut work, g, jg);
                            identity_plus(n, offsets[s], prev, tmp);
                            for i in 0..n {
                                for c in 0..n {
                                    let mut d = Interval::ZERO;
                                    for l in 0..n {
                                        d = d + jg[i * n + l] * tmp[l * n + c];
                                    }
                                    prev[i * n + c] = d;
                                    sum[i * n + c] = sum[i * n + c] + d * RK4_WEIGHTS[s];
                                }
                            }
                            accumulate(acc, g, RK4_WEIGHTS[s], k);
                        }
                        let sixth = ts / 6.0;
                        advance(x, sixth, acc, value);
                        identity_plus(n, sixth, sum, jac);
                    }
                }
                _ => self.enclose(&self.rhs, x, u.as_slice(), &mut work, value, jac),
            }
            write(out, value, Some(jac));
        });
        Ok(())
    }

    fn h_enclosure(&self, x: &[Interval], u: &DVector<f64>, out: &mut TaylorEnclosure) -> Result<(), ModelError> {
        let d = self.dims();
        let (n, m) = (d.states, d.outputs);
        self.check_box("h enclosure", m, x, u, out)?;
        out.clear();
        out.set_hessian_invalid();
        self.with_work(m + m * n, |mut work, rest| {
            let (value, jac) = rest.split_at_mut(m);
            self.enclose(&self.out, x, u.as_slice(), &mut work, value, jac);
            write(out, value, Some(jac));
        });
        Ok(())
    }

    /// As [`SecondOrderModel::f_enclosure`]'s values, without the forward-mode Jacobian (the same
    /// bits: the values never read the derivatives).
    fn f_value_enclosure(&self, x: &[Interval], u: &DVector<f64>, out: &mut TaylorEnclosure) -> Result<(), ModelError> {
        let n = self.dims().states;
        let TimeModel::Continuous { ts, discretization } = self.time else {
            self.check_box("f enclosure", n, x, u, out)?;
            out.clear();
            out.set_hessian_invalid();
            self.with_value_work(n, |values, value| {
                self.enclose_values(&self.rhs, x, u.as_slice(), values, value);
                write(out, value, None);
            });
            return Ok(());
        };
        if discretization == Discretization::Zoh {
            // Already cheap: a product by the hold's matrices.
            return self.f_enclosure(x, u, out);
        }
        self.check_box("f enclosure", n, x, u, out)?;
        out.clear();
        out.set_hessian_invalid();
        let ts = Interval::point(ts);
        self.with_value_work(5 * n, |values, rest| {
            let (value, rest) = rest.split_at_mut(n);
            let (g, rest) = rest.split_at_mut(n);
            let (acc, rest) = rest.split_at_mut(n);
            let (k, xs) = rest.split_at_mut(n);
            self.enclose_values(&self.rhs, x, u.as_slice(), values, g);
            if discretization == Discretization::Euler {
                advance(x, ts, g, value);
            } else {
                // RK4's stages as in `f_enclosure`, without the chain rule.
                let offsets = [Interval::ZERO, ts * 0.5, ts * 0.5, ts];
                acc.copy_from_slice(g);
                k.copy_from_slice(g);
                for s in 1..4 {
                    advance(x, offsets[s], k, xs);
                    self.enclose_values(&self.rhs, xs, u.as_slice(), values, g);
                    accumulate(acc, g, RK4_WEIGHTS[s], k);
                }
                advance(x, ts / 6.0, acc, value);
            }
            write(out, value, None);
        });
        Ok(())
    }

    /// As [`SecondOrderModel::h_enclosure`]'s values, without the Jacobian.
    fn h_value_enclosure(&self, x: &[Interval], u: &DVector<f64>, out: &mut TaylorEnclosure) -> Result<(), ModelError> {
        let d = self.dims();
        self.check_box("h enclosure", d.outputs, x, u, out)?;
        out.clear();
        out.set_hessian_invalid();
        self.with_value_work(d.outputs, |values, value| {
            self.enclose_values(&self.out, x, u.as_slice(), values, value);
            write(out, value, None);
        });
        Ok(())
    }
}
