//! A tape's graph evaluated in affine arithmetic: each node once, in the
//! builder's order (operands first), so a node shared by several outputs
//! (a premise z(x) and an entry of A(x)) has one form in all of them.
//! Checked divisions whose value no output reads are not evaluated (they
//! only decide where the interpreter reports a division by 0).

use super::{binary, unary, Affine, Form, Noise, Unbounded};
use crate::tape::build::Node;
use crate::tape::{Builder, Id};

/// The nodes `outputs` read, directly or through other nodes.
fn live(b: &Builder, outputs: &[Id]) -> Vec<bool> {
    let nodes = b.nodes();
    let mut live = vec![false; nodes.len()];
    let mut stack: Vec<usize> = outputs.iter().map(|id| id.index()).collect();
    while let Some(k) = stack.pop() {
        if k >= nodes.len() || std::mem::replace(&mut live[k], true) {
            continue;
        }
        match nodes[k] {
            Node::Un(_, a) => stack.push(a.index()),
            Node::Bin(_, a, c) => stack.extend([a.index(), c.index()]),
            Node::Input(_) | Node::Const(_) => {}
        }
    }
    live
}

/// Per input of `b`: whether any of `outputs` depends on it.
pub fn depends_on(b: &Builder, outputs: &[Id]) -> Vec<bool> {
    let live = live(b, outputs);
    (0..b.input_count()).map(|k| live[k]).collect()
}

/// Affine enclosures of `outputs` of `b`'s graph, its inputs given as forms
/// (`inputs[k]` for input `k`; a missing input is `Unbounded`).
pub fn enclose(b: &Builder, outputs: &[Id], inputs: &[Form], noise: &mut Noise) -> Vec<Form> {
    let nodes = b.nodes();
    let live = live(b, outputs);
    let mut val: Vec<Option<Form>> = vec![None; nodes.len()];
    for (k, node) in nodes.iter().enumerate() {
        if !live[k] {
            continue;
        }
        let get = |id: Id| -> Result<&Affine, Unbounded> {
            match val.get(id.index()) {
                Some(Some(Ok(x))) => Ok(x),
                _ => Err(Unbounded),
            }
        };
        let v = match *node {
            Node::Input(i) => inputs.get(i as usize).cloned().unwrap_or(Err(Unbounded)),
            Node::Const(bits) => Affine::constant(f64::from_bits(bits)),
            Node::Un(f, a) => get(a).and_then(|x| unary(f, x, noise)),
            Node::Bin(f, a, c) => match (get(a), get(c)) {
                (Ok(x), Ok(y)) => binary(f, x, y, noise),
                _ => Err(Unbounded),
            },
        };
        val[k] = Some(v);
    }
    outputs
        .iter()
        .map(|id| {
            val.get(id.index())
                .cloned()
                .flatten()
                .unwrap_or(Err(Unbounded))
        })
        .collect()
}
