//! Narrower sector ranges, advised when a `rules sector;` model is
//! infeasible on its declared premise box.
//!
//! A sector model is multilinear in its premises, so the model at any premise
//! value inside the box is the multilinear interpolation of the vertex rules:
//! the vertex rules of a narrower box follow without re-fitting. The box is
//! narrowed around the premises' values at x = 0 (the equilibrium), to 1/2,
//! 1/4, 1/8 and 1/16 of the distance to each end; the widest that is
//! feasible (the plan re-solved with the printed, rounded ranges) is advised.
//! The certificate then covers only the states whose premises stay inside.

use super::advice::round_toward;
use super::design::SolverLog;
use super::plan::Plan;
use super::search::Runner;
use crate::model::premise_values;
use crate::model::TsModel;

/// Fractions of the distance from the value at x = 0 to each end, tried in order.
const FRACTIONS: [f64; 4] = [0.5, 0.25, 0.125, 0.0625];

/// One sector premise: its name, declared range and value at x = 0.
struct Span {
    name: String,
    lo: f64,
    hi: f64,
    at_rest: f64,
}

/// The advice of narrower premise ranges for `plan` (infeasible on the
/// declared box), or None when the model is not a sector model or no
/// narrowing tried is feasible.
pub(super) fn advice(runner: &mut Runner<'_>, plan: &Plan) -> Option<String> {
    let model = runner.model;
    let spans = sector_spans(model)?;
    for s in FRACTIONS {
        let ranges: Vec<(f64, f64)> = spans
            .iter()
            .map(|p| {
                let lo = p.at_rest - s * (p.at_rest - p.lo);
                let hi = p.at_rest + s * (p.hi - p.at_rest);
                (round_toward(lo, p.at_rest), round_toward(hi, p.at_rest))
            })
            .collect();
        if ranges.iter().any(|(lo, hi)| lo >= hi) {
            continue;
        }
        let narrowed = with_ranges(model, &spans, &ranges);
        let mut trial = Runner {
            model: &narrowed,
            settings: runner.settings,
            log: SolverLog::default(),
            accept_almost: false,
        };
        let feasible = matches!(trial.run(plan, plan.goal()), Ok(Some(_)));
        runner.log.count_also(&trial.log);
        if feasible {
            let write = spans
                .iter()
                .zip(&ranges)
                .filter(|(p, (lo, hi))| (*lo, *hi) != (p.lo, p.hi))
                .map(|(p, (lo, hi))| format!("`premise {} range {lo} .. {hi}`", p.name))
                .collect::<Vec<_>>()
                .join(", ");
            return Some(format!(
                "the sector premises' box is too wide for one common Lyapunov matrix: narrowed around their values at x = 0 to {s} of the distance to each end, the objectives are feasible (re-solved): write {write} (the certificate then covers only states whose premises stay in these ranges)"
            ));
        }
    }
    None
}

/// The sector premises of `model` with their ranges and values at x = 0;
/// None unless the rules are the 2^p vertices of `rules sector;`.
fn sector_spans(model: &TsModel) -> Option<Vec<Span>> {
    let sector = model.spec.sector.as_ref()?;
    let p = sector.premises.len();
    if p == 0 || p >= usize::BITS as usize || model.r() != 1 << p {
        return None;
    }
    let z = premise_values(&model.spec, &vec![0.0; model.n]).ok()?;
    let mut offsets = Vec::with_capacity(model.spec.premises.len());
    let mut at = 0;
    for premise in &model.spec.premises {
        offsets.push(at);
        at += if premise.component.is_some() {
            1
        } else {
            premise.dim
        };
    }
    sector
        .premises
        .iter()
        .map(|&k| {
            let premise = model.spec.premises.get(k)?;
            let (lo, hi) = premise.range?;
            let z0 = *z.get(*offsets.get(k)?)?;
            (z0.is_finite() && lo < hi).then(|| Span {
                name: premise.name.clone(),
                lo,
                hi,
                at_rest: z0.clamp(lo, hi),
            })
        })
        .collect()
}

/// `model` with its vertex rules moved to the corners of `ranges`: each new
/// vertex is the multilinear interpolation of the old ones (rule v: bit k of
/// v, premise k first most significant, picks the range's low end when set).
fn with_ranges(model: &TsModel, spans: &[Span], ranges: &[(f64, f64)]) -> TsModel {
    let p = spans.len();
    let bit = |v: usize, k: usize| (v >> (p - 1 - k)) & 1 == 1;
    let mut out = model.clone();
    for (v, rule) in out.rules.iter_mut().enumerate() {
        let corner: Vec<f64> = (0..p)
            .map(|k| if bit(v, k) { ranges[k].0 } else { ranges[k].1 })
            .collect();
        let weight = |u: usize| -> f64 {
            (0..p)
                .map(|k| {
                    let (lo, hi) = (spans[k].lo, spans[k].hi);
                    let max = (corner[k] - lo) / (hi - lo);
                    if bit(u, k) {
                        1.0 - max
                    } else {
                        max
                    }
                })
                .product()
        };
        rule.a = rule.a.map(|_| 0.0);
        rule.b = rule.b.map(|_| 0.0);
        rule.d = rule.d.map(|_| 0.0);
        for (u, old) in model.rules.iter().enumerate() {
            let w = weight(u);
            rule.a += &old.a * w;
            rule.b += &old.b * w;
            rule.d += &old.d * w;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sector model of z' = -z * z + u on |z| <= 2: narrowed to
    /// [-0.5, 1], the vertices are A(1) = -1 and A(-0.5) = 0.5 exactly
    /// (A = -z is affine in the premise z).
    #[test]
    fn narrowed_vertices_are_the_model_at_the_new_corners() {
        let model = crate::model::scalar_sector_model(2.0);
        let spans = sector_spans(&model).expect("a sector model"); // ok: unit test
        assert_eq!(
            (spans[0].lo, spans[0].hi, spans[0].at_rest),
            (-2.0, 2.0, 0.0)
        );
        let m = with_ranges(&model, &spans, &[(-0.5, 1.0)]);
        // Rule 0 is z_max (the high end), rule 1 z_min.
        assert!(
            (m.rules[0].a[(0, 0)] + 1.0).abs() < 1e-15,
            "{}",
            m.rules[0].a
        );
        assert!(
            (m.rules[1].a[(0, 0)] - 0.5).abs() < 1e-15,
            "{}",
            m.rules[1].a
        );
    }
}
