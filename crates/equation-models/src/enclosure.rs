//! Interval enclosures of a model written as equations over a box of states
//! (`models::SecondOrderModel`), for the nonlinear set-membership filter: the graph evaluated in
//! outward-rounded interval arithmetic with the forward-mode Jacobian (module `interval_rules`),
//! then the integration scheme on intervals — Euler `x + ts·g`, RK4 through its stages with the
//! chain rule `D_s = J(x_s)(I + c_s D_{s−1})`, the exact zero-order hold `A_d x + B_d u`.
//!
//! Only first derivatives are enclosed: the Hessians are declared invalid, and the filter bounds
//! the linearisation remainder by the mean-value form, valid also across the kinks of `abs`,
//! `min`, `max`. A function undefined or discontinuous on the box gives unbounded enclosures,
//! which the filter reports instead of publishing a set. Each call allocates its interval
//! scratch (a few kilobytes).

use intervals::Interval;
use models::{DiscreteModel, ModelError, SecondOrderModel, TaylorEnclosure, check_enclosure_dims};
use nalgebra::DVector;

use crate::file::{Discretization, TimeModel};
use crate::model::{EquationModel, Rows};

/// Interval scratch: one value and `n` derivatives per node.
struct Work {
    values: Vec<Interval>,
    grads: Vec<Interval>,
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
        self.graph.run_enclosure(&rows.schedule, n, &self.varies, &mut work.values, &mut work.grads);
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

    fn work(&self) -> Work {
        let nodes = self.graph.len();
        let n = self.dims().states;
        Work { values: vec![Interval::ZERO; nodes], grads: vec![Interval::ZERO; nodes * n] }
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

impl SecondOrderModel for EquationModel {
    fn f_enclosure(&self, x: &[Interval], u: &DVector<f64>, out: &mut TaylorEnclosure) -> Result<(), ModelError> {
        let n = self.dims().states;
        self.check_box("f enclosure", n, x, u, out)?;
        out.clear();
        out.set_hessian_invalid();
        let mut value = vec![Interval::ZERO; n];
        let mut jac = vec![Interval::ZERO; n * n];
        match self.time {
            TimeModel::Continuous { discretization: Discretization::Zoh, .. } => {
                let (a, b) = self
                    .zoh
                    .as_ref()
                    .ok_or_else(|| ModelError::Evaluation("zero-order hold without its matrices".to_owned()))?;
                for i in 0..n {
                    let mut s = Interval::ZERO;
                    for j in 0..n {
                        s = s + x[j] * a[(i, j)];
                        jac[i * n + j] = Interval::point(a[(i, j)]);
                    }
                    for k in 0..u.len() {
                        s = s + Interval::point(b[(i, k)]) * u[k];
                    }
                    value[i] = s;
                }
            }
            TimeModel::Discrete => {
                let mut work = self.work();
                self.enclose(&self.rhs, x, u.as_slice(), &mut work, &mut value, &mut jac);
            }
            TimeModel::Continuous { ts, discretization } => {
                let mut work = self.work();
                let ts = Interval::point(ts);
                let (mut g, mut jg) = (vec![Interval::ZERO; n], vec![Interval::ZERO; n * n]);
                self.enclose(&self.rhs, x, u.as_slice(), &mut work, &mut g, &mut jg);
                if discretization == Discretization::Euler {
                    for i in 0..n {
                        value[i] = x[i] + ts * g[i];
                    }
                    identity_plus(n, ts, &jg, &mut jac);
                } else {
                    // RK4: stages k_s, their points x_s = x + c_s k_{s−1}, the chain rule.
                    let offsets = [Interval::ZERO, ts * 0.5, ts * 0.5, ts];
                    let weights = [1.0, 2.0, 2.0, 1.0];
                    let (mut prev, mut tmp, mut sum) = (jg.clone(), vec![Interval::ZERO; n * n], jg.clone());
                    let mut acc: Vec<Interval> = g.clone();
                    let mut k = g.clone();
                    let mut xs = vec![Interval::ZERO; n];
                    for s in 1..4 {
                        for i in 0..n {
                            xs[i] = x[i] + offsets[s] * k[i];
                        }
                        self.enclose(&self.rhs, &xs, u.as_slice(), &mut work, &mut g, &mut jg);
                        identity_plus(n, offsets[s], &prev, &mut tmp);
                        for i in 0..n {
                            for c in 0..n {
                                let mut d = Interval::ZERO;
                                for l in 0..n {
                                    d = d + jg[i * n + l] * tmp[l * n + c];
                                }
                                prev[i * n + c] = d;
                                sum[i * n + c] = sum[i * n + c] + d * weights[s];
                            }
                        }
                        for i in 0..n {
                            acc[i] = acc[i] + g[i] * weights[s];
                        }
                        k.copy_from_slice(&g);
                    }
                    let sixth = ts / 6.0;
                    for i in 0..n {
                        value[i] = x[i] + sixth * acc[i];
                    }
                    identity_plus(n, sixth, &sum, &mut jac);
                }
            }
        }
        for i in 0..n {
            out.set_value(i, value[i]);
            for j in 0..n {
                out.set_jacobian(i, j, jac[i * n + j]);
            }
        }
        Ok(())
    }

    fn h_enclosure(&self, x: &[Interval], u: &DVector<f64>, out: &mut TaylorEnclosure) -> Result<(), ModelError> {
        let d = self.dims();
        let (n, m) = (d.states, d.outputs);
        self.check_box("h enclosure", m, x, u, out)?;
        out.clear();
        out.set_hessian_invalid();
        let (mut value, mut jac) = (vec![Interval::ZERO; m], vec![Interval::ZERO; m * n]);
        let mut work = self.work();
        self.enclose(&self.out, x, u.as_slice(), &mut work, &mut value, &mut jac);
        for i in 0..m {
            out.set_value(i, value[i]);
            for j in 0..n {
                out.set_jacobian(i, j, jac[i * n + j]);
            }
        }
        Ok(())
    }
}
