//! Model-reference adaptive T-S control (Wang, Gao & He 2013, generalized to
//! several inputs with a matched error signal; see the compiler's
//! `docs/adaptive.md`).
//!
//! With the error signal `s = C x` (one component per input), the reference
//! model `s_m' = A_m (s_m - r)` (B_m = -A_m, unit DC gain), the tracking
//! error `eps = s - s_m`, `p = P eps` (`A_m' P + P A_m = -Q`) and the
//! normalized firing strengths `h_i`, one step computes, per input `k`,
//!
//! ```text
//! u_k = ( (A_m (s - r))_k - sum_i h_i a_ik' x - d sat(p_k / phi) ) / sum_i h_i b_ik
//! ```
//!
//! then integrates the update laws over the step `dt` (explicit Euler, at the
//! controller rate) and projects every estimate onto its box:
//! `a_ik' = g_a h_i x p_k`, `b_ik' = g_b h_i u_k p_k`, `d' = g_d sum_k |p_k|`.
//! A rate of 0 keeps the quantity at its initial value.
//!
//! The state (estimates and reference model) is owned by the caller; the
//! step allocates nothing and never panics. Non-finite inputs give `u = 0`,
//! an error, and leave the state unchanged. Every sum starts from +0 and adds
//! in index order (the C runtime's `tsf_mrac_step` does the same).
//!
//! [`AdaptiveController`] is what generated code runs: the rules' firing
//! strengths (as [`FactoredController`](crate::FactoredController)) and the
//! law over a fixed period.

use crate::controller::{premises_linear, strengths, Flags, Term};
use crate::factored::{factored_weights, term_degrees};

/// Most inputs (error components) of an adaptive law: the step keeps its
/// work in fixed arrays of this size.
pub const MAX_INPUTS: usize = 8;

/// Adaptation rate and projection box of one adapted quantity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Adaptation {
    /// Rate (0: not adapted).
    pub rate: f64,
    /// Lower projection bound.
    pub lo: f64,
    /// Upper projection bound.
    pub hi: f64,
}

impl Adaptation {
    /// `v + dv` projected onto `[lo, hi]`; `v` when the step is not finite.
    #[allow(clippy::manual_clamp)] // `f64::clamp` panics on bounds lo > hi; this never does
    fn update(&self, v: f64, dv: f64) -> f64 {
        let next = v + self.rate * dv;
        // Not `f64::clamp`: it panics on bad bounds; this never does.
        if !next.is_finite() {
            v
        } else if next < self.lo {
            self.lo
        } else if next > self.hi {
            self.hi
        } else {
            next
        }
    }
}

/// The fixed tables of an adaptive law (row-major matrices).
#[derive(Debug, Clone, Copy)]
pub struct AdaptiveLaw<'a> {
    /// States n.
    pub n: usize,
    /// Inputs m (= error components), at most [`MAX_INPUTS`].
    pub m: usize,
    /// Rules.
    pub rules: usize,
    /// C (m x n).
    pub c: &'a [f64],
    /// A_m (m x m).
    pub a_m: &'a [f64],
    /// P (m x m).
    pub p: &'a [f64],
    /// State-coefficient estimates a_ik (n numbers per rule and input).
    pub a: Adaptation,
    /// Input-gain estimates b_ik (one per rule and input; the box excludes 0).
    pub b: Adaptation,
    /// Disturbance-bound estimate d.
    pub d: Adaptation,
    /// Boundary-layer width phi (> 0).
    pub layer: f64,
}

/// The caller-owned state of an adaptive law.
#[derive(Debug)]
pub struct AdaptiveState<'s> {
    /// a_ik: rule-major, then input, then state (rules x m x n).
    pub a_hat: &'s mut [f64],
    /// b_ik: rule-major (rules x m).
    pub b_hat: &'s mut [f64],
    /// d.
    pub d_hat: &'s mut f64,
    /// Reference-model state s_m (m).
    pub s_m: &'s mut [f64],
}

