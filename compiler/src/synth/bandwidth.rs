//! A two-parameter gain family for few transmissions (docs/event_trigger.md,
//! "Few transmissions"): the LQR gain of the rule nearest the origin with
//! state weight Q = I + c sqrt(r) Pi_B and input weight R = r B'B, Pi_B the
//! projector onto range(B), swept in r (the bandwidth) for c in
//! [`DAMPING`].
//!
//! Charging an input for the state rate it causes (|B u|^2) makes the family
//! depend on range(B) only: on a rigid body (B = [J^-1; 0]) every member is
//! a J-scaled PD law, the shape a hand-tuned attitude loop has, and a larger
//! r is a lower closed-loop bandwidth, i.e. a softer, less often transmitting
//! loop. The extra weight c sqrt(r) on the directly actuated states keeps the
//! damping as r grows: on the double integrator c = 1 is critical damping
//! for large r, c = 0 gives damping ratio 1/sqrt(2). The search certifies
//! members with the unchanged trigger step; they are placed by their
//! stiffness max_i ||B_i F|| (the quantity the soften route minimizes),
//! halving from the start design's, then the softest member within the
//! gamma bound is refined by bisection in log r.
//!
//! The Riccati equation is solved by Kleinman's Newton iteration (Kleinman,
//! "On an iterative technique for Riccati equation computations", 1968) from
//! a stabilizing gain, each step a Lyapunov equation
//! ([`super::adaptive::lyapunov::solve`]).

use super::adaptive::lyapunov;
use super::codesign::stiffness;
use crate::model::TsModel;
use nalgebra::DMatrix;

/// Members of the family the search certifies per damping weight (stiffness
/// 1/2, 1/4, ..., 1/2^k of the start design's); docs/limits.md.
pub const MEMBERS: u32 = 6;

/// Bisection steps in log r between the softest member within the bound and
/// the next, softer one (per damping weight); docs/limits.md.
pub const BISECTIONS: u32 = 3;

/// The damping weights c of the family.
pub const DAMPING: [f64; 2] = [0.0, 1.0];

/// States above which the family is not computed (each Newton step is an
/// n^2 x n^2 LU); docs/limits.md.
pub const MAX_STATES: usize = 16;

/// Newton steps of one Riccati solve at most.
const NEWTON_STEPS: usize = 60;

/// Relative change of the gain at which Newton's iteration has converged.
const NEWTON_TOL: f64 = 1e-12;

/// Values of r tried to place the members: 10^(k/8), k = -40 ..= 80.
const R_GRID: std::ops::RangeInclusive<i32> = -40..=80;

/// The local model (A, B) the family is designed on: the rule whose
/// operating point is nearest the origin, else the mean of the rules.
pub fn nominal(model: &TsModel) -> (DMatrix<f64>, DMatrix<f64>) {
    let nearest = model
        .rules
        .iter()
        .filter_map(|r| {
            r.at.as_ref()
                .map(|at| (at.iter().map(|v| v * v).sum::<f64>(), r))
        })
        .min_by(|a, b| a.0.total_cmp(&b.0));
    if let Some((_, r)) = nearest {
        return (r.a.clone(), r.b.clone());
    }
    let k = model.rules.len().max(1) as f64;
    let a = model
        .rules
        .iter()
        .fold(DMatrix::zeros(model.n, model.n), |s, r| s + &r.a)
        / k;
    let b = model
        .rules
        .iter()
        .fold(DMatrix::zeros(model.n, model.m), |s, r| s + &r.b)
        / k;
    (a, b)
}

/// The LQR gain F (u = F x) of (a, b) for x'(I + c sqrt(r) Pi_B) x + r |B u|^2,
/// by Newton's iteration from the stabilizing gain `f0`; `None` when B'B is
/// singular or an iterate is not stabilizing.
pub fn lqr(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    (r, c): (f64, f64),
    f0: &DMatrix<f64>,
) -> Option<DMatrix<f64>> {
    let btb = b.transpose() * b;
    let btb_inv = btb.clone().try_inverse()?;
    let weight = &btb * r;
    let inv = &btb_inv / r;
    let projector = b * &btb_inv * b.transpose();
    let q = DMatrix::identity(a.nrows(), a.nrows()) + projector * (c * r.sqrt());
    let mut f = f0.clone();
    for _ in 0..NEWTON_STEPS {
        let closed = a + b * &f;
        let cost = &q + f.transpose() * &weight * &f;
        let p = lyapunov::solve(&closed, &cost).ok()?.p;
        let next = -(&inv * b.transpose() * p);
        let change = (&next - &f).norm() / next.norm().max(f64::MIN_POSITIVE);
        f = next;
        if change <= NEWTON_TOL {
            return Some(f);
        }
    }
    None
}

/// The family of one damping weight `c` on a model: its nominal (A, B) and
/// gains from Newton's iteration, each started from the nearest computed one.
pub struct Family {
    a: DMatrix<f64>,
    b: DMatrix<f64>,
    c: f64,
    /// (r, F, stiffness) on the grid of r, increasing r.
    grid: Vec<(f64, DMatrix<f64>, f64)>,
}

