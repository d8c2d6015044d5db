//! The a posteriori check of a fuzzy Lyapunov function's assumption
//! |dh_k/dt| <= phi_k on the closed loop of the T-S model.
//!
//! V(x) = x' P(h(x)) x >= min_k x' P_k x, so the level set L_c = {V <= c} lies
//! in the union of the ellipsoids E_k(c) = {x' P_k x <= c}. If on that union
//! every premise is inside its declared range and |dh_k/dt| <= phi_k for every
//! k, then dV/dt < 0 on L_c \ {0}: L_c is invariant and every trajectory from
//! it converges; the set {max_k x' P_k x <= c} is inside L_c, so it is a
//! certified set of initial states.
//!
//! The check is sampled, not a proof: along [`DIRECTIONS`] rays of each
//! ellipsoid (evenly spaced for n = 2, a fixed pseudo-random set otherwise)
//! it evaluates the memberships through the runtime and dh/dt = grad h . f(x) by a
//! central difference along the closed-loop flow f, at [`STEPS`] radii
//! (geometric, then linear, up to where a premise leaves its range). The
//! largest level c* at which every sample passes is shrunk by [`SHRINK`]
//! (radius factor 0.9) as a margin for the points between samples.

use crate::model::TsModel;
use crate::model::{premise_values, rule_weight};
use nalgebra::{DMatrix, DVector};
use serde::Serialize;

/// Rays per ellipsoid.
pub const DIRECTIONS: usize = 180;
/// Radii per ray (half geometric, half linear).
pub const STEPS: usize = 120;
/// The certified level is c* times this (radius factor 0.9).
pub const SHRINK: f64 = 0.81;
/// Rays are followed at most this far (in the metric of P_k).
const T_CAP: f64 = 1e6;

/// Where the membership-derivative assumption was checked to hold.
#[derive(Debug, Clone, Serialize, PartialEq, schemars::JsonSchema)]
pub struct Region {
    /// The certified level c: on {V <= c} the sampled |dh_k/dt| <= phi_k.
    pub level: f64,
    /// The largest sampled |dh_k/dt| of each rule inside the region.
    pub max_hdot: Vec<f64>,
    /// Samples taken.
    pub samples: usize,
    /// What limits the region: `phi of rule <name>`, `premise range`, or `cap`.
    pub limited_by: String,
}

/// Normalized memberships h(x) through the runtime, and whether every premise
/// is inside its declared range (`None` when no rule fires or a premise
/// cannot be evaluated).
fn memberships(model: &TsModel, x: &[f64]) -> Option<(Vec<f64>, bool)> {
    let z = premise_values(&model.spec, x).ok()?;
    let inside = model.premises.slots.iter().all(|s| {
        z[s.first..s.first + s.dim]
            .iter()
            .all(|v| *v >= s.range.0 && *v <= s.range.1)
    });
    let w: Vec<f64> = model.terms.iter().map(|t| rule_weight(t, &z)).collect();
    let sum: f64 = w.iter().sum();
    (sum > 0.0 && sum.is_finite()).then(|| (w.iter().map(|v| v / sum).collect(), inside))
}

/// The closed-loop vector field of the T-S model, sum_i h_i (A_i + B_i F(h)) x.
fn flow(model: &TsModel, gains: &[DMatrix<f64>], h: &[f64], x: &DVector<f64>) -> DVector<f64> {
    let u = gains
        .iter()
        .zip(h)
        .fold(DVector::zeros(model.m), |acc, (f, hj)| acc + f * x * *hj);
    model
        .rules
        .iter()
        .zip(h)
        .fold(DVector::zeros(model.n), |acc, (rule, hi)| {
            acc + (&rule.a * x + &rule.b * &u) * *hi
        })
}

/// What one sample says: out of the premise box, or |dh_k/dt| per rule.
enum Sample {
    Outside,
    Hdot(Vec<f64>),
}

/// The memberships' time derivatives at `x` (central difference along the flow).
fn sample(model: &TsModel, gains: &[DMatrix<f64>], x: &DVector<f64>) -> Sample {
    let Some((h, inside)) = memberships(model, x.as_slice()) else {
        return Sample::Outside;
    };
    if !inside {
        return Sample::Outside;
    }
    let f = flow(model, gains, &h, x);
    let fnorm = f.norm();
    if fnorm == 0.0 {
        return Sample::Hdot(vec![0.0; h.len()]);
    }
    let s = 1e-6 * (1.0 + x.norm()) / fnorm;
    let (Some((hp, _)), Some((hm, _))) = (
        memberships(model, (x + &f * s).as_slice()),
        memberships(model, (x - &f * s).as_slice()),
    ) else {
        return Sample::Outside;
    };
    Sample::Hdot(
        hp.iter()
            .zip(&hm)
            .map(|(a, b)| ((a - b) / (2.0 * s)).abs())
            .collect(),
    )
}

