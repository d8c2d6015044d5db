//! The sector variants of the spacecraft specs (issue 34, item 5):
//! `specs/zhang2013_sector.tsf` and `specs/xu2020_sector.tsf`. Checked here,
//! independently of tsfc's membership and plant code: (a) the sector blend
//! equals A(x), both re-computed in the test from the spec's formulas (and
//! A(x) x equals the paper's vector field), at 10,000 seeded states of the
//! claim's region; (b) the plant claim holds in an RK4 simulation of the
//! paper's nonlinear plant, written here, with the report's gains, from 16
//! points of the boundary of E(P, c): V stays <= c, the state stays in the
//! region; (c) the claimed decay rate (Zhang) and V decreasing (Xu) on
//! those runs; (d) `specs/xu2020_sector_large.tsf`'s claim contains the
//! paper's x(0), holds from it on the paper's plant, and its certified set
//! lies where the clamped premise is the paper's q0.

use crate::common::{self, Rng};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
use std::sync::OnceLock;
use tsfc::driver::compile::{Compiled, Status};
use tsfc::driver::plant::{production_bound, PlantRequest};
use tsfc::model::TsModel;

const ZHANG: &str = "zhang2013_sector.tsf";
const XU: &str = "xu2020_sector.tsf";
const XU_LARGE: &str = "xu2020_sector_large.tsf";

/// Xu & Huang's x(0) (|q(0)| = 0.66).
const XU_X0: [f64; 6] = [0.0, 0.0, 0.0, -0.3802, 0.2124, 0.5013];

/// The radius of `xu2020_sector_large.tsf`'s clamp: its premise is
/// sqrt(1 - q'q) where q'q <= R^2.
const XU_LARGE_R: f64 = 0.8;

/// The plant-claim compile of a shipped spec (its `plant region`).
fn compiled(name: &'static str) -> &'static (TsModel, Compiled) {
    static ZHANG_CELL: OnceLock<(TsModel, Compiled)> = OnceLock::new();
    static XU_CELL: OnceLock<(TsModel, Compiled)> = OnceLock::new();
    static XU_LARGE_CELL: OnceLock<(TsModel, Compiled)> = OnceLock::new();
    let cell = match name {
        ZHANG => &ZHANG_CELL,
        XU => &XU_CELL,
        _ => &XU_LARGE_CELL,
    };
    cell.get_or_init(|| {
        let model = common::shipped(name);
        let request = PlantRequest {
            bound: production_bound(),
            region: None,
        };
        let c = common::plant::run(&model, request);
        (model, c)
    })
}

/// Zhang's J, Xu's J.
fn inertia(name: &str) -> Matrix3<f64> {
    if name == ZHANG {
        Matrix3::new(127.0, 1.8, -3.4, 1.8, 117.0, -2.3, -3.4, -2.3, 210.0)
    } else {
        Matrix3::new(350.0, 3.0, 4.0, 3.0, 270.0, 10.0, 4.0, 10.0, 190.0)
    }
}

/// The cross-product matrix: skew(a) b = a x b.
fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v[2], v[1], v[2], 0.0, -v[0], -v[1], v[0], 0.0)
}

/// The premise values (w0, w1, w2, s) of the spec at x, from its formulas.
fn premises(name: &str, x: &[f64]) -> [f64; 4] {
    let (w, r) = (
        Vector3::new(x[0], x[1], x[2]),
        Vector3::new(x[3], x[4], x[5]),
    );
    let s = match name {
        ZHANG => r.dot(&w),
        XU => (1.0 - r.dot(&r)).abs().sqrt(),
        // sqrt(max(1 - q'q, 1 - R^2)).
        _ => (1.0 - r.dot(&r)).max(1.0 - XU_LARGE_R * XU_LARGE_R).sqrt(),
    };
    [w[0], w[1], w[2], s]
}

/// The spec's sector factorization A(x) (written here from the spec's text).
fn a_of(name: &str, x: &[f64]) -> DMatrix<f64> {
    let j = inertia(name);
    let ji = j.try_inverse().expect("J invertible");
    let w = Vector3::new(x[0], x[1], x[2]);
    let z = premises(name, x);
    let mut a = DMatrix::zeros(6, 6);
    let (top, br, bl) = if name == ZHANG {
        // Phi(w) = -skew(w).
        let phi = -skew(&w);
        (
            -ji * phi * j,
            0.5 * z[3] * Matrix3::identity() + 0.5 * phi,
            0.5 * Matrix3::identity(),
        )
    } else {
        (
            -ji * skew(&w) * j,
            -0.5 * skew(&w),
            0.5 * z[3] * Matrix3::identity(),
        )
    };
    a.view_mut((0, 0), (3, 3)).copy_from(&top);
    a.view_mut((3, 0), (3, 3)).copy_from(&bl);
    a.view_mut((3, 3), (3, 3)).copy_from(&br);
    a
}