impl Family {
    /// The family with damping weight `c`; `f0` stabilizes the nominal model.
    pub fn new(model: &TsModel, f0: &DMatrix<f64>, c: f64) -> Self {
        let (a, b) = nominal(model);
        let mut grid = Vec::new();
        let mut from = f0.clone();
        for k in R_GRID.take_while(|_| model.n <= MAX_STATES) {
            let r = 10f64.powf(f64::from(k) / 8.0);
            if let Some(f) = lqr(&a, &b, (r, c), &from) {
                let s = stiffness(model, &f);
                from = f.clone();
                grid.push((r, f, s));
            }
        }
        Family { a, b, c, grid }
    }

    /// Up to [`MEMBERS`] members (r, F) with stiffness nearest 1/2, 1/4, ...
    /// of `start_stiffness`, softest last.
    pub fn members(&self, start_stiffness: f64) -> Vec<(f64, DMatrix<f64>)> {
        let mut out: Vec<(f64, DMatrix<f64>)> = Vec::new();
        for k in 1..=MEMBERS {
            let target = start_stiffness / 2f64.powi(k as i32);
            let best = self.grid.iter().min_by(|x, y| {
                (x.2 / target)
                    .ln()
                    .abs()
                    .total_cmp(&(y.2 / target).ln().abs())
            });
            if let Some((r, f, _)) = best {
                if !out.iter().any(|(q, _)| q == r) {
                    out.push((*r, f.clone()));
                }
            }
        }
        out
    }

    /// The member at `r` (Newton started from the grid's nearest gain).
    pub fn at(&self, r: f64) -> Option<DMatrix<f64>> {
        let (_, from, _) = self
            .grid
            .iter()
            .min_by(|x, y| (x.0 / r).ln().abs().total_cmp(&(y.0 / r).ln().abs()))?;
        lqr(&self.a, &self.b, (r, self.c), from)
    }

    /// Its damping weight c.
    pub fn damping(&self) -> f64 {
        self.c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One axis of a rigid body: w' = u / j, q' = w / 2.
    fn axis(j: f64) -> (DMatrix<f64>, DMatrix<f64>) {
        let a = DMatrix::from_row_slice(2, 2, &[0.0, 0.0, 0.5, 0.0]);
        let b = DMatrix::from_row_slice(2, 1, &[1.0 / j, 0.0]);
        (a, b)
    }

    #[test]
    fn lqr_matches_the_closed_form_and_scales_with_the_inertia() {
        // For v = u / j, x'x + r v^2 on w' = v, q' = w/2, the Riccati solution
        // gives v = -(kd w + kp q) with kp = 1/sqrt(r) and
        // kd = sqrt((1 + sqrt(r)) / r) (the 2 x 2 ARE solved by hand:
        // p2 = sqrt(r), p1 = sqrt(r (1 + p2)), p3 = 2 p1 p2 / r).
        for (j, r) in [(1.0, 1.0), (350.0, 4.0), (190.0, 100.0)] {
            let (a, b) = axis(j);
            let f0 = DMatrix::from_row_slice(1, 2, &[-j, -j]);
            let f = lqr(&a, &b, (r, 0.0), &f0).expect("converges");
            let kp = 1.0 / r.sqrt();
            let kd = ((1.0 + r.sqrt()) / r).sqrt();
            assert!((f[(0, 0)] + j * kd).abs() <= 1e-9 * j, "{f} kd {kd}");
            assert!((f[(0, 1)] + j * kp).abs() <= 1e-9 * j, "{f} kp {kp}");
            let closed = &a + &b * &f;
            let re = lyapunov::eigenvalue_real_parts(&closed).expect("eigenvalues");
            assert!(re.iter().all(|x| *x < 0.0), "{re:?}");
        }
    }

    #[test]
    fn the_damping_weight_gives_critical_damping_for_slow_loops() {
        // Q = diag(1 + c sqrt(r), 1): kd = sqrt((1 + c sqrt(r) + sqrt(r)) / r);
        // the closed loop q'' + kd q' + kp q / 2 = 0 has damping ratio
        // kd / (2 sqrt(kp / 2)) -> 1 for c = 1 and r large.
        let (a, b) = axis(350.0);
        let f0 = DMatrix::from_row_slice(1, 2, &[-350.0, -350.0]);
        for r in [1e2, 1e4] {
            let f = lqr(&a, &b, (r, 1.0), &f0).expect("converges");
            let (kd, kp) = (-f[(0, 0)] / 350.0, -f[(0, 1)] / 350.0);
            let exact = ((1.0 + 2.0 * r.sqrt()) / r).sqrt();
            assert!((kd - exact).abs() <= 1e-9 * exact, "kd {kd} vs {exact}");
            assert!((kp - 1.0 / r.sqrt()).abs() <= 1e-9 * kp);
            let zeta = kd / (2.0 * (kp / 2.0).sqrt());
            assert!((1.0..1.0 + 1.0 / r.sqrt()).contains(&zeta), "zeta {zeta}");
        }
    }

    #[test]
    fn lqr_refuses_a_destabilizing_start() {
        let (a, b) = axis(1.0);
        let f0 = DMatrix::from_row_slice(1, 2, &[1.0, 1.0]);
        assert!(lqr(&a, &b, (1.0, 0.0), &f0).is_none());
    }
}
