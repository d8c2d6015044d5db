//! Synthesis: a [`TsModel`] and its objectives become PDC gains F_j = M_j X^{-1}.
//!
//! One SDP per [`Plan`] ([`build`]); a maximized decay rate is found by
//! bisection over feasibility problems, an L-inf gain without a fixed phi by a
//! line search over phi ([`search`]). Infeasible specs are diagnosed: each
//! fixed bound is optimized with the others kept, to say what is achievable.
//! When the rules give their gains, the same conditions analyze them instead
//! ([`given`]).
//! Objective families live in [`objectives`], one file each; relaxations in
//! [`relaxations`]. This stage knows nothing about Clarabel: it talks to
//! `tsf_lmi`.

pub mod achieved;
pub mod adaptive;
mod advice;
pub mod bandwidth;
mod blocks;
pub mod build;
pub mod codesign;
mod design;
mod diagnose;
pub mod experimental;
pub mod given;
pub mod l2_channel;
pub mod loop_error;
pub mod loops;
pub mod lyapunov;
pub mod markov;
mod narrowed;
pub mod objective;
pub mod objectives;
pub mod observer;
pub mod pair_stability;
pub mod plan;
pub mod reduction;
pub mod region_auto;
pub mod relaxation;
pub mod relaxations;
mod sampled;
pub mod sampling;
mod search;
pub mod signal_trigger;
pub mod solved;
pub mod transmissions;
pub mod trigger;
mod trigger_region;
pub mod trigger_request;
mod trigger_scale;
pub mod vertices;

pub use crate::util::matrix::rows;
pub use achieved::{Achieved, Quantity};
pub use blocks::common_b;
pub use build::{build, Built};
pub use design::{
    Candidate, Design, SampledDesign, Settings, SolverLog, SynthError, TriggerDesign, Verifier,
};
pub use given::Verdict;
pub use objective::BuildError;
pub use plan::{Bound, Goal, Plan};
pub use reduction::Reduction;
pub use sampled::Block12;
pub use trigger::{TriggerBuilt, TriggerPlan};

use crate::model::TsModel;
pub use search::Runner;

/// Synthesizes gains for `model`'s objectives.
pub fn synthesize(model: &TsModel, settings: &Settings) -> Result<Design, SynthError> {
    synthesize_logged(model, settings).0
}

/// [`synthesize`], with the solver log also when synthesis fails (how many
/// SDPs were solved and what the last one ended on).
pub fn synthesize_logged(
    model: &TsModel,
    settings: &Settings,
) -> (Result<Design, SynthError>, SolverLog) {
    let mut runner = Runner {
        model,
        settings,
        log: SolverLog::default(),
        accept_almost: false,
    };
    let out = synthesize_with(&mut runner).map_err(|e| observer::static_output::advise(model, e));
    let log = std::mem::take(&mut runner.log);
    (
        out.map(|mut d| {
            d.log = log.clone();
            d
        }),
        log,
    )
}

