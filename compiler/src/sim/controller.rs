//! The controller in the loop: `tsf_runtime::Controller` built from the
//! design's [`Tables`] (the same data the generated module declares), so the
//! simulation runs the runtime's arithmetic and nothing else.
//!
//! The runtime is const-generic in the sizes `N, M, P, R`. The simulator
//! instantiates it for a few size classes and pads the tables: padded states,
//! premises and inputs are 0, padded gains are 0, padded rules have a term on
//! an out-of-range premise (degree 0, so they never fire) and NaN centres (so
//! the nearest-rule fallback never picks them). Padding adds only exact zeros
//! to the runtime's sums, so the commands equal the unpadded controller's.

use super::SimError;
use crate::model::TermSpec;
use crate::tables::{PremiseCode, Tables};
use tsf_runtime::{premises_linear, Controller, Flags, Membership, Rule, Term};

/// A padding rule's only term: premise index `usize::MAX` is out of range, degree 0.
static NEVER: [Term<'static, f64>; 1] = [Term::Is {
    var: usize::MAX,
    set: Membership::tri(0.0, 0.0, 0.0),
}];

/// The runtime terms of every rule (borrowing `about` points from the tables).
pub fn runtime_terms(tables: &Tables) -> Vec<Vec<Term<'_, f64>>> {
    tables
        .terms
        .iter()
        .map(|rule| rule.iter().map(TermSpec::runtime).collect())
        .collect()
}

/// A controller evaluation: state in, saturated command out.
pub trait Law {
    /// Writes `u = sat(sum_j h_j(z(x)) F_j x)` for the controller state `x`
    /// (length n) into `u` (length m) and returns the runtime's flags.
    fn command(&self, x: &[f64], u: &mut [f64]) -> Flags;

    /// [`Law::command`] with the premise vector `z(x)` already computed
    /// (length p; see [`super::premise::Premises`]).
    fn command_with(&self, x: &[f64], z: &[f64], u: &mut [f64]) -> Flags;

    /// Writes the normalized firing strengths `h_j(z)` the controller blends
    /// with at state `x` into `h` (length r), with the premise vector `z` if
    /// the caller computed it (else from `x`, as [`Law::command`] does).
    fn strengths(&self, x: &[f64], z: Option<&[f64]>, h: &mut [f64]);
}

struct Padded<'a, const N: usize, const M: usize, const P: usize, const R: usize> {
    ctrl: Box<Controller<'a, f64, N, M, P, R>>,
    premise: &'a PremiseCode,
    n: usize,
    m: usize,
}

fn pad<const K: usize>(v: &[f64], fill: f64) -> [f64; K] {
    std::array::from_fn(|i| v.get(i).copied().unwrap_or(fill))
}

impl<'a, const N: usize, const M: usize, const P: usize, const R: usize> Padded<'a, N, M, P, R> {
    fn new(tables: &'a Tables, terms: &'a [Vec<Term<'a, f64>>]) -> Self {
        let empty: Vec<f64> = Vec::new();
        let l = match &tables.premise {
            PremiseCode::Linear(rows) => rows.clone(),
            PremiseCode::Exprs(_) => Vec::new(),
        };
        let ctrl = Box::new(Controller {
            premise_map: std::array::from_fn(|p| pad(l.get(p).unwrap_or(&empty), 0.0)),
            rules: std::array::from_fn(|j| match terms.get(j) {
                Some(t) => Rule::new(t),
                None => Rule::new(&NEVER),
            }),
            centres: std::array::from_fn(|j| match tables.centres.get(j) {
                Some(c) => pad(c, 0.0),
                None => [f64::NAN; P],
            }),
            gains: std::array::from_fn(|j| {
                let f = tables.gains.get(j);
                std::array::from_fn(|s| pad(f.and_then(|f| f.get(s)).unwrap_or(&empty), 0.0))
            }),
            u_max: pad(&tables.u_max, 0.0),
        });
        Padded {
            ctrl,
            premise: &tables.premise,
            n: tables.n,
            m: tables.m,
        }
    }
}

impl<const N: usize, const M: usize, const P: usize, const R: usize> Law
    for Padded<'_, N, M, P, R>
{
    fn command(&self, x: &[f64], u: &mut [f64]) -> Flags {
        let (xs, z) = self.premises(x);
        self.apply(&xs, &z, u)
    }

    fn command_with(&self, x: &[f64], z: &[f64], u: &mut [f64]) -> Flags {
        let xs: [f64; N] = pad(&x[..self.n.min(x.len())], 0.0);
        self.apply(&xs, &pad(z, 0.0), u)
    }

    fn strengths(&self, x: &[f64], z: Option<&[f64]>, h: &mut [f64]) {
        let z: [f64; P] = match z {
            Some(z) => pad(z, 0.0),
            None => self.premises(x).1,
        };
        let (w, _) = self.ctrl.strengths(&z);
        for (o, v) in h.iter_mut().zip(&w) {
            *o = *v;
        }
    }
}

impl<const N: usize, const M: usize, const P: usize, const R: usize> Padded<'_, N, M, P, R> {
    /// The padded state and the premise vector computed from it.
    fn premises(&self, x: &[f64]) -> ([f64; N], [f64; P]) {
        let xs: [f64; N] = pad(&x[..self.n.min(x.len())], 0.0);
        let z: [f64; P] = match self.premise {
            PremiseCode::Linear(_) => premises_linear(&self.ctrl.premise_map, &xs),
            PremiseCode::Exprs(e) => std::array::from_fn(|p| e.get(p).map_or(0.0, |s| s.eval(x))),
        };
        (xs, z)
    }

    fn apply(&self, xs: &[f64; N], z: &[f64; P], u: &mut [f64]) -> Flags {
        let step = self.ctrl.step_with_premises(xs, z);
        for (o, v) in u.iter_mut().zip(&step.u[..self.m]) {
            *o = *v;
        }
        step.flags
    }
}

/// Builds the runtime controller for `tables` (terms from [`runtime_terms`]).
pub fn law<'a>(
    tables: &'a Tables,
    terms: &'a [Vec<Term<'a, f64>>],
) -> Result<Box<dyn Law + 'a>, SimError> {
    let (n, m, p, r) = (tables.n, tables.m, tables.p, tables.r);
    let fits = |cn, cm, cp, cr| n <= cn && m <= cm && p <= cp && r <= cr;
    if fits(4, 2, 4, 8) {
        Ok(Box::new(Padded::<4, 2, 4, 8>::new(tables, terms)))
    } else if fits(8, 4, 8, 16) {
        Ok(Box::new(Padded::<8, 4, 8, 16>::new(tables, terms)))
    } else if fits(16, 8, 16, 64) {
        Ok(Box::new(Padded::<16, 8, 16, 64>::new(tables, terms)))
    } else {
        Err(SimError::unsupported(format!(
            "the simulator handles at most 16 states, 8 inputs, 16 premise components and 64 rules \
             (this controller: n = {n}, m = {m}, p = {p}, r = {r})"
        )))
    }
}
