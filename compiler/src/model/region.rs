//! The premise region of a local certificate (`region z = lo .. hi;` in an
//! aperiodic trigger): rigorous bounds of the normalized memberships on the
//! premise box, the polytope those bounds leave for h, and a small vertex set
//! enclosing any linear image of it (the blended model, the blended gains).
//!
//! Soundness: for every x with z(x) in the box, h(x) lies in
//! H = {h : sum h = 1, lo_i <= h_i <= hi_i}, so sum h_i M_i lies in the convex
//! hull of the images of H's vertices, which [`enclose`] covers by the corners
//! of a box in the principal coordinates of their affine span (or by the
//! images themselves when they are fewer). The LMIs imposed at those vertices
//! then hold for every such x. The certificate keeps the states it speaks of
//! inside the box by the LMIs E(P, c) inside |c_k x| <= b_k (premises linear in x).
//! A `region` naming a state bounds that state instead (faces |x_k| <= b_k),
//! and the premises it reads are enclosed over the state box ([`states`]).

pub mod drift;
pub mod states;

use super::premise::TermSpec;
use super::TsModel;
use nalgebra::{DMatrix, DVector};
use serde::Serialize;
use tsf_lang::Diagnostic;
use tsf_runtime::membership::about_degree;

/// Largest number of rules a region accepts (H has at most r 2^(r-1) vertex candidates).
pub const MAX_REGION_RULES: usize = 16;
/// Largest number of vertices of an enclosure (per side: plant, controller).
pub const MAX_REGION_VERTICES: usize = 64;
/// Relative outward widening of every membership bound (rounding of exp and products).
const WIDEN: f64 = 1e-12;
/// The help of a premise not linear in the state.
const LINEAR_HELP: &str = "bound premises that are states (or linear combinations of states), or bound the states a nonlinear premise reads (`region theta = lo .. hi;`, theta a state)";
/// Singular values below this fraction of the largest span no direction.
const RANK_TOL: f64 = 1e-10;

/// One face pair of the box in state coordinates: |row x| <= bound.
#[derive(Debug, Clone, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Face {
    /// The premise component, e.g. `q[1]`.
    pub name: String,
    /// Its row of z = C x (1 x n).
    #[serde(skip)]
    pub row: DMatrix<f64>,
    /// min(-lo, hi): the ellipsoid is symmetric, the nearer side binds.
    pub bound: f64,
}

/// The premise box of the `region` settings.
#[derive(Debug, Clone, PartialEq, Serialize, schemars::JsonSchema)]
pub struct PremiseBox {
    /// Per component of z: its interval (the premise's range where no region is given).
    pub z: Vec<(f64, f64)>,
    /// The bounded components as faces in state coordinates.
    pub faces: Vec<Face>,
    /// Bounds [lo_i, hi_i] of each rule's normalized membership h_i on the box.
    pub h_bounds: Vec<(f64, f64)>,
    /// Vertices of H = {sum h = 1, lo <= h <= hi} (weights over the rules).
    #[serde(skip)]
    pub h_vertices: Vec<Vec<f64>>,
    /// Their number (for the report).
    pub h_vertex_count: usize,
    /// With `region` settings on states: the premise components enclosed
    /// over the state box (absent when every setting names a premise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub enclosure: Option<states::PremiseEnclosure>,
}

/// Why the `region` settings give no premise box: a spec error, which the
/// model stage reports at a `region` setting ([`diagnose`]); synthesis keeps
/// it as a refusal (last line of defence).
#[derive(Debug, Clone, PartialEq)]
pub struct RegionError {
    /// The premise variable at fault, if one is.
    pub premise: Option<String>,
    /// The name of the `region` setting at fault when it is not the
    /// premise's (a state box the premise is enclosed over).
    pub setting: Option<String>,
    /// What is wrong.
    pub message: String,
    /// What to do about it.
    pub help: String,
}

impl std::fmt::Display for RegionError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "region: {}; {}", self.message, self.help)
    }
}

