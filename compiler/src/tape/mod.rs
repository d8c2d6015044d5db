//! Straight-line code for the hot paths: the simulator's plant right-hand
//! side, disturbance signals and premise vector, and the model stage's
//! consistency grid (A(x), B(x) and z(x) at up to 20,000 states), compiled
//! once from the spec's expressions into a [`Tape`] of scalar instructions
//! over a flat register file. A shared utility of the model and simulation
//! stages (it depends on the language only).
//!
//! A tape is built by a [`Builder`] (a hash-consed expression graph: common
//! subexpressions are shared, constants folded, products with a constant 0
//! dropped) from the language's matrix expressions by [`lower`]. Constant
//! subexpressions are evaluated by the language's evaluator itself, so their
//! values are the interpreter's to the bit; the remaining scalar operations
//! run in the interpreter's order (left-to-right sums like nalgebra's small
//! products), so a tape and the interpreter agree to rounding.
//!
//! Evaluation allocates nothing: the caller owns the register file
//! ([`Tape::registers`]), writes the inputs into its first slots, runs the
//! tape and reads the outputs. Register numbers are `u16` and the file has
//! exactly [`REGISTERS`] slots, so every access is in bounds by construction
//! (no bounds checks in the loop); a larger tape is not built. A division by a value that is 0 at run time
//! is a [`Fault`], never an infinity: the caller then re-evaluates with the
//! interpreter, which reports the error with its span (or computes the value,
//! should it succeed). Divisions are kept even where their value is unused
//! (multiplied by 0), as the interpreter evaluates every subexpression.

pub mod affine;
mod build;
pub mod lower;

pub use build::{Builder, Id};

/// A scalar function of one argument.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Unary {
    /// `-v`
    Neg,
    /// `sqrt`
    Sqrt,
    /// `sin`
    Sin,
    /// `cos`
    Cos,
    /// `tan`
    Tan,
    /// `atan`
    Atan,
    /// `exp`
    Exp,
    /// `log` (natural)
    Ln,
    /// `abs`
    Abs,
    /// `sign` (0 at 0 and NaN, like the language's)
    Sign,
    /// The runtime's `sinc`.
    Sinc,
    /// The runtime's `exprel`.
    Exprel,
}

impl Unary {
    /// The function, with the language evaluator's definition.
    pub fn apply(self, v: f64) -> f64 {
        match self {
            Unary::Neg => -v,
            Unary::Sqrt => v.sqrt(),
            Unary::Sin => v.sin(),
            Unary::Cos => v.cos(),
            Unary::Tan => v.tan(),
            Unary::Atan => v.atan(),
            Unary::Exp => v.exp(),
            Unary::Ln => v.ln(),
            Unary::Abs => v.abs(),
            Unary::Sign => tsf_runtime::math::sign(v),
            Unary::Sinc => tsf_runtime::math::sinc(v),
            Unary::Exprel => tsf_runtime::math::exprel(v),
        }
    }

    /// The language's built-in of this name.
    pub fn builtin(name: &str) -> Option<Unary> {
        Some(match name {
            "sqrt" => Unary::Sqrt,
            "sin" => Unary::Sin,
            "cos" => Unary::Cos,
            "tan" => Unary::Tan,
            "atan" => Unary::Atan,
            "exp" => Unary::Exp,
            "log" => Unary::Ln,
            "abs" => Unary::Abs,
            "sign" => Unary::Sign,
            "sinc" => Unary::Sinc,
            "exprel" => Unary::Exprel,
            _ => return None,
        })
    }
}

/// A scalar function of two arguments.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Binary {
    /// `a + b`
    Add,
    /// `a - b`
    Sub,
    /// `a * b`
    Mul,
    /// `a / b` (IEEE: a zero divisor gives an infinity or NaN)
    Div,
    /// `a / b`, a [`Fault`] when `b == 0` (the language's `/`)
    DivChecked,
    /// `a ^ b` (`powf`)
    Pow,
    /// `atan2(a, b)`
    Atan2,
    /// `min` (`f64::min`)
    Min,
    /// `max` (`f64::max`)
    Max,
}

