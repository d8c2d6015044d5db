//! The expression graph a tape is built from: every node is created once
//! (hash-consing shares common subexpressions), constants are folded with the
//! functions the tape runs, and a few exact identities (`a + 0`, `a * 1`,
//! `a * 0`, `a / 1`, `--a`) are applied. Checked divisions are remembered as
//! guards: they stay in the tape even when their value is unused.

use super::{Batch, Binary, Instr, Kind, Tape, Unary, REGISTERS, SHORT_RUN};
use std::collections::HashMap;

/// A node of the graph (an input, a constant or an operation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Id(u32);

impl Id {
    /// The node's index in [`Builder`]'s order.
    pub(super) fn index(self) -> usize {
        self.0 as usize
    }
}

/// What a node computes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(super) enum Node {
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
        if let (Unary::Neg, Some(Node::Un(Unary::Neg, inner))) = (f, self.nodes.get(a.0 as usize)) {
            return *inner;
        }
        self.intern(Node::Un(f, a))
    }

    fn node(&self, id: Id) -> Option<Node> {
        self.nodes.get(id.0 as usize).copied()
    }

    /// Every node, operands before the nodes that read them.
    pub(super) fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// The number of inputs.
    pub(super) fn input_count(&self) -> usize {
        self.inputs
    }

    /// The operand of a negation.
    fn negated(&self, id: Id) -> Option<Id> {
        match self.node(id) {
            Some(Node::Un(Unary::Neg, x)) => Some(x),
            _ => None,
        }
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
        // Exact identities only: IEEE defines a - b as a + (-b), and a
        // negation or a product by +-1 is exact.
        match (f, va, vb) {
            (Binary::Add, Some(0.0), _) => return b,
            (Binary::Add | Binary::Sub, _, Some(0.0)) => return a,
            (Binary::Sub, Some(0.0), _) => return self.un(Unary::Neg, b),
            (Binary::Mul, Some(0.0), _) | (Binary::Mul, _, Some(0.0)) => return self.constant(0.0),
            (Binary::Mul, Some(1.0), _) => return b,
            (Binary::Mul, _, Some(1.0)) => return a,
            (Binary::Mul, Some(-1.0), _) => return self.un(Unary::Neg, b),
            (Binary::Mul, _, Some(-1.0)) => return self.un(Unary::Neg, a),
            (Binary::Mul, Some(k), _) if self.negated(b).is_some() => {
                let (k, x) = (self.constant(-k), self.negated(b).unwrap_or(b));
                return self.bin(Binary::Mul, k, x);
            }
            (Binary::Mul, _, Some(k)) if self.negated(a).is_some() => {
                let (k, x) = (self.constant(-k), self.negated(a).unwrap_or(a));
                return self.bin(Binary::Mul, x, k);
            }
            (Binary::Div | Binary::DivChecked, _, Some(1.0)) => return a,
            // A constant nonzero divisor never faults.
            (Binary::DivChecked, _, Some(_)) if !checked_zero => {
                return self.bin(Binary::Div, a, b)
            }
            _ => {}
        }
        match (f, self.negated(a), self.negated(b)) {
            (Binary::Add, _, Some(y)) => return self.bin(Binary::Sub, a, y),
            (Binary::Add, Some(x), None) => return self.bin(Binary::Sub, b, x),
            (Binary::Sub, _, Some(y)) => return self.bin(Binary::Add, a, y),
            _ => {}
        }
        let before = self.nodes.len();
        let id = self.intern(Node::Bin(f, a, b));
        if f == Binary::DivChecked && self.nodes.len() > before {
            self.guards.push(id);
        }
        id
    }

    /// The tape computing `outputs` (and every guard), or `None` when it
    /// needs more than [`REGISTERS`] registers. Registers: inputs, constants,
    /// results. Products and sums of up to three products read once, by a
    /// sum or difference, are fused into it (`x + a * b`, `a * b + c * d`,
    /// ..., each operation rounded as before); instructions are ordered by
    /// level (longest path from the inputs) and, within a level, by kind, and
    /// runs of one kind form a batch.
    pub fn finish(self, outputs: &[Id]) -> Option<Tape> {
        let count = self.nodes.len();
        let mut uses = vec![0u32; count];
        let mut live = vec![false; count];
        let mut stack: Vec<Id> = outputs.iter().chain(&self.guards).copied().collect();
        for id in &stack {
            // Outputs and guards are read outside the instruction stream.
            uses[id.0 as usize] += 2;
        }
        while let Some(id) = stack.pop() {
            let k = id.0 as usize;
            if std::mem::replace(&mut live[k], true) {
                continue;
            }
            let operands = match self.nodes[k] {
                Node::Un(_, a) => vec![a],
                Node::Bin(_, a, b) => vec![a, b],
                Node::Input(_) | Node::Const(_) => Vec::new(),
            };
            for a in operands {
                uses[a.0 as usize] += 1;
                stack.push(a);
            }
        }
        let live_count = live.iter().filter(|&&l| l).count();
        if self.inputs + live_count > REGISTERS {
            return None;
        }
        // Each live operation becomes an instruction; a product or sum of
        // products read only by a sum or difference is absorbed into it.
        let mut at: Vec<Option<usize>> = vec![None; count];
        let mut slots: Vec<Option<Pending>> = Vec::new();
        for (k, node) in self.nodes.iter().enumerate() {
            if !live[k] {
                continue;
            }
            // The instruction of a single-use operand, to absorb.
            let peek = |slots: &[Option<Pending>], id: Id| -> Option<(Kind, [Id; 6])> {
                let i = at[id.0 as usize].filter(|_| uses[id.0 as usize] == 1)?;
                slots[i].map(|(kind, _, ops)| (kind, ops))
            };
            let absorb = |slots: &mut Vec<Option<Pending>>, ids: &[Id]| {
                for id in ids {
                    if let Some(i) = at[id.0 as usize] {
                        slots[i] = None;
                    }
                }
            };
            let (kind, ops) = match *node {
                Node::Input(_) | Node::Const(_) => continue,
                Node::Un(Unary::Neg, a) => (Kind::Neg, [a; 6]),
                Node::Un(f, a) => (Kind::Call(f), [a; 6]),
                Node::Bin(f @ (Binary::Add | Binary::Sub), x, y) => {
                    let (px, py) = (peek(&slots, x), peek(&slots, y));
                    let add = f == Binary::Add;
                    match (px, py) {
                        (Some((Kind::Mul, [a, b, ..])), Some((Kind::Mul, [c, e, ..]))) => {
                            absorb(&mut slots, &[x, y]);
                            let kind = if add { Kind::Dot2 } else { Kind::Dot2Sub };
                            (kind, [a, b, c, e, e, e])
                        }
                        (Some((Kind::Dot2, [a, b, c, e, ..])), Some((Kind::Mul, [g, h, ..])))
                        | (Some((Kind::Mul, [g, h, ..])), Some((Kind::Dot2, [a, b, c, e, ..])))
                            if add =>
                        {
                            absorb(&mut slots, &[x, y]);
                            (Kind::Dot3, [a, b, c, e, g, h])
                        }
                        (Some((Kind::MulAdd, [z, a, b, ..])), Some((Kind::Mul, [c, e, ..])))
                        | (Some((Kind::Mul, [c, e, ..])), Some((Kind::MulAdd, [z, a, b, ..])))
                            if add =>
                        {
                            absorb(&mut slots, &[x, y]);
                            (Kind::MulAdd2, [z, a, b, c, e, e])
                        }
                        (_, Some((Kind::Mul, [a, b, ..]))) => {
                            absorb(&mut slots, &[y]);
                            let kind = if add { Kind::MulAdd } else { Kind::MulSub };
                            (kind, [x, a, b, b, b, b])
                        }
                        (Some((Kind::Mul, [a, b, ..])), _) if add => {
                            absorb(&mut slots, &[x]);
                            (Kind::MulAdd, [y, a, b, b, b, b])
                        }
                        _ => (Kind::of(f), [x, y, y, y, y, y]),
                    }
                }
                Node::Bin(f, a, b) => (Kind::of(f), [a, b, b, b, b, b]),
            };
            at[k] = Some(slots.len());
            slots.push(Some((kind, k, ops)));
        }
        let mut instrs: Vec<Pending> = slots.into_iter().flatten().collect();
        // Levels: inputs and constants 0, an instruction one above its operands.
        let mut level = vec![0u32; count];
        for (_, k, ops) in &instrs {
            level[*k] = 1 + ops.iter().map(|a| level[a.0 as usize]).max().unwrap_or(0);
        }
        instrs.sort_by_key(|(kind, k, _)| (level[*k], kind.rank()));
        let mut reg = vec![u16::MAX; count];
        let mut init = vec![0.0; self.inputs];
        for (k, node) in self.nodes.iter().enumerate() {
            match *node {
                // ok: at most REGISTERS registers (checked above), so u16.
                Node::Input(i) => reg[k] = i as u16,
                Node::Const(bits) if live[k] => {
                    reg[k] = init.len() as u16;
                    init.push(f64::from_bits(bits));
                }
                _ => {}
            }
        }
        for (_, k, _) in &instrs {
            reg[*k] = init.len() as u16;
            init.push(0.0);
        }
        let instrs: Vec<Instr> = instrs
            .iter()
            .map(|(kind, k, ops)| {
                let r = |id: Id| reg[id.0 as usize];
                Instr {
                    kind: *kind,
                    regs: [
                        reg[*k],
                        r(ops[0]),
                        r(ops[1]),
                        r(ops[2]),
                        r(ops[3]),
                        r(ops[4]),
                        r(ops[5]),
                    ],
                }
            })
            .collect();
        let batches = batches(&instrs);
        Some(Tape {
            batches,
            instrs,
            init,
            inputs: self.inputs,
            outputs: outputs.iter().map(|id| reg[id.0 as usize]).collect(),
        })
    }
}

