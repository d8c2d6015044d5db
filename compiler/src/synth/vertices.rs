//! The vertices the sampled-loop LMIs are imposed at: each plant rule's
//! (A_i, B_i, D_i) and each controller rule's (F_j, G_j), or, with a premise
//! region (`region z = lo .. hi;`), vertex sets enclosing the blended model
//! sum h_i (A_i, B_i, D_i) and the blended gains sum h_j (F_j, G_j) over the
//! memberships the box allows ([`crate::model::region`]). Lambda_{ij r}(h) is
//! affine in (A, B, D) and in (F, G) but for h Phi' Y Phi, which is convex
//! in each (Y > 0), so conditions at the vertices imply them on the hulls.

use super::design::TriggerPlan;
use super::trigger::Factor;
use crate::model::region::{enclose, images, Enclosure};
use crate::model::TsModel;
use nalgebra::DMatrix;
use serde::Serialize;
use tsf_lmi::LmiError;

/// One plant vertex: (A, B, D) of the L-inf channel (D empty without it).
#[derive(Debug, Clone, PartialEq)]
pub struct PlantVertex {
    /// A.
    pub a: DMatrix<f64>,
    /// B.
    pub b: DMatrix<f64>,
    /// D (the disturbance columns of the L-inf channel).
    pub d: DMatrix<f64>,
}

impl PlantVertex {
    /// The entries of A, B, D in one vector.
    fn data(&self) -> Vec<f64> {
        [self.a.as_slice(), self.b.as_slice(), self.d.as_slice()].concat()
    }
}

/// How the vertex sets of a regional certificate were found (for the report).
#[derive(Debug, Clone, PartialEq, Serialize, schemars::JsonSchema)]
pub struct RegionVertices {
    /// Enclosure of the blended plant data.
    pub plant: Enclosure,
    /// Enclosure of the blended gains F (`None`: one common gain, no enclosure
    /// needed); the sector gain is one G for all vertices.
    pub controller: Option<Enclosure>,
}

/// The enclosures of a regional plan (`None` without a region), for the report.
pub fn describe(model: &TsModel, plan: &TriggerPlan) -> Result<Option<RegionVertices>, LmiError> {
    if plan.region.is_none() {
        return Ok(None);
    }
    let (_, plant) = plant_vertices(model, plan)?;
    let gains: Vec<Factor<'_>> = plan.gains.iter().map(Factor::Val).collect();
    let sector: Vec<Factor<'_>> = plan.sector.iter().map(Factor::Val).collect();
    let controller = match controller_vertices(plan, &gains, &sector)? {
        ControllerVertices::Rules(_) => None,
        ControllerVertices::Blended { enclosure, .. } => enclosure,
    };
    Ok(plant.map(|plant| RegionVertices { plant, controller }))
}

/// The plant vertices of `plan`: its rules, or the enclosure of the blended
/// (A, B, D) over the region's membership polytope.
pub fn plant_vertices(
    model: &TsModel,
    plan: &TriggerPlan,
) -> Result<(Vec<PlantVertex>, Option<Enclosure>), LmiError> {
    let rules: Vec<PlantVertex> = model
        .rules
        .iter()
        .enumerate()
        .map(|(i, r)| PlantVertex {
            a: r.a.clone(),
            b: r.b.clone(),
            d: plan
                .d
                .get(i)
                .cloned()
                .unwrap_or_else(|| DMatrix::zeros(model.n, 0)),
        })
        .collect();
    let Some(region) = &plan.region else {
        return Ok((rules, None));
    };
    let data: Vec<Vec<f64>> = rules.iter().map(PlantVertex::data).collect();
    let e = enclose(&images(&region.h_vertices, &data)).map_err(region_error)?;
    let (n, m, q) = (model.n, model.m, rules[0].d.ncols());
    let vertices = e
        .vertices
        .iter()
        .map(|v| PlantVertex {
            a: DMatrix::from_column_slice(n, n, &v[..n * n]),
            b: DMatrix::from_column_slice(n, m, &v[n * n..n * n + n * m]),
            d: DMatrix::from_column_slice(n, q, &v[n * n + n * m..]),
        })
        .collect();
    Ok((vertices, Some(e)))
}