/// The diagnostic of `model`'s `region` settings when they give no premise
/// box, at the setting of the premise at fault (else the first setting).
pub fn diagnose(model: &TsModel) -> Option<Diagnostic> {
    let first = model.spec.trigger_region.first()?;
    let e = checked(model).err()?;
    let at = e
        .setting
        .as_ref()
        .or(e.premise.as_ref())
        .and_then(|p| model.spec.trigger_region.iter().find(|b| &b.premise == p))
        .unwrap_or(first);
    let d = Diagnostic::error(at.span, e.message);
    let d = match &e.premise {
        Some(p) if *p != at.premise && e.setting.is_none() => d.with_label(format!(
            "premise `{p}` is not bounded here, but every premise must be linear in the state"
        )),
        _ => d,
    };
    Some(d.with_help(e.help))
}

/// The box of the `region` settings in state coordinates and its membership
/// bounds, checked (`None` without settings).
struct Checked {
    z: Vec<(f64, f64)>,
    faces: Vec<Face>,
    h_bounds: Vec<(f64, f64)>,
    enclosure: Option<states::PremiseEnclosure>,
}

/// [`Checked`] for `model`, or why the settings give no box.
fn checked(model: &TsModel) -> Result<Option<Checked>, RegionError> {
    let bounds = &model.spec.trigger_region;
    if bounds.is_empty() {
        return Ok(None);
    }
    if model.r() > MAX_REGION_RULES {
        return Err(RegionError {
            premise: None,
            setting: None,
            message: format!(
                "{} rules, at most {MAX_REGION_RULES} with `region` (the membership polytope has up to r 2^(r-1) vertices)",
                model.r()
            ),
            help: "leave out `region` (the certificate then holds on the whole premise range), or use fewer rules".into(),
        });
    }
    if bounds.iter().any(|b| b.state.is_some()) {
        return states::checked(model).map(Some);
    }
    let c = premise_matrix(model)?;
    let mut z: Vec<(f64, f64)> = Vec::new();
    let mut faces = Vec::new();
    for slot in &model.premises.slots {
        let given = bounds.iter().find(|b| b.premise == slot.name);
        for k in slot.first..slot.first + slot.dim {
            z.push(given.map_or(slot.range, |b| b.range));
            if let Some(b) = given {
                faces.push(Face {
                    name: model.premises.component_name(k),
                    row: c.rows(k, 1).into_owned(),
                    bound: (-b.range.0).min(b.range.1),
                });
            }
        }
    }
    let h_bounds = box_memberships(model, &z)?;
    Ok(Some(Checked {
        z,
        faces,
        h_bounds,
        enclosure: None,
    }))
}

/// [`membership_bounds`] of `model`'s rules on the premise box `z`, or the
/// region's error.
fn box_memberships(model: &TsModel, z: &[(f64, f64)]) -> Result<Vec<(f64, f64)>, RegionError> {
    membership_bounds(&model.terms, z).map_err(|message| RegionError {
        premise: None,
        setting: None,
        message,
        help: "shrink the region or widen the premise sets".into(),
    })
}

/// The premise box of `model`'s `region` settings (`None` without any), with
/// its membership bounds and the vertices of H; an error when a premise is not
/// linear in the state, no rule fires on the box, or the problem is too large
/// (the model stage reports these first, [`diagnose`]).
pub fn premise_box(model: &TsModel) -> Result<Option<PremiseBox>, String> {
    let Some(Checked {
        z,
        faces,
        h_bounds,
        enclosure,
    }) = checked(model).map_err(|e| e.to_string())?
    else {
        return Ok(None);
    };
    let h_vertices = polytope_vertices(&h_bounds);
    Ok(Some(PremiseBox {
        z,
        faces,
        h_vertex_count: h_vertices.len(),
        h_bounds,
        h_vertices,
        enclosure,
    }))
}

