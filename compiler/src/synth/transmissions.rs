//! A design for few transmissions (`weight = synthesize transmissions(points
//! = N, gamma = g);`, docs/event_trigger.md "Few transmissions").
//!
//! Transmissions of an event-triggered loop are set mostly by the gains'
//! stiffness, and every gamma-minimizing route stiffens them. This search
//! starts from the two-step design at the spec's certified threshold and runs
//! up to N co-design points, each
//!
//! - a gain step ([`GainGoal::Soften`]): P, Y, T known from the last trigger
//!   step; one common gain F, G, L1, L2, Upsilon, xi, gamma and the stiffness
//!   bound kappa unknown; minimize kappa subject to ||B_i F||_2 <= kappa, the
//!   trigger conditions at the threshold and gamma <= g;
//! - a trigger step (the unchanged [`super::trigger`] problem for those
//!   gains at the threshold, minimizing gamma): the certified point.
//!
//! The last trigger step's point is feasible for the next gain step, so the
//! stiffness does not increase from point to point: the points sweep the
//! stiffness bound downwards until it stalls (less than
//! [`super::codesign::CODESIGN_REL_TOL`] in a point) or N points are done.
//! When the driver hands in a [`super::design::Scorer`] (the simulator, run
//! on the spec's scenario), each point's transmissions are counted and the
//! point within the bound with the fewest ships (ties: the later, softer
//! point); without one, the softest point within the bound ships.

use super::codesign::{stiffness, GainGoal, CODESIGN_REL_TOL};
use super::design::{Design, SynthError, TriggerDesign};
use super::search::Runner;
use super::trigger::{self, certified_threshold, TriggerPlan};
use serde::Serialize;
use std::time::Instant;

/// One point of the few-transmissions search, for the report and the docs'
/// trade-off table.
#[derive(Debug, Clone, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Point {
    /// 0: the two-step start; k: after the k-th gain step.
    pub point: u32,
    /// Certified threshold of the point's trigger step.
    pub nu: f64,
    /// Its certified event-triggered L-inf gamma.
    pub gamma: f64,
    /// Largest ||F_j||_2 of its gains.
    pub gain_norm: f64,
    /// Its stiffness max_i ||B_i F_j||_2 (what the gain steps minimize).
    pub stiffness: f64,
    /// Transmissions in the spec's scenario (null without a scenario or a scorer).
    pub transmissions: Option<u64>,
    /// Whether gamma is within the search's bound.
    pub within_bound: bool,
    /// Whether this point's design ships.
    pub shipped: bool,
    /// Seconds of its gain step and trigger step.
    pub seconds: f64,
}

impl Point {
    fn of(
        model: &crate::model::TsModel,
        point: u32,
        t: &TriggerDesign,
        bound: f64,
        s: f64,
    ) -> Self {
        let gain_norm = t
            .plan
            .gains
            .iter()
            .map(|f| f.clone().singular_values().max())
            .fold(0.0, f64::max);
        let stiff = t
            .plan
            .gains
            .iter()
            .map(|f| stiffness(model, f))
            .fold(0.0, f64::max);
        Point {
            point,
            nu: t.plan.nu,
            gamma: t.gamma,
            gain_norm,
            stiffness: stiff,
            transmissions: None,
            within_bound: t.gamma <= bound,
            shipped: false,
            seconds: s,
        }
    }
}

/// The index of the point that ships: within the bound, fewest transmissions
/// (ties and missing counts: the later point), else the last within the bound.
pub fn pick(points: &[Point]) -> Option<usize> {
    let within = || points.iter().enumerate().filter(|(_, p)| p.within_bound);
    let counted = within()
        .filter_map(|(i, p)| p.transmissions.map(|t| (t, i)))
        .min_by_key(|&(t, i)| (t, std::cmp::Reverse(i)));
    counted
        .map(|(_, i)| i)
        .or_else(|| within().map(|(i, _)| i).next_back())
}

/// The trade-off table of a search, one line per point (report notes and summary).
pub fn table(points: &[Point]) -> String {
    points
        .iter()
        .map(|p| {
            format!(
                "{}{}: nu {:.4}, gamma {:.4}{}, max ||F|| {:.2}, stiffness {:.4}, transmissions {} ({:.1} s)",
                p.point,
                if p.shipped { " (shipped)" } else { "" },
                p.nu,
                p.gamma,
                if p.within_bound { "" } else { " (over the bound)" },
                p.gain_norm,
                p.stiffness,
                p.transmissions.map_or("-".into(), |t| t.to_string()),
                p.seconds
            )
        })
        .collect::<Vec<_>>()
        .join("; ")
}

