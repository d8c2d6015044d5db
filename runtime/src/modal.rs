//! The mode-dependent controller of a design with Markov-switching modes
//! (actuator faults): one gain set per mode, the active mode given by the
//! caller (fault detection) at every step.
//!
//! [`ModalController::step`] is [`FactoredController::step`](crate::FactoredController::step)
//! with the gain set of the active mode: the same premise terms, strengths,
//! blend and saturation, operation for operation. A mode index outside
//! `0 .. K` selects mode 0 and raises [`Flags::MODE_OUT_OF_RANGE`]; nothing
//! panics.

use crate::controller::{premises_linear, run, Flags, Step, Term};
use crate::factored::{factored_weights, term_degrees};
use crate::Real;

/// The gain set to use for `mode` among `k` modes: `(mode, NONE)` when
/// `mode < k`, else `(0, MODE_OUT_OF_RANGE)`.
#[inline]
pub const fn select_mode(mode: u8, k: usize) -> (usize, Flags) {
    if (mode as usize) < k {
        (mode as usize, Flags::NONE)
    } else {
        (0, Flags::MODE_OUT_OF_RANGE)
    }
}

/// A T-S PDC controller with one gain set per mode.
///
/// `N` states, `M` inputs, `P` premise variables, `R` rules, `D` distinct
/// premise terms, `K` modes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModalController<
    'a,
    T,
    const N: usize,
    const M: usize,
    const P: usize,
    const R: usize,
    const D: usize,
    const K: usize,
> {
    /// Linear premise map `z = L x` used by [`ModalController::step`].
    pub premise_map: [[T; N]; P],
    /// The distinct premise terms, each evaluated once per step.
    pub terms: [Term<'a, T>; D],
    /// Rule premises: indices into `terms`, multiplied in order.
    pub rules: [&'a [usize]; R],
    /// Rule centres in premise space (for the no-rule-fired fallback).
    pub centres: [[T; P]; R],
    /// PDC gains `F_aj` (`M x N`, row-major): per mode `a`, one per rule `j`.
    pub gains: [[[[T; N]; M]; R]; K],
    /// Saturation levels `u_bar_s` (`+inf` for an unlimited channel).
    pub u_max: [T; M],
}

impl<
        T: Real,
        const N: usize,
        const M: usize,
        const P: usize,
        const R: usize,
        const D: usize,
        const K: usize,
    > ModalController<'_, T, N, M, P, R, D, K>
{
    /// Evaluate in mode `mode` with premises from the linear map `z = L x`.
    #[inline]
    pub fn step(&self, mode: u8, x: &[T; N]) -> Step<T, M, R> {
        let z = premises_linear(&self.premise_map, x);
        self.step_with_premises(mode, x, &z)
    }

    /// Rule weights at premise vector `z` (distinct terms evaluated once).
    #[inline]
    pub fn weights(&self, z: &[T; P]) -> [T; R] {
        factored_weights(&term_degrees(&self.terms, z), &self.rules)
    }

    /// Evaluate in mode `mode` with premise values `z` computed by the
    /// caller. The edge cases are
    /// [`Controller::step_with_premises`](crate::Controller::step_with_premises)'s;
    /// an out-of-range `mode` uses mode 0's gains and adds
    /// [`Flags::MODE_OUT_OF_RANGE`] (with `K == 0` there is no gain set: the
    /// command is 0).
    #[inline]
    pub fn step_with_premises(&self, mode: u8, x: &[T; N], z: &[T; P]) -> Step<T, M, R> {
        let (a, flag) = select_mode(mode, K);
        let mut step = match self.gains.get(a) {
            Some(gains) => run(x, z, |z| self.weights(z), &self.centres, gains, &self.u_max),
            None => Step {
                u: [T::ZERO; M],
                h: [T::ZERO; R],
                flags: Flags::NONE,
            },
        };
        step.flags |= flag;
        step
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{FactoredController, Membership};

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

    fn modal() -> ModalController<'static, f64, 2, 1, 1, 2, 2, 2> {
        ModalController {
            premise_map: [[1.0, 0.0]],
            terms: TERMS,
            rules: [&R1, &R2],
            centres: [[-1.0], [1.0]],
            gains: [
                [[[-1.0, -2.0]], [[-3.0, -0.5]]],
                [[[-4.0, -1.0]], [[-0.25, -6.0]]],
            ],
            u_max: [5.0],
        }
    }

    fn factored(a: usize) -> FactoredController<'static, f64, 2, 1, 1, 2, 2> {
        let m = modal();
        FactoredController {
            premise_map: m.premise_map,
            terms: m.terms,
            rules: m.rules,
            centres: m.centres,
            gains: m.gains[a],
            u_max: m.u_max,
        }
    }

    #[test]
    fn each_mode_is_the_factored_controller_with_its_gains() {
        let m = modal();
        for x in [[0.3, -0.7], [1.5, 2.0], [-5.0, 1.0], [f64::NAN, 0.0]] {
            for a in 0..2u8 {
                let s = m.step(a, &x);
                let f = factored(a as usize).step(&x);
                assert_eq!(s.u.map(f64::to_bits), f.u.map(f64::to_bits));
                assert_eq!(s.h.map(f64::to_bits), f.h.map(f64::to_bits));
                assert_eq!(s.flags, f.flags);
            }
        }
    }

    #[test]
    fn an_out_of_range_mode_uses_mode_0_and_raises_its_flag() {
        let m = modal();
        let x = [0.3, -0.7];
        for bad in [2u8, 3, 200, u8::MAX] {
            let s = m.step(bad, &x);
            let f = factored(0).step(&x);
            assert_eq!(s.u, f.u);
            assert!(s.flags.contains(Flags::MODE_OUT_OF_RANGE));
            assert_eq!(s.flags.0 & !Flags::MODE_OUT_OF_RANGE.0, f.flags.0);
        }
        assert!(!m.step(1, &x).flags.contains(Flags::MODE_OUT_OF_RANGE));
        // A NaN state in an unknown mode: both flags, zero command.
        let s = m.step(9, &[f64::NAN, 0.0]);
        assert!(s.flags.contains(Flags::MODE_OUT_OF_RANGE) && s.flags.is_fault());
        assert_eq!(s.u, [0.0]);
        assert_eq!(select_mode(0, 0), (0, Flags::MODE_OUT_OF_RANGE));
    }

    #[test]
    fn no_modes_give_a_zero_command() {
        let m: ModalController<'static, f64, 2, 1, 1, 2, 2, 0> = ModalController {
            premise_map: [[1.0, 0.0]],
            terms: TERMS,
            rules: [&R1, &R2],
            centres: [[-1.0], [1.0]],
            gains: [],
            u_max: [5.0],
        };
        let s = m.step(0, &[1.0, 1.0]);
        assert_eq!(s.u, [0.0]);
        assert_eq!(s.flags, Flags::MODE_OUT_OF_RANGE);
    }
}