/// The model the continuous loop's LMIs are imposed on when the spec has a
/// premise region and one common given gain F (a given spec's, or the one a
/// co-design re-analyzes): its rules are the vertices enclosing the blended
/// (A, B, D) over the membership polytope, each with that F. The closed loop
/// sum h_i (A_i + B_i F) is then exactly a convex combination of the vertex
/// loops, for every relaxation. `None` without a region, without given
/// gains, or with gains that differ between rules (the continuous loop is
/// then certified on the whole premise range).
pub fn continuous_model(model: &TsModel) -> Result<Option<(TsModel, PremiseBox)>, String> {
    let Some(gains) = model.spec.given_gains() else {
        return Ok(None);
    };
    if gains.iter().any(|f| f != &gains[0]) {
        return Ok(None);
    }
    let Some(region) = premise_box(model)? else {
        return Ok(None);
    };
    let data: Vec<Vec<f64>> = model
        .rules
        .iter()
        .map(|r| [r.a.as_slice(), r.b.as_slice(), r.d.as_slice()].concat())
        .collect();
    let e = enclose(&images(&region.h_vertices, &data))?;
    let (n, m, q) = (model.n, model.m, model.q);
    let mut local = model.clone();
    local.rules = e
        .vertices
        .iter()
        .enumerate()
        .map(|(k, v)| super::LocalModel {
            name: format!("V{}", k + 1),
            a: DMatrix::from_column_slice(n, n, &v[..n * n]),
            b: DMatrix::from_column_slice(n, m, &v[n * n..n * n + n * m]),
            d: DMatrix::from_column_slice(n, q, &v[n * n + n * m..]),
            at: None,
        })
        .collect();
    let k = local.rules.len();
    let first = model.spec.rules[0].clone();
    local.spec.rules = (0..k)
        .map(|v| tsf_lang::spec::RuleSpec {
            name: format!("V{}", v + 1),
            ..first.clone()
        })
        .collect();
    local.terms = vec![model.terms[0].clone(); k];
    local.centers = vec![model.centers[0].clone(); k];
    Ok(Some((local, region)))
}

/// C of z = C x, checked: z(0) = 0 and z(x) = C x at two further states (a
/// premise such as sin(x1) has no box in state coordinates).
pub(crate) fn premise_matrix(model: &TsModel) -> Result<DMatrix<f64>, RegionError> {
    linear_rows(model, |_| true)
}

/// C of z = C x, the rows `linear` marks (premise components) checked as
/// [`premise_matrix`] checks every row; the others are not checked.
fn linear_rows(
    model: &TsModel,
    linear: impl Fn(usize) -> bool,
) -> Result<DMatrix<f64>, RegionError> {
    let n = model.n;
    let z = |x: &[f64]| {
        super::premise_values(&model.spec, x).map_err(|d| RegionError {
            premise: None,
            setting: None,
            message: d.message,
            help: LINEAR_HELP.into(),
        })
    };
    let cols = (0..n)
        .map(|k| {
            let mut x = vec![0.0; n];
            x[k] = 1.0;
            z(&x)
        })
        .collect::<Result<Vec<_>, _>>()?;
    let p = model.premises.len();
    let c = DMatrix::from_fn(p, n, |r, k| cols[k][r]);
    let probes: [Vec<f64>; 3] = [
        vec![0.0; n],
        (0..n).map(|k| 0.01 * (k as f64 + 1.0)).collect(),
        (0..n).map(|k| -0.003 * (2.0 * k as f64 - 1.0)).collect(),
    ];
    for x in &probes {
        let got = DVector::from_vec(z(x)?);
        let want = &c * DVector::from_column_slice(x);
        let scale = 1.0 + want.amax();
        if let Some(k) = (0..p).find(|&k| linear(k) && (got[k] - want[k]).abs() > 1e-9 * scale) {
            let name = model
                .premises
                .slots
                .iter()
                .find(|s| k >= s.first && k < s.first + s.dim)
                .map_or_else(|| model.premises.component_name(k), |s| s.name.clone());
            return Err(RegionError {
                message: format!("premise variable `{name}` is not linear in the state, so the premise box has no faces in state coordinates"),
                premise: Some(name),
                setting: None,
                help: LINEAR_HELP.into(),
            });
        }
    }
    Ok(c)
}

/// Bounds of one conjunct's membership degree on the box `z`.
fn term_bounds(t: &TermSpec, z: &[(f64, f64)]) -> (f64, f64) {
    match t {
        TermSpec::Is { var, set } => {
            let m = super::premise::membership(*set);
            let (lo, hi) = z[*var];
            let (a, b) = (m.degree(lo), m.degree(hi));
            // Tri, trap and gauss are quasi-concave (largest at the peak);
            // sigmoid is monotone (its peak is never inside).
            let peak = match *set {
                tsf_lang::spec::SetShape::Tri(_, p, _) => Some((p, p)),
                tsf_lang::spec::SetShape::Trap(_, p, q, _) => Some((p, q)),
                tsf_lang::spec::SetShape::Gauss(p, _) => Some((p, p)),
                tsf_lang::spec::SetShape::Sigmoid(..) => None,
            };
            let top = match peak {
                Some((p, q)) if q >= lo && p <= hi => 1.0,
                _ => a.max(b),
            };
            (a.min(b), top)
        }
        TermSpec::About {
            first,
            point,
            sigma,
        } => {
            // ||z - p||^2 over the box: per component, the nearest and farthest point.
            let (mut near, mut far) = (Vec::new(), Vec::new());
            for (k, p) in point.iter().enumerate() {
                let (lo, hi) = z[first + k];
                near.push(p.clamp(lo, hi));
                far.push(if (p - lo).abs() >= (hi - p).abs() {
                    lo
                } else {
                    hi
                });
            }
            (
                about_degree(&far, point, *sigma),
                about_degree(&near, point, *sigma),
            )
        }
    }
}

