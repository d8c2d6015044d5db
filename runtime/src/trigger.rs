//! Transmission/sampling trigger primitives: small state machines with a
//! `const fn new` and a `decide` method, no allocation.
//!
//! Conventions shared by the event triggers: the first call always transmits
//! (there is no previous transmission); a comparison that cannot be decided
//! because of NaN transmits (so a faulty measurement reaches the controller,
//! which flags it, and the trigger recovers as soon as samples are finite
//! again); the stored "last transmitted" value is updated on every
//! transmission.

use crate::Real;

/// `v' U v = sum_i v_i (sum_j U_ij v_j)` (index order, from 0).
pub fn quad_form<T: Real, const N: usize>(u: &[[T; N]; N], v: &[T; N]) -> T {
    u.iter().zip(v).fold(T::ZERO, |acc, (row, &vi)| {
        let r = row
            .iter()
            .zip(v)
            .fold(T::ZERO, |a, (&uij, &vj)| a + uij * vj);
        acc + vi * r
    })
}

/// Euclidean norm `sqrt(sum v_i^2)` (no rescaling: overflow gives `+inf`).
pub fn norm<T: Real>(v: &[T]) -> T {
    v.iter().fold(T::ZERO, |acc, &vi| acc + vi * vi).sqrt()
}

/// Element-wise `a - b`.
fn sub<T: Real, const N: usize>(a: &[T; N], b: &[T; N]) -> [T; N] {
    let mut d = [T::ZERO; N];
    for ((di, &ai), &bi) in d.iter_mut().zip(a).zip(b) {
        *di = ai - bi;
    }
    d
}

/// Periodic sampling: transmit on the first tick and then every `every`
/// ticks of the caller's base rate (`every = 0` behaves as 1). Periods are
/// integer multiples of the base tick so there is no floating-point drift;
/// the compiler chooses `every = round(h / dt)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PeriodicTrigger {
    every: u32,
    count: u32,
}

impl PeriodicTrigger {
    /// Transmit every `every` ticks, starting with the first.
    pub const fn new(every: u32) -> Self {
        PeriodicTrigger { every, count: 0 }
    }

    /// Advance one tick; `true` if this tick transmits.
    pub fn decide(&mut self) -> bool {
        let fire = self.count == 0;
        self.count = self.count.saturating_add(1);
        if self.count >= self.every {
            self.count = 0;
        }
        fire
    }
}

/// Static relative trigger (Xu & Huang 2020, condition (10) with constant
/// `nu`; Peng & Zhang 2015): at a sampling instant with state `x`, let
/// `x_k` be the last transmitted state and `e = x - x_k`; transmit iff
/// `e' U e >= nu * x_k' U x_k` (evaluated as `!(lhs < rhs)`, so NaN
/// transmits).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RelativeTrigger<T, const N: usize> {
    /// Weight matrix `U` (`Upsilon` in the paper), symmetric PSD.
    pub weight: [[T; N]; N],
    /// Threshold `nu >= 0`.
    pub nu: T,
    last: [T; N],
    has_last: bool,
}

impl<T: Real, const N: usize> RelativeTrigger<T, N> {
    /// Trigger with weight `U` and threshold `nu`; nothing transmitted yet.
    pub const fn new(weight: [[T; N]; N], nu: T) -> Self {
        RelativeTrigger {
            weight,
            nu,
            last: [T::ZERO; N],
            has_last: false,
        }
    }

    /// Last transmitted state `x(t_k)`, if any.
    pub fn last(&self) -> Option<&[T; N]> {
        if self.has_last {
            Some(&self.last)
        } else {
            None
        }
    }

    /// Check sample `x`; on `true` it becomes the last transmitted state.
    pub fn decide(&mut self, x: &[T; N]) -> bool {
        self.decide_with_error(x).is_some()
    }

    /// Like [`Self::decide`], returning the transmitted jump
    /// `x(t_{k+1}) - x(t_k)` (`None` if no transmission; zeros on the first).
    fn decide_with_error(&mut self, x: &[T; N]) -> Option<[T; N]> {
        if !self.has_last {
            self.last = *x;
            self.has_last = true;
            return Some([T::ZERO; N]);
        }
        let e = sub(x, &self.last);
        let lhs = quad_form(&self.weight, &e);
        let rhs = self.nu * quad_form(&self.weight, &self.last);
        if lhs < rhs {
            None
        } else {
            self.last = *x;
            Some(e)
        }
    }
}