impl Runner<'_> {
    /// The few-transmissions search from the continuous `design`: the
    /// shipped trigger design (its plan carries the gains, its `search` the
    /// points) and notes. `points` gain steps at most; `gamma` the bound
    /// (default: the two-step design's gamma).
    pub(super) fn transmissions(
        &mut self,
        design: &Design,
        points: u32,
        gamma: Option<f64>,
    ) -> Result<(TriggerDesign, Vec<String>), SynthError> {
        let base = trigger::plan_for(self.model, design)?;
        let target = certified_threshold(self.model);
        let t0 = Instant::now();
        let Some(start) = self.trigger_attempt(&TriggerPlan {
            nu: target,
            ..base.clone()
        })?
        else {
            return Err(SynthError::Infeasible {
                message: format!(
                    "few-transmissions design: the gains of the continuous design are not certified for aperiodic sampling in [{}, {}] s at nu = {target}, so the search has no start",
                    base.sampling.0, base.sampling.1
                ),
                achievable: vec!["lower the threshold, shorten h_max, or add a premise `region`".into()],
            });
        };
        let bound = gamma.unwrap_or(start.gamma);
        let mut found = vec![Point::of(
            self.model,
            0,
            &start,
            bound,
            t0.elapsed().as_secs_f64(),
        )];
        let mut designs = vec![start];
        let mut stopped = format!("{points} points done");
        for k in 1..=points {
            let last = designs.last().cloned().ok_or_else(|| {
                SynthError::Internal("few-transmissions search without a start".into())
            })?;
            let t1 = Instant::now();
            let goal = GainGoal::Soften {
                gamma_cap: bound.max(last.gamma),
            };
            let Some(step) = self.gain_step(&last.plan, &last, goal)? else {
                stopped = format!("point {k}: the gain step gave no solution");
                break;
            };
            let plan = TriggerPlan {
                nu: target,
                gains: step.gains,
                sector: step.sector,
                ..last.plan.clone()
            };
            let Some(next) = self.trigger_attempt(&plan)? else {
                stopped =
                    format!("point {k}: the trigger step for the softer gains gave no solution");
                break;
            };
            let p = Point::of(self.model, k, &next, bound, t1.elapsed().as_secs_f64());
            let before = found.last().map_or(f64::INFINITY, |q| q.stiffness);
            let stalled = before - p.stiffness <= CODESIGN_REL_TOL * before;
            found.push(p);
            designs.push(next);
            if stalled {
                stopped = format!(
                    "point {k}: the stiffness fell by less than {}%",
                    CODESIGN_REL_TOL * 100.0
                );
                break;
            }
        }
        if let Some(score) = self.settings.scorer {
            for (p, t) in found.iter_mut().zip(&designs) {
                p.transmissions = score(self.model, design, t)?;
            }
        }
        let Some(i) = pick(&found) else {
            let best = found.iter().map(|p| p.gamma).fold(f64::INFINITY, f64::min);
            return Err(SynthError::Infeasible {
                message: format!(
                    "few-transmissions design: no point certifies the event-triggered gamma <= {bound} (best {best:.4}; stopped at {stopped})"
                ),
                achievable: vec![
                    format!("write `gamma = {}` or more", super::advice::round_up(best)),
                    format!("points: {}", table(&found)),
                ],
            });
        };
        found[i].shipped = true;
        let (mut shipped, grown) = self.grow_region(designs.swap_remove(i), bound)?;
        let mut notes = Vec::new();
        if let Some(note) = grown {
            let sent = match self.settings.scorer {
                Some(score) => score(self.model, design, &shipped)?,
                None => None,
            };
            notes.push(format!(
                "{note}; transmissions of the design on that box: {}",
                sent.map_or("-".into(), |t| t.to_string())
            ));
        }
        notes.push(format!(
            "few-transmissions design for nu(t_k) <= {target} and event-triggered gamma <= {bound}: point {i} ships (L-inf gamma {:.6}, xi {:.6}), stopped at {stopped}; points (point: nu, gamma, max ||F||, stiffness max ||B F||, transmissions in the spec's scenario, seconds): {}",
            shipped.gamma,
            shipped.xi,
            table(&found)
        ));
        shipped.method = "transmissions";
        shipped.search = found;
        Ok((shipped, notes))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(k: u32, within: bool, sent: Option<u64>) -> Point {
        Point {
            point: k,
            nu: 0.25,
            gamma: 0.1,
            gain_norm: 1.0,
            stiffness: 1.0,
            transmissions: sent,
            within_bound: within,
            shipped: false,
            seconds: 0.0,
        }
    }

    #[test]
    fn pick_prefers_fewest_transmissions_within_the_bound() {
        let pts = [
            point(0, true, Some(200)),
            point(1, true, Some(90)),
            point(2, false, Some(50)),
            point(3, true, Some(120)),
        ];
        assert_eq!(pick(&pts), Some(1));
        let tie = [point(0, true, Some(90)), point(1, true, Some(90))];
        assert_eq!(pick(&tie), Some(1));
    }

    #[test]
    fn pick_without_counts_takes_the_softest_within_the_bound() {
        let pts = [
            point(0, true, None),
            point(1, true, None),
            point(2, false, None),
        ];
        assert_eq!(pick(&pts), Some(1));
        assert_eq!(pick(&[point(0, false, None)]), None);
    }
}
