//! The rigorous model-error bound (`tsfc::model::error_bound`, issue 34):
//! exact (0 to rounding) for the `rules sector;` specs, and never below the
//! error found by dense seeded sampling with the interpreter (the spec's
//! A(x), B(x) and the runtime's memberships, not the affine evaluator) on the
//! other shipped specs.

use crate::common::shipped;
use nalgebra::DMatrix;
use tsf_lang::eval::Mode;
use tsfc::model::error_bound::{bound, default_region, BoundLimits, ModelErrorBound, StateBox};
use tsfc::model::{premise_values, rule_weight, TsModel};
use tsfc::util::rng::SplitMix64;

/// Relative tolerance of a "zero" bound: the bound over the largest entry
/// of the rules' matrices.
const ZERO_TOL: f64 = 1e-12;

fn largest_entry(model: &TsModel) -> (f64, f64) {
    let a = model.rules.iter().map(|r| r.a.amax()).fold(0.0, f64::max);
    let b = model.rules.iter().map(|r| r.b.amax()).fold(0.0, f64::max);
    (a, b)
}

/// The bound of a shipped spec on `region` (default limits), timed.
fn bound_of(model: &TsModel, region: &StateBox) -> ModelErrorBound {
    let t = std::time::Instant::now();
    let b = bound(model, &model.spec, region, &BoundLimits::default())
        .unwrap_or_else(|d| panic!("{}: {}", model.spec.controller.node, d.message));
    eprintln!(
        "{}: a_norm {:.3e}, b_norm {:.3e}, sampled {:.3e} / {:.3e}, {} boxes, converged {}, {:.3} s",
        model.spec.controller.node,
        b.a_norm,
        b.b_norm,
        b.sampled_max.0,
        b.sampled_max.1,
        b.boxes,
        b.converged,
        t.elapsed().as_secs_f64()
    );
    b
}

#[test]
fn sector_specs_have_a_zero_bound() {
    for name in ["lorenz_sector.tsf", "truck_trailer_sector.tsf"] {
        let model = shipped(name);
        let region = default_region(&model).expect("a sector box");
        let b = bound_of(&model, &region);
        let (sa, sb) = largest_entry(&model);
        assert!(
            b.a_entry.amax() <= ZERO_TOL * sa,
            "{name}: A bound {:e} (largest entry {sa})",
            b.a_entry.amax()
        );
        assert!(
            b.b_entry.amax() <= ZERO_TOL * sb.max(1.0),
            "{name}: B bound {:e}",
            b.b_entry.amax()
        );
        assert!(
            b.a_norm <= ZERO_TOL * sa * 3.0,
            "{name}: a_norm {:e}",
            b.a_norm
        );
    }
}

/// The largest entrywise |M(x) - sum h_i M_i| and spectral norms over
/// `samples` seeded states of `region` (interpreter and runtime memberships;
/// states whose premise values leave their ranges are skipped), per target
/// A, B.
fn sampled(
    model: &TsModel,
    region: &StateBox,
    samples: usize,
    seed: u64,
) -> [(DMatrix<f64>, f64); 2] {
    let spec = &model.spec;
    let mut rng = SplitMix64::new(seed);
    let ranges = model.premises.component_ranges();
    let mut out = [
        (DMatrix::zeros(model.n, model.n), 0.0),
        (DMatrix::zeros(model.n, model.m), 0.0),
    ];
    let mut counted = 0;
    for s in 0..samples {
        // Corners first, then uniform states.
        let x: Vec<f64> = region
            .iter()
            .enumerate()
            .map(|(k, &(lo, hi))| {
                if s < 1 << region.len().min(10) {
                    if (s >> k) & 1 == 1 {
                        hi
                    } else {
                        lo
                    }
                } else {
                    rng.uniform(lo, hi)
                }
            })
            .collect();
        let z = premise_values(spec, &x).expect("premises");
        if !z
            .iter()
            .zip(&ranges)
            .all(|(v, (lo, hi))| v >= lo && v <= hi)
        {
            continue;
        }
        let w: Vec<f64> = model.terms.iter().map(|t| rule_weight(t, &z)).collect();
        let total: f64 = w.iter().sum();
        assert!(total > 0.0);
        let env = spec.state_env(&x, Mode::Exact);
        let exact = [
            env.eval(&spec.a.as_ref().expect("A").expr).expect("A(x)"),
            env.eval(&spec.b.as_ref().expect("B").expr).expect("B(x)"),
        ];
        for (k, m) in exact.iter().enumerate() {
            let mut blend = DMatrix::zeros(m.nrows(), m.ncols());
            for (wi, r) in w.iter().zip(&model.rules) {
                blend += [&r.a, &r.b][k] * (wi / total);
            }
            let e = (blend - m).abs();
            out[k].1 = f64::max(out[k].1, e.clone().singular_values().max());
            out[k].0 = out[k].0.zip_map(&e, f64::max);
        }
        counted += 1;
    }
    assert!(
        counted > samples / 10,
        "{counted} states in the premise ranges"
    );
    out
}