/// Xu & Huang (2020) aperiodic event trigger with adaptive threshold.
///
/// Condition (10): at sampling instant `t_k^l` transmit iff
/// `e' U e >= nu(t_k) x(t_k)' U x(t_k)`, `e = x(t_k^l) - x(t_k)`
/// (see [`RelativeTrigger`]). After each transmission (text following
/// (10)):
///
/// `nu(t_{k+1}) = max{ nu(t_k) (1 - (2 mu1/pi) atan[mu2 (||x(t_{k+1}) -
/// x(t_k)|| - mu3)]), nu_min }`, `nu(0) = nu_min`, `mu1, mu2, mu3 >= 0`,
/// `nu_min in [0, 1)` (paper values: `nu = 0.2, mu1 = 10, mu2 = 1,
/// mu3 = 0.02`).
///
/// Evaluated as `g = (mu1 * (2/pi)) * atan(mu2 * (||e|| - mu3))`,
/// `cand = nu * (1 - g)`, `||.||` Euclidean. Floating-point additions to the
/// law: `cand` is clamped to `<= nu_max` ([`AdaptiveTrigger::with_max`];
/// `T::MAX` by default: the law is unbounded above and an infinite `nu` would
/// make `nu * 0` NaN), and a NaN `cand` resets `nu` to `nu_min`. A stability
/// certificate obtained for `nu <= nu_cert` holds for the adaptive law only
/// with `nu_max = nu_cert`. The first transmission has no previous state and leaves
/// `nu` unchanged.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptiveTrigger<T, const N: usize> {
    inner: RelativeTrigger<T, N>,
    /// `mu1`: gain of the update.
    pub mu1: T,
    /// `mu2`: slope inside the atan.
    pub mu2: T,
    /// `mu3`: jump size at which `nu` stays constant.
    pub mu3: T,
    /// Lower bound `nu_min` (the paper's underlined nu), also `nu(0)`.
    pub nu_min: T,
    /// Upper bound `nu_max` of the law (`T::MAX` unless set by [`AdaptiveTrigger::with_max`]).
    pub nu_max: T,
}

impl<T: Real, const N: usize> AdaptiveTrigger<T, N> {
    /// Trigger with weight `U`, `nu(0) = nu_min` and parameters `mu1..mu3`.
    pub const fn new(weight: [[T; N]; N], nu_min: T, mu1: T, mu2: T, mu3: T) -> Self {
        AdaptiveTrigger {
            inner: RelativeTrigger::new(weight, nu_min),
            mu1,
            mu2,
            mu3,
            nu_min,
            nu_max: T::MAX,
        }
    }

    /// The same trigger with `nu(t_k)` kept `<= nu_max` (`nu_max >= nu_min`;
    /// a smaller value is raised to `nu_min`).
    pub const fn with_max(mut self, nu_max: T) -> Self {
        self.nu_max = nu_max;
        self
    }

    /// Current threshold `nu(t_k)`.
    pub fn nu(&self) -> T {
        self.inner.nu
    }

    /// Last transmitted state `x(t_k)`, if any.
    pub fn last(&self) -> Option<&[T; N]> {
        self.inner.last()
    }

    /// Check sample `x` against (10); on transmission update `nu`.
    pub fn decide(&mut self, x: &[T; N]) -> bool {
        let first = !self.inner.has_last;
        let Some(e) = self.inner.decide_with_error(x) else {
            return false;
        };
        if !first {
            let g = (self.mu1 * T::FRAC_2_PI) * (self.mu2 * (norm(&e) - self.mu3)).atan();
            let cand = self.inner.nu * (T::ONE - g);
            self.inner.nu = if cand >= self.nu_min {
                if cand > self.nu_max {
                    // nu_max < nu_min (misuse) keeps nu_min.
                    if self.nu_max >= self.nu_min {
                        self.nu_max
                    } else {
                        self.nu_min
                    }
                } else {
                    cand
                }
            } else {
                // Below the bound, or NaN.
                self.nu_min
            };
        }
        true
    }
}

