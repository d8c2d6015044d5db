//! The observer-based PDC controller (output feedback): a fuzzy observer of
//! the state runs inside the controller at its period `T`.
//!
//! Continuous design (Tanaka & Wang 2001, ch. 5): the estimate follows
//! `xhat' = sum_i h_i ((A_i - L_i C) xhat + B_i u + L_i y)`; the compiler
//! discretizes every rule exactly at the period (zero-order hold on `u` and
//! `y`, memberships frozen at the sample) into `Phi_i`, `Gu_i`, `Gy_i`, and
//! [`Observer::step`] runs, with `xhat_k` the caller-owned estimate:
//!
//! 1. premises `z` from the measured output (`z = L (S y)`, `S` the
//!    [`Observer::output_map`]) or from the estimate (`z = L xhat_k`);
//! 2. fault check: any non-finite `y_k` or `xhat_k` raises
//!    [`Flags::STATE_NONFINITE`], any non-finite `z_p`
//!    [`Flags::PREMISE_NONFINITE`]; then `u = 0`, `h = 0`, and the estimate
//!    is kept, except a non-finite estimate, which is reset to 0
//!    ([`Flags::ESTIMATE_RESET`]);
//! 3. strengths, blend and saturation of
//!    [`FactoredController`]: `u_k = sat(sum_j h_j F_j xhat_k)`;
//! 4. update, rule-major, rules whose `h_i` is not `> 0` skipped:
//!    `xhat_{k+1} = sum_i h_i ((Phi_i xhat_k + Gu_i u_k) + Gy_i y_k)`, each
//!    product a dot product in index order, accumulated from 0 as
//!    `e_r = e_r + h_i * v_r`; a non-finite result resets the estimate to 0
//!    ([`Flags::ESTIMATE_RESET`]).

use crate::controller::{premises_linear, run, Flags, Step};
use crate::factored::FactoredController;
use crate::Real;

/// `sum_k a_k b_k` in index order from the first product (0 when empty),
/// the runtime's dot product.
#[inline]
fn dot<T: Real>(a: &[T], b: &[T]) -> T {
    let mut terms = a.iter().zip(b).map(|(&ai, &bi)| ai * bi);
    let first = terms.next().unwrap_or(T::ZERO);
    terms.fold(first, |acc, t| acc + t)
}

/// An observer-based T-S PDC controller: the controller's tables plus the
/// discretized observer of every rule.
///
/// `N` states, `M` inputs, `Q` measured outputs, `P` premise variables,
/// `R` rules, `D` distinct premise terms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Observer<
    'a,
    T,
    const N: usize,
    const M: usize,
    const Q: usize,
    const P: usize,
    const R: usize,
    const D: usize,
> {
    /// Premises, rules, gains `F_j` and saturation; its `premise_map` is the
    /// premise map `z = L v` of the state-like vector `v`
    /// ([`Observer::premise_state`]).
    pub controller: FactoredController<'a, T, N, M, P, R, D>,
    /// `Some(S)` (N x Q): the premises read the measured output, `v = S y`
    /// (the measured components of the state put back in their places);
    /// `None`: the premises read the estimate, `v = xhat`.
    pub output_map: Option<[[T; Q]; N]>,
    /// `Phi_i = expm((A_i - L_i C) T)` (N x N), one per rule.
    pub phi: [[[T; N]; N]; R],
    /// `Gu_i = int_0^T expm((A_i - L_i C) s) ds B_i` (N x M), one per rule.
    pub gu: [[[T; M]; N]; R],
    /// `Gy_i = int_0^T expm((A_i - L_i C) s) ds L_i` (N x Q), one per rule.
    pub gy: [[[T; Q]; N]; R],
}

/// `true` if every component is finite.
#[inline]
fn finite<T: Real>(v: &[T]) -> bool {
    v.iter().all(|x| x.is_finite())
}