/// Why a step gave `u = 0` and left the state unchanged.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AdaptiveError {
    /// A slice does not have the law's size (or m > [`MAX_INPUTS`]).
    Shape,
    /// A non-finite input, strength, step or command.
    NonFinite,
}

/// `sat(v) = max(-1, min(1, v))`.
fn sat(v: f64) -> f64 {
    // Constant, ordered bounds: `clamp` cannot panic here.
    v.clamp(-1.0, 1.0)
}

/// `((0 + a_0 b_0) + a_1 b_1) + ...`: every sum of the law starts from +0 and
/// adds in index order (the C runtime's `tsf_adaptive_step` does the same).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).fold(0.0, |acc, (x, y)| acc + x * y)
}

/// `sum_l row_l (s_l - r_l)` from +0, in index order.
fn drift(row: &[f64], s: &[f64], r: &[f64]) -> f64 {
    row.iter()
        .zip(s.iter().zip(r))
        .fold(0.0, |acc, (a, (sl, rl))| acc + a * (sl - rl))
}

impl AdaptiveLaw<'_> {
    fn shapes_fit(&self, st: &AdaptiveState, x: &[f64], h: &[f64], r: &[f64], u: &[f64]) -> bool {
        let (n, m, q) = (self.n, self.m, self.rules);
        m <= MAX_INPUTS
            && n > 0
            && m > 0
            && self.c.len() == m * n
            && self.a_m.len() == m * m
            && self.p.len() == m * m
            && st.a_hat.len() == q * m * n
            && st.b_hat.len() == q * m
            && st.s_m.len() == m
            && x.len() == n
            && h.len() == q
            && r.len() == m
            && u.len() == m
    }

    /// `p = P (C x - s_m)` and `C x`, in fixed arrays.
    fn errors(&self, st: &AdaptiveState, x: &[f64]) -> ([f64; MAX_INPUTS], [f64; MAX_INPUTS]) {
        let mut s = [0.0; MAX_INPUTS];
        let mut eps = [0.0; MAX_INPUTS];
        for (((sk, ek), row), smk) in s
            .iter_mut()
            .zip(eps.iter_mut())
            .zip(self.c.chunks_exact(self.n))
            .zip(st.s_m.iter())
        {
            *sk = dot(row, x);
            *ek = *sk - smk;
        }
        let mut p = [0.0; MAX_INPUTS];
        for (pk, row) in p.iter_mut().zip(self.p.chunks_exact(self.m)) {
            *pk = dot(row, &eps);
        }
        (s, p)
    }

    /// One controller step: writes `u`, then advances the estimates and the
    /// reference model by `dt`. `h` are the normalized firing strengths
    /// (>= 0, summing to 1), `r` the reference input.
    pub fn step(
        &self,
        st: &mut AdaptiveState,
        x: &[f64],
        h: &[f64],
        r: &[f64],
        dt: f64,
        u: &mut [f64],
    ) -> Result<(), AdaptiveError> {
        u.iter_mut().for_each(|v| *v = 0.0);
        if !self.shapes_fit(st, x, h, r, u) {
            return Err(AdaptiveError::Shape);
        }
        let finite = |v: &[f64]| v.iter().all(|z| z.is_finite());
        if !(finite(x) && finite(h) && finite(r) && dt.is_finite() && dt >= 0.0) {
            return Err(AdaptiveError::NonFinite);
        }
        let (n, m) = (self.n, self.m);
        let (s, p) = self.errors(st, x);
        let d_hat = *st.d_hat;
        for (k, uk) in u.iter_mut().enumerate() {
            let mut ax = 0.0;
            let mut bh = 0.0;
            for ((a_rule, b_rule), hi) in st
                .a_hat
                .chunks_exact(m * n)
                .zip(st.b_hat.chunks_exact(m))
                .zip(h)
            {
                ax += hi * a_rule.chunks_exact(n).nth(k).map_or(0.0, |a| dot(a, x));
                bh += hi * b_rule.get(k).copied().unwrap_or(0.0);
            }
            let row = self.a_m.chunks_exact(m).nth(k).unwrap_or(&[]);
            let v = drift(row, &s, r);
            let pk = p.get(k).copied().unwrap_or(0.0);
            let w = d_hat * sat(pk / self.layer);
            *uk = (v - ax - w) / bh;
        }
        if !finite(u) {
            u.iter_mut().for_each(|v| *v = 0.0);
            return Err(AdaptiveError::NonFinite);
        }
        self.adapt(st, x, h, r, &p, u, dt);
        Ok(())
    }

    /// The update laws over `dt`, with projection.
    #[allow(clippy::too_many_arguments)]
    fn adapt(
        &self,
        st: &mut AdaptiveState,
        x: &[f64],
        h: &[f64],
        r: &[f64],
        p: &[f64; MAX_INPUTS],
        u: &[f64],
        dt: f64,
    ) {
        let (n, m) = (self.n, self.m);
        for ((a_rule, b_rule), hi) in st
            .a_hat
            .chunks_exact_mut(m * n)
            .zip(st.b_hat.chunks_exact_mut(m))
            .zip(h)
        {
            for (((a_row, b), pk), uk) in a_rule
                .chunks_exact_mut(n)
                .zip(b_rule.iter_mut())
                .zip(p.iter())
                .zip(u)
            {
                if self.a.rate > 0.0 {
                    for (a, xj) in a_row.iter_mut().zip(x) {
                        *a = self.a.update(*a, dt * hi * xj * pk);
                    }
                }
                if self.b.rate > 0.0 {
                    *b = self.b.update(*b, dt * hi * uk * pk);
                }
            }
        }
        if self.d.rate > 0.0 {
            let sum = p.iter().take(m).fold(0.0, |acc, v| acc + v.abs());
            *st.d_hat = self.d.update(*st.d_hat, dt * sum);
        }
        let mut ds = [0.0; MAX_INPUTS];
        for (dk, row) in ds.iter_mut().zip(self.a_m.chunks_exact(m)) {
            *dk = drift(row, st.s_m, r);
        }
        for (sk, dk) in st.s_m.iter_mut().zip(ds) {
            let next = *sk + dt * dk;
            if next.is_finite() {
                *sk = next;
            }
        }
    }
}