/// Amrr et al. (2019) mixed relative/absolute trigger, condition (28):
/// `t_{i+1} = min{ t >= t_i : ||Xi|| >= beta ||sigma|| + rho }` with
/// `Xi = sigma(t_i) - sigma` (27), `sigma` the current feedback vector and
/// `sigma(t_i)` the last transmitted one. In the paper `sigma` is the
/// single feedback vector (25) `sigma = omega + alpha p + alpha (p'p) p`
/// (angular velocity `omega`, MRP `p`; see [`amrr_sigma`]); here any
/// `K`-vector can be used (e.g. the state). Transmit iff
/// `!(||Xi|| < beta ||sigma|| + rho)`, norms Euclidean.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MixedTrigger<T, const K: usize> {
    /// Relative coefficient `beta` (0 < beta < 1 in the paper).
    pub beta: T,
    /// Absolute offset `rho > 0` (excludes Zeno behaviour, (73)).
    pub rho: T,
    last: [T; K],
    has_last: bool,
}

impl<T: Real, const K: usize> MixedTrigger<T, K> {
    /// Trigger with `beta` and `rho`; nothing transmitted yet.
    pub const fn new(beta: T, rho: T) -> Self {
        MixedTrigger {
            beta,
            rho,
            last: [T::ZERO; K],
            has_last: false,
        }
    }

    /// Last transmitted vector `sigma(t_i)`, if any.
    pub fn last(&self) -> Option<&[T; K]> {
        if self.has_last {
            Some(&self.last)
        } else {
            None
        }
    }

    /// Whether [`Self::decide`] would transmit `sigma` now (nothing changes):
    /// a monitor locating the crossing inside a step asks this.
    pub fn would_transmit(&self, sigma: &[T; K]) -> bool {
        if !self.has_last {
            return true;
        }
        let xi = norm(&sub(&self.last, sigma));
        let threshold = self.beta * norm(sigma) + self.rho;
        // NaN anywhere: not `<`, so it transmits.
        if xi < threshold {
            return false;
        }
        true
    }

    /// Check the current `sigma`; on `true` it becomes `sigma(t_i)`.
    pub fn decide(&mut self, sigma: &[T; K]) -> bool {
        if !self.would_transmit(sigma) {
            return false;
        }
        self.last = *sigma;
        self.has_last = true;
        true
    }
}

/// The mixed trigger on a signal of the state (Amrr et al. 2019 with `sigma = s(x)`):
/// the sensor computes `s(x)` each call, checks the law on it, and on a
/// transmission sends (and holds) the **state** `x(t_i)`, from which the controller
/// computes `u = PDC(x(t_i))`; `s(x(t_i))` is kept for the next comparisons.
/// NaN policy of [`MixedTrigger`]: a NaN signal transmits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SignalTrigger<T, const N: usize, const K: usize> {
    /// The law on the signal.
    pub law: MixedTrigger<T, K>,
    held: [T; N],
}

impl<T: Real, const N: usize, const K: usize> SignalTrigger<T, N, K> {
    /// Trigger with `beta` and `rho`; nothing transmitted yet.
    pub const fn new(beta: T, rho: T) -> Self {
        SignalTrigger {
            law: MixedTrigger::new(beta, rho),
            held: [T::ZERO; N],
        }
    }

    /// Checks state `x` with its signal `s = s(x)`: `Some(x)` when it is
    /// transmitted (it becomes the held `x(t_i)`), `None` otherwise.
    pub fn decide(&mut self, x: &[T; N], s: &[T; K]) -> Option<[T; N]> {
        if self.law.decide(s) {
            self.held = *x;
            Some(*x)
        } else {
            None
        }
    }

    /// The held state `x(t_i)`, if any was transmitted.
    pub fn last(&self) -> Option<&[T; N]> {
        self.law.last().map(|_| &self.held)
    }
}

/// Amrr et al. (2019) feedback vector (25):
/// `sigma_i = (omega_i + alpha p_i) + (alpha (p'p)) p_i`.
pub fn amrr_sigma<T: Real>(omega: &[T; 3], p: &[T; 3], alpha: T) -> [T; 3] {
    let pp = p.iter().fold(T::ZERO, |acc, &v| acc + v * v);
    let k = alpha * pp;
    let mut s = [T::ZERO; 3];
    for ((si, &wi), &pi) in s.iter_mut().zip(omega).zip(p) {
        *si = (wi + alpha * pi) + k * pi;
    }
    s
}