/// Bounds of every rule's normalized membership h_i = w_i / sum w on the box:
/// w_i between the products of its conjuncts' bounds (all in [0, 1]), then
/// h_i in [wlo_i / (wlo_i + sum_k!=i whi_k), whi_i / (whi_i + sum_k!=i wlo_k)],
/// widened outward by [`WIDEN`].
pub fn membership_bounds(
    terms: &[Vec<TermSpec>],
    z: &[(f64, f64)],
) -> Result<Vec<(f64, f64)>, String> {
    let w: Vec<(f64, f64)> = terms
        .iter()
        .map(|ts| {
            ts.iter().fold((1.0, 1.0), |(lo, hi), t| {
                let (a, b) = term_bounds(t, z);
                (lo * a, hi * b)
            })
        })
        .map(|(lo, hi)| (lo * (1.0 - WIDEN), (hi * (1.0 + WIDEN)).min(1.0)))
        .collect();
    let (sum_lo, sum_hi) = w
        .iter()
        .fold((0.0, 0.0), |(a, b), (lo, hi)| (a + lo, b + hi));
    if sum_lo <= 0.0 {
        return Err(format!(
            "some state of the premise box may fire no rule (the smallest total firing strength bound is {sum_lo:e})"
        ));
    }
    Ok(w.iter()
        .map(|&(lo, hi)| {
            let lo_h = lo / (lo + (sum_hi - hi).max(0.0));
            let hi_h = hi / (hi + (sum_lo - lo).max(0.0));
            (
                (lo_h * (1.0 - WIDEN)).max(0.0),
                (hi_h * (1.0 + WIDEN)).min(1.0),
            )
        })
        .collect())
}

/// Vertices of H = {h : sum h = 1, lo <= h <= hi}: at a vertex every
/// coordinate but at most one sits at a bound, so each choice of the free
/// coordinate and of the bounds of the others is tried (r 2^(r-1) candidates).
pub fn polytope_vertices(bounds: &[(f64, f64)]) -> Vec<Vec<f64>> {
    let r = bounds.len();
    let mut found: Vec<Vec<f64>> = Vec::new();
    for free in 0..r {
        for mask in 0u32..(1u32 << (r - 1)) {
            let mut h = vec![0.0; r];
            let mut bit = 0;
            for (i, hi) in h.iter_mut().enumerate() {
                if i == free {
                    continue;
                }
                *hi = if mask >> bit & 1 == 1 {
                    bounds[i].1
                } else {
                    bounds[i].0
                };
                bit += 1;
            }
            let rest: f64 = h.iter().sum();
            let v = 1.0 - rest;
            let (lo, hi) = bounds[free];
            let tol = 1e-12;
            if v >= lo - tol && v <= hi + tol {
                h[free] = v.clamp(lo, hi);
                found.push(h);
            }
        }
    }
    distinct(found)
}

/// The points, each once: equal to 1e-12 of the largest coordinate (a
/// vertex reached from several free coordinates, rounding apart), first
/// occurrences kept in order. Hashing keeps this linear in the number of
/// points (16 rules give up to 16 x 32,768 candidates).
fn distinct(points: Vec<Vec<f64>>) -> Vec<Vec<f64>> {
    let scale = points
        .iter()
        .flatten()
        .fold(0.0f64, |m, v| m.max(v.abs()))
        .max(f64::MIN_POSITIVE);
    let quantum = 1e-12 * scale;
    let mut seen = std::collections::HashSet::new();
    points
        .into_iter()
        .filter(|p| {
            let key: Vec<i64> = p.iter().map(|v| (v / quantum).round() as i64).collect();
            seen.insert(key)
        })
        .collect()
}

