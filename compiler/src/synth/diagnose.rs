//! Explains an infeasible plan: which fixed bounds conflict, and the best
//! value of each one when the others are kept.

use super::design::SynthError;
use super::plan::Goal;
use super::plan::Plan;
use super::search::Runner;

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
                match best {
                    Some(b) if search == Goal::MaxDecay => format!("infeasible with {bound}; the largest feasible decay rate with the other objectives is {b:.6}{approx}"),
                    Some(b) => format!("infeasible with {bound}; the smallest feasible bound with the other objectives is {b:.6}{approx}"),
                    None => format!("{kind}: no value found"),
                }
            }
            Ok(None) => format!(
                "{kind}: infeasible whatever its value (the other objectives conflict on their own)"
            ),
            Err(e) => format!("{kind}: could not be optimized ({e})"),
        };
        achievable.push(line);
    }
    let message = if fixed.is_empty() {
        "infeasible: no PDC controller with a common quadratic Lyapunov function meets the objectives under this relaxation".to_string()
    } else {
        format!("infeasible: the objectives cannot be met together ({list})")
    };
    SynthError::Infeasible {
        message,
        achievable,
    }
}
