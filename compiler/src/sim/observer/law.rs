//! The runtime's [`Observer`] built from the design's tables, padded to a
//! few size classes like the state-feedback controller
//! ([`crate::sim::controller`]): padded states, outputs, inputs and premises
//! are 0 with zero rows and columns in every table, padded rules reference
//! an out-of-range term (degree 0, never fire) and have NaN centres (never
//! the nearest rule). Padding adds only exact zeros to the runtime's sums.

use crate::model::TermSpec;
use crate::sim::SimError;
use crate::tables::{ObserverTables, Tables};
use tsf_runtime::{FactoredController, Flags, Membership, Observer, Term};

/// A padding rule's term list: index `usize::MAX` is out of range, degree 0.
static NEVER: [usize; 1] = [usize::MAX];

/// A padding term (never referenced by a rule).
const UNUSED: Term<'static, f64> = Term::Is {
    var: usize::MAX,
    set: Membership::tri(0.0, 0.0, 0.0),
};

/// One observer step on vectors of the design's sizes.
pub trait ObserverLaw {
    /// The state-like vector `v` (length n) the premises are computed from.
    fn premise_state(&self, xhat: &[f64], y: &[f64], v: &mut [f64]);
    /// Writes `u_k` into `u` (length m), advances `xhat` (length n) with the
    /// output `y` (length q); `z` is the premise vector when the caller
    /// computed it (premise expressions), else `z = L v`. Returns the flags.
    fn step(&self, xhat: &mut [f64], y: &[f64], z: Option<&[f64]>, u: &mut [f64]) -> Flags;
}

fn pad<const K: usize>(v: &[f64], fill: f64) -> [f64; K] {
    std::array::from_fn(|i| v.get(i).copied().unwrap_or(fill))
}

/// `rows` (a matrix as rows) padded to `R x C` with zeros.
fn pad2<const R: usize, const C: usize>(rows: Option<&Vec<Vec<f64>>>) -> [[f64; C]; R] {
    std::array::from_fn(|i| match rows.and_then(|r| r.get(i)) {
        Some(row) => pad(row, 0.0),
        None => [0.0; C],
    })
}

struct Padded<
    'a,
    const N: usize,
    const M: usize,
    const Q: usize,
    const P: usize,
    const R: usize,
    const D: usize,
> {
    obs: Box<Observer<'a, f64, N, M, Q, P, R, D>>,
    n: usize,
    m: usize,
    q: usize,
}

impl<
        'a,
        const N: usize,
        const M: usize,
        const Q: usize,
        const P: usize,
        const R: usize,
        const D: usize,
    > Padded<'a, N, M, Q, P, R, D>
{
    fn new(t: &'a Tables, o: &'a ObserverTables, terms: &'a [Term<'a, f64>]) -> Self {
        let l = match &t.premise {
            crate::tables::PremiseCode::Linear(rows) => Some(rows),
            crate::tables::PremiseCode::Exprs(_) => None,
        };
        let obs = Box::new(Observer {
            controller: FactoredController {
                premise_map: pad2(l),
                terms: std::array::from_fn(|k| terms.get(k).copied().unwrap_or(UNUSED)),
                rules: std::array::from_fn(|j| match t.factored.rules.get(j) {
                    Some(r) => r.as_slice(),
                    None => &NEVER[..],
                }),
                centres: std::array::from_fn(|j| match t.centres.get(j) {
                    Some(c) => pad(c, 0.0),
                    None => [f64::NAN; P],
                }),
                gains: std::array::from_fn(|j| pad2(t.gains.get(j))),
                u_max: pad(&t.u_max, 0.0),
            },
            output_map: o.output_map.as_ref().map(|s| pad2(Some(s))),
            phi: std::array::from_fn(|j| pad2(o.phi.get(j))),
            gu: std::array::from_fn(|j| pad2(o.gu.get(j))),
            gy: std::array::from_fn(|j| pad2(o.gy.get(j))),
        });
        Padded {
            obs,
            n: t.n,
            m: t.m,
            q: o.q,
        }
    }
}

impl<
        const N: usize,
        const M: usize,
        const Q: usize,
        const P: usize,
        const R: usize,
        const D: usize,
    > ObserverLaw for Padded<'_, N, M, Q, P, R, D>
{
    fn premise_state(&self, xhat: &[f64], y: &[f64], v: &mut [f64]) {
        let vs = self
            .obs
            .premise_state(&pad(&xhat[..self.n], 0.0), &pad(&y[..self.q], 0.0));
        for (o, x) in v.iter_mut().zip(&vs) {
            *o = *x;
        }
    }

    fn step(&self, xhat: &mut [f64], y: &[f64], z: Option<&[f64]>, u: &mut [f64]) -> Flags {
        let mut xs: [f64; N] = pad(&xhat[..self.n], 0.0);
        let ys: [f64; Q] = pad(&y[..self.q], 0.0);
        let step = match z {
            Some(z) => self.obs.step_with_premises(&mut xs, &ys, &pad(z, 0.0)),
            None => self.obs.step(&mut xs, &ys),
        };
        xhat.copy_from_slice(&xs[..self.n]);
        u.copy_from_slice(&step.u[..self.m]);
        step.flags
    }
}

/// The runtime terms of the distinct premise terms (borrowing `about`
/// points from the tables).
pub fn factored_terms(t: &Tables) -> Vec<Term<'_, f64>> {
    t.factored.terms.iter().map(TermSpec::runtime).collect()
}

/// Builds the runtime observer of `t` (`terms` from [`factored_terms`]).
pub fn observer_law<'a>(
    t: &'a Tables,
    o: &'a ObserverTables,
    terms: &'a [Term<'a, f64>],
) -> Result<Box<dyn ObserverLaw + 'a>, SimError> {
    let (n, m, q, p, r, d) = (t.n, t.m, o.q, t.p, t.r, terms.len());
    let fits = |c: [usize; 6]| {
        [n, m, q, p, r, d]
            .iter()
            .zip(c)
            .all(|(&size, cap)| size <= cap)
    };
    if fits([4, 2, 4, 4, 8, 16]) {
        Ok(Box::new(Padded::<4, 2, 4, 4, 8, 16>::new(t, o, terms)))
    } else if fits([8, 4, 8, 8, 16, 32]) {
        Ok(Box::new(Padded::<8, 4, 8, 8, 16, 32>::new(t, o, terms)))
    } else if fits([16, 8, 16, 16, 64, 64]) {
        Ok(Box::new(Padded::<16, 8, 16, 16, 64, 64>::new(t, o, terms)))
    } else {
        Err(SimError::unsupported(format!(
            "the simulator runs observers of at most 16 states, 8 inputs, 16 outputs, 16 premise components, 64 rules and 64 distinct premise terms \
             (this one: n = {n}, m = {m}, q = {q}, p = {p}, r = {r}, terms = {d})"
        )))
    }
}