/// Unit directions in R^n: evenly spaced on the circle for n = 2, +-1 for
/// n = 1, a fixed pseudo-random set (xorshift, Box-Muller) otherwise.
fn directions(n: usize) -> Vec<DVector<f64>> {
    match n {
        1 => vec![
            DVector::from_element(1, 1.0),
            DVector::from_element(1, -1.0),
        ],
        2 => (0..DIRECTIONS)
            .map(|k| {
                let a = 2.0 * std::f64::consts::PI * k as f64 / DIRECTIONS as f64;
                DVector::from_vec(vec![a.cos(), a.sin()])
            })
            .collect(),
        _ => {
            let mut s = 0x9E37_79B9_7F4A_7C15u64;
            let mut uniform = move || {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                ((s >> 11) as f64 + 0.5) / (1u64 << 53) as f64
            };
            (0..DIRECTIONS * n)
                .map(|_| {
                    let v = DVector::from_fn(n, |_, _| {
                        let (u1, u2) = (uniform(), uniform());
                        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
                    });
                    let norm = v.norm();
                    v / norm
                })
                .collect()
        }
    }
}

/// The first distance along `d` (points t d) at which a premise leaves its
/// range, found by doubling then bisection ([`T_CAP`] if none).
fn exit_distance(model: &TsModel, d: &DVector<f64>) -> f64 {
    let out = |t: f64| memberships(model, (d * t).as_slice()).is_none_or(|(_, inside)| !inside);
    let mut hi = 1e-6;
    while !out(hi) {
        hi *= 2.0;
        if hi > T_CAP {
            return T_CAP;
        }
    }
    let mut lo = 0.0;
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if out(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    lo
}

/// Checks the assumption on level sets of V for the design's gains and
/// P_k; `None` when no level c > 0 passes (the design is then refused).
pub fn verify(
    model: &TsModel,
    gains: &[DMatrix<f64>],
    p: &[DMatrix<f64>],
    phi: &[f64],
) -> Option<Region> {
    let r = model.r();
    let dirs = directions(model.n);
    // Samples along every ray of every ellipsoid: (t^2 in the metric of P_k, |dh/dt|).
    let mut seen: Vec<(f64, Vec<f64>)> = Vec::new();
    let mut c_star = f64::INFINITY;
    let mut limited_by = "cap".to_string();
    let mut samples = 0;
    for pk in p {
        let chol = pk.clone().cholesky()?;
        // x = t L^{-T} u has x' P_k x = t^2 |u|^2.
        let lt_inv = chol.l().transpose().try_inverse()?;
        for u in &dirs {
            let d = &lt_inv * u;
            let t_exit = exit_distance(model, &d);
            let half = STEPS / 2;
            let mut ts: Vec<f64> = (1..=half)
                .map(|k| t_exit * 10f64.powf(-6.0 * (1.0 - k as f64 / half as f64)))
                .chain((1..=half).map(|k| t_exit * k as f64 / half as f64))
                .collect();
            ts.sort_by(f64::total_cmp);
            let mut good = 0.0;
            let mut stop = if t_exit < T_CAP {
                Some("premise range".to_string())
            } else {
                None
            };
            for &t in &ts {
                samples += 1;
                match sample(model, gains, &(&d * t)) {
                    Sample::Outside => {
                        stop = Some("premise range".into());
                        break;
                    }
                    Sample::Hdot(hd) => {
                        if let Some(k) = (0..r).find(|&k| hd[k] > phi[k]) {
                            stop = Some(format!("phi of rule {}", model.rules[k].name));
                            break;
                        }
                        good = t;
                        seen.push((t * t, hd));
                    }
                }
            }
            let c = if stop.is_some() {
                good * good
            } else {
                T_CAP * T_CAP
            };
            if c < c_star {
                c_star = c;
                limited_by = stop.unwrap_or_else(|| "cap".into());
            }
        }
    }
    let level = SHRINK * c_star;
    if !(level > 0.0 && level.is_finite()) {
        return None;
    }
    let mut max_hdot = vec![0.0f64; r];
    for (t2, hd) in &seen {
        if *t2 <= level {
            for (m, v) in max_hdot.iter_mut().zip(hd) {
                *m = m.max(*v);
            }
        }
    }
    Some(Region {
        level,
        max_hdot,
        samples,
        limited_by,
    })
}

/// The report note of a fuzzy Lyapunov design: what it is certified under and
/// where that was checked.
pub fn note(f: &super::FuzzyDesign) -> String {
    let phi: Vec<String> = f.phi.iter().map(|v| format!("{v}")).collect();
    match &f.region {
        Some(r) => format!(
            "fuzzy Lyapunov function (mu = {}): certified under |dh_k/dt| <= phi_k = [{}]; a sampled check ({} samples) finds that it holds on the level set V(x) = x' P(h) x <= {:.6e} (limited by {}), so initial states with max_k x' P_k x <= {:.6e} are certified; largest sampled |dh_k/dt| there: [{}]",
            f.mu,
            phi.join(", "),
            r.samples,
            r.level,
            r.limited_by,
            r.level,
            r.max_hdot
                .iter()
                .map(|v| format!("{v:.4}"))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        None => format!(
            "fuzzy Lyapunov function (mu = {}): the LMIs hold under |dh_k/dt| <= phi_k = [{}], but no level set of V was found on which the closed loop keeps that bound: refused",
            f.mu,
            phi.join(", ")
        ),
    }
}