fn synthesize_with(runner: &mut Runner<'_>) -> Result<Design, SynthError> {
    let (model, settings) = (runner.model, runner.settings);
    if let Some(modes) = &model.spec.modes {
        // The mode design is the core; its loop law closes the shipped loop.
        let mut d = markov::synthesize(runner, modes)?;
        let (plan, goal) = plan::initial_plan(&model.spec, settings.default_phi);
        let start = loops::Start { plan, goal };
        let law = loops::law_of(model).design(runner, &mut d, &start);
        d.loop_design = kept(runner, &d, law)?;
        return Ok(d);
    }
    if let Some(x) = experimental::experiment_of(model) {
        return Err(x.run(model, settings));
    }
    let analysis = given::analysis(model);
    let (mut plan, goal) = plan::initial_plan(&model.spec, settings.default_phi);
    let fuzzy = lyapunov::fuzzy::phi(model).is_some();
    if fuzzy {
        plan.mu = Some(lyapunov::fuzzy::choose_mu(runner, &plan, goal)?);
    }
    let outcome = if fuzzy && goal == Goal::MaxDecay {
        lyapunov::fuzzy::max_decay_over_mu(runner, &plan)
    } else {
        runner.run(&plan, goal)
    };
    match outcome {
        Ok(Some(mut d)) => {
            if let Some(f) = &mut d.fuzzy {
                f.region = lyapunov::region::verify(model, &d.gains, &f.p, &f.phi);
                d.notes.push(lyapunov::region::note(f));
            }
            // An observer-based loop's input bound is the augmented one: the
            // levels are checked against it after the observer step.
            let observer_based = model.spec.control.kind == observer::ControlKind::ObserverBased;
            if !observer_based {
                let covered = saturation_covered(model, &mut d);
                kept(runner, &d, covered)?;
            }
            if let Some(note) = objectives::hinf::regional_note(&d) {
                d.notes.push(note);
            }
            if analysis {
                d.verdicts = given::together(&d);
            }
            // The observer first: the sampled observer loop's law certifies it.
            let observed = observer::observe(runner, &mut d);
            kept(runner, &d, observed)?;
            if observer_based {
                let covered = saturation_covered(model, &mut d);
                kept(runner, &d, covered)?;
            }
            let start = loops::Start { plan, goal };
            let law = loops::law_of(model).design(runner, &mut d, &start);
            d.loop_design = kept(runner, &d, law)?;
            if let Some(w) = gain_warning(model, &d) {
                d.notes.push(w);
            }
            Ok(d)
        }
        Ok(None) | Err(SynthError::Solver { .. }) if analysis => Err(runner.alone(&plan)),
        Ok(None) => Err(diagnose::diagnose(runner, &plan)),
        Err(SynthError::Solver { status, .. }) => {
            // No verdict: still say what relaxing each bound achieves.
            let achievable = match diagnose::diagnose(runner, &plan) {
                SynthError::Infeasible { achievable, .. } => achievable,
                _ => Vec::new(),
            };
            Err(SynthError::Solver {
                status,
                message: format!(
                    "the solver stopped ({status}) without proving the objectives feasible or infeasible; they are most likely infeasible or nearly so{}",
                    if plan.fixed_bounds().is_empty() { String::new() } else { format!(" ({})", plan.fixed_bounds().iter().map(|(n, v)| format!("{n} {v}")).collect::<Vec<_>>().join(", ")) }
                ),
                achievable,
            })
        }
        Err(e) => Err(e),
    }
}

/// `step`'s result; when it refuses `d`, the gains and P are kept in the
/// runner's log as the failed report's candidate.
fn kept<T>(
    runner: &mut Runner<'_>,
    d: &Design,
    step: Result<T, SynthError>,
) -> Result<T, SynthError> {
    if let Err(e) = &step {
        runner.log.candidate = Some(design::Candidate {
            gains: d.gains.clone(),
            p: d.p.clone(),
            refused_by: e.first_line(),
        });
    }
    step
}

/// Declared `saturate` levels must be inside the certificate: by the
/// saturation region (asked for or implied, noted), or by a certified input
/// bound no larger than the smallest level (then the actuator never
/// saturates from the certified initial set).
fn saturation_covered(model: &TsModel, d: &mut Design) -> Result<(), SynthError> {
    let Some(levels) = &model.spec.saturation else {
        return Ok(());
    };
    if let Some(s) = d.plan.saturation() {
        if s.implied {
            d.notes.push("saturation region implied by the declared `saturate` levels: the certificate covers the saturated loop on E(P, 1) (write `objective saturation region;` to say so, or bound `input_norm` below the levels)".into());
        }
        return Ok(());
    }
    let smallest = levels.iter().copied().fold(f64::INFINITY, f64::min);
    match d.achieved.get(Quantity::InputNormBound) {
        Some(mu) if mu <= smallest => {
            d.notes.push(format!("the certified input bound {mu:.6} is within the smallest `saturate` level {smallest}: the actuator does not saturate from the certified initial set"));
            Ok(())
        }
        mu => Err(SynthError::Unsupported(format!(
            "the declared `saturate` level {smallest} is outside the certificate: the certified input bound is {}; bound the input with `objective input_norm(u) <= {smallest} for x0 = ...` or add `objective saturation region;`",
            mu.map_or_else(|| "missing".to_string(), |m| format!("{m:.6}"))
        ))),
    }
}

