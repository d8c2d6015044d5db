//! The problem builder: variables, constraints and objective.

use std::collections::HashSet;
use std::sync::atomic::{AtomicU64, Ordering};

use crate::cone::{ConeBlock, ConeProgram};
use crate::constraint::{Constraint, ConstraintId, ConstraintKind, LmiSense, Relation};
use crate::error::{check_finite, check_shape, LmiError, Result};
use crate::expr::Expr;
use crate::lower::{assemble, lower_linear_form, lower_lmi, lower_scalar};
use crate::objective::{Objective, ObjectiveSense};
use crate::var::{Var, VarKind};

static NEXT_PROBLEM_ID: AtomicU64 = AtomicU64::new(1);

/// An LMI problem under construction: create variables, add named constraints,
/// set an objective, then [`Problem::solve`].
#[derive(Debug)]
pub struct Problem {
    pub(crate) id: u64,
    pub(crate) vars: Vec<(String, Var)>,
    pub(crate) unknowns: usize,
    pub(crate) constraints: Vec<Constraint>,
    pub(crate) objective: Objective,
    var_names: HashSet<String>,
    constraint_names: HashSet<String>,
}

impl Default for Problem {
    fn default() -> Self {
        Problem::new()
    }
}

impl Problem {
    /// An empty feasibility problem.
    pub fn new() -> Problem {
        Problem {
            id: NEXT_PROBLEM_ID.fetch_add(1, Ordering::Relaxed),
            vars: Vec::new(),
            unknowns: 0,
            constraints: Vec::new(),
            objective: Objective::default(),
            var_names: HashSet::new(),
            constraint_names: HashSet::new(),
        }
    }

    /// New symmetric `n x n` variable.
    pub fn symmetric(&mut self, name: &str, n: usize) -> Result<Var> {
        self.add_var(name, VarKind::Symmetric(n))
    }

    /// New unstructured `rows x cols` variable.
    pub fn full(&mut self, name: &str, rows: usize, cols: usize) -> Result<Var> {
        self.add_var(name, VarKind::Full(rows, cols))
    }

    /// New diagonal `n x n` variable.
    pub fn diagonal(&mut self, name: &str, n: usize) -> Result<Var> {
        self.add_var(name, VarKind::Diagonal(n))
    }

    /// New scalar variable.
    pub fn scalar(&mut self, name: &str) -> Result<Var> {
        self.add_var(name, VarKind::Scalar)
    }

    /// New variable of any kind; names must be unique and non-empty, sizes positive.
    pub fn add_var(&mut self, name: &str, kind: VarKind) -> Result<Var> {
        let (r, c) = kind.shape();
        if r == 0 || c == 0 {
            return Err(LmiError::Dimension {
                what: format!("variable '{name}' has shape {r}x{c}"),
            });
        }
        claim_name(&mut self.var_names, name, "variable")?;
        let var = Var {
            problem: self.id,
            index: self.vars.len(),
            offset: self.unknowns,
            kind,
        };
        self.unknowns += kind.unknowns();
        self.vars.push((name.to_owned(), var));
        Ok(var)
    }

    /// `expr ⪰ margin · I` (strict LMIs via a positive margin, which is recorded).
    pub fn psd(&mut self, name: &str, expr: Expr, margin: f64) -> Result<ConstraintId> {
        self.add_lmi(name, expr, LmiSense::Psd, margin)
    }

    /// `expr ⪯ -margin · I` (strict LMIs via a positive margin, which is recorded).
    pub fn nsd(&mut self, name: &str, expr: Expr, margin: f64) -> Result<ConstraintId> {
        self.add_lmi(name, expr, LmiSense::Nsd, margin)
    }

    /// Adds an LMI on a square expression that must be symmetric coefficient by
    /// coefficient; the margin must be finite and non-negative.
    pub fn add_lmi(
        &mut self,
        name: &str,
        expr: Expr,
        sense: LmiSense,
        margin: f64,
    ) -> Result<ConstraintId> {
        let (r, c) = expr.shape();
        check_shape(
            || format!("LMI '{name}' (needs a square matrix)"),
            (r, r),
            (r, c),
        )?;
        if r == 0 {
            return Err(LmiError::Dimension {
                what: format!("LMI '{name}' is empty"),
            });
        }
        if !(margin.is_finite() && margin >= 0.0) {
            return Err(LmiError::NonFinite {
                what: format!("margin {margin} of LMI '{name}' (must be finite and >= 0)"),
            });
        }
        self.check_expr(&expr)?;
        let lowered = lower_lmi(name, &expr, sense, margin)?;
        let kind = ConstraintKind::Lmi {
            sense,
            margin,
            size: r,
        };
        self.push_constraint(name, expr, kind, lowered)
    }

