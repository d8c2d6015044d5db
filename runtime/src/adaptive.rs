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
//! an error, and leave the state unchanged.

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

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
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
            let v: f64 = row
                .iter()
                .zip(s.iter().zip(r))
                .map(|(a, (sl, rl))| a * (sl - rl))
                .sum();
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
            let sum: f64 = p.iter().take(m).map(|v| v.abs()).sum();
            *st.d_hat = self.d.update(*st.d_hat, dt * sum);
        }
        let mut ds = [0.0; MAX_INPUTS];
        for (dk, row) in ds.iter_mut().zip(self.a_m.chunks_exact(m)) {
            *dk = row
                .iter()
                .zip(st.s_m.iter().zip(r))
                .map(|(a, (sl, rl))| a * (sl - rl))
                .sum();
        }
        for (sk, dk) in st.s_m.iter_mut().zip(ds) {
            let next = *sk + dt * dk;
            if next.is_finite() {
                *sk = next;
            }
        }
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