/// The paper's nonlinear plant with input torque `u` (no disturbance):
/// Zhang (1), (3)-(4) as printed, Xu (2)-(3).
fn plant(name: &str, x: &[f64], u: &Vector3<f64>) -> DVector<f64> {
    let j = inertia(name);
    let ji = j.try_inverse().expect("J invertible");
    let (w, r) = (
        Vector3::new(x[0], x[1], x[2]),
        Vector3::new(x[3], x[4], x[5]),
    );
    let (wd, rd) = if name == ZHANG {
        let phi = |v: &Vector3<f64>| -skew(v);
        (
            ji * (u - phi(&w) * j * w),
            0.5 * (Matrix3::identity() - phi(&r) + r * r.transpose()) * w,
        )
    } else {
        let q0 = (1.0 - r.dot(&r)).sqrt();
        (
            ji * (-w.cross(&(j * w)) + u),
            0.5 * (q0 * Matrix3::identity() + skew(&r)) * w,
        )
    };
    DVector::from_iterator(6, wd.iter().chain(rd.iter()).copied())
}

/// The sector memberships of every rule at x, from the sector formula
/// (max: (z - lo)/(hi - lo), min: (hi - z)/(hi - lo)) and the rule's name
/// (`w0_max_w1_min_w2_max_s_min`), and each rule's vertex values.
fn memberships(model: &TsModel, name: &str, x: &[f64]) -> Vec<f64> {
    let z = premises(name, x);
    let ranges: Vec<(f64, f64)> = model.premises.slots.iter().map(|s| s.range).collect();
    assert_eq!(ranges.len(), 4);
    model
        .rules
        .iter()
        .map(|rule| {
            let words: Vec<&str> = rule.name.split('_').collect();
            assert_eq!(words.len(), 8, "{}", rule.name);
            (0..4)
                .map(|k| {
                    let (lo, hi) = ranges[k];
                    match words[2 * k + 1] {
                        "max" => (z[k] - lo) / (hi - lo),
                        "min" => (hi - z[k]) / (hi - lo),
                        other => panic!("{other} in {}", rule.name),
                    }
                })
                .product()
        })
        .collect()
}

/// The claim's region (every component bounded).
fn region(c: &Compiled) -> Vec<(f64, f64)> {
    c.report
        .plant
        .region
        .iter()
        .map(|r| r.expect("a bounded component"))
        .collect()
}