impl<
        T: Real,
        const N: usize,
        const M: usize,
        const Q: usize,
        const P: usize,
        const R: usize,
        const D: usize,
    > Observer<'_, T, N, M, Q, P, R, D>
{
    /// The state-like vector the premises are computed from: `S y` when the
    /// premises read the output (each component a dot product), else `xhat`.
    #[inline]
    pub fn premise_state(&self, xhat: &[T; N], y: &[T; Q]) -> [T; N] {
        match &self.output_map {
            Some(s) => {
                let mut v = [T::ZERO; N];
                for (vk, row) in v.iter_mut().zip(s) {
                    *vk = dot(row, y);
                }
                v
            }
            None => *xhat,
        }
    }

    /// One step with linear premises `z = L v`, `v` from
    /// [`Observer::premise_state`]: returns `u_k` (and the strengths and
    /// flags) and advances the estimate `xhat` to `xhat_{k+1}`.
    #[inline]
    pub fn step(&self, xhat: &mut [T; N], y: &[T; Q]) -> Step<T, M, R> {
        let v = self.premise_state(xhat, y);
        let z = premises_linear(&self.controller.premise_map, &v);
        self.step_with_premises(xhat, y, &z)
    }

    /// One step with the premise vector `z` computed by the caller (from
    /// [`Observer::premise_state`] by the spec's premise expressions).
    pub fn step_with_premises(&self, xhat: &mut [T; N], y: &[T; Q], z: &[T; P]) -> Step<T, M, R> {
        let mut flags = Flags::NONE;
        let estimate_ok = finite(xhat);
        if !(finite(y) && estimate_ok) {
            flags |= Flags::STATE_NONFINITE;
        }
        if !finite(z) {
            flags |= Flags::PREMISE_NONFINITE;
        }
        if flags.is_fault() {
            if !estimate_ok {
                *xhat = [T::ZERO; N];
                flags |= Flags::ESTIMATE_RESET;
            }
            return Step {
                u: [T::ZERO; M],
                h: [T::ZERO; R],
                flags,
            };
        }
        let c = &self.controller;
        let step = run(xhat, z, |z| c.weights(z), &c.centres, &c.gains, &c.u_max);
        let next = self.update(&step.h, xhat, &step.u, y);
        let mut out = step;
        if finite(&next) {
            *xhat = next;
        } else {
            *xhat = [T::ZERO; N];
            out.flags |= Flags::ESTIMATE_RESET;
        }
        out
    }

    /// `sum_i h_i ((Phi_i xhat + Gu_i u) + Gy_i y)`, rules whose `h_i` is not
    /// `> 0` skipped, accumulated from 0 rule by rule.
    #[inline]
    pub fn update(&self, h: &[T; R], xhat: &[T; N], u: &[T; M], y: &[T; Q]) -> [T; N] {
        let mut e = [T::ZERO; N];
        let blocks = self.phi.iter().zip(&self.gu).zip(&self.gy);
        for (&hi, ((phi, gu), gy)) in h.iter().zip(blocks) {
            // Rules that do not fire (h_i not > 0, NaN included) are skipped.
            if hi.partial_cmp(&T::ZERO) != Some(core::cmp::Ordering::Greater) {
                continue;
            }
            for (((er, pr), ur), yr) in e.iter_mut().zip(phi).zip(gu).zip(gy) {
                let a = dot(pr, xhat);
                let b = dot(ur, u);
                let c = dot(yr, y);
                let v = (a + b) + c;
                *er += hi * v;
            }
        }
        e
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Membership, Term};

    static TERMS: [Term<'static, f64>; 2] = [
        Term::Is {
            var: 0,
            set: Membership::Tri {
                a: -2.0,
                b: -1.0,
                c: 1.0,
            },
        },
        Term::Is {
            var: 0,
            set: Membership::Tri {
                a: -1.0,
                b: 1.0,
                c: 2.0,
            },
        },
    ];
    static R1: [usize; 1] = [0];
    static R2: [usize; 1] = [1];

    fn observer(from_output: bool) -> Observer<'static, f64, 2, 1, 1, 1, 2, 2> {
        Observer {
            controller: FactoredController {
                premise_map: [[1.0, 0.0]],
                terms: TERMS,
                rules: [&R1, &R2],
                centres: [[-1.0], [1.0]],
                gains: [[[-1.0, -2.0]], [[-3.0, -0.5]]],
                u_max: [5.0],
            },
            output_map: from_output.then_some([[1.0], [0.0]]),
            phi: [[[0.9, 0.1], [-0.2, 0.8]], [[0.7, 0.05], [0.0, 0.95]]],
            gu: [[[0.0], [0.1]], [[0.01], [0.2]]],
            gy: [[[0.1], [0.3]], [[0.25], [0.02]]],
        }
    }

    #[test]
    fn one_step_by_hand() {
        let o = observer(true);
        let mut xhat = [0.5, -0.25];
        let y = [0.0];
        let s = o.step(&mut xhat, &y);
        // z = y = 0: h = (0.5, 0.5).
        assert_eq!(s.h, [0.5, 0.5]);
        let f1 = -0.5 + 0.5;
        let f2 = -1.5 + 0.125;
        let u = 0.5 * f1 + 0.5 * f2;
        assert_eq!(s.u, [u]);
        let r1 = [0.9 * 0.5 - 0.1 * 0.25, -0.2 * 0.5 - 0.8 * 0.25 + 0.1 * u];
        let r2 = [0.7 * 0.5 - 0.05 * 0.25 + 0.01 * u, -0.95 * 0.25 + 0.2 * u];
        for k in 0..2 {
            assert!((xhat[k] - (0.5 * r1[k] + 0.5 * r2[k])).abs() < 1e-15);
        }
        // From the estimate, z = xhat_0 = 0.5: other strengths.
        let mut xe = [0.5, -0.25];
        let s2 = observer(false).step(&mut xe, &y);
        assert_eq!(s2.h, [0.25, 0.75]);
    }

    #[test]
    fn faults_keep_a_finite_estimate_and_reset_a_broken_one() {
        let o = observer(true);
        let mut xhat = [0.5, -0.25];
        let s = o.step(&mut xhat, &[f64::NAN]);
        assert_eq!(s.u, [0.0]);
        assert!(s.flags.contains(Flags::STATE_NONFINITE));
        assert!(!s.flags.contains(Flags::ESTIMATE_RESET));
        assert_eq!(xhat, [0.5, -0.25]);
        let mut bad = [f64::INFINITY, 0.0];
        let s = o.step(&mut bad, &[0.1]);
        assert_eq!(s.u, [0.0]);
        assert!(s
            .flags
            .contains(Flags::STATE_NONFINITE | Flags::ESTIMATE_RESET));
        assert_eq!(bad, [0.0, 0.0]);
        // An update that overflows resets the estimate.
        let mut o2 = observer(true);
        o2.phi[0][0][0] = 4.0;
        o2.phi[1][0][0] = 4.0;
        let mut big = [1e308, 0.0];
        let s = o2.step(&mut big, &[0.0]);
        assert!(s.flags.contains(Flags::ESTIMATE_RESET), "{:?}", s.flags);
        assert_eq!(big, [0.0, 0.0]);
        // Premises from the estimate: a NaN estimate is a premise fault too.
        let mut nan = [f64::NAN, 0.0];
        let s = observer(false).step(&mut nan, &[0.1]);
        assert!(s
            .flags
            .contains(Flags::PREMISE_NONFINITE | Flags::ESTIMATE_RESET));
    }
}
