//! The truth plant: either the spec's design model
//! `x' = A(x) x + B(x) sat(u) + D(x) w` or its explicit `dynamics { }` block
//! (which may add states the controller does not see). With
//! [`Evaluator::Compiled`] the right-hand side is compiled once into a
//! [`Tape`] (inputs `t, s, u, w`); with [`Evaluator::Interpreter`], or where
//! the tape cannot express it, the language's evaluator evaluates the
//! expressions at every call (constant matrices once). A tape that faults
//! (a division by zero) hands the call to the evaluator, which reports it.

use super::source::SpecSource;
use super::tape::lower::{Lowerer, Scope, SymMat, Unsupported};
use super::tape::{Builder, Registers, Tape};
use super::{Evaluator, SimError};
use nalgebra::DMatrix;
use tsf_lang::ast::Expr;
use tsf_lang::eval::Mode;
use tsf_lang::spec::{Dynamics, ModelMatrix, Spec};

/// A model matrix: constant, or an expression of the state.
enum Coef<'a> {
    Const(DMatrix<f64>),
    StateDependent(&'a Expr),
}

enum Truth<'a> {
    Model {
        a: Coef<'a>,
        b: Coef<'a>,
        d: Option<Coef<'a>>,
    },
    Dynamics(&'a Dynamics),
}

/// The compiled right-hand side and its register file.
struct Compiled {
    tape: Tape,
    regs: Box<Registers>,
}

/// The plant's right-hand side.
pub struct Plant<'a> {
    spec: &'a Spec,
    source: &'a SpecSource,
    n: usize,
    m: usize,
    extra: usize,
    truth: Truth<'a>,
    compiled: Option<Compiled>,
}

impl<'a> Plant<'a> {
    /// The truth plant of `spec`: its `dynamics` block if the scenario has one,
    /// else the design model, evaluated by `evaluator`. Evaluation errors
    /// point into `source`.
    pub fn new(
        spec: &'a Spec,
        source: &'a SpecSource,
        evaluator: Evaluator,
    ) -> Result<Self, SimError> {
        let mut plant = Self::interpreted(spec, source)?;
        if evaluator == Evaluator::Compiled {
            plant.compiled = plant.compile().ok().map(|tape| Compiled {
                regs: tape.registers(),
                tape,
            });
        }
        Ok(plant)
    }

    fn interpreted(spec: &'a Spec, source: &'a SpecSource) -> Result<Self, SimError> {
        let n = spec.n();
        if let Some(dynamics) = spec.simulate.as_ref().and_then(|s| s.dynamics.as_ref()) {
            return Ok(Plant {
                spec,
                source,
                n,
                m: spec.m(),
                extra: dynamics.extra_states.iter().map(|s| s.len).sum(),
                truth: Truth::Dynamics(dynamics),
                compiled: None,
            });
        }
        let env = spec.state_env(&vec![0.0; n], Mode::Exact);
        let coef = |m: &'a ModelMatrix, name: &str| -> Result<Coef<'a>, SimError> {
            if m.state_dependent {
                Ok(Coef::StateDependent(&m.expr))
            } else {
                env.eval(&m.expr)
                    .map(Coef::Const)
                    .map_err(|d| source.eval_error(name, 0.0, d))
            }
        };
        let (Some(a), Some(b)) = (&spec.a, &spec.b) else {
            return Err(SimError::spec("the spec has no model matrices A and B"));
        };
        let d = match &spec.d {
            Some(d) => Some(coef(d, "D")?),
            None => None,
        };
        Ok(Plant {
            spec,
            source,
            n,
            m: spec.m(),
            extra: 0,
            truth: Truth::Model {
                a: coef(a, "A")?,
                b: coef(b, "B")?,
                d,
            },
            compiled: None,
        })
    }

    /// Whether the right-hand side runs as a compiled tape (else the
    /// interpreter evaluates it).
    pub fn is_compiled(&self) -> bool {
        self.compiled.is_some()
    }

    /// The compiled right-hand side, if any.
    pub fn tape(&self) -> Option<&Tape> {
        self.compiled.as_ref().map(|c| &c.tape)
    }