/// A vertex set enclosing the convex hull of some points.
#[derive(Debug, Clone, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Enclosure {
    /// The vertices.
    #[serde(skip)]
    pub vertices: Vec<Vec<f64>>,
    /// Their number.
    pub vertex_count: usize,
    /// Dimension of the points' affine span.
    pub dim: usize,
    /// Largest distance of a point from that span (left out of the box; below
    /// rounding of the data when the span is found right).
    pub residual: f64,
    /// `points` (the distinct images themselves) or `box` (corners of a box in
    /// the principal coordinates of the span).
    pub how: &'static str,
}

/// Encloses the convex hull of `points`: the distinct points themselves when
/// they are at most 2^dim, else the 2^dim corners of their bounding box in the
/// principal coordinates of their affine span; an error above [`MAX_REGION_VERTICES`].
pub fn enclose(points: &[Vec<f64>]) -> Result<Enclosure, String> {
    let distinct = distinct(points.to_vec());
    let k = distinct.len();
    let len = distinct.first().map_or(0, Vec::len);
    if k <= 1 || len == 0 {
        return Ok(Enclosure {
            vertex_count: distinct.len(),
            vertices: distinct,
            dim: 0,
            residual: 0.0,
            how: "points",
        });
    }
    let mean = DVector::from_fn(len, |c, _| {
        distinct.iter().map(|p| p[c]).sum::<f64>() / k as f64
    });
    let centred = DMatrix::from_fn(k, len, |r, c| distinct[r][c] - mean[c]);
    let svd = centred.clone().svd(false, true);
    let v_t = svd.v_t.ok_or("region: no singular vectors")?;
    let top = svd.singular_values.max();
    let dirs: Vec<usize> = (0..svd.singular_values.len())
        .filter(|&i| svd.singular_values[i] > RANK_TOL * top)
        .collect();
    let dim = dirs.len();
    let basis = DMatrix::from_fn(len, dim, |c, l| v_t[(dirs[l], c)]);
    let coords = &centred * &basis;
    let residual = (0..k)
        .map(|r| (centred.row(r).transpose() - &basis * coords.row(r).transpose()).norm())
        .fold(0.0, f64::max);
    if k <= 1usize << dim.min(30) {
        if k > MAX_REGION_VERTICES {
            return Err(too_many(k));
        }
        return Ok(Enclosure {
            vertex_count: k,
            vertices: distinct,
            dim,
            residual,
            how: "points",
        });
    }
    if dim > 6 {
        return Err(too_many(1usize << dim.min(30)));
    }
    let lo: Vec<f64> = (0..dim).map(|l| coords.column(l).min()).collect();
    let hi: Vec<f64> = (0..dim).map(|l| coords.column(l).max()).collect();
    let vertices: Vec<Vec<f64>> = (0..1usize << dim)
        .map(|mask| {
            let t = DVector::from_fn(dim, |l, _| if mask >> l & 1 == 1 { hi[l] } else { lo[l] });
            (&mean + &basis * t).as_slice().to_vec()
        })
        .collect();
    Ok(Enclosure {
        vertex_count: vertices.len(),
        vertices,
        dim,
        residual,
        how: "box",
    })
}

/// The error for an enclosure with `k` vertices.
fn too_many(k: usize) -> String {
    format!("region: the blended data needs {k} vertices, at most {MAX_REGION_VERTICES}; shrink the region or use gains that vary less between rules")
}

