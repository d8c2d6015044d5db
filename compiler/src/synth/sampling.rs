//! The sampled loop a spec ships. `trigger periodic { every = h; }` holds the
//! command for h seconds; `trigger aperiodic` without a threshold holds it for
//! any interval in [h_min, h_max], `trigger jittered` for any interval in
//! [h - j, h + j] (its law: [`super::loops::jittered`]). The continuous design's gains F_j (and
//! sector gains G_j under saturation) are certified for that loop with the
//! looped functional of [`super::trigger`] (Seuret, "A novel stability analysis
//! of linear systems under asynchronous samplings", 2012; Xu & Huang 2020) with
//! every sample transmitted (e = 0), phi = 0: the sampled loop is
//! asymptotically stable and, under saturation, E(P, 1) is a region of
//! attraction of it. When the gains are not certified for the spec's
//! sampling, synthesis is refused with the longest sampling interval that is
//! (bisection, re-solved at the advised value).

use super::advice::{about, round_down};
use super::design::{Design, SampledDesign, SolverLog, SynthError, TriggerPlan};
use super::pair_stability;
use super::search::Runner;
use super::solved::{names, Solved};
use super::trigger;
use super::trigger_scale::LoopedSolve;
use crate::model::TsModel;
use nalgebra::DMatrix;
use tsf_lang::limits::MAX_MISMATCH_RULES;
use tsf_lang::spec::{Relaxation, Trigger};

/// Sampling intervals [h_min, h_max] of a loop that transmits every sample,
/// if the spec's trigger is one (periodic, or aperiodic without a threshold
/// and not designed by the event-trigger synthesis).
pub fn wanted(model: &TsModel) -> Option<(f64, f64)> {
    match model.spec.trigger.as_ref().map(|t| &t.node)? {
        Trigger::Periodic { every } => Some((*every, *every)),
        Trigger::Aperiodic {
            sampling,
            threshold: None,
            ..
        } if !trigger::wanted(model) => Some(*sampling),
        _ => None,
    }
}

/// The sampled-loop problem for the gains of `design` with intervals `sampling`.
pub fn plan_for(model: &TsModel, design: &Design, sampling: (f64, f64)) -> TriggerPlan {
    let sat = design.plan.saturation();
    let sector = match sat {
        Some(_) => (0..model.r())
            .map(|j| {
                design
                    .values
                    .sector_product(j)
                    .map_or_else(|| DMatrix::zeros(model.m, model.n), |z| z * &design.p)
            })
            .collect(),
        None => Vec::new(),
    };
    let contain = sat
        .and_then(|s| s.contain.clone())
        .map(|set| ("initial set".to_string(), set))
        .into_iter()
        .collect();
    TriggerPlan {
        sampling,
        event: false,
        linf: false,
        contain,
        nu: 0.0,
        phi: 0.0,
        xi_max: 0.0,
        tau_bar: 0.0,
        levels: sat.map(|s| s.levels.clone()).unwrap_or_default(),
        gains: design.gains.clone(),
        sector,
        d: Vec::new(),
        c: DMatrix::zeros(0, model.n),
        g: DMatrix::zeros(0, 0),
        region: None,
        model_error: super::loop_error::LoopError::of(model),
        dz_input: Vec::new(),
        sector_multiplier: None,
        drift: None,
        observer_bounds: None,
        l2: None,
    }
}

/// What the sampled-loop certificate covers, in words (report and notes).
pub fn covers(plan: &TriggerPlan) -> String {
    let (lo, hi) = plan.sampling;
    let sampling = if lo == hi {
        format!("sampled every {hi} s (zero-order hold)")
    } else {
        format!("sampled at any intervals in [{lo}, {hi}] s (zero-order hold)")
    };
    let region = if plan.levels.is_empty() {
        "asymptotically stable for every state the rules cover".to_string()
    } else {
        "asymptotically stable with the saturating actuator from every state of E(P, 1) (P of this certificate)".to_string()
    };
    format!("the loop {sampling} is {region}; disturbance and performance bounds are certified for the continuous loop only")
}

/// Relative width at which the bisection on the sampling interval stops.
const PERIOD_REL_TOL: f64 = 0.02;

/// The largest scaling s in [1/1024, 1] of the sampling intervals that
/// `certifies` (bisection to [`PERIOD_REL_TOL`]; s = 1 is taken as already
/// refused), or None when even s = 1/1024 does not.
pub(super) fn longest_scale<F>(mut certifies: F) -> Result<Option<f64>, SynthError>
where
    F: FnMut(f64) -> Result<bool, SynthError>,
{
    let lo = 1.0 / 1024.0;
    if !certifies(lo)? {
        return Ok(None);
    }
    bisect(lo, 1.0, certifies).map(Some)
}