impl Binary {
    /// The function (a checked division by 0 gives what IEEE gives; the tape
    /// faults before it is used).
    pub fn apply(self, a: f64, b: f64) -> f64 {
        match self {
            Binary::Add => a + b,
            Binary::Sub => a - b,
            Binary::Mul => a * b,
            Binary::Div | Binary::DivChecked => a / b,
            Binary::Pow => a.powf(b),
            Binary::Atan2 => a.atan2(b),
            Binary::Min => a.min(b),
            Binary::Max => a.max(b),
        }
    }
}

/// Size of a register file: every `u16` register number is in bounds.
pub const REGISTERS: usize = 1 << 16;

/// A register file.
pub type Registers = [f64; REGISTERS];

/// What an instruction computes from its operand registers `a, b, c, e, f,
/// g` (of `[d, a, b, c, e, f, g]`; result in register `d`). Each product and
/// sum is rounded on its own, as the separate operations would be.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    /// `a + b`
    Add,
    /// `a - b`
    Sub,
    /// `a * b`
    Mul,
    /// `a / b`
    Div,
    /// `a / b`, a fault when `b == 0`
    DivChecked,
    /// `-a`
    Neg,
    /// `a + b * c` (two roundings, like the sum of a product)
    MulAdd,
    /// `a - b * c` (two roundings)
    MulSub,
    /// `(a + b * c) + e * f`
    MulAdd2,
    /// `a * b + c * e`
    Dot2,
    /// `a * b - c * e`
    Dot2Sub,
    /// `(a * b + c * e) + f * g`
    Dot3,
    /// `f(a)`
    Call(Unary),
    /// `f(a, b)`
    Call2(Binary),
}

impl Kind {
    /// The kind of a two-operand node (sums and differences have their own).
    fn of(f: Binary) -> Kind {
        match f {
            Binary::Add => Kind::Add,
            Binary::Sub => Kind::Sub,
            Binary::Mul => Kind::Mul,
            Binary::Div => Kind::Div,
            Binary::DivChecked => Kind::DivChecked,
            f => Kind::Call2(f),
        }
    }

    /// Order of kinds within a level (groups one kind into one batch).
    fn rank(self) -> u8 {
        match self {
            Kind::Add => 0,
            Kind::Sub => 1,
            Kind::Mul => 2,
            Kind::Div => 3,
            Kind::DivChecked => 4,
            Kind::Neg => 5,
            Kind::MulAdd => 6,
            Kind::MulSub => 7,
            Kind::MulAdd2 => 8,
            Kind::Dot2 => 9,
            Kind::Dot2Sub => 10,
            Kind::Dot3 => 11,
            Kind::Call(f) => 12 + f as u8,
            Kind::Call2(f) => 32 + f as u8,
        }
    }
}

/// One instruction: its kind and registers `[d, a, b, c, e, f, g]` (result `d`).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Instr {
    kind: Kind,
    regs: [u16; 7],
}

/// Runs of one kind at most this long are merged into a mixed batch, where
/// each instruction is dispatched on its own kind (cheaper than a batch each).
const SHORT_RUN: usize = 3;

/// Instructions `start..end`: all of one kind, or of mixed kinds (`None`).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Batch {
    kind: Option<Kind>,
    start: usize,
    end: usize,
}

/// A division by zero met while running a tape: the caller falls back to
/// the interpreter, which reports it with its span.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Fault;

/// Compiled straight-line code: `inputs` registers in, `outputs` read out.
#[derive(Debug, Clone)]
pub struct Tape {
    batches: Vec<Batch>,
    instrs: Vec<Instr>,
    /// The register file's initial contents (inputs 0, constants loaded).
    init: Vec<f64>,
    inputs: usize,
    outputs: Vec<u16>,
}

impl Tape {
    /// A fresh register file for this tape (constants loaded): allocate it
    /// once and reuse it for every evaluation.
    pub fn registers(&self) -> Box<Registers> {
        let mut regs = vec![0.0; REGISTERS];
        regs[..self.init.len()].copy_from_slice(&self.init);
        match regs.into_boxed_slice().try_into() {
            Ok(file) => file,
            // ok: the vector has exactly REGISTERS elements.
            Err(_) => unreachable!("a register file has REGISTERS slots"),
        }
    }

