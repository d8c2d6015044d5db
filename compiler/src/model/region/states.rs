//! `region` settings that name states (`region theta = -0.5 .. 0.5;`, issue
//! 35): the box bounds states, and the premises, which may be nonlinear
//! functions of them (sinc(theta), cos(theta), products of states), are
//! enclosed over it.
//!
//! Each premise component that reads only bounded states is evaluated over
//! the state box in affine arithmetic with outward rounding (the evaluator of
//! the plant certificate, `tape::affine`): first the premise-range check of
//! the model-error bound ([`premise_range::check`]) proves that every state
//! of the box has its premise value in the declared range (else the box is
//! refused: a witness state outside it, or no proof within
//! [`MAX_PREMISE_BOXES`] sub-boxes); then [`premise_range::hull`] encloses
//! the value over a uniform cover of the box, and that interval (within the
//! range) replaces the range in the premise box. Other premise components
//! keep their range, or their own `region` (premises linear in x, as before).
//!
//! Soundness: for every x in the state box, z(x) lies in the enclosure, so
//! h(x) lies in the polytope H of the membership bounds on it, and the
//! vertex LMIs hold at x (the parent module). The certificate keeps the
//! states inside the box by E(P, c) inside |x_k| <= b_k (one face per bounded
//! state component, b_k = min(-lo, hi)), the faces the LMIs already impose.

use super::{box_memberships, linear_rows, Checked, Face, RegionError};
use crate::model::consistency::StateGraph;
use crate::model::error_bound::premise_range::{self, PremiseRange, MAX_PREMISE_BOXES};
use crate::model::TsModel;
use crate::tape::affine;
use nalgebra::DMatrix;
use serde::Serialize;

/// How the premise box of state `region` settings was enclosed (report).
#[derive(Debug, Clone, PartialEq, Serialize, schemars::JsonSchema)]
pub struct PremiseEnclosure {
    /// The premise components enclosed over the state box (those reading
    /// only bounded states); the others keep their range or their own box.
    pub premises: Vec<String>,
    /// Sub-boxes the premise-range check evaluated.
    pub range_boxes: usize,
    /// Sub-boxes of the cover whose hull gives the premise intervals.
    pub hull_boxes: usize,
}

/// The help of a box whose premise values are not proved in range.
const SHRINK_HELP: &str = "shrink the state box so that the premise stays in its declared range (where the rules describe the plant), or widen the premise's range";

