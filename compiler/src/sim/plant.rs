//! The truth plant: either the spec's design model
//! `x' = A(x) x + B(x) sat(u) + D(x) w` or its explicit `dynamics { }` block
//! (which may add states the controller does not see). Expressions are
//! evaluated with the language's evaluator; constant matrices are evaluated
//! once.

use super::source::SpecSource;
use super::SimError;
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

/// The plant's right-hand side.
pub struct Plant<'a> {
    spec: &'a Spec,
    source: &'a SpecSource,
    n: usize,
    extra: usize,
    truth: Truth<'a>,
}

impl<'a> Plant<'a> {
    /// The truth plant of `spec`: its `dynamics` block if the scenario has one,
    /// else the design model. Evaluation errors point into `source`.
    pub fn new(spec: &'a Spec, source: &'a SpecSource) -> Result<Self, SimError> {
        let n = spec.n();
        if let Some(dynamics) = spec.simulate.as_ref().and_then(|s| s.dynamics.as_ref()) {
            return Ok(Plant {
                spec,
                source,
                n,
                extra: dynamics.extra_states.iter().map(|s| s.len).sum(),
                truth: Truth::Dynamics(dynamics),
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
            extra: 0,
            truth: Truth::Model {
                a: coef(a, "A")?,
                b: coef(b, "B")?,
                d,
            },
        })
    }

    /// Dimension of the plant state (controller states, then extra states).
    pub fn dim(&self) -> usize {
        self.n + self.extra
    }

    /// Names of the extra state components (the controller does not see them).
    pub fn extra_names(&self) -> Vec<String> {
        match &self.truth {
            Truth::Dynamics(d) => d
                .extra_states
                .iter()
                .flat_map(|s| s.component_names())
                .collect(),
            Truth::Model { .. } => Vec::new(),
        }
    }

    /// `ds = f(t, s, u, w)` with `u` the (saturated) command and `w` the disturbance.
    pub fn rhs(
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