    /// Number of inputs (the first registers).
    pub fn inputs(&self) -> usize {
        self.inputs
    }

    /// Number of outputs.
    pub fn outputs(&self) -> usize {
        self.outputs.len()
    }

    /// Number of instructions.
    pub fn len(&self) -> usize {
        self.instrs.len()
    }

    /// `true` when the outputs are inputs or constants.
    pub fn is_empty(&self) -> bool {
        self.instrs.is_empty()
    }

    /// Number of batches (runs of one kind of instruction).
    pub fn batches(&self) -> usize {
        self.batches.len()
    }

    /// Runs the tape on `regs` (from [`Tape::registers`], inputs written into
    /// its first [`Tape::inputs`] slots).
    pub fn run(&self, regs: &mut Registers) -> Result<(), Fault> {
        // One instruction of kind `$kind` (a constant in a batch of one kind,
        // so the match folds away there).
        macro_rules! step {
            ($kind:expr, $regs:expr) => {{
                let [d, a, b, c, e, f, g] = $regs.map(usize::from);
                regs[d] = match $kind {
                    Kind::Add => regs[a] + regs[b],
                    Kind::Sub => regs[a] - regs[b],
                    Kind::Mul => regs[a] * regs[b],
                    Kind::Div => regs[a] / regs[b],
                    Kind::DivChecked => {
                        if regs[b] == 0.0 {
                            return Err(Fault);
                        }
                        regs[a] / regs[b]
                    }
                    Kind::Neg => -regs[a],
                    Kind::MulAdd => regs[a] + regs[b] * regs[c],
                    Kind::MulSub => regs[a] - regs[b] * regs[c],
                    Kind::MulAdd2 => (regs[a] + regs[b] * regs[c]) + regs[e] * regs[f],
                    Kind::Dot2 => regs[a] * regs[b] + regs[c] * regs[e],
                    Kind::Dot2Sub => regs[a] * regs[b] - regs[c] * regs[e],
                    Kind::Dot3 => (regs[a] * regs[b] + regs[c] * regs[e]) + regs[f] * regs[g],
                    Kind::Call(h) => h.apply(regs[a]),
                    Kind::Call2(h) => h.apply(regs[a], regs[b]),
                };
            }};
        }
        for batch in &self.batches {
            let instrs = &self.instrs[batch.start..batch.end];
            macro_rules! each {
                ($kind:expr) => {
                    for i in instrs {
                        step!($kind, i.regs)
                    }
                };
            }
            match batch.kind {
                None => {
                    for i in instrs {
                        step!(i.kind, i.regs)
                    }
                }
                Some(Kind::Add) => each!(Kind::Add),
                Some(Kind::Sub) => each!(Kind::Sub),
                Some(Kind::Mul) => each!(Kind::Mul),
                Some(Kind::Div) => each!(Kind::Div),
                Some(Kind::DivChecked) => each!(Kind::DivChecked),
                Some(Kind::Neg) => each!(Kind::Neg),
                Some(Kind::MulAdd) => each!(Kind::MulAdd),
                Some(Kind::MulSub) => each!(Kind::MulSub),
                Some(Kind::MulAdd2) => each!(Kind::MulAdd2),
                Some(Kind::Dot2) => each!(Kind::Dot2),
                Some(Kind::Dot2Sub) => each!(Kind::Dot2Sub),
                Some(Kind::Dot3) => each!(Kind::Dot3),
                Some(Kind::Call(h)) => each!(Kind::Call(h)),
                Some(Kind::Call2(h)) => each!(Kind::Call2(h)),
            }
        }
        Ok(())
    }

    /// Copies the outputs of a run out of `regs` into `out` (as many as fit).
    pub fn read(&self, regs: &Registers, out: &mut [f64]) {
        for (o, &r) in out.iter_mut().zip(&self.outputs) {
            *o = regs[r as usize];
        }
    }

    /// Writes `values` into the inputs starting at input `at`.
    pub fn write(&self, regs: &mut Registers, at: usize, values: &[f64]) {
        let end = (at + values.len()).min(self.inputs);
        for (r, v) in regs[at.min(end)..end].iter_mut().zip(values) {
            *r = *v;
        }
    }
}

#[cfg(test)]
mod tests;
