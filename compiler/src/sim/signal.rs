//! Disturbance signals `name(t) = expr` of the `simulate` block: compiled
//! into a [`Tape`] of `t` ([`Evaluator::Compiled`]; the last value is kept,
//! so the integrator's repeated stage times cost nothing), else evaluated
//! with the language's evaluator and `t` bound.

use super::source::SpecSource;
use super::tape::lower::{Lowerer, SymMat, Unsupported};
use super::tape::{Builder, Registers, Tape};
use super::{Evaluator, SimError};
use tsf_lang::ast::Expr;
use tsf_lang::eval::{Env, Mode};
use tsf_lang::spec::Spec;

/// The compiled signals, their register file and the time of the last value.
struct Compiled {
    tape: Tape,
    regs: Box<Registers>,
    last: Option<u64>,
}

/// The disturbance vector `w(t)` (components without a signal are 0).
pub struct Signals<'a> {
    spec: &'a Spec,
    source: &'a SpecSource,
    /// `(offset, len, expr)` per defined signal.
    parts: Vec<(usize, usize, &'a Expr)>,
    q: usize,
    compiled: Option<Compiled>,
    /// The last value.
    w: Vec<f64>,
}

impl<'a> Signals<'a> {
    /// The signals of `spec`'s scenario, evaluated by `evaluator` (evaluation
    /// errors point into `source`).
    pub fn new(spec: &'a Spec, source: &'a SpecSource, evaluator: Evaluator) -> Self {
        let parts = spec
            .simulate
            .iter()
            .flat_map(|s| &s.signals)
            .filter_map(|(k, e)| spec.disturbances.get(*k).map(|d| (d.offset, d.len, e)))
            .collect();
        let mut signals = Signals {
            spec,
            source,
            parts,
            q: spec.q(),
            compiled: None,
            w: vec![0.0; spec.q()],
        };
        if evaluator == Evaluator::Compiled {
            signals.compiled = signals.compile().ok().map(|tape| Compiled {
                regs: tape.registers(),
                tape,
                last: None,
            });
        }
        signals
    }

    /// The signals as a tape of the input `t`.
    fn compile(&self) -> Result<Tape, Unsupported> {
        let mut lw = Lowerer::new(Builder::new(1), &self.spec.consts, &self.spec.fns);
        let zero = lw.b.constant(0.0);
        let mut out = vec![zero; self.q];
        let scope = [("t".to_string(), SymMat::column(vec![lw.b.input(0)]))];
        for &(offset, len, e) in &self.parts {
            let v = lw.expr(e, &scope)?;
            match out.get_mut(offset..offset + len) {
                Some(dst) if v.data.len() == len => dst.copy_from_slice(&v.data),
                _ => return Err(Unsupported("signal length".into())),
            }
        }
        lw.finish(&out)
    }

    /// Whether the signals run as a compiled tape.
    pub fn is_compiled(&self) -> bool {
        self.compiled.is_some()
    }

    /// The compiled signals, if any.
    pub fn tape(&self) -> Option<&Tape> {
        self.compiled.as_ref().map(|c| &c.tape)
    }

    /// Total disturbance dimension q.
    pub fn len(&self) -> usize {
        self.q
    }

    /// `true` when there is no disturbance input.
    pub fn is_empty(&self) -> bool {
        self.q == 0
    }

    /// Writes `w(t)` into `w` (length q).
    pub fn eval(&mut self, t: f64, w: &mut [f64]) -> Result<(), SimError> {
        let v = self.at(t)?;
        w.copy_from_slice(v);
        Ok(())
    }

    /// `w(t)` (length q), valid until the next call.
    pub fn at(&mut self, t: f64) -> Result<&[f64], SimError> {
        let Some(c) = &mut self.compiled else {
            let mut w = std::mem::take(&mut self.w);
            let r = self.interpret(t, &mut w);
            self.w = w;
            return r.map(|()| &self.w[..]);
        };
        if c.last != Some(t.to_bits()) {
            c.regs[0] = t;
            if c.tape.run(&mut c.regs).is_err() {
                c.last = None;
                let mut w = std::mem::take(&mut self.w);
                let r = self.interpret(t, &mut w);
                self.w = w;
                return r.map(|()| &self.w[..]);
            }
            c.tape.read(&c.regs, &mut self.w);
            c.last = Some(t.to_bits());
        }
        Ok(&self.w)
    }

    /// [`Signals::eval`] by the language's evaluator (the reference path).
    fn interpret(&self, t: f64, w: &mut [f64]) -> Result<(), SimError> {
        w.iter_mut().for_each(|v| *v = 0.0);
        if self.parts.is_empty() {
            return Ok(());
        }
        let env = Env {
            consts: &self.spec.consts,
            fns: &self.spec.fns,
            locals: vec![("t".to_string(), nalgebra::DMatrix::from_element(1, 1, t))],
            unavailable: Vec::new(),
            mode: Mode::Exact,
        };
        for &(offset, len, e) in &self.parts {
            let v = env
                .eval(e)
                .map_err(|d| self.source.eval_error("disturbance signal", t, d))?;
            if v.len() != len {
                return Err(self.source.error_at(
                    e.span,
                    format!(
                        "disturbance signal has {} components, expected {len}",
                        v.len()
                    ),
                    "give the signal as many components as the disturbance",
                ));
            }
            if let Some(dst) = w.get_mut(offset..offset + len) {
                dst.copy_from_slice(v.as_slice());
            }
        }
        Ok(())
    }
}