    /// The right-hand side as a tape over the inputs `[t, s, u, w]`.
    fn compile(&self) -> Result<Tape, Unsupported> {
        let spec = self.spec;
        let (n, dim, m, q) = (self.n, self.dim(), spec.m(), spec.q());
        let mut lw = Lowerer::new(Builder::new(1 + dim + m + q), &spec.consts, &spec.fns);
        let (x, u, w) = (
            lw.inputs(1, n),
            lw.inputs(1 + dim, m),
            lw.inputs(1 + dim + m, q),
        );
        // The evaluator's bindings, in its order (later ones shadow).
        let mut scope = vec![("x".to_string(), x.clone())];
        scope.extend(lw.bind(&spec.states, 1));
        let outputs = match &self.truth {
            Truth::Model { a, b, d } => {
                let mut coef = |c: &Coef, scope: &Scope| match c {
                    Coef::Const(m) => Ok(lw.constant(m)),
                    Coef::StateDependent(e) => lw.expr(e, scope),
                };
                let (a, b) = (coef(a, &scope)?, coef(b, &scope)?);
                let d = d.as_ref().map(|d| coef(d, &scope)).transpose()?;
                let times = |lw: &mut Lowerer, m: &SymMat, v: &SymMat| {
                    if m.cols == v.rows && m.rows == n {
                        Ok(lw.product(m, v))
                    } else {
                        Err(Unsupported("model matrix shape".into()))
                    }
                };
                let (ax, bu) = (times(&mut lw, &a, &x)?, times(&mut lw, &b, &u)?);
                let mut dx = lw.add(&ax, &bu)?;
                if let Some(d) = d {
                    let dw = times(&mut lw, &d, &w)?;
                    dx = lw.add(&dx, &dw)?;
                }
                dx.data
            }
            Truth::Dynamics(dy) => {
                for (name, value) in &dy.consts {
                    let c = lw.constant(value);
                    scope.push((name.clone(), c));
                }
                scope.extend(lw.bind(&dy.extra_states, 1 + n));
                scope.extend(lw.bind(&spec.inputs, 1 + dim));
                scope.extend(lw.bind(&spec.disturbances, 1 + dim + m));
                scope.push(("t".to_string(), lw.inputs(0, 1)));
                let mut out = Vec::with_capacity(dim);
                for (_, e) in &dy.derivatives {
                    out.extend(lw.expr(e, &scope)?.data);
                }
                out
            }
        };
        if outputs.len() != dim {
            return Err(Unsupported("derivative count".into()));
        }
        lw.finish(&outputs)
    }

    /// Dimension of the plant state (controller states, then extra states).
    pub fn dim(&self) -> usize {
        self.n + self.extra
    }

    /// Names of the extra state components (the controller does not see them).
    pub fn extra_names(&self) -> Vec<String> {
        match &self.truth {
            Truth::Dynamics(d) => tsf_lang::spec::Signal::names_of(&d.extra_states),
            Truth::Model { .. } => Vec::new(),
        }
    }

    /// `ds = f(t, s, u, w)` with `u` the (saturated) command and `w` the
    /// disturbance (`s`, `u`, `w`, `ds` of the plant's, the spec's sizes).
    pub fn rhs(
        &mut self,
        t: f64,
        s: &[f64],
        u: &[f64],
        w: &[f64],
        ds: &mut [f64],
    ) -> Result<(), SimError> {
        let (dim, m) = (self.dim(), self.m);
        if let Some(c) = &mut self.compiled {
            let regs = &mut c.regs;
            regs[0] = t;
            c.tape.write(regs, 1, &s[..dim.min(s.len())]);
            c.tape.write(regs, 1 + dim, &u[..m.min(u.len())]);
            c.tape.write(regs, 1 + dim + m, w);
            if c.tape.run(regs).is_ok() {
                c.tape.read(regs, ds);
                return Ok(());
            }
        }
        self.interpret(t, s, u, w, ds)
    }

    /// [`Plant::rhs`] by the language's evaluator (the reference path).
    fn interpret(
        &self,
        t: f64,
        s: &[f64],
        u: &[f64],
        w: &[f64],
        ds: &mut [f64],
    ) -> Result<(), SimError> {
        let x = s.get(..self.n).unwrap_or(s);
        let mut env = self.spec.state_env(x, Mode::Exact);
        match &self.truth {
            Truth::Model { a, b, d } => {
                let get = |c: &Coef, name: &str| -> Result<DMatrix<f64>, SimError> {
                    match c {
                        Coef::Const(m) => Ok(m.clone()),
                        Coef::StateDependent(e) => {
                            env.eval(e).map_err(|d| self.source.eval_error(name, t, d))
                        }
                    }
                };
                let xv = DMatrix::from_column_slice(x.len(), 1, x);
                let mut dx = get(a, "A(x)")? * &xv
                    + get(b, "B(x)")? * DMatrix::from_column_slice(u.len(), 1, u);
                if let Some(d) = d {
                    dx += get(d, "D(x)")? * DMatrix::from_column_slice(w.len(), 1, w);
                }
                ds.copy_from_slice(dx.as_slice());
            }
            Truth::Dynamics(dy) => {
                let col = |v: &[f64]| DMatrix::from_column_slice(v.len(), 1, v);
                let extra = s.get(self.n..).unwrap_or(&[]);
                env.locals.extend(dy.consts.iter().cloned());
                let signals = [
                    (&dy.extra_states, extra),
                    (&self.spec.inputs, u),
                    (&self.spec.disturbances, w),
                ];
                for (sigs, values) in signals {
                    for sig in sigs {
                        let v = values.get(sig.offset..sig.offset + sig.len).unwrap_or(&[]);
                        env.locals.push((sig.name.clone(), col(v)));
                    }
                }
                env.locals
                    .push(("t".into(), DMatrix::from_element(1, 1, t)));
                let mut at = 0;
                for (name, e) in &dy.derivatives {
                    let v = env
                        .eval(e)
                        .map_err(|d| self.source.eval_error(&format!("{name}'"), t, d))?;
                    let dst = ds.get_mut(at..at + v.len()).ok_or_else(|| {
                        self.source.error_at(
                            e.span,
                            format!("`{name}'` has more components than the state"),
                            "give one derivative component per state component",
                        )
                    })?;
                    dst.copy_from_slice(v.as_slice());
                    at += v.len();
                }
            }
        }
        Ok(())
    }
}
