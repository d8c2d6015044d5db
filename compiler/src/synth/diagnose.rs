//! Explains an infeasible plan: which fixed bounds conflict, and the best
//! value of each one when the others are kept.

use super::advice::{round_down, round_up};
use super::design::SynthError;
use super::objective::Bound;
use super::plan::Goal;
use super::plan::Plan;
use super::search::Runner;
use tsf_lang::spec::ObjectiveKind;

/// The diagnosis of `plan`, which was found infeasible (or gave no verdict).
pub(super) fn diagnose(runner: &mut Runner<'_>, plan: &Plan) -> SynthError {
    let fixed = plan.fixed_bounds();
    let describe = |kind, v: f64| {
        plan.find(kind)
            .map_or_else(|| format!("{kind} {v}"), |o| o.describe_bound(v))
    };
    let list = fixed
        .iter()
        .map(|&(k, v)| describe(k, v))
        .collect::<Vec<_>>()
        .join(", ");
    let mut achievable = Vec::new();
    runner.accept_almost = true;
    for &(kind, value) in &fixed {
        let relaxed = plan.optimizing(kind);
        let Some(objective) = relaxed.find(kind) else {
            continue;
        };
        let (search, headline) = (objective.search(), objective.headline());
        let bound = describe(kind, value);
        let line = match runner.run(&relaxed, search) {
            Ok(Some(d)) => {
                let approx = if d.approximate {
                    " (approximate: the solver reached only reduced accuracy)"
                } else {
                    ""
                };
                let best = d
                    .achieved
                    .decay_bracket
                    .map(|b| b.0)
                    .filter(|_| search == Goal::MaxDecay)
                    .or_else(|| headline.and_then(|q| d.achieved.get(q)));
                let (found, advised) = match best {
                    Some(b) if search == Goal::MaxDecay => (format!("infeasible with {bound}; the largest feasible decay rate with the other objectives is {b:.6}{approx}"), round_down(b)),
                    Some(b) => (format!("infeasible with {bound}; the smallest feasible bound with the other objectives is {b:.6}{approx}"), round_up(b)),
                    None => {
                        achievable.push(format!("{kind}: no value found"));
                        continue;
                    }
                };
                let write = format!("`{}`", describe(kind, advised));
                format!(
                    "{found}: {}",
                    resolved(runner, plan, (kind, advised), &write, &describe)
                )
            }
            Ok(None) => format!("{kind}: infeasible whatever its value together with the others"),
            Err(e) => format!("{kind}: could not be optimized ({e})"),
        };
        achievable.push(line);
    }
    if let Some(line) = coupling(runner, plan) {
        achievable.push(line);
    }
    // No bound's value helps (or there is none): the box of a sector model
    // may be what binds.
    if !achievable.iter().any(|l| l.contains("write `")) {
        if let Some(line) = super::narrowed::advice(runner, plan) {
            achievable.push(line);
        }
    }
    let message = if fixed.is_empty() && super::lyapunov::fuzzy::phi(runner.model).is_some() {
        format!("infeasible: no PDC controller with a fuzzy Lyapunov function in the Finsler form (mu in {:?}) meets the objectives under this relaxation and these phi", super::lyapunov::fuzzy::MU_GRID)
    } else if fixed.is_empty() {
        "infeasible: no PDC controller with a common quadratic Lyapunov function meets the objectives under this relaxation".to_string()
    } else {
        format!("infeasible: the objectives cannot be met together ({list})")
    };
    SynthError::Infeasible {
        message,
        achievable,
    }
}

/// The advice `write` (`kind` bounded by `advised`), re-solved on the
/// whole plan before it is printed: "write ... (re-solved: feasible)";
/// when the plan still fails with it, what binds instead (a minimized
/// objective the solver could not finish is bounded at the value the
/// relaxed problem reached, re-solved too); else that the advice alone
/// does not suffice.
fn resolved(
    runner: &mut Runner<'_>,
    plan: &Plan,
    (kind, advised): (ObjectiveKind, f64),
    write: &str,
    describe: &dyn Fn(ObjectiveKind, f64) -> String,
) -> String {
    let with = plan.bounding(kind, advised);
    if matches!(runner.run(&with, with.goal()), Ok(Some(_))) {
        return format!("write {write} (re-solved: feasible)");
    }
    // The minimization itself may be what fails (solver trouble at the
    // optimum): bound the minimized quantity at what the feasibility
    // problem reaches instead.
    let minimized = plan
        .objectives()
        .find(|o| o.target() == Some(Bound::Minimize))
        .map(|o| (o.kind(), o.headline()));
    if let Some((m, Some(q))) = minimized {
        let free = with.unoptimized();
        if let Ok(Some(d)) = runner.run(&free, free.goal()) {
            if let Some(g) = d.achieved.get(q) {
                let cap = round_up(g);
                let both = free.bounding(m, cap);
                if matches!(runner.run(&both, both.goal()), Ok(Some(_))) {
                    return format!(
                        "re-solved with {write}, the minimization of {m} still fails: write {write} and `{}` in place of `minimize` (re-solved: feasible)",
                        describe(m, cap)
                    );
                }
            }
        }
    }
    let others = plan
        .objectives()
        .filter(|o| o.kind() != kind)
        .map(|o| o.kind().to_string())
        .collect::<Vec<_>>();
    format!("{write} alone does not make the objectives feasible (re-solved, also with nothing minimized): {} bind(s) too at that value; relax one of them", if others.is_empty() { "the relaxation".to_string() } else { others.join(", ") })
}

/// Objectives that put an initial set inside E(P, 1) (x0' P x0 <= 1).
const WITH_INITIAL_SET: [ObjectiveKind; 3] = [
    ObjectiveKind::InputNorm,
    ObjectiveKind::OutputNorm,
    ObjectiveKind::SaturationRegion,
];

/// When every objective of `plan` is feasible alone but not together, the
/// cause is the one Lyapunov matrix they share: names it (and the initial-set
/// condition that fixes its scale, if any).
fn coupling(runner: &mut Runner<'_>, plan: &Plan) -> Option<String> {
    let all: Vec<_> = plan.objectives().map(|o| o.clone_box()).collect();
    if all.len() < 2 {
        return None;
    }
    let mut names = Vec::new();
    for o in &all {
        let alone = Plan::new(vec![o.clone_box()]);
        match runner.run(&alone, alone.goal()) {
            Ok(Some(_)) => names.push(o.kind().to_string()),
            _ => return None,
        }
    }
    let anchored: Vec<String> = all
        .iter()
        .map(|o| o.kind())
        .filter(|k| WITH_INITIAL_SET.contains(k))
        // An implied saturation region without `for x0` anchors nothing.
        .filter(|k| {
            *k != ObjectiveKind::SaturationRegion
                || plan.saturation().is_some_and(|s| s.contain.is_some())
        })
        .map(|k| k.to_string())
        .collect();
    let why = if anchored.is_empty() {
        String::new()
    } else {
        format!(
            "; {} put(s) the initial state inside E(P, 1) (x0' P x0 <= 1), which fixes the scale of P that the other objectives' LMIs need",
            anchored.join(", ")
        )
    };
    Some(format!(
        "each objective is feasible on its own ({}), not together: all are certified with one common Lyapunov matrix P (X = P^-1){why}; relax one of them, or certify them in separate designs",
        names.join(", ")
    ))
}
