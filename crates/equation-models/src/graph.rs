//! The compiled model as a computation graph: every operation of every definition and equation
//! is one node, operands before the nodes that use them, so that one pass in index order
//! evaluates them all and a definition used by several equations is computed once.
//!
//! Derivatives are propagated forward through the same pass (dense rows over the seeded slots),
//! with a hand-written rule for each operation and function.

use std::collections::HashMap;

use crate::ops::{Bin, Fun};

/// One node of the graph; operands are indices of earlier nodes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Op {
    /// State or input number `s` (node `s`).
    Slot,
    Const(f64),
    Neg(u32),
    Unary(Fun, u32),
    Binary(Bin, u32, u32),
}

/// The nodes, states and inputs first (node `s` is slot `s`).
#[derive(Debug, Clone)]
pub(crate) struct Graph {
    ops: Vec<Op>,
    slots: usize,
    /// While building: the node of each operation already in the graph (an operation written
    /// twice, `B * alpha` in a Magic Formula say, is computed once).
    seen: HashMap<(u8, u64, u32, u32), u32>,
}

/// Which slots carry derivative seeds in a pass: `lo..lo + width`, and the nodes that depend on
/// them (`varies`, one flag per node).
pub(crate) struct Seeds<'a> {
    pub lo: usize,
    pub width: usize,
    pub varies: &'a [bool],
}

impl Graph {
    /// A graph holding only the `slots` states and inputs.
    pub(crate) fn new(slots: usize) -> Self {
        Self { ops: vec![Op::Slot; slots], slots, seen: HashMap::new() }
    }

    /// Ends the building (frees the table of operations).
    pub(crate) fn finish(&mut self) {
        self.seen = HashMap::new();
    }

    /// The operation of node `i`.
    pub(crate) fn op(&self, i: u32) -> Op {
        self.ops[i as usize]
    }

    /// Number of nodes.
    pub(crate) fn len(&self) -> usize {
        self.ops.len()
    }

    fn constant(&self, i: u32) -> Option<f64> {
        match self.ops[i as usize] {
            Op::Const(c) => Some(c),
            _ => None,
        }
    }

    /// Appends `op` (folded to a constant when its operands are constants: the same arithmetic
    /// as at evaluation) and returns its node.
    pub(crate) fn push(&mut self, op: Op) -> u32 {
        let folded = match op {
            Op::Neg(a) => self.constant(a).map(|a| -a),
            Op::Unary(f, a) => self.constant(a).map(|a| f.apply(a)),
            Op::Binary(g, a, b) => self.constant(a).zip(self.constant(b)).map(|(a, b)| g.apply(a, b)),
            Op::Slot | Op::Const(_) => None,
        };
        let op = folded.map_or(op, Op::Const);
        let key = match op {
            Op::Slot => None,
            Op::Const(c) => Some((0, c.to_bits(), 0, 0)),
            Op::Neg(a) => Some((1, 0, a, 0)),
            Op::Unary(f, a) => Some((2, f as u64, a, 0)),
            Op::Binary(g, a, b) => Some((3, g as u64, a, b)),
        };
        if let Some(&node) = key.as_ref().and_then(|k| self.seen.get(k)) {
            return node;
        }
        self.ops.push(op);
        let node = (self.ops.len() - 1) as u32;
        if let Some(k) = key {
            self.seen.insert(k, node);
        }
        node
    }

    /// The nodes (not states or inputs) that `roots` need, in evaluation order.
    pub(crate) fn schedule(&self, roots: &[u32]) -> Vec<u32> {
        let mut needed = vec![false; self.ops.len()];
        for &r in roots {
            needed[r as usize] = true;
        }
        for i in (self.slots..self.ops.len()).rev() {
            if needed[i] {
                match self.ops[i] {
                    Op::Neg(a) | Op::Unary(_, a) => needed[a as usize] = true,
                    Op::Binary(_, a, b) => {
                        needed[a as usize] = true;
                        needed[b as usize] = true;
                    }
                    Op::Slot | Op::Const(_) => {}
                }
            }
        }
        (self.slots..self.ops.len()).filter(|&i| needed[i]).map(|i| i as u32).collect()
    }