/// The controller vertices: one per controller rule, or with a region the
/// gains F enclosed (one vertex when every rule's F is the same, known or
/// unknown) and the one sector gain G all rules share (the trigger plan of a
/// region sets G = 0, a co-design's gain step a common unknown:
/// [`crate::synth::trigger::plan_for`]). Unknown F that differ between rules
/// cannot be blended linearly, and G that differ are not expected: errors.
pub(super) fn controller_vertices<'a>(
    plan: &TriggerPlan,
    gains: &[Factor<'a>],
    sector: &[Factor<'a>],
) -> Result<ControllerVertices<'a>, LmiError> {
    let sector_of = |j: usize| sector.get(j).copied().unwrap_or(gains[j]);
    let Some(region) = &plan.region else {
        return Ok(ControllerVertices::Rules(
            (0..gains.len()).map(|j| (gains[j], sector_of(j))).collect(),
        ));
    };
    let known = |f: &[Factor<'a>]| -> Option<Vec<&'a DMatrix<f64>>> {
        f.iter()
            .map(|x| match x {
                Factor::Val(m) => Some(*m),
                Factor::Var(_) => None,
            })
            .collect()
    };
    let common = |f: &[Factor<'a>]| f.iter().all(|x| same(*x, f[0]));
    let g = if sector.is_empty() {
        None
    } else if common(sector) {
        Some(sector[0])
    } else {
        return Err(region_error(
            "region: sector gains that differ between controller rules (the regional trigger plan uses G = 0)".into(),
        ));
    };
    if common(gains) {
        return Ok(ControllerVertices::Blended {
            gains: vec![GainVertex::Factor(gains[0])],
            sector: g,
            enclosure: None,
        });
    }
    let Some(fs) = known(gains) else {
        return Err(region_error(
            "region: unknown gains that differ between controller rules cannot be blended (the co-design keeps one common gain)".into(),
        ));
    };
    let data: Vec<Vec<f64>> = fs.iter().map(|f| f.as_slice().to_vec()).collect();
    let e = enclose(&images(&region.h_vertices, &data)).map_err(region_error)?;
    let (m, n) = fs[0].shape();
    let owned = e
        .vertices
        .iter()
        .map(|v| GainVertex::Blend(DMatrix::from_column_slice(m, n, v)))
        .collect();
    Ok(ControllerVertices::Blended {
        gains: owned,
        sector: g,
        enclosure: Some(e),
    })
}

/// A controller vertex's gain: a factor of the plan, or a blend.
pub(super) enum GainVertex<'a> {
    /// As given (known or unknown).
    Factor(Factor<'a>),
    /// A blend of known gains.
    Blend(DMatrix<f64>),
}

impl GainVertex<'_> {
    /// As a factor.
    pub(super) fn factor(&self) -> Factor<'_> {
        match self {
            GainVertex::Factor(f) => *f,
            GainVertex::Blend(m) => Factor::Val(m),
        }
    }
}

/// The controller vertices: one (F_j, G_j) per rule, or a region's gains
/// with one sector gain.
pub(super) enum ControllerVertices<'a> {
    /// (F, G) factors, one per rule.
    Rules(Vec<(Factor<'a>, Factor<'a>)>),
    /// A region's: gain vertices, the common sector gain (`None` without
    /// saturation), and the enclosure of the gains (`None`: one common gain).
    Blended {
        /// Gain vertices.
        gains: Vec<GainVertex<'a>>,
        /// The sector gain.
        sector: Option<Factor<'a>>,
        /// How the gains were enclosed.
        enclosure: Option<Enclosure>,
    },
}

impl ControllerVertices<'_> {
    /// The (F, G) pairs (G = F where there is no sector gain: unused then).
    pub(super) fn pairs(&self) -> Vec<(Factor<'_>, Factor<'_>)> {
        match self {
            ControllerVertices::Rules(p) => p.clone(),
            ControllerVertices::Blended { gains, sector, .. } => gains
                .iter()
                .map(|f| {
                    let f = f.factor();
                    (f, sector.unwrap_or(f))
                })
                .collect(),
        }
    }
}

/// Whether two factors are the same unknown or equal known values.
pub(super) fn same(a: Factor<'_>, b: Factor<'_>) -> bool {
    match (a, b) {
        (Factor::Val(x), Factor::Val(y)) => x == y,
        (Factor::Var(x), Factor::Var(y)) => x == y,
        _ => false,
    }
}

/// A region error as an LMI-building error.
fn region_error(what: String) -> LmiError {
    LmiError::Dimension { what }
}