/// Gains this many times above what the smallest `saturate` level allows at
/// the edge of the modelled region (the rules' operating points) draw a warning.
pub const GAIN_WARNING_FACTOR: f64 = 100.0;

/// Gains this many times above the smallest `saturate` level at the edge of
/// the certified set E(P, c) draw a warning: the set is where the design is
/// meant to work, so a smaller factor than [`GAIN_WARNING_FACTOR`].
pub const CERTIFIED_SET_GAIN_FACTOR: f64 = 10.0;

/// A warning when the gains ask for far more than the smallest `saturate`
/// level: the actuator then saturates on almost every sample (certified or
/// not, such a loop is rarely what was meant). Measured, for every rule kind,
/// at the edge of the certified set E(P, c) when the design has one
/// (max over x'Px <= c of |(F_j x)_k| = sqrt(c F_jk P^-1 F_jk'), against
/// [`CERTIFIED_SET_GAIN_FACTOR`]), and at the largest operating-point norm
/// r when the rules have operating points (||F_j||_2 r, against
/// [`GAIN_WARNING_FACTOR`]); the first that exceeds its factor is said.
fn gain_warning(model: &TsModel, d: &Design) -> Option<String> {
    let levels = model.spec.saturation.as_ref()?;
    let level = levels.iter().copied().fold(f64::INFINITY, f64::min);
    let largest = |demand: &dyn Fn(&nalgebra::DMatrix<f64>) -> f64| {
        d.gains
            .iter()
            .map(demand)
            .enumerate()
            .fold(
                (0, 0.0),
                |best, (j, g)| if g > best.1 { (j, g) } else { best },
            )
    };
    let rule = |j: usize| model.rules.get(j).map_or("?", |r| r.name.as_str());
    let certified = d.certified_region().and_then(|(p, c)| {
        let p_inv = p.clone().try_inverse()?;
        let (j, demand) = largest(&|f| {
            f.row_iter()
                .map(|row| {
                    (c * (row * &p_inv * row.transpose())[(0, 0)])
                        .max(0.0)
                        .sqrt()
                })
                .fold(0.0, f64::max)
        });
        (demand > CERTIFIED_SET_GAIN_FACTOR * level).then(|| {
            format!(
                "warning: the gain of rule `{}` asks for |u| up to {demand:.3e} at the edge of the certified set E(P, c), {:.0} times the `saturate` level {level}: the actuator saturates on most of the certified set; bound the input (`objective input_norm(u) <= ..`) or weaken the objectives that set the gains",
                rule(j),
                demand / level
            )
        })
    });
    if certified.is_some() {
        return certified;
    }
    let r = model
        .rules
        .iter()
        .filter_map(|rule| rule.at.as_ref())
        .map(|x| x.iter().map(|v| v * v).sum::<f64>().sqrt())
        .fold(0.0, f64::max);
    let (j, gain) = largest(&|f| f.clone().svd(false, false).singular_values.max());
    let demand = gain * r;
    (r > 0.0 && demand > GAIN_WARNING_FACTOR * level).then(|| {
        format!(
            "warning: the gain of rule `{}` (||F|| = {gain:.3e}) asks for |u| up to {demand:.3e} at the edge of the modelled region (||x|| = {r:.3}), {:.0} times the `saturate` level {level}: the actuator saturates on almost every sample; bound the input (`objective input_norm(u) <= ..`) or the gains",
            rule(j),
            demand / level
        )
    })
}