    /// For every node, the set of slots it depends on and the set of slots in which it is not
    /// linear (a conservative, structural test), as bit sets of `words` words per node.
    pub(crate) fn dependencies(&self) -> (Vec<u64>, Vec<u64>, usize) {
        let words = self.slots.div_ceil(64).max(1);
        let n = self.ops.len();
        let (mut dep, mut nl) = (vec![0u64; n * words], vec![0u64; n * words]);
        for s in 0..self.slots {
            dep[s * words + s / 64] |= 1 << (s % 64);
        }
        let empty = |set: &[u64], i: u32| set[i as usize * words..(i as usize + 1) * words].iter().all(|&w| w == 0);
        for i in self.slots..n {
            for k in 0..words {
                let (d, l) = match self.ops[i] {
                    Op::Slot | Op::Const(_) => (0, 0),
                    Op::Neg(a) => (dep[a as usize * words + k], nl[a as usize * words + k]),
                    Op::Unary(_, a) => (dep[a as usize * words + k], dep[a as usize * words + k]),
                    Op::Binary(g, a, b) => {
                        let (ia, ib) = (a as usize * words + k, b as usize * words + k);
                        let d = dep[ia] | dep[ib];
                        let l = match g {
                            Bin::Add | Bin::Sub => nl[ia] | nl[ib],
                            Bin::Mul if empty(&dep, a) => nl[ib],
                            Bin::Mul | Bin::Div if empty(&dep, b) => nl[ia],
                            Bin::Pow if empty(&dep, b) && self.constant(b) == Some(1.0) => nl[ia],
                            _ => d,
                        };
                        (d, l)
                    }
                };
                dep[i * words + k] = d;
                nl[i * words + k] = l;
            }
        }
        (dep, nl, words)
    }

    /// Evaluates the `schedule` into `values` (the states and inputs already in its first
    /// `slots` entries) and, with `grads`, the derivatives of every node that varies with the
    /// seeds: row `i` of `grads` (`width` wide) for node `i`.
    pub(crate) fn run(&self, schedule: &[u32], values: &mut [f64], grads: Option<(&mut [f64], &Seeds<'_>)>) {
        let Some((grads, seeds)) = grads else {
            for &i in schedule {
                let i = i as usize;
                values[i] = match self.ops[i] {
                    Op::Slot => values[i],
                    Op::Const(c) => c,
                    Op::Neg(a) => -values[a as usize],
                    Op::Unary(f, a) => f.apply(values[a as usize]),
                    Op::Binary(g, a, b) => g.apply(values[a as usize], values[b as usize]),
                };
            }
            return;
        };
        let w = seeds.width;
        for s in seeds.lo..seeds.lo + w {
            let row = &mut grads[s * w..(s + 1) * w];
            row.fill(0.0);
            row[s - seeds.lo] = 1.0;
        }
        let varies = seeds.varies;
        for &i in schedule {
            let i = i as usize;
            let (done, rest) = grads.split_at_mut(i * w);
            let row = &mut rest[..w];
            let ga = |a: u32| &done[a as usize * w..(a as usize + 1) * w];
            match self.ops[i] {
                Op::Slot => {}
                Op::Const(c) => values[i] = c,
                Op::Neg(a) => {
                    values[i] = -values[a as usize];
                    if varies[i] {
                        for (r, &d) in row.iter_mut().zip(ga(a)) {
                            *r = -d;
                        }
                    }
                }
                Op::Unary(f, a) => {
                    let x = values[a as usize];
                    let v = f.apply(x);
                    values[i] = v;
                    if varies[i] {
                        let d = f.derivative(x, v);
                        for (r, &g) in row.iter_mut().zip(ga(a)) {
                            *r = d * g;
                        }
                    }
                }
                Op::Binary(g, a, b) => {
                    let (x, y) = (values[a as usize], values[b as usize]);
                    let v = g.apply(x, y);
                    values[i] = v;
                    if varies[i] {
                        let (va, vb) = (varies[a as usize], varies[b as usize]);
                        let (da, db) = g.partials(x, y, v, va, vb);
                        match (va, vb) {
                            (true, true) => {
                                for ((r, &p), &q) in row.iter_mut().zip(ga(a)).zip(ga(b)) {
                                    *r = da * p + db * q;
                                }
                            }
                            (true, false) => {
                                for (r, &p) in row.iter_mut().zip(ga(a)) {
                                    *r = da * p;
                                }
                            }
                            _ => {
                                for (r, &q) in row.iter_mut().zip(ga(b)) {
                                    *r = db * q;
                                }
                            }
                        }
                    }
                }
            }
        }
    }
}

impl Graph {
    /// [`Graph::run_enclosure`] without the derivatives: only the value enclosures (the same bits
    /// as that run's values, which never read the derivatives).
    pub(crate) fn run_value_enclosure(&self, schedule: &[u32], values: &mut [intervals::Interval]) {
        use crate::interval_rules::{apply, bin_apply};
        use intervals::Interval;
        for &i in schedule {
            let i = i as usize;
            values[i] = match self.ops[i] {
                Op::Slot => values[i],
                Op::Const(c) => Interval::point(c),
                Op::Neg(a) => -values[a as usize],
                Op::Unary(f, a) => apply(f, values[a as usize]),
                Op::Binary(g, a, b) => bin_apply(g, values[a as usize], values[b as usize]),
            };
        }
    }