/// The bound on `region` is never below the sampled error, entrywise and in
/// norm; returns the ratio bound / sampled of the A norm.
fn check_above_sampling(name: &str, region: StateBox) -> f64 {
    let model = shipped(name);
    let b = bound_of(&model, &region);
    let [(sa, na), (sb, nb)] = sampled(&model, &region, 20_000, 34);
    // The sampled errors carry the float evaluation's own rounding
    // (relative 1e-14 of the rules' largest entry).
    let (ta, tb) = largest_entry(&model);
    let (ta, tb) = (1e-14 * ta, 1e-14 * tb);
    for (what, bound, found, tol) in [("A", &b.a_entry, &sa, ta), ("B", &b.b_entry, &sb, tb)] {
        for (u, v) in bound.iter().zip(found.iter()) {
            assert!(
                u + tol >= *v,
                "{name}: {what} entry bound {u:e} below sampled {v:e}"
            );
        }
    }
    assert!(
        b.a_norm + ta >= na,
        "{name}: a_norm {} < sampled {na}",
        b.a_norm
    );
    assert!(
        b.b_norm + tb >= nb,
        "{name}: b_norm {} < sampled {nb}",
        b.b_norm
    );
    assert!(
        b.sampled_max.0 <= b.a_norm + ta,
        "the bound's own samples are below it"
    );
    let ratio = b.a_norm / na.max(f64::MIN_POSITIVE);
    eprintln!(
        "{name}: A bound / sampled = {ratio:.3} ({} / {na:.4e}); B {} / {nb:.4e}",
        b.a_norm, b.b_norm
    );
    ratio
}

#[test]
fn zhang_bound_is_above_dense_sampling() {
    let model = shipped("zhang2013_multiobjective.tsf");
    let region = default_region(&model).expect("operating points span a box");
    // The whole operating box: the premise kinks (mean(w) = 0, a diagonal
    // plane) cross every sub-box along it, so the bound is looser there.
    let ratio = check_above_sampling("zhang2013_multiobjective.tsf", region);
    assert!(ratio < 10.0, "ratio {ratio}");
    // A box between the kinks (every membership linear): tight.
    let small: StateBox = [vec![(0.02, 0.08); 3], vec![(0.03, 0.12); 3]].concat();
    let ratio = check_above_sampling("zhang2013_multiobjective.tsf", small);
    assert!(ratio < 3.0, "ratio {ratio}");
}

#[test]
fn pendulum_bound_is_above_dense_sampling() {
    let region = vec![(-1.5, 1.5), (-2.0, 2.0)];
    let ratio = check_above_sampling("inverted_pendulum.tsf", region);
    assert!(ratio < 3.0, "ratio {ratio}");
}

#[test]
fn xu_bound_is_above_dense_sampling() {
    let region = vec![(-0.2, 0.2); 6];
    let ratio = check_above_sampling("xu2020_event_triggered.tsf", region);
    assert!(ratio < 3.0, "ratio {ratio}");
}