/// The tables of a generated adaptive controller: the premise map and the
/// rule premises (for the firing strengths, as in
/// [`FactoredController`](crate::FactoredController)), the law and its step.
///
/// `N` states, `M` inputs, `P` premise variables, `R` rules, `D` distinct
/// premise terms.
#[derive(Debug, Clone, Copy)]
pub struct AdaptiveController<
    'a,
    const N: usize,
    const M: usize,
    const P: usize,
    const R: usize,
    const D: usize,
> {
    /// Linear premise map `z = L x` used by [`AdaptiveController::step`].
    pub premise_map: [[f64; N]; P],
    /// The distinct premise terms, each evaluated once per step.
    pub terms: [Term<'a, f64>; D],
    /// Rule premises: indices into `terms`, multiplied in order.
    pub rules: [&'a [usize]; R],
    /// Rule centres in premise space (for the no-rule-fired fallback).
    pub centres: [[f64; P]; R],
    /// The adaptive law (its slices sized for `N`, `M`, `R`).
    pub law: AdaptiveLaw<'a>,
    /// Controller period in seconds: the update laws are integrated over it.
    pub dt: f64,
}

/// What one [`AdaptiveController`] step did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AdaptiveStep<const M: usize, const R: usize> {
    /// The command (0 when the step was refused).
    pub u: [f64; M],
    /// Normalized firing strengths (all 0 on a non-finite state or premise).
    pub h: [f64; R],
    /// [`Flags::STATE_NONFINITE`], [`Flags::PREMISE_NONFINITE`] or
    /// [`Flags::NO_RULE_FIRED`] (the nearest rule's strength 1).
    pub flags: Flags,
    /// Why the law refused the step (`u = 0`, state unchanged), if it did.
    pub error: Option<AdaptiveError>,
}

impl<const N: usize, const M: usize, const P: usize, const R: usize, const D: usize>
    AdaptiveController<'_, N, M, P, R, D>
{
    /// One step with premises from the linear map `z = L x`.
    pub fn step(&self, st: &mut AdaptiveState, x: &[f64; N], r: &[f64; M]) -> AdaptiveStep<M, R> {
        let z = premises_linear(&self.premise_map, x);
        self.step_with_premises(st, x, &z, r)
    }

    /// One step with premise values `z` computed by the caller: the firing
    /// strengths of the rules at `z` (a non-finite `x` or `z` refuses the
    /// step with flags, `u = 0` and the state unchanged; no rule firing
    /// gives the nearest rule's strength 1), then [`AdaptiveLaw::step`] over
    /// [`AdaptiveController::dt`].
    pub fn step_with_premises(
        &self,
        st: &mut AdaptiveState,
        x: &[f64; N],
        z: &[f64; P],
        r: &[f64; M],
    ) -> AdaptiveStep<M, R> {
        let mut out = AdaptiveStep {
            u: [0.0; M],
            h: [0.0; R],
            flags: Flags::NONE,
            error: None,
        };
        if !x.iter().all(|v| v.is_finite()) {
            out.flags |= Flags::STATE_NONFINITE;
        }
        if !z.iter().all(|v| v.is_finite()) {
            out.flags |= Flags::PREMISE_NONFINITE;
        }
        if out.flags.is_fault() {
            out.error = Some(AdaptiveError::NonFinite);
            return out;
        }
        let w = factored_weights(&term_degrees(&self.terms, z), &self.rules);
        (out.h, out.flags) = strengths(&w, &self.centres, z);
        out.error = self.law.step(st, x, &out.h, r, self.dt, &mut out.u).err();
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn law<'a>(p: &'a [f64], a_m: &'a [f64], c: &'a [f64]) -> AdaptiveLaw<'a> {
        AdaptiveLaw {
            n: 1,
            m: 1,
            rules: 1,
            c,
            a_m,
            p,
            a: Adaptation {
                rate: 4.0,
                lo: -10.0,
                hi: 0.5,
            },
            b: Adaptation {
                rate: 0.0,
                lo: 0.5,
                hi: 2.0,
            },
            d: Adaptation {
                rate: 1.0,
                lo: 0.0,
                hi: 0.1,
            },
            layer: 0.01,
        }
    }

    #[test]
    fn scalar_step_is_the_certainty_equivalence_law_and_projects() {
        let (p, a_m, c) = ([0.5], [-2.0], [1.0]);
        let l = law(&p, &a_m, &c);
        let (mut a, mut b, mut d, mut sm) = ([0.0], [1.0], 0.0, [0.0]);
        let mut st = AdaptiveState {
            a_hat: &mut a,
            b_hat: &mut b,
            d_hat: &mut d,
            s_m: &mut sm,
        };
        let mut u = [0.0];
        l.step(&mut st, &[1.0], &[1.0], &[0.0], 1.0, &mut u)
            .unwrap();
        // u = (A_m s - a x - d sat(p/phi)) / b = -2 at d = 0.
        assert_eq!(u[0], -2.0);
        // a' = 4 * 1 * 1 * 0.5 = 2 over dt = 1 -> 2, projected to 0.5; d -> 0.5 -> 0.1.
        assert_eq!(a[0], 0.5);
        assert_eq!(d, 0.1);
        assert_eq!(b[0], 1.0);
    }

    /// Two rules on z = x (shoulders meeting at 0, centres -1 and 1).
    fn controller<'a>(l: AdaptiveLaw<'a>) -> AdaptiveController<'a, 1, 1, 1, 2, 2> {
        use crate::Membership;
        AdaptiveController {
            premise_map: [[1.0]],
            terms: [
                Term::Is {
                    var: 0,
                    set: Membership::Trap {
                        a: -10.0,
                        b: -10.0,
                        c: -1.0,
                        d: 1.0,
                    },
                },
                Term::Is {
                    var: 0,
                    set: Membership::Trap {
                        a: -1.0,
                        b: 1.0,
                        c: 10.0,
                        d: 10.0,
                    },
                },
            ],
            rules: [&[0], &[1]],
            centres: [[-1.0], [1.0]],
            law: AdaptiveLaw { rules: 2, ..l },
            dt: 0.1,
        }
    }

    #[test]
    fn controller_step_is_the_law_at_the_rules_strengths() {
        let (p, a_m, c) = ([0.5], [-2.0], [1.0]);
        let ctl = controller(law(&p, &a_m, &c));
        let (mut a, mut b, mut d, mut sm) = ([0.2, -0.1], [1.0, 1.5], 0.0, [0.0]);
        let (mut a2, mut b2, mut d2, mut sm2) = (a, b, d, sm);
        let mut st = AdaptiveState {
            a_hat: &mut a,
            b_hat: &mut b,
            d_hat: &mut d,
            s_m: &mut sm,
        };
        let s = ctl.step(&mut st, &[0.5], &[0.25]);
        assert_eq!((s.h, s.flags, s.error), ([0.25, 0.75], Flags::NONE, None));
        let mut st2 = AdaptiveState {
            a_hat: &mut a2,
            b_hat: &mut b2,
            d_hat: &mut d2,
            s_m: &mut sm2,
        };
        let mut u = [0.0];
        ctl.law
            .step(&mut st2, &[0.5], &[0.25, 0.75], &[0.25], 0.1, &mut u)
            .unwrap();
        assert_eq!(s.u, u);
        assert_eq!((a, b, d, sm), (a2, b2, d2, sm2));
        // Far outside both sets: the nearest rule alone.
        let mut st = AdaptiveState {
            a_hat: &mut a,
            b_hat: &mut b,
            d_hat: &mut d,
            s_m: &mut sm,
        };
        let s = ctl.step(&mut st, &[20.0], &[0.0]);
        assert_eq!(
            (s.h, s.flags, s.error),
            ([0.0, 1.0], Flags::NO_RULE_FIRED, None)
        );
        // A NaN state: zero command, flags, the state held.
        let before = (a, b, d, sm);
        let mut st = AdaptiveState {
            a_hat: &mut a,
            b_hat: &mut b,
            d_hat: &mut d,
            s_m: &mut sm,
        };
        let s = ctl.step(&mut st, &[f64::NAN], &[0.0]);
        assert_eq!(s.u, [0.0]);
        assert_eq!(s.error, Some(AdaptiveError::NonFinite));
        assert!(s.flags.contains(Flags::STATE_NONFINITE) && s.flags.is_fault());
        assert_eq!((a, b, d, sm), before);
    }

    #[test]
    fn non_finite_and_bad_shapes_give_zero_and_keep_the_state() {
        let (p, a_m, c) = ([0.5], [-2.0], [1.0]);
        let l = law(&p, &a_m, &c);
        let (mut a, mut b, mut d, mut sm) = ([0.3], [1.0], 0.05, [0.0]);
        let mut st = AdaptiveState {
            a_hat: &mut a,
            b_hat: &mut b,
            d_hat: &mut d,
            s_m: &mut sm,
        };
        let mut u = [7.0];
        assert_eq!(
            l.step(&mut st, &[f64::NAN], &[1.0], &[0.0], 0.1, &mut u),
            Err(AdaptiveError::NonFinite)
        );
        assert_eq!(u[0], 0.0);
        assert_eq!(
            l.step(&mut st, &[1.0, 2.0], &[1.0], &[0.0], 0.1, &mut u),
            Err(AdaptiveError::Shape)
        );
        // All strengths zero: b_hat blends to 0, the command is not finite.
        assert_eq!(
            l.step(&mut st, &[1.0], &[0.0], &[0.0], 0.1, &mut u),
            Err(AdaptiveError::NonFinite)
        );
        assert_eq!((a[0], d), (0.3, 0.05));
    }
}