/// An instruction before registers are assigned: kind, node, operands.
type Pending = (Kind, usize, [Id; 6]);

/// Runs of one kind become batches; neighbouring runs of at most
/// [`SHORT_RUN`] instructions are merged into one mixed batch.
fn batches(instrs: &[Instr]) -> Vec<Batch> {
    let mut runs: Vec<Batch> = Vec::new();
    for (i, instr) in instrs.iter().enumerate() {
        match runs.last_mut() {
            Some(b) if b.kind == Some(instr.kind) => b.end = i + 1,
            _ => runs.push(Batch {
                kind: Some(instr.kind),
                start: i,
                end: i + 1,
            }),
        }
    }
    let mut out: Vec<Batch> = Vec::with_capacity(runs.len());
    for run in runs {
        let short = run.end - run.start <= SHORT_RUN;
        match out.last_mut() {
            Some(b) if short && (b.kind.is_none() || b.end - b.start <= SHORT_RUN) => {
                b.kind = None;
                b.end = run.end;
            }
            _ => out.push(run),
        }
    }
    // A mixed batch of one run is that run.
    for b in &mut out {
        if b.kind.is_none()
            && instrs[b.start..b.end]
                .iter()
                .all(|i| i.kind == instrs[b.start].kind)
        {
            b.kind = Some(instrs[b.start].kind);
        }
    }
    out
}
