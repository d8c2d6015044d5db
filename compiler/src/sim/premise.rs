//! The premise vector `z(x)` compiled into a [`Tape`] of the controller
//! state ([`Evaluator::Compiled`]): the rows of `z = L x` or the scalar
//! premise expressions of the tables, evaluated once per sample and shared by
//! the controller and the premise-region check. With
//! [`Evaluator::Interpreter`] there is none: the controller and the region
//! compute `z` themselves, as before.

use super::tape::{Binary, Builder, Id, Registers, Tape, Unary};
use super::Evaluator;
use crate::tables::sym::{Func, Sym};
use crate::tables::{PremiseCode, Tables};

/// The compiled premise vector and its register file.
pub struct Premises {
    tape: Tape,
    regs: Box<Registers>,
}

fn unary(f: Func) -> Unary {
    match f {
        Func::Sin => Unary::Sin,
        Func::Cos => Unary::Cos,
        Func::Exp => Unary::Exp,
        Func::Sqrt => Unary::Sqrt,
        Func::Atan => Unary::Atan,
        Func::Abs => Unary::Abs,
        Func::Sinc => Unary::Sinc,
        Func::Exprel => Unary::Exprel,
    }
}

/// `s` as a node of `b` (state components out of range are NaN, as in `Sym::eval`).
fn lower(b: &mut Builder, s: &Sym, n: usize) -> Id {
    match s {
        Sym::Const(v) => b.constant(*v),
        Sym::X(k) if *k < n => b.input(*k),
        Sym::X(_) => b.constant(f64::NAN),
        Sym::Add(x, y) | Sym::Mul(x, y) | Sym::Div(x, y) => {
            let f = match s {
                Sym::Add(..) => Binary::Add,
                Sym::Mul(..) => Binary::Mul,
                _ => Binary::Div,
            };
            let (x, y) = (lower(b, x, n), lower(b, y, n));
            b.bin(f, x, y)
        }
        Sym::Neg(x) => {
            let x = lower(b, x, n);
            b.un(Unary::Neg, x)
        }
        Sym::Call(f, x) => {
            let x = lower(b, x, n);
            b.un(unary(*f), x)
        }
    }
}

impl Premises {
    /// The premise vector of `tables` as a tape, or `None` for the
    /// interpreter (also when the tape would be too large).
    pub fn new(tables: &Tables, evaluator: Evaluator) -> Option<Self> {
        if evaluator != Evaluator::Compiled {
            return None;
        }
        let n = tables.n;
        let mut b = Builder::new(n);
        let z: Vec<Id> = match &tables.premise {
            PremiseCode::Linear(rows) => rows
                .iter()
                .map(|row| {
                    let mut acc = b.constant(0.0);
                    for (k, &l) in row.iter().enumerate().take(n) {
                        let (c, x) = (b.constant(l), b.input(k));
                        let t = b.bin(Binary::Mul, c, x);
                        acc = b.bin(Binary::Add, acc, t);
                    }
                    acc
                })
                .collect(),
            PremiseCode::Exprs(e) => e.iter().map(|s| lower(&mut b, s, n)).collect(),
        };
        let tape = b.finish(&z)?;
        Some(Premises {
            regs: tape.registers(),
            tape,
        })
    }

    /// Number of premise components.
    pub fn len(&self) -> usize {
        self.tape.outputs()
    }

    /// `true` without premise components.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Writes `z(x)` (x: the controller state) into `z`.
    pub fn eval(&mut self, x: &[f64], z: &mut [f64]) {
        self.tape
            .write(&mut self.regs, 0, &x[..x.len().min(self.tape.inputs())]);
        // ok: premise tapes contain no checked division, so they never fault.
        let _ = self.tape.run(&mut self.regs);
        self.tape.read(&self.regs, z);
    }
}