/// `sum_i h_i data_i` for each h in `weights`.
pub fn images(weights: &[Vec<f64>], data: &[Vec<f64>]) -> Vec<Vec<f64>> {
    weights
        .iter()
        .map(|h| {
            let len = data.first().map_or(0, Vec::len);
            (0..len)
                .map(|c| h.iter().zip(data).map(|(w, d)| w * d[c]).sum())
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whether two points agree to 1e-13 in every coordinate (relative to 1).
    fn close(a: &[f64], b: &[f64]) -> bool {
        a.iter()
            .zip(b)
            .all(|(x, y)| (x - y).abs() <= 1e-13 * (1.0 + x.abs()))
    }

    #[test]
    fn polytope_of_a_simplex_box_has_the_expected_vertices() {
        // h1 in [0.2, 0.5], h2 in [0.1, 0.6], h3 in [0.3, 0.4]: the vertices
        // by hand (two bounds set, the third from the sum).
        let v = polytope_vertices(&[(0.2, 0.5), (0.1, 0.6), (0.3, 0.4)]);
        let want = [
            [0.5, 0.2, 0.3],
            [0.5, 0.1, 0.4],
            [0.2, 0.5, 0.3],
            [0.2, 0.4, 0.4],
        ];
        assert_eq!(v.len(), want.len(), "{v:?}");
        for w in want {
            assert!(v.iter().any(|p| close(p, &w)), "{w:?} missing from {v:?}");
        }
    }

    #[test]
    fn enclosure_of_planar_points_is_their_principal_box() {
        // Points of a tilted square in R^3 (a 2-D span): 9 points, 4 corners.
        let mut pts = Vec::new();
        for a in [-1.0, 0.0, 1.0] {
            for b in [-2.0, 0.0, 2.0] {
                pts.push(vec![1.0 + a + b, 2.0 + a - b, 3.0 + 2.0 * a]);
            }
        }
        let e = enclose(&pts).unwrap(); // ok: test
        assert_eq!((e.dim, e.how, e.vertices.len()), (2, "box", 4));
        assert!(e.residual < 1e-12);
        // Every point lies in the parallelogram of the corners (mask order:
        // 0 = (lo, lo), 1 = (hi, lo), 2 = (lo, hi)): p = v0 + a e1 + b e2
        // with a, b in [0, 1], solved from the corners alone.
        let v = |k: usize| DVector::from_column_slice(&e.vertices[k]);
        let edges = DMatrix::from_columns(&[v(1) - v(0), v(2) - v(0)]);
        for p in &pts {
            let rhs = DVector::from_column_slice(p) - v(0);
            let ab = edges.clone().svd(true, true).solve(&rhs, 1e-12).unwrap(); // ok: test
            assert!((&edges * &ab - &rhs).amax() < 1e-9, "{p:?} off the plane");
            assert!(
                ab.iter().all(|c| (-1e-9..=1.0 + 1e-9).contains(c)),
                "{p:?} outside: {ab}"
            );
        }
        // The fourth corner closes the parallelogram.
        assert!((v(3) - v(0) - (v(1) - v(0)) - (v(2) - v(0))).amax() < 1e-9);
    }

    #[test]
    fn polytope_of_sixteen_narrow_rules_has_every_vertex_once() {
        // h_i in [0.04, 0.08], r = 16: sum = 1 needs exactly 9 coordinates at
        // 0.08 and 7 at 0.04, so the vertices are the C(16, 9) = 11,440 such
        // vectors, each found from 16 choices of the free coordinate.
        let v = polytope_vertices(&[(0.04, 0.08); 16]);
        assert_eq!(v.len(), 11_440);
        for p in &v {
            let high = p.iter().filter(|x| (**x - 0.08).abs() < 1e-12).count();
            let low = p.iter().filter(|x| (**x - 0.04).abs() < 1e-12).count();
            assert_eq!((high, low), (9, 7), "{p:?}");
        }
    }

    #[test]
    fn enclosure_refuses_more_than_its_vertex_limit() {
        // 200 points spanning 7 dimensions: neither they nor 2^7 corners fit.
        let pts: Vec<Vec<f64>> = (0..200)
            .map(|i| {
                (0..7)
                    .map(|k| (i as f64 * (k as f64 + 1.3)).sin())
                    .collect()
            })
            .collect();
        let err = enclose(&pts).expect_err("too many vertices");
        assert!(err.contains("at most 64"), "{err}");
    }

    #[test]
    fn about_bounds_bracket_sampled_degrees() {
        let t = TermSpec::About {
            first: 0,
            point: vec![0.5, -0.2],
            sigma: 0.4,
        };
        let z = [(-0.1, 0.3), (-0.3, 0.1)];
        let (lo, hi) = term_bounds(&t, &z);
        for i in 0..=20 {
            for j in 0..=20 {
                let p = [-0.1 + 0.02 * i as f64, -0.3 + 0.02 * j as f64];
                let d = about_degree(&p, &[0.5, -0.2], 0.4);
                assert!(d >= lo && d <= hi, "{d} outside [{lo}, {hi}]");
            }
        }
        // Attained at the corners: nearest (0.3, -0.2), farthest (-0.1, 0.1).
        assert_eq!(hi, about_degree(&[0.3, -0.2], &[0.5, -0.2], 0.4));
        assert_eq!(lo, about_degree(&[-0.1, 0.1], &[0.5, -0.2], 0.4));
    }
}