/// The premise box of `model`'s `region` settings when some name a state.
pub(super) fn checked(model: &TsModel) -> Result<Checked, RegionError> {
    let n = model.n;
    let bounds = &model.spec.trigger_region;
    let slots = &model.premises.slots;
    let p = model.premises.len();
    // The premise-named settings: faces of linear premises, as without states.
    let given: Vec<Option<(f64, f64)>> = (0..p)
        .map(|k| {
            let slot = slots
                .iter()
                .find(|s| (s.first..s.first + s.dim).contains(&k))?;
            let b = bounds
                .iter()
                .find(|b| b.state.is_none() && b.premise == slot.name)?;
            Some(b.range)
        })
        .collect();
    let mut faces = Vec::new();
    if given.iter().any(Option::is_some) {
        let c = linear_rows(model, |k| given[k].is_some())?;
        for (k, g) in given.iter().enumerate() {
            if let Some((lo, hi)) = g {
                faces.push(Face {
                    name: model.premises.component_name(k),
                    row: c.rows(k, 1).into_owned(),
                    bound: (-lo).min(*hi),
                });
            }
        }
    }
    // The state box and its faces |x_k| <= b_k.
    let mut bx = vec![(0.0, 0.0); n];
    let mut owner: Vec<Option<&str>> = vec![None; n];
    for b in bounds {
        let Some((first, len)) = b.state else {
            continue;
        };
        for k in first..first + len {
            bx[k] = b.range;
            owner[k] = Some(&b.premise);
            faces.push(Face {
                name: match len {
                    1 => b.premise.clone(),
                    _ => format!("{}[{}]", b.premise, k - first),
                },
                row: DMatrix::from_fn(1, n, |_, c| if c == k { 1.0 } else { 0.0 }),
                bound: (-b.range.0).min(b.range.1),
            });
        }
    }
    let first_state = owner.iter().flatten().next().map(|s| s.to_string());
    let graph = StateGraph::lower(&model.spec, &[]).map_err(|e| RegionError {
        premise: None,
        setting: first_state.clone(),
        message: format!(
            "the premises cannot be enclosed over the state box: the tape cannot express them ({})",
            e.0
        ),
        help: "bound the premise variables themselves (`region z = lo .. hi;`, premises linear in the state)".into(),
    })?;
    let z = &graph.outputs[..graph.nz];
    let ranges = model.premises.component_ranges();
    // Per component: the setting bounding the first state it reads, if it
    // reads only bounded states (and some).
    let setting: Vec<Option<String>> = z
        .iter()
        .map(|id| {
            let reads = affine::depends_on(&graph.builder, &[*id]);
            let read = || reads.iter().enumerate().filter(|(_, r)| **r);
            if read().all(|(s, _)| owner[s].is_some()) {
                read().find_map(|(s, _)| owner[s].map(str::to_string))
            } else {
                None
            }
        })
        .collect();
    let selected: Vec<usize> = (0..p).filter(|&k| setting[k].is_some()).collect();
    let ids: Vec<_> = selected.iter().map(|&k| z[k]).collect();
    let sel_ranges: Vec<(f64, f64)> = selected.iter().map(|&k| ranges[k]).collect();
    let fault = |k: usize, message: String| RegionError {
        premise: Some(model.premises.component_name(k)),
        setting: setting[k].clone(),
        message,
        help: SHRINK_HELP.into(),
    };
    let range_boxes = match premise_range::check(&graph.builder, &ids, &sel_ranges, &bx) {
        PremiseRange::Inside { boxes } => boxes,
        PremiseRange::Leaves { premise, x, z } => {
            let k = selected[premise];
            let (lo, hi) = ranges[k];
            return Err(fault(
                k,
                format!(
                    "the state box reaches premise value {} = {z:.6} (at x = {}), outside its range {lo} .. {hi}",
                    model.premises.component_name(k),
                    show(&x)
                ),
            ));
        }
        PremiseRange::Unproven { bx: sub } => {
            let k = selected.first().copied().unwrap_or(0);
            return Err(fault(
                k,
                format!(
                    "tsfc cannot prove that the premises stay in their ranges over the state box: an enclosure (affine arithmetic, outward rounding) still leaves its range, or is unbounded, on the sub-box {} after {MAX_PREMISE_BOXES} sub-boxes",
                    show_box(&sub)
                ),
            ));
        }
    };
    let hull = premise_range::hull(&graph.builder, &ids, &bx);
    let mut zs: Vec<(f64, f64)> = (0..p).map(|k| given[k].unwrap_or(ranges[k])).collect();
    for (&k, r) in selected.iter().zip(&hull.ranges) {
        if let Some((lo, hi)) = r.filter(|(lo, hi)| lo.is_finite() && hi.is_finite()) {
            // Proved inside the range (to its slack): clamped to it.
            let (a, b) = zs[k];
            zs[k] = (lo.clamp(a, b), hi.clamp(a, b));
        }
    }
    let h_bounds = box_memberships(model, &zs)?;
    Ok(Checked {
        z: zs,
        faces,
        h_bounds,
        enclosure: Some(PremiseEnclosure {
            premises: selected
                .iter()
                .map(|&k| model.premises.component_name(k))
                .collect(),
            range_boxes,
            hull_boxes: hull.boxes,
        }),
    })
}

/// A state for a message: `[0.1, -0.2]`.
fn show(x: &[f64]) -> String {
    let parts: Vec<String> = x.iter().map(|v| format!("{v:.6}")).collect();
    format!("[{}]", parts.join(", "))
}

/// A box for a message: `[0 .. 0.1, -0.2 .. 0]`.
fn show_box(bx: &[(f64, f64)]) -> String {
    let parts: Vec<String> = bx
        .iter()
        .map(|(lo, hi)| format!("{lo:.6} .. {hi:.6}"))
        .collect();
    format!("[{}]", parts.join(", "))
}
