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

use super::bandwidth;
use super::codesign::{stiffness, GainGoal, CODESIGN_REL_TOL};
use super::design::{Design, SynthError, TriggerDesign};
use super::search::Runner;
use super::trigger::{self, certified_threshold, TriggerPlan};
use serde::Serialize;
use std::time::Instant;

/// With `region z = auto`, the share of the gamma goal a point may use on the
/// seed box to be shipped; the rest is left for growing the box
/// (docs/limits.md).
pub const REGION_HEADROOM: f64 = 0.75;

/// One point of the few-transmissions search, for the report and the docs'
/// trade-off table.
#[derive(Debug, Clone, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Point {
    /// 0: the two-step start; then the points in the order they were made.
    pub point: u32,
    /// How its gains were made: `two-step`, `soften` (a gain step) or
    /// `lqr r = ..` (a member of [`super::bandwidth`]'s family).
    pub route: String,
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
        (point, route): (u32, String),
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
            route,
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
                "{} {}{}: nu {:.4}, gamma {:.4}{}, max ||F|| {:.2}, stiffness {:.4}, transmissions {} ({:.1} s)",
                p.point,
                p.route,
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
        let goal = gamma.unwrap_or(start.gamma);
        // With `region z = auto` the points are scored on the seed box and
        // the shipped one's box is grown until gamma reaches the goal: keep
        // headroom for that growth.
        let bound = if super::region_auto::wanted(self.model) {
            REGION_HEADROOM * goal
        } else {
            goal
        };
        let mut found = vec![Point::of(
            self.model,
            (0, "two-step".into()),
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
            let p = Point::of(
                self.model,
                (k, "soften".into()),
                &next,
                bound,
                t1.elapsed().as_secs_f64(),
            );
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
        self.bandwidth_points(&mut found, &mut designs, bound, target)?;
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
        let (mut shipped, grown) = self.grow_region(designs.swap_remove(i), goal)?;
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
            "few-transmissions design for nu(t_k) <= {target} and event-triggered gamma <= {goal} (points scored at gamma <= {bound} on the seed box): point {i} ships (L-inf gamma {:.6}, xi {:.6}), stopped at {stopped}; points (point: nu, gamma, max ||F||, stiffness max ||B F||, transmissions in the spec's scenario, seconds): {}",
            shipped.gamma,
            shipped.xi,
            table(&found)
        ));
        shipped.method = "transmissions";
        shipped.search = found;
        Ok((shipped, notes))
    }
}

impl Runner<'_> {
    /// Appends the certified members of the LQR bandwidth family
    /// ([`super::bandwidth`]) at the threshold `nu`: one common gain, the
    /// start design's trigger plan otherwise; per damping weight, the members
    /// halving the start's stiffness, then a bisection in log r between the
    /// softest member within the bound and the next, softer one.
    fn bandwidth_points(
        &mut self,
        found: &mut Vec<Point>,
        designs: &mut Vec<TriggerDesign>,
        bound: f64,
        nu: f64,
    ) -> Result<(), SynthError> {
        let (Some(start), Some(first)) = (designs.first().cloned(), found.first()) else {
            return Ok(());
        };
        let start_stiffness = first.stiffness;
        let (a, _) = bandwidth::nominal(self.model);
        // The start's gain of the rule the family is designed on stabilizes it.
        let f0 = self
            .model
            .rules
            .iter()
            .position(|r| r.a == a)
            .and_then(|i| start.plan.gains.get(i))
            .or(start.plan.gains.first())
            .cloned()
            .ok_or_else(|| SynthError::Internal("few-transmissions start without gains".into()))?;
        for c in bandwidth::DAMPING {
            let family = bandwidth::Family::new(self.model, &f0, c);
            // (r, within the bound) of the members tried, increasing r.
            let mut tried: Vec<(f64, bool)> = Vec::new();
            for (r, f) in family.members(start_stiffness) {
                let ok = self.bandwidth_point(found, designs, (&start, bound, nu), (r, c), f)?;
                tried.push((r, ok));
            }
            let softest = tried.iter().rposition(|t| t.1);
            let (Some(i), Some(&(r_hi, _))) = (softest, softest.and_then(|i| tried.get(i + 1)))
            else {
                continue;
            };
            let (mut lo, mut hi) = (tried[i].0.ln(), r_hi.ln());
            for _ in 0..bandwidth::BISECTIONS {
                let r = (0.5 * (lo + hi)).exp();
                let Some(f) = family.at(r) else { break };
                if self.bandwidth_point(found, designs, (&start, bound, nu), (r, c), f)? {
                    lo = r.ln();
                } else {
                    hi = r.ln();
                }
            }
        }
        Ok(())
    }

    /// Certifies the member (r, c) with gain `f` at the start's plan and
    /// threshold; appends it when certified. Whether it is within the bound.
    fn bandwidth_point(
        &mut self,
        found: &mut Vec<Point>,
        designs: &mut Vec<TriggerDesign>,
        (start, bound, nu): (&TriggerDesign, f64, f64),
        (r, c): (f64, f64),
        f: nalgebra::DMatrix<f64>,
    ) -> Result<bool, SynthError> {
        let t = Instant::now();
        let plan = TriggerPlan {
            nu,
            gains: vec![f; self.model.r()],
            ..start.plan.clone()
        };
        let Some(next) = self.trigger_attempt(&plan)? else {
            return Ok(false);
        };
        let k = found.len() as u32;
        let p = Point::of(
            self.model,
            (k, format!("lqr r = {r:.4e}, c = {c}")),
            &next,
            bound,
            t.elapsed().as_secs_f64(),
        );
        let within = p.within_bound;
        found.push(p);
        designs.push(next);
        Ok(within)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(k: u32, within: bool, sent: Option<u64>) -> Point {
        Point {
            point: k,
            route: "soften".into(),
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
