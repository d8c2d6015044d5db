//! The blend of a rule base that is a full grid over two or more premise
//! factors (every combination of one set per premise is exactly one rule,
//! as `rules sector;` builds them), evaluated factor by factor.
//!
//! With p factors and degrees mu_{k,c}(z_k), the total weight is
//! S = prod_k S_k, S_k = sum_c mu_{k,c}, so h_i = prod_k nu_{k,c_i(k)} with
//! nu_{k,c} = mu_{k,c} / S_k, and the blend sum_i h_i M_i is the contraction
//! of the rules' grid of values, one factor at a time:
//! T' = T_0 + sum_{c >= 1} nu_c (T_c - T_0) (sum_c nu_c = 1 in the reals).
//! In affine arithmetic the products of memberships of the flat sum
//! sum_i w_i M_i each get a fresh symbol, so a blend that is multilinear in
//! the premises (a sector model with several premises) does not cancel
//! against M(x); in the contracted form the differences T_c - T_0 of an
//! entry affine in the premises are constants (to rounding), the products
//! with nu_c stay linear, and the blend cancels to rounding. The bound is
//! used beside the flat one (the smaller holds: both enclose the same real
//! value).

use crate::model::premise::TermSpec;
use crate::tape::affine::{recip_within, Affine, Noise, Unbounded};

/// A rule base that is a full grid over its premise factors.
pub(super) struct Grid {
    /// Per factor: its distinct terms (sets of one premise value), in
    /// first-seen order.
    factors: Vec<Vec<TermSpec>>,
    /// The rule of each grid cell, row-major (the last factor fastest).
    cells: Vec<usize>,
}

impl Grid {
    /// The grid of `terms` (one entry per rule), or `None` when the rules
    /// are not a full grid over at least two factors of `Is` terms.
    pub fn of(terms: &[Vec<TermSpec>]) -> Option<Grid> {
        let first = terms.first()?;
        let vars: Vec<usize> = first
            .iter()
            .map(|t| match t {
                TermSpec::Is { var, .. } => Some(*var),
                TermSpec::About { .. } => None,
            })
            .collect::<Option<_>>()?;
        let p = vars.len();
        if p < 2 || (1..p).any(|k| vars[..k].contains(&vars[k])) {
            return None;
        }
        let mut factors: Vec<Vec<TermSpec>> = vec![Vec::new(); p];
        let mut index: Vec<Vec<usize>> = Vec::with_capacity(terms.len());
        for rule in terms {
            if rule.len() != p {
                return None;
            }
            let mut at = Vec::with_capacity(p);
            for (k, &v) in vars.iter().enumerate() {
                let t = rule
                    .iter()
                    .find(|t| matches!(t, TermSpec::Is { var, .. } if *var == v))?;
                let c = match factors[k].iter().position(|u| u == t) {
                    Some(c) => c,
                    None => {
                        factors[k].push(t.clone());
                        factors[k].len() - 1
                    }
                };
                at.push(c);
            }
            index.push(at);
        }
        let size = factors.iter().map(Vec::len).product::<usize>();
        if size != terms.len() {
            return None;
        }
        let mut cells = vec![usize::MAX; size];
        for (i, at) in index.iter().enumerate() {
            let cell = at
                .iter()
                .zip(&factors)
                .fold(0, |acc, (c, f)| acc * f.len() + c);
            if cells[cell] != usize::MAX {
                return None;
            }
            cells[cell] = i;
        }
        Some(Grid { factors, cells })
    }

    /// The per-factor normalized degrees nu_{k,c} on the box, from each
    /// term's degree `degree` (every term of the grid); `None` when some
    /// S_k is not proved positive (the flat bound is used alone then).
    pub fn normalized(
        &self,
        degree: impl Fn(&TermSpec) -> Option<Affine>,
        noise: &mut Noise,
    ) -> Option<Vec<Vec<Affine>>> {
        let mut out = Vec::with_capacity(self.factors.len());
        for f in &self.factors {
            let d: Vec<Affine> = f.iter().map(&degree).collect::<Option<_>>()?;
            // Degrees lie in [0, 1]: an interval enclosure of S_k.
            let (mut lo, mut hi) = (0.0f64, 0.0f64);
            for x in &d {
                let (a, b) = x.range();
                lo = (lo + a.clamp(0.0, 1.0)).next_down();
                hi = crate::tape::affine::add_up(hi, b.clamp(0.0, 1.0));
            }
            let parts: Vec<(f64, &Affine)> = d.iter().map(|x| (1.0, x)).collect();
            let s = Affine::combine(&parts, 0.0, noise).ok()?;
            let (a, b) = s.range();
            let inv = recip_within(&s, (a.max(lo), b.min(hi)), noise).ok()?;
            out.push(
                d.iter()
                    .map(|x| x.mul(&inv, noise))
                    .collect::<Result<_, _>>()
                    .ok()?,
            );
        }
        Some(out)
    }

    /// `sum_i h_i v_i` for the rules' values `v` (one per rule), contracted
    /// factor by factor with the normalized degrees `nu`.
    pub fn blend(
        &self,
        nu: &[Vec<Affine>],
        v: &[f64],
        noise: &mut Noise,
    ) -> Result<Affine, Unbounded> {
        let mut t: Vec<Affine> = self
            .cells
            .iter()
            .map(|&i| Affine::constant(v[i]))
            .collect::<Result<_, _>>()?;
        for nu_k in nu.iter().rev() {
            let n = nu_k.len();
            let mut next = Vec::with_capacity(t.len() / n);
            for block in t.chunks(n) {
                let base = &block[0];
                let mut terms = Vec::with_capacity(n - 1);
                for (c, x) in block.iter().enumerate().skip(1) {
                    terms.push(nu_k[c].mul(&x.sub(base, noise)?, noise)?);
                }
                let mut parts = vec![(1.0, base)];
                parts.extend(terms.iter().map(|x| (1.0, x)));
                next.push(Affine::combine(&parts, 0.0, noise)?);
            }
            t = next;
        }
        t.pop().ok_or(Unbounded)
    }
}
