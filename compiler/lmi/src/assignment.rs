//! Numeric values for the variables of a problem.

use nalgebra::DMatrix;

use crate::error::{check_finite, check_shape, LmiError, Result};
use crate::problem::Problem;
use crate::var::{Var, VarKind};

/// One numeric value per variable of a problem: the solver's iterate, or
/// values set by hand (e.g. rounded gains) to be checked with
/// [`Problem::margins`].
#[derive(Clone, Debug, PartialEq)]
pub struct Assignment {
    problem: u64,
    vars: Vec<(String, Var)>,
    values: Vec<DMatrix<f64>>,
}

impl Assignment {
    /// The value of `v`.
    pub fn value(&self, v: Var) -> Result<&DMatrix<f64>> {
        self.check_var(v)?;
        Ok(&self.values[v.index])
    }

    /// Sets the value of `v`; it must have the variable's shape and structure
    /// (exactly symmetric, exactly zero off a diagonal) and be finite.
    pub fn set(&mut self, v: Var, value: DMatrix<f64>) -> Result<()> {
        self.check_var(v)?;
        let name = &self.vars[v.index].0;
        check_shape(|| format!("value of '{name}'"), v.shape(), value.shape())?;
        check_finite(|| format!("value of '{name}'"), value.iter())?;
        let broken = match v.kind() {
            VarKind::Symmetric(_) => (value != value.transpose()).then_some("not symmetric"),
            VarKind::Diagonal(_) => {
                (value != DMatrix::from_diagonal(&value.diagonal())).then_some("not diagonal")
            }
            VarKind::Full(..) | VarKind::Scalar => None,
        };
        if let Some(what) = broken {
            return Err(LmiError::Value {
                var: name.clone(),
                what: what.into(),
            });
        }
        self.values[v.index] = value;
        Ok(())
    }

    /// The values of the scalar unknowns, in the solver's order.
    pub fn unknowns(&self) -> Vec<f64> {
        let total = self.vars.iter().map(|(_, v)| v.kind.unknowns()).sum();
        let mut x = vec![0.0; total];
        for ((_, v), value) in self.vars.iter().zip(&self.values) {
            for (i, j, u) in v.kind.entries() {
                x[v.offset + u] = value[(i, j)];
            }
        }
        x
    }

    /// Values built from the solver's unknowns (symmetric values are exactly symmetric).
    pub(crate) fn from_unknowns(problem: &Problem, x: &[f64]) -> Assignment {
        let values = problem
            .vars
            .iter()
            .map(|(_, v)| {
                let (r, c) = v.shape();
                DMatrix::from_fn(r, c, |i, j| {
                    v.unknown_of(i, j)
                        .and_then(|u| x.get(u).copied())
                        .unwrap_or(0.0)
                })
            })
            .collect();
        Assignment {
            problem: problem.id,
            vars: problem.vars.clone(),
            values,
        }
    }

    fn check_var(&self, v: Var) -> Result<()> {
        match self.vars.get(v.index) {
            Some((_, own)) if v.problem == self.problem && *own == v => Ok(()),
            _ => Err(LmiError::Variable {
                what: format!("variable #{} is not part of this assignment", v.index),
            }),
        }
    }

    /// Errors unless the assignment was made for `problem` (and has all its variables).
    pub(crate) fn check_problem(&self, problem: &Problem) -> Result<()> {
        if self.problem == problem.id && self.vars.len() == problem.vars.len() {
            Ok(())
        } else {
            Err(LmiError::Variable {
                what: "assignment belongs to another problem (or an older state of it)".into(),
            })
        }
    }
}

impl Problem {
    /// An all-zero assignment for the current variables, to fill with [`Assignment::set`].
    pub fn assignment(&self) -> Assignment {
        Assignment::from_unknowns(self, &[])
    }
}
