//! The expression graph a tape is built from: every node is created once
//! (hash-consing shares common subexpressions), constants are folded with the
//! functions the tape runs, and a few exact identities (`a + 0`, `a * 1`,
//! `a * 0`, `a / 1`, `--a`) are applied. Checked divisions are remembered as
//! guards: they stay in the tape even when their value is unused.

use super::{Binary, Op, Tape, Unary};
use std::collections::HashMap;

/// A node of the graph (an input, a constant or an operation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Id(u32);

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Node {
    Input(u32),
    /// The constant's bits (so NaN constants hash and compare).
    Const(u64),
    Un(Unary, Id),
    Bin(Binary, Id, Id),
}

/// Builds the graph of a tape with a fixed number of inputs.
#[derive(Debug, Clone)]
pub struct Builder {
    nodes: Vec<Node>,
    memo: HashMap<Node, Id>,
    guards: Vec<Id>,
    inputs: usize,
}

impl Builder {
    /// A graph over `inputs` inputs (nodes `input(0) .. input(inputs - 1)`).
    pub fn new(inputs: usize) -> Self {
        let mut b = Builder {
            nodes: Vec::new(),
            memo: HashMap::new(),
            guards: Vec::new(),
            inputs,
        };
        for k in 0..inputs {
            b.intern(Node::Input(k as u32));
        }
        b
    }

    fn intern(&mut self, node: Node) -> Id {
        if let Some(&id) = self.memo.get(&node) {
            return id;
        }
        let id = Id(self.nodes.len() as u32);
        self.nodes.push(node);
        self.memo.insert(node, id);
        id
    }

    /// Number of nodes so far.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// `true` before the first node (a graph without inputs).
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Input `k` (`k < inputs`).
    pub fn input(&self, k: usize) -> Id {
        debug_assert!(k < self.inputs);
        Id(k as u32)
    }

    /// The constant `v`.
    pub fn constant(&mut self, v: f64) -> Id {
        self.intern(Node::Const(v.to_bits()))
    }

    /// The value of a constant node.
    pub fn value(&self, id: Id) -> Option<f64> {
        match self.nodes.get(id.0 as usize) {
            Some(Node::Const(bits)) => Some(f64::from_bits(*bits)),
            _ => None,
        }
    }

    /// `f(a)`.
    pub fn un(&mut self, f: Unary, a: Id) -> Id {
        if let Some(v) = self.value(a) {
            return self.constant(f.apply(v));
        }
        if let (Unary::Neg, Some(Node::Un(Unary::Neg, inner))) = (f, self.nodes.get(a.0 as usize))
        {
            return *inner;
        }
        self.intern(Node::Un(f, a))
    }

    /// `f(a, b)`.
    pub fn bin(&mut self, f: Binary, a: Id, b: Id) -> Id {
        let (va, vb) = (self.value(a), self.value(b));
        let checked_zero = f == Binary::DivChecked && vb == Some(0.0);
        if let (Some(x), Some(y)) = (va, vb) {
            if !checked_zero {
                return self.constant(f.apply(x, y));
            }
        }
        match (f, va, vb) {
            (Binary::Add, Some(z), _) if z == 0.0 => return b,
            (Binary::Add | Binary::Sub, _, Some(z)) if z == 0.0 => return a,
            (Binary::Sub, Some(z), _) if z == 0.0 => return self.un(Unary::Neg, b),
            (Binary::Mul, Some(z), _) | (Binary::Mul, _, Some(z)) if z == 0.0 => {
                return self.constant(0.0)
            }
            (Binary::Mul, Some(o), _) if o == 1.0 => return b,
            (Binary::Mul, _, Some(o)) if o == 1.0 => return a,
            (Binary::Mul, Some(m), _) if m == -1.0 => return self.un(Unary::Neg, b),
            (Binary::Mul, _, Some(m)) if m == -1.0 => return self.un(Unary::Neg, a),
            (Binary::Div | Binary::DivChecked, _, Some(o)) if o == 1.0 => return a,
            // A constant nonzero divisor never faults.
            (Binary::DivChecked, _, Some(_)) if !checked_zero => {
                return self.bin(Binary::Div, a, b)
            }
            _ => {}
        }
        let id = self.intern(Node::Bin(f, a, b));
        if f == Binary::DivChecked && !self.guards.contains(&id) {
            self.guards.push(id);
        }
        id
    }

    /// The tape computing `outputs` (and every guard): nodes in creation
    /// order (operands before their uses), registers `inputs, constants,
    /// results`.
    pub fn finish(self, outputs: &[Id]) -> Tape {
        let mut live = vec![false; self.nodes.len()];
        let mut stack: Vec<Id> = outputs.iter().chain(&self.guards).copied().collect();
        while let Some(id) = stack.pop() {
            let k = id.0 as usize;
            if std::mem::replace(&mut live[k], true) {
                continue;
            }
            match self.nodes[k] {
                Node::Un(_, a) => stack.push(a),
                Node::Bin(_, a, b) => stack.extend([a, b]),
                Node::Input(_) | Node::Const(_) => {}
            }
        }
        let mut reg = vec![u32::MAX; self.nodes.len()];
        let mut init = vec![0.0; self.inputs];
        for (k, node) in self.nodes.iter().enumerate() {
            match *node {
                Node::Input(i) => reg[k] = i,
                Node::Const(bits) if live[k] => {
                    reg[k] = init.len() as u32;
                    init.push(f64::from_bits(bits));
                }
                _ => {}
            }
        }
        let mut ops = Vec::new();
        for (k, node) in self.nodes.iter().enumerate() {
            if !live[k] {
                continue;
            }
            let r = |id: Id| reg[id.0 as usize];
            let d = init.len() as u32;
            let op = match *node {
                Node::Input(_) | Node::Const(_) => continue,
                Node::Un(Unary::Neg, a) => Op::Neg(d, r(a)),
                Node::Un(f, a) => Op::Call(f, d, r(a)),
                Node::Bin(f, a, b) => {
                    let (a, b) = (r(a), r(b));
                    match f {
                        Binary::Add => Op::Add(d, a, b),
                        Binary::Sub => Op::Sub(d, a, b),
                        Binary::Mul => Op::Mul(d, a, b),
                        Binary::Div => Op::Div(d, a, b),
                        Binary::DivChecked => Op::DivChecked(d, a, b),
                        f => Op::Call2(f, d, a, b),
                    }
                }
            };
            reg[k] = d;
            init.push(0.0);
            ops.push(op);
        }
        Tape {
            ops,
            init,
            inputs: self.inputs,
            outputs: outputs.iter().map(|id| reg[id.0 as usize]).collect(),
        }
    }
}