    /// Adds the scalar constraint `expr (relation) rhs` for a `1 x 1` expression.
    pub fn add_scalar(
        &mut self,
        name: &str,
        expr: Expr,
        relation: Relation,
        rhs: f64,
    ) -> Result<ConstraintId> {
        check_shape(
            || format!("scalar constraint '{name}'"),
            (1, 1),
            expr.shape(),
        )?;
        check_finite(|| format!("right-hand side of '{name}'"), [rhs].iter())?;
        self.check_expr(&expr)?;
        let lowered = lower_scalar(&expr, relation, rhs);
        let kind = ConstraintKind::Scalar { relation, rhs };
        self.push_constraint(name, expr, kind, lowered)
    }

    /// Minimise a `1 x 1` expression (e.g. `Expr::var(g)` or `Expr::var(X).trace()?`).
    pub fn minimize(&mut self, expr: Expr) -> Result<()> {
        self.set_objective(ObjectiveSense::Minimize, expr)
    }

    /// Maximise a `1 x 1` expression.
    pub fn maximize(&mut self, expr: Expr) -> Result<()> {
        self.set_objective(ObjectiveSense::Maximize, expr)
    }

    /// Drops the objective: the problem becomes a pure feasibility problem.
    pub fn feasibility(&mut self) {
        self.objective = Objective::default();
    }

    /// The objective's sense.
    pub fn objective_sense(&self) -> ObjectiveSense {
        self.objective.sense
    }

    /// The problem lowered to the solver-neutral [`ConeProgram`]: what
    /// [`Problem::solve`] hands to the solver. Unknowns are numbered as in
    /// [`crate::Assignment::unknowns`]; a maximisation is stated as the
    /// minimisation of the negated objective, and the objective's constant is
    /// left out.
    pub fn cone_program(&self) -> ConeProgram {
        assemble(
            self.unknowns,
            self.constraints.iter().map(|c| &c.lowered),
            self.objective.cost(self.unknowns),
        )
    }

    /// Variables with their names, in creation order.
    pub fn vars(&self) -> impl Iterator<Item = (&str, Var)> + '_ {
        self.vars.iter().map(|(n, v)| (n.as_str(), *v))
    }

    /// Constraint handles, in creation order.
    pub fn constraints(&self) -> impl Iterator<Item = ConstraintId> + '_ {
        (0..self.constraints.len()).map(|index| ConstraintId {
            problem: self.id,
            index,
        })
    }

    /// Name and kind of a constraint.
    pub fn constraint_info(&self, id: ConstraintId) -> Result<(&str, ConstraintKind)> {
        let c = self.constraint(id)?;
        Ok((c.name.as_str(), c.kind))
    }

    /// Name of a variable of this problem.
    pub fn var_name(&self, v: Var) -> Result<&str> {
        self.check_var(v)?;
        Ok(self.vars[v.index].0.as_str())
    }

    /// Number of scalar unknowns.
    pub fn unknowns(&self) -> usize {
        self.unknowns
    }

    /// The stored constraint behind a handle.
    pub(crate) fn constraint(&self, id: ConstraintId) -> Result<&Constraint> {
        if id.problem != self.id {
            return Err(LmiError::UnknownConstraint);
        }
        self.constraints
            .get(id.index)
            .ok_or(LmiError::UnknownConstraint)
    }

    /// Errors unless `v` was created by this problem.
    pub(crate) fn check_var(&self, v: Var) -> Result<()> {
        match self.vars.get(v.index) {
            Some((_, own)) if v.problem == self.id && *own == v => Ok(()),
            _ => Err(LmiError::Variable {
                what: format!("variable #{} belongs to another problem", v.index),
            }),
        }
    }

    fn check_expr(&self, expr: &Expr) -> Result<()> {
        expr.terms()
            .iter()
            .try_for_each(|t| self.check_var(t.var()))
    }

    fn set_objective(&mut self, sense: ObjectiveSense, expr: Expr) -> Result<()> {
        check_shape(|| "objective".into(), (1, 1), expr.shape())?;
        self.check_expr(&expr)?;
        self.objective = Objective {
            sense,
            form: lower_linear_form(&expr),
        };
        Ok(())
    }

    fn push_constraint(
        &mut self,
        name: &str,
        expr: Expr,
        kind: ConstraintKind,
        lowered: ConeBlock,
    ) -> Result<ConstraintId> {
        claim_name(&mut self.constraint_names, name, "constraint")?;
        self.constraints.push(Constraint {
            name: name.to_owned(),
            expr,
            kind,
            lowered,
        });
        Ok(ConstraintId {
            problem: self.id,
            index: self.constraints.len() - 1,
        })
    }
}

/// Registers a unique, non-empty name.
fn claim_name(names: &mut HashSet<String>, name: &str, what: &str) -> Result<()> {
    if name.is_empty() {
        return Err(LmiError::Name {
            name: name.into(),
            what: format!("{what} names must not be empty"),
        });
    }
    if !names.insert(name.to_owned()) {
        return Err(LmiError::Name {
            name: name.into(),
            what: format!("{what} name used twice"),
        });
    }
    Ok(())
}