    /// [`Graph::run`] on intervals (module `interval_rules`): `values` holds enclosures of the
    /// states (slots `0..n`) and inputs; afterwards every scheduled node's value enclosure, and in
    /// `grads` (`n` per node) the enclosure of its derivatives with respect to the states, for the
    /// nodes that `varies` marks.
    pub(crate) fn run_enclosure(
        &self,
        schedule: &[u32],
        n: usize,
        varies: &[bool],
        values: &mut [intervals::Interval],
        grads: &mut [intervals::Interval],
    ) {
        use crate::interval_rules::{apply, bin_apply, bin_partials, derivative};
        use intervals::Interval;
        for s in 0..n {
            let row = &mut grads[s * n..(s + 1) * n];
            row.fill(Interval::ZERO);
            row[s] = Interval::point(1.0);
        }
        for &i in schedule {
            let i = i as usize;
            let (done, rest) = grads.split_at_mut(i * n);
            let row = &mut rest[..n];
            let ga = |a: u32| &done[a as usize * n..(a as usize + 1) * n];
            match self.ops[i] {
                Op::Slot => {}
                Op::Const(c) => values[i] = Interval::point(c),
                Op::Neg(a) => {
                    values[i] = -values[a as usize];
                    if varies[i] {
                        for (r, &d) in row.iter_mut().zip(ga(a)) {
                            *r = -d;
                        }
                    }
                }
                Op::Unary(f, a) => {
                    let x = values[a as usize];
                    let v = apply(f, x);
                    values[i] = v;
                    if varies[i] {
                        let d = derivative(f, x, v);
                        for (r, &g) in row.iter_mut().zip(ga(a)) {
                            *r = d * g;
                        }
                    }
                }
                Op::Binary(g, a, b) => {
                    let (x, y) = (values[a as usize], values[b as usize]);
                    let v = bin_apply(g, x, y);
                    values[i] = v;
                    if varies[i] {
                        let (va, vb) = (varies[a as usize], varies[b as usize]);
                        let (da, db) = bin_partials(g, x, y, v, va, vb);
                        for (k, r) in row.iter_mut().enumerate() {
                            let mut acc = Interval::ZERO;
                            if va {
                                acc = acc + da * ga(a)[k];
                            }
                            if vb {
                                acc = acc + db * ga(b)[k];
                            }
                            *r = acc;
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constants_fold_and_shared_nodes_are_scheduled_once() {
        let mut g = Graph::new(2);
        let two = g.push(Op::Const(2.0));
        let three = g.push(Op::Const(3.0));
        assert_eq!(g.push(Op::Binary(Bin::Mul, two, three)), 4);
        assert!(matches!(g.ops[4], Op::Const(6.0)));
        assert_eq!(g.push(Op::Const(6.0)), 4);
        let s = g.push(Op::Unary(Fun::Sin, 0));
        let e1 = g.push(Op::Binary(Bin::Mul, s, 1));
        let e2 = g.push(Op::Binary(Bin::Add, s, 4));
        assert_eq!(g.schedule(&[e1, e2]), vec![4, s, e1, e2]);
        assert_eq!(g.schedule(&[e1]), vec![s, e1]);
        assert_eq!(g.schedule(&[e2]), vec![4, s, e2]);
    }
}