fn blend_equals_a(name: &'static str) {
    let (model, c) = compiled(name);
    assert_eq!(model.r(), 16);
    let bx = region(c);
    let mut rng = Rng::new(34);
    let mut worst = 0.0f64;
    for k in 0..10_000 {
        let x: Vec<f64> = bx
            .iter()
            .enumerate()
            .map(|(i, &(lo, hi))| match k {
                // The corners of the box along each axis pair first.
                0..=63 => [lo, hi][(k >> i) & 1],
                _ => rng.uniform(lo, hi),
            })
            .collect();
        let h = memberships(model, name, &x);
        assert!((h.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert!(h.iter().all(|v| *v >= -1e-15), "{h:?} at {x:?}");
        let blend = model
            .rules
            .iter()
            .zip(&h)
            .fold(DMatrix::zeros(6, 6), |acc, (r, hi)| acc + &r.a * *hi);
        let a = a_of(name, &x);
        let rel = (&blend - &a).amax() / a.amax().max(1.0);
        worst = worst.max(rel);
        assert!(rel <= 1e-12, "{name}: blend - A(x) = {rel:e} at {x:?}");
        // The factorization: A(x) x is the paper's vector field (for the
        // clamped premise where the clamp is inactive, q'q <= R^2).
        let q2: f64 = x[3..].iter().map(|v| v * v).sum();
        if name == XU_LARGE && q2 > XU_LARGE_R * XU_LARGE_R {
            continue;
        }
        let xv = DVector::from_column_slice(&x);
        let f = plant(name, &x, &Vector3::zeros());
        let e = (&a * &xv - &f).amax();
        assert!(
            e <= 1e-14 * (1.0 + f.amax()),
            "{name}: A(x) x - f(x) = {e:e}"
        );
    }
    // The report's bound is rounding too.
    let b = c.report.plant.error_bound.as_ref().expect("a bound");
    assert!(b.a <= 1e-12 && b.b == 0.0, "{name}: {} {}", b.a, b.b);
    eprintln!(
        "{name}: max |blend - A(x)| / max |A| = {worst:.2e} at 10,000 states; bound {:.2e}",
        b.a
    );
}

#[test]
fn zhang_sector_blend_equals_a_of_x() {
    blend_equals_a(ZHANG);
}

#[test]
fn xu_sector_blend_equals_a_of_x() {
    blend_equals_a(XU);
}

/// One RK4 step of the plant under u = sat(sum_j h_j(x) F_j x).
fn step(
    model: &TsModel,
    name: &str,
    gains: &[DMatrix<f64>],
    level: Option<f64>,
    x: &DVector<f64>,
    dt: f64,
) -> DVector<f64> {
    let f = |x: &DVector<f64>| {
        let h = memberships(model, name, x.as_slice());
        let u = gains
            .iter()
            .zip(&h)
            .fold(DVector::zeros(3), |acc, (g, hi)| acc + g * x * *hi);
        let u = Vector3::from_fn(|i, _| match level {
            Some(l) => u[i].clamp(-l, l),
            None => u[i],
        });
        plant(name, x.as_slice(), &u)
    };
    let k1 = f(x);
    let k2 = f(&(x + &k1 * (0.5 * dt)));
    let k3 = f(&(x + &k2 * (0.5 * dt)));
    let k4 = f(&(x + &k3 * dt));
    x + (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (dt / 6.0)
}

/// From 16 seeded points of the boundary of E(P, c): V(t) <= V(0) e^{-2 a t}
/// (relative tolerance `tol`), x in the region, and V(T) <= `end` V(0).
fn claim_holds(name: &'static str, dt: f64, steps: usize, end: f64) {
    let (model, c) = compiled(name);
    assert_eq!(c.status, Status::Certified, "{:?}", c.report.diagnosis);
    let plant_section = &c.report.plant;
    let claim = plant_section
        .claim
        .as_ref()
        .unwrap_or_else(|| panic!("{:?}", plant_section.note));
    eprintln!("{name}: {claim}");
    let rows = plant_section.p.as_ref().expect("P");
    let p = DMatrix::from_fn(6, 6, |i, j| rows[i][j]);
    let level = plant_section.level.expect("a level");
    let alpha = c.report.objectives.decay_rate.unwrap_or(0.0);
    let sat = model.spec.saturation.as_ref().map(|_| 2.0);
    let gains = &c.outcome.as_ref().expect("a design").0.gains;
    let bx = region(c);
    let v = |x: &DVector<f64>| (x.transpose() * &p * x)[(0, 0)];
    let mut rng = Rng::new(7);
    let mut starts: Vec<DVector<f64>> = (0..16)
        .map(|_| {
            let d = DVector::from_fn(6, |_, _| rng.uniform(-1.0, 1.0));
            &d * (level / v(&d)).sqrt()
        })
        .collect();
    if name == XU_LARGE {
        // The paper's start is inside the claim (the report says so).
        let x0 = DVector::from_column_slice(&XU_X0);
        assert!(v(&x0) <= level, "x0'Px0 = {} > c = {level}", v(&x0));
        starts.push(x0);
    }
    let (mut peak, mut last, mut q2_max) = (0.0f64, 0.0f64, 0.0f64);
    for start in &starts {
        let mut x = start.clone();
        let v0 = v(&x);
        // V(t) e^{2 a t}: non-increasing along the run (RK4's error allowed).
        let mut prev = v0;
        for k in 1..=steps {
            x = step(model, name, gains, sat, &x, dt);
            let t = k as f64 * dt;
            let bound = v0 * (-2.0 * alpha * t).exp();
            assert!(
                v(&x) <= bound * (1.0 + 1e-6),
                "{name}: V = {} above {bound} at t = {t}",
                v(&x)
            );
            let scaled = v(&x) * (2.0 * alpha * t).exp();
            assert!(
                scaled <= prev * (1.0 + 1e-7),
                "{name}: V e^(2at) rose from {prev} to {scaled} at t = {t}"
            );
            prev = scaled;
            for (i, (lo, hi)) in bx.iter().enumerate() {
                assert!(
                    x[i] >= *lo && x[i] <= *hi,
                    "{name}: x[{i}] = {} left the region",
                    x[i]
                );
                peak = peak.max(x[i].abs() / hi);
            }
            q2_max = q2_max.max(x.rows(3, 3).norm_squared());
        }
        last = last.max(v(&x) / v0);
        assert!(v(&x) <= end * v0, "{name}: V(T) / V(0) = {}", v(&x) / v0);
    }
    eprintln!(
        "{name}: {} runs from the boundary of E(P, {level:.4}){}: largest |x_i| / bound {peak:.3}, largest V(T)/V(0) {last:.3e} (decay claimed {alpha}), largest |q| {:.4}",
        starts.len(),
        if starts.len() > 16 { " and the paper's x(0)" } else { "" },
        q2_max.sqrt()
    );
    if name == XU_LARGE {
        // The runs stay where the clamped premise is the paper's q0.
        assert!(q2_max <= XU_LARGE_R * XU_LARGE_R, "|q| = {}", q2_max.sqrt());
    }
}

#[test]
fn zhang_sector_claim_holds_on_the_nonlinear_plant() {
    // Decay 0.01: V(T) <= e^{-2 * 0.01 * 100} V(0) = 0.135 V(0) at T = 100 s.
    claim_holds(ZHANG, 0.05, 2000, (-2.0f64).exp());
}

#[test]
fn xu_sector_claim_holds_on_the_nonlinear_plant() {
    // No decay rate is claimed: V non-increasing, and well below V(0) after 60 s.
    claim_holds(XU, 0.01, 6000, 0.5);
}

#[test]
fn xu_sector_large_blend_equals_a_of_x() {
    blend_equals_a(XU_LARGE);
}

#[test]
fn xu_sector_large_claim_holds_from_the_paper_start() {
    // Decay 0.005: V(T) <= e^{-2 * 0.005 * 300} V(0) = 0.050 V(0) at T = 300 s.
    claim_holds(XU_LARGE, 0.05, 6000, (-3.0f64).exp());
}

/// The claim of `xu2020_sector_large.tsf` is about the paper's plant: its
/// certified set E(P, c) lies inside |q| <= R (c lambda_max((P^-1)_qq) <= R^2,
/// computed here from the report's P), where the clamped premise equals
/// sqrt(1 - q'q), so A(x) x is the paper's vector field on it; it contains
/// x(0); and the report's claim says so.
#[test]
fn xu_sector_large_set_is_where_the_model_is_the_paper_s() {
    let (_, c) = compiled(XU_LARGE);
    assert_eq!(c.status, Status::Certified, "{:?}", c.report.diagnosis);
    let plant_section = &c.report.plant;
    let rows = plant_section.p.as_ref().expect("P");
    let p = DMatrix::from_fn(6, 6, |i, j| rows[i][j]);
    let level = plant_section.level.expect("a level");
    let x = p.clone().try_inverse().expect("P invertible");
    let xqq = x.view((3, 3), (3, 3)).into_owned();
    let top = xqq.symmetric_eigenvalues().max();
    let radius = (level * top).sqrt();
    assert!(radius <= XU_LARGE_R, "E(P, c) reaches |q| = {radius}");
    let x0 = DVector::from_column_slice(&XU_X0);
    let l0 = (x0.transpose() * &p * &x0)[(0, 0)];
    assert!(l0 <= level, "x0'Px0 = {l0} > c = {level}");
    let reported = plant_section
        .scenario_x0_level
        .expect("the report's x0'Px0");
    assert!((reported - l0).abs() <= 1e-12 * l0, "{reported} vs {l0}");
    let claim = plant_section.claim.as_deref().expect("a claim");
    assert!(
        claim.contains("the simulate block's x(0) is in it"),
        "{claim}"
    );
    eprintln!("xu2020_sector_large: x0'Px0 = {l0:.6} <= c = {level:.6}; E(P, c) reaches |q| <= {radius:.4}");
}

/// The model-error bound of `xu2020_sector_large.tsf` on its claim's box:
/// the premise ranges are proved by splitting only the states the unproved
/// premise reads (s reads q alone), well inside the work limits, and the
/// bound is rounding-sized.
#[test]
fn xu_sector_large_bound_splits_the_states_of_the_premise_that_leaves() {
    use tsfc::model::error_bound::premise_range::{PremiseRange, MAX_PREMISE_BOXES};
    use tsfc::model::error_bound::{bound, BoundLimits, MAX_BOXES};
    let model = common::shipped(XU_LARGE);
    let region = model.spec.plant_region.clone().expect("a plant region");
    let b = bound(&model, &model.spec, &region, &BoundLimits::default())
        .unwrap_or_else(|d| panic!("{}", d.message));
    let PremiseRange::Inside { boxes } = b.premise else {
        panic!("{:?}", b.premise)
    };
    assert!(boxes < MAX_PREMISE_BOXES / 4, "{boxes} premise sub-boxes");
    assert!(b.boxes <= MAX_BOXES);
    assert!(
        b.a_norm <= 1e-12 && b.b_norm == 0.0,
        "{} {}",
        b.a_norm,
        b.b_norm
    );
    eprintln!(
        "xu2020_sector_large: ||dA|| <= {:.2e} ({} sub-boxes), premise ranges proved on {boxes}",
        b.a_norm, b.boxes
    );
}