/// Representatives of the plant vertices whose Lambda_{ij r}(h) differ: a
/// vertex enters only through (A_i, B_i, D_i), so one with the same three as an
/// earlier one repeats that vertex's conditions exactly.
pub(super) fn distinct_plant_rules(plant: &[PlantVertex]) -> Vec<usize> {
    (0..plant.len())
        .filter(|&i| (0..i).all(|e| plant[e] != plant[i]))
        .collect()
}

/// Relative tolerance of [`on_segment`] (rounding of the rule matrices).
const SEGMENT_TOL: f64 = 1e-12;

/// Whether `x` lies on the segment from `a` to `b` (to rounding).
fn on_segment(x: &[f64], a: &[f64], b: &[f64]) -> bool {
    let dot = |u: &mut dyn Iterator<Item = (f64, f64)>| u.map(|(p, q)| p * q).sum::<f64>();
    let d: Vec<f64> = b.iter().zip(a).map(|(p, q)| p - q).collect();
    let xa: Vec<f64> = x.iter().zip(a).map(|(p, q)| p - q).collect();
    let dd = dot(&mut d.iter().copied().zip(d.iter().copied()));
    if dd == 0.0 {
        return false;
    }
    let t = dot(&mut xa.iter().copied().zip(d.iter().copied())) / dd;
    let scale = [x, a, b]
        .iter()
        .flat_map(|v| v.iter())
        .fold(0.0f64, |m, v| m.max(v.abs()));
    let off = xa
        .iter()
        .zip(&d)
        .fold(0.0f64, |m, (p, q)| m.max((p - t * q).abs()));
    (-SEGMENT_TOL..=1.0 + SEGMENT_TOL).contains(&t) && off <= SEGMENT_TOL * scale.max(1.0)
}

/// The plant rules the solved trigger problem keeps: the representatives of
/// [`distinct_plant_rules`] less every rule whose (A_i, B_i, D_i) lies on the
/// segment between two rules still kept. x' = Phi_ij psi is affine in
/// (A_i, B_i, D_i), Xi is affine in Phi and h Phi' Y Phi is matrix-convex in Phi
/// (Y > 0), so Lambda_{ij r}(h) at a convex combination is at most the same
/// combination of the kept ones: the left-out conditions are implied, with at
/// least their margin. Removing one at a time keeps the convex hull of the
/// kept rules (Xu & Huang: R1 is the midpoint of R4, R5 and R2 of R6, R7).
pub(super) fn kept_plant_rules(plant: &[PlantVertex]) -> Vec<usize> {
    let mut kept = distinct_plant_rules(plant);
    let points: Vec<Vec<f64>> = plant
        .iter()
        .map(|v| [v.a.as_slice(), v.b.as_slice(), v.d.as_slice()].concat())
        .collect();
    while let Some(at) = kept.iter().position(|&i| {
        let others: Vec<usize> = kept.iter().copied().filter(|&k| k != i).collect();
        others.iter().enumerate().any(|(u, &k)| {
            others[u + 1..]
                .iter()
                .any(|&l| on_segment(&points[i], &points[k], &points[l]))
        })
    }) {
        kept.remove(at);
    }
    kept
}

/// Representatives of the controller vertices whose gains (F_j, G_j) differ:
/// known gains equal bit for bit, or the same unknown.
pub(super) fn distinct_controller_rules(ctrl: &[(Factor<'_>, Factor<'_>)]) -> Vec<usize> {
    let same = |a: usize, b: usize| same(ctrl[a].0, ctrl[b].0) && same(ctrl[a].1, ctrl[b].1);
    (0..ctrl.len())
        .filter(|&j| (0..j).all(|e| !same(e, j)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::on_segment;

    #[test]
    fn on_segment_accepts_points_of_the_segment_only() {
        let (a, b) = ([1.0, -2.0, 0.5], [3.0, 2.0, 0.5]);
        assert!(on_segment(&[2.0, 0.0, 0.5], &a, &b));
        assert!(on_segment(&a, &a, &b));
        assert!(on_segment(&[2.5, 1.0, 0.5], &a, &b));
        // on the line, outside the segment
        assert!(!on_segment(&[4.0, 4.0, 0.5], &a, &b));
        assert!(!on_segment(&[0.0, -4.0, 0.5], &a, &b));
        // off the line by 1e-9 relative
        assert!(!on_segment(&[2.0, 0.0, 0.5 + 1e-9], &a, &b));
        // a degenerate segment
        assert!(!on_segment(&a, &a, &a));
    }
}