/// As [`longest_scale`], but searching down from s = 1/2 by halving (at most
/// 10 solves) before the bisection: the shortest intervals, where the SDP is
/// worst conditioned, are solved only when needed.
pub(super) fn longest_scale_from_above<F>(mut certifies: F) -> Result<Option<f64>, SynthError>
where
    F: FnMut(f64) -> Result<bool, SynthError>,
{
    let mut s = 0.5;
    while !certifies(s)? {
        s *= 0.5;
        if s < 1.0 / 1024.0 {
            return Ok(None);
        }
    }
    bisect(s, 2.0 * s, certifies).map(Some)
}

/// Bisection on [lo, hi] (lo certified, hi not) to [`PERIOD_REL_TOL`]: the
/// largest scaling found certified.
fn bisect<F>(mut lo: f64, mut hi: f64, mut certifies: F) -> Result<f64, SynthError>
where
    F: FnMut(f64) -> Result<bool, SynthError>,
{
    while hi - lo > PERIOD_REL_TOL * hi {
        let mid = 0.5 * (lo + hi);
        if certifies(mid)? {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(lo)
}

/// How a refusal advises a shorter sampling: for the advised longest
/// interval, the intervals it is re-solved at and the trigger text that
/// asks for them.
pub(super) type Advise<'a> = &'a dyn Fn(f64) -> ((f64, f64), String);

/// The trigger text that asks for `sampling` scaled to the longest interval
/// `advice` (`trigger periodic { every = ..; }` or `sampling = .. ..;`).
pub(super) fn write_sampling(sampling: (f64, f64), advice: f64) -> String {
    if sampling.0 == sampling.1 {
        format!("`trigger periodic {{ every = {advice}; }}`")
    } else {
        format!(
            "`sampling = {} .. {advice};`",
            round_down(sampling.0 * advice / sampling.1)
        )
    }
}

impl Runner<'_> {
    /// One sampled-loop SDP: the design, or None when not solved.
    fn sampled_attempt(&mut self, plan: &TriggerPlan) -> Result<Option<SampledDesign>, SynthError> {
        let Some((built, all)) =
            self.solve_looped(plan, "sampled-loop problem", LoopedSolve::default())?
        else {
            return Ok(None);
        };
        Ok(Some(SampledDesign {
            plan: plan.clone(),
            p: all.required(names::LOOP_P)?,
            values: all,
            reductions: built.reductions,
        }))
    }

    /// The sampled-loop certificate for the gains of `design` at the spec's
    /// sampling, or the refusal with the longest sampling that certifies
    /// (advised as `periodic { every }` or `sampling = h_min .. h_max`).
    pub(super) fn sampled(
        &mut self,
        design: &Design,
        sampling: (f64, f64),
    ) -> Result<(SampledDesign, String), SynthError> {
        let scaled = |advice: f64| {
            let s = advice / sampling.1;
            (
                (sampling.0 * s, sampling.1 * s),
                write_sampling(sampling, advice),
            )
        };
        self.sampled_with(design, sampling, &scaled)
    }

    /// [`Runner::sampled`] with the refusal's advice written by `advise`.
    pub(super) fn sampled_with(
        &mut self,
        design: &Design,
        sampling: (f64, f64),
        advise: Advise<'_>,
    ) -> Result<(SampledDesign, String), SynthError> {
        let base = plan_for(self.model, design, sampling);
        if let Some(d) = self.sampled_attempt(&base)? {
            let note = format!("sampled loop certified: {}", covers(&base));
            return Ok((d, note));
        }
        // The longest interval that certifies: scale [h_min, h_max] by s in (0, 1).
        let at = |s: f64| TriggerPlan {
            sampling: (sampling.0 * s, sampling.1 * s),
            ..base.clone()
        };
        let what = if sampling.0 == sampling.1 {
            format!("sampling every {} s", sampling.1)
        } else {
            format!("sampling intervals in [{}, {}] s", sampling.0, sampling.1)
        };
        let Some(lo) = longest_scale(|s| Ok(self.sampled_attempt(&at(s))?.is_some()))? else {
            return Err(self.no_interval_refusal(design, &what));
        };
        if let Some(h) = super::objectives::discrete::period(self.model) {
            return Err(self.discrete_refusal(h, h * lo));
        }
        // Advise a short-printed value, re-solved: advice must certify when used.
        let mut advice = round_down(sampling.1 * lo);
        let mut written = advise(advice);
        for _ in 0..4 {
            let plan = TriggerPlan {
                sampling: written.0,
                ..base.clone()
            };
            if self.sampled_attempt(&plan)?.is_some() {
                break;
            }
            advice = round_down(advice * 0.95);
            written = advise(advice);
        }
        let write = written.1;
        Err(SynthError::Infeasible {
            message: format!("the sampled loop is not certified: the gains of the continuous design are not certified for {what}"),
            achievable: vec![format!(
                "the longest certified sampling interval is about {} s: write {write} (certified), or weaken the objectives that set the gains",
                about(sampling.1 * lo)
            )],
        })
    }

    /// The refusal when not even intervals 1024 times shorter certify the
    /// gains of `design`. When a plant/controller pair is not Hurwitz, no
    /// interval can ([`pair_stability`]): the refusal names the pair and its
    /// eigenvalue and advises gains designed for every pair, re-solved (and
    /// certified) before it is advised.
    fn no_interval_refusal(&mut self, design: &Design, what: &str) -> SynthError {
        let kind = if super::objectives::discrete::period(self.model).is_some() {
            "discrete-time"
        } else {
            "continuous"
        };
        let head = format!(
            "the gains of the {kind} design are not certified for {what}, nor for intervals 1024 times shorter"
        );
        let weaken = "weaken the objectives that set the gains (large gains need fast sampling), or declare a faster trigger";
        match pair_stability::worst(self.model, &design.gains) {
            // NaN (no eigenvalues) is named too.
            Some(w) if w.abscissa >= 0.0 || w.abscissa.is_nan() => SynthError::Infeasible {
                message: format!(
                    "{head}: the sampled loop holds the memberships of the last sample, so its conditions impose every plant/controller rule pair, and {}: no sampling interval certifies these gains",
                    w.describe(self.model)
                ),
                achievable: vec![self.every_pair_advice()],
            },
            worst => {
                let message = match worst {
                    Some(w) => format!(
                        "{head}; every plant/controller pair A_i + B_i F_j is stable (the least stable: {}), but no one Lyapunov matrix certifies them all with the held memberships",
                        w.describe(self.model)
                    ),
                    None => head,
                };
                let advice = self.every_pair_advice();
                let achievable = if advice.starts_with("write") {
                    vec![advice]
                } else {
                    vec![advice, self.slower_decay_advice().unwrap_or_else(|| weaken.into())]
                };
                SynthError::Infeasible {
                    message,
                    achievable,
                }
            }
        }
    }

    /// Advice for gains that leave a plant/controller pair unstable: the
    /// relaxation that designs the gains for every pair,
    /// `membership_mismatch(kappa = 1)`, tried on the whole synthesis (with
    /// its sampled loop) and advised only as what it gave.
    pub(super) fn every_pair_advice(&mut self) -> String {
        let every = Relaxation::MembershipMismatch { kappa: 1.0 };
        let write = format!("`relaxation {every};`");
        let already = matches!(self.model.spec.relaxation.node, Relaxation::MembershipMismatch { kappa } if kappa >= 1.0);
        if already
            || self.model.r() > MAX_MISMATCH_RULES
            || self.model.spec.modes.is_some()
            || super::lyapunov::fuzzy::phi(self.model).is_some()
        {
            return "weaken the objectives that set the gains: every pair must be stable under the held memberships".into();
        }
        let mut model = self.model.clone();
        model.spec.relaxation.node = every;
        match self.resynthesized(&model) {
            Ok(true) => format!(
                "write {write}: it designs the gains for every plant/controller pair (re-solved: certified with the sampled loop), or weaken the objectives that set the gains"
            ),
            Ok(false) => format!(
                "{write} designs the gains for every plant/controller pair; re-solved, it synthesizes but is not certified: weaken the objectives that set the gains"
            ),
            Err(e) => format!(
                "{write} (gains for every plant/controller pair) was tried and is refused too ({}): weaken the objectives that set the gains",
                e.first_line()
            ),
        }
    }

    /// A fixed decay rate that the whole synthesis (with its sampled loop)
    /// certifies: the spec's rate halved, at most 4 times, each re-solved;
    /// None without a fixed decay rate or when none certifies.
    pub(super) fn slower_decay_advice(&mut self) -> Option<String> {
        let at = self.model.spec.objectives.iter().position(|o| {
            matches!(
                o.node,
                tsf_lang::spec::Objective::DecayRate(tsf_lang::spec::Target::Fixed(_))
            )
        })?;
        let tsf_lang::spec::Objective::DecayRate(tsf_lang::spec::Target::Fixed(alpha)) =
            self.model.spec.objectives[at].node
        else {
            return None;
        };
        let mut rate = alpha;
        for _ in 0..4 {
            rate = round_down(rate / 2.0);
            let mut model = self.model.clone();
            model.spec.objectives[at].node =
                tsf_lang::spec::Objective::DecayRate(tsf_lang::spec::Target::Fixed(rate));
            if matches!(self.resynthesized(&model), Ok(true)) {
                return Some(format!(
                    "or write `decay_rate >= {rate}` (re-solved: certified with the sampled loop; the rate sets the gains)"
                ));
            }
        }
        None
    }

    /// The whole synthesis of `model` (its continuous design and its loop),
    /// its SDPs counted in this runner's log: Ok(true) when the certificate's
    /// verdict holds, Ok(false) when synthesized but not certified (or no
    /// verdict is available), the refusal otherwise.
    fn resynthesized(&mut self, model: &TsModel) -> Result<bool, SynthError> {
        let mut runner = Runner {
            model,
            settings: self.settings,
            log: SolverLog::default(),
            accept_almost: false,
        };
        let tried = super::synthesize_with(&mut runner);
        self.log.count_also(&runner.log);
        let d = tried?;
        Ok(match self.settings.verifier {
            Some(verify) => verify(model, &d).unwrap_or(false),
            None => false,
        })
    }

    /// The refusal of a discrete-time design whose gains (designed for the
    /// period `h`) are certified for the shipped loop only up to `reach`. Its
    /// gains depend on the period, so an advised period is designed and
    /// certified again (discretization, synthesis, sampled loop) before it is
    /// advised: at most 4 candidates, each 10 % shorter.
    fn discrete_refusal(&mut self, h: f64, reach: f64) -> SynthError {
        let mut advice = round_down(reach);
        let mut found = None;
        for _ in 0..4 {
            if self.discrete_certifies(advice) {
                found = Some(advice);
                break;
            }
            advice = round_down(advice * 0.9);
        }
        let message = format!("the sampled loop is not certified: the gains designed in discrete time for h = {h} s are certified for the continuous plant sampled every {reach:.4} s at most (the memberships move between samples)");
        let achievable = vec![match found {
            Some(a) => format!("write `trigger periodic {{ every = {a}; design = discrete; }}` (designed and certified at that period), or weaken the objectives that set the gains"),
            None => "no shorter period tried certifies (4 tried, each 10 % shorter): weaken the objectives that set the gains, or use `design = emulation`".into(),
        }];
        SynthError::Infeasible {
            message,
            achievable,
        }
    }

    /// Whether the discrete-time design for the period `h` exists and its
    /// gains are certified for the loop sampled every `h`.
    fn discrete_certifies(&mut self, h: f64) -> bool {
        let mut model = self.model.clone();
        if let Some(t) = model.spec.trigger.as_mut() {
            t.node = Trigger::Periodic { every: h };
        }
        let mut runner = Runner {
            model: &model,
            settings: self.settings,
            log: SolverLog::default(),
            accept_almost: false,
        };
        let (plan, goal) = super::plan::initial_plan(&model.spec, self.settings.default_phi);
        let design = match runner.run(&plan, goal) {
            Ok(Some(d)) => d,
            _ => return false,
        };
        let sampled = runner.sampled_attempt(&plan_for(&model, &design, (h, h)));
        self.log.solves += runner.log.solves;
        self.log.unscaled_retries += runner.log.unscaled_retries;
        matches!(sampled, Ok(Some(_)))
    }
}

#[cfg(test)]
mod tests {
    use super::{longest_scale, longest_scale_from_above, PERIOD_REL_TOL};

    #[test]
    fn both_searches_find_a_threshold_from_below_within_the_tolerance() {
        for edge in [0.9, 0.3, 0.0891, 0.002] {
            let ok = |s: f64| Ok(s <= edge);
            for found in [longest_scale(ok), longest_scale_from_above(ok)] {
                let s = found.expect("no error").expect("found"); // ok: unit test
                assert!(
                    s <= edge && s >= edge * (1.0 - 2.0 * PERIOD_REL_TOL),
                    "{edge}: {s}"
                );
            }
        }
        // Nothing certifies: None, and the descending search stops at 1/1024.
        let mut calls = 0;
        let none = longest_scale_from_above(|_| {
            calls += 1;
            Ok(false)
        });
        assert!(none.expect("no error").is_none()); // ok: unit test
        assert_eq!(calls, 10);
    }
}
