//! Regions on nonlinear premises (issue 35, item 3): `region theta = ..`
//! names a state, and the premise s = sinc(theta) is enclosed over that state
//! box (specs/pendulum_regional.tsf). Checked here, independently of tsfc's
//! membership code: the premise interval and the membership bounds contain
//! those of 20,000 seeded sampled states (h recomputed from sin(theta)/theta
//! and the rules' own local models); the spec certifies with E(P, c) inside
//! the box; an RK4 run of the nonlinear pendulum under the event trigger,
//! from the boundary of E(P, c), stays inside the box; a box on which the
//! premise leaves its range is refused at the setting.

use crate::common::{self, Rng};
use nalgebra::{DMatrix, DVector};
use std::sync::OnceLock;
use tsfc::driver::compile::Compiled;
use tsfc::model::region::premise_box;
use tsfc::model::TsModel;

const SPEC: &str = "pendulum_regional.tsf";
/// The spec's box: |theta| <= BOX.
const BOX: f64 = 0.3;
/// The spec's constants: g / l, friction b / J, 1 / J, input level, disturbance bound.
const G_L: f64 = 9.81 / 0.5;
const B_J: f64 = 0.05 / 0.125;
const INV_J: f64 = 1.0 / 0.125;
const U_BAR: f64 = 5.0;
const W_BAR: f64 = 0.2;

fn compiled() -> &'static (TsModel, Compiled) {
    static CELL: OnceLock<(TsModel, Compiled)> = OnceLock::new();
    CELL.get_or_init(|| common::compile_shipped(SPEC))
}

/// sin(theta) / theta (1 at 0).
fn sinc(theta: f64) -> f64 {
    if theta == 0.0 {
        1.0
    } else {
        theta.sin() / theta
    }
}

/// The normalized memberships at `theta`, from the rules' local models alone:
/// rule i's A[1, 0] is (g / l) s_i, and the sector blend sum h_i s_i = s with
/// sum h_i = 1 fixes h for two rules.
fn memberships(model: &TsModel, theta: f64) -> [f64; 2] {
    let s: Vec<f64> = model.rules.iter().map(|r| r.a[(1, 0)] / G_L).collect();
    let h0 = (sinc(theta) - s[1]) / (s[0] - s[1]);
    [h0, 1.0 - h0]
}

#[test]
fn premise_and_membership_bounds_contain_those_of_sampled_states() {
    let model = common::shipped(SPEC);
    assert_eq!(model.r(), 2);
    let b = premise_box(&model)
        .expect("a premise box")
        .expect("region settings");
    let e = b.enclosure.as_ref().expect("enclosed over the state box");
    assert_eq!(e.premises, ["s"]);
    assert_eq!(b.faces.len(), 1);
    assert_eq!((b.faces[0].name.as_str(), b.faces[0].bound), ("theta", BOX));
    assert_eq!(b.faces[0].row.as_slice(), &[1.0, 0.0]);
    let (zlo, zhi) = b.z[0];
    let mut rng = Rng::new(35);
    let mut thetas = vec![-BOX, 0.0, BOX];
    thetas.extend((0..20_000).map(|_| rng.uniform(-BOX, BOX)));
    for &theta in &thetas {
        let z = sinc(theta);
        assert!(
            z >= zlo && z <= zhi,
            "s = {z} outside [{zlo}, {zhi}] at theta = {theta}"
        );
        for (j, (h, (lo, hi))) in memberships(&model, theta)
            .iter()
            .zip(&b.h_bounds)
            .enumerate()
        {
            assert!(
                h >= lo && h <= hi,
                "h_{j} = {h} outside [{lo}, {hi}] at theta = {theta}"
            );
        }
    }
    // Not vacuous: the enclosure is tight (the exact minimum is sinc(0.3))
    // and far inside the premise range 2/pi .. 1.
    assert!(
        (zlo - sinc(BOX)).abs() < 1e-12 && zhi == 1.0,
        "[{zlo}, {zhi}]"
    );
    let (h_lo, h_hi) = b.h_bounds[0];
    assert!(h_lo > 0.95 && h_hi - h_lo < 0.05, "h_1 in [{h_lo}, {h_hi}]");
}

#[test]
fn the_spec_certifies_with_its_set_inside_the_state_box() {
    let (_, comp) = compiled();
    let t = common::event_design(comp);
    assert_eq!(t.plan.nu, 0.1, "certified for the spec's threshold");
    // The extent of E(P, c) along theta, sqrt(c (P^-1)_00), a closed form.
    let p_inv = t.p.clone().try_inverse().expect("P invertible");
    let extent = (t.level() * p_inv[(0, 0)]).sqrt();
    assert!(extent <= BOX, "E(P, c) reaches |theta| = {extent}");
    let region = comp
        .report
        .trigger
        .as_ref()
        .and_then(|r| r.region.as_ref())
        .expect("the report's trigger.region");
    assert_eq!(region.extents.len(), 1);
    assert!((region.extents[0] - extent).abs() <= 1e-9 * extent);
    assert!(region.premise_box.enclosure.is_some());
}

/// The truth pendulum's derivative.
fn pendulum(x: &[f64; 2], u: f64, w: f64) -> [f64; 2] {
    [x[1], G_L * x[0].sin() - B_J * x[1] + INV_J * (u + w)]
}

/// Largest |theta| and final x'(P/c)x of an RK4 run (1 ms) of the event-
/// triggered loop from `x0`: sampling intervals of 1 .. 20 ms (seeded), a
/// transmission when e'Ue >= nu x_k'Ux_k, u = sat(sum_j h_j(x_k) F_j x_k).
fn run(model: &TsModel, x0: [f64; 2], w: &dyn Fn(f64) -> f64, seconds: f64) -> (f64, f64) {
    let (_, comp) = compiled();
    let t = common::event_design(comp);
    let dt = 1e-3;
    let level = |x: &[f64; 2]| {
        let v = DVector::from_column_slice(x);
        (v.transpose() * &t.p * &v)[(0, 0)] / t.level()
    };
    let mut rng = Rng::new(7);
    let (mut x, mut xk) = (x0, DVector::<f64>::zeros(2));
    let (mut u, mut next, mut sent) = (0.0, 0usize, false);
    let mut peak = x0[0].abs();
    for k in 0..(seconds / dt).round() as usize {
        if k == next {
            let xs = DVector::from_column_slice(&x);
            let e = &xs - &xk;
            let lhs = (e.transpose() * &t.weight * &e)[(0, 0)];
            let rhs = t.plan.nu * (xk.transpose() * &t.weight * &xk)[(0, 0)];
            if !sent || lhs >= rhs {
                sent = true;
                xk = xs;
                let h = memberships(model, xk[0]);
                let f: DMatrix<f64> =
                    (0..2).fold(DMatrix::zeros(1, 2), |acc, j| acc + &t.plan.gains[j] * h[j]);
                u = (&f * &xk)[(0, 0)].clamp(-U_BAR, U_BAR);
            }
            next = k + 1 + (rng.uniform(0.0, 20.0) as usize).min(19);
        }
        let wk = w(k as f64 * dt);
        let step = |x: &[f64; 2], d: &[f64; 2], c: f64| [x[0] + c * d[0], x[1] + c * d[1]];
        let k1 = pendulum(&x, u, wk);
        let k2 = pendulum(&step(&x, &k1, 0.5 * dt), u, wk);
        let k3 = pendulum(&step(&x, &k2, 0.5 * dt), u, wk);
        let k4 = pendulum(&step(&x, &k3, dt), u, wk);
        x = std::array::from_fn(|i| x[i] + dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
        peak = peak.max(x[0].abs());
    }
    (peak, level(&x))
}

#[test]
fn the_nonlinear_loop_from_the_certified_boundary_stays_in_the_box() {
    let (model, comp) = compiled();
    let t = common::event_design(comp);
    // Points of the boundary x'Px = c in 16 directions.
    let starts: Vec<[f64; 2]> = (0..16)
        .map(|i| {
            let a = i as f64 * std::f64::consts::PI / 8.0;
            let d = DVector::from_vec(vec![a.cos(), a.sin()]);
            let r = (t.level() / (d.transpose() * &t.p * &d)[(0, 0)]).sqrt();
            [r * d[0], r * d[1]]
        })
        .collect();
    let mut worst = (0.0f64, 0.0f64);
    for x0 in &starts {
        // The bounded disturbance of the spec's scenario, and none.
        let (peak, _) = run(model, *x0, &|s| W_BAR * (3.0 * s).sin(), 4.0);
        let (_, rest) = run(model, *x0, &|_| 0.0, 4.0);
        worst = (worst.0.max(peak), worst.1.max(rest));
        assert!(peak <= BOX, "from {x0:?}: |theta| reached {peak}");
        assert!(
            rest < 0.05,
            "from {x0:?}: x'(P/c)x = {rest} after 4 s without disturbance"
        );
    }
    eprintln!(
        "from 16 points of the boundary of E(P, c): max |theta| {:.4} (box {BOX}); without disturbance the level after 4 s is at most {:.2e}",
        worst.0, worst.1
    );
}

/// The spec with its `region` line replaced by `line`.
fn with_region(line: &str) -> String {
    let text = std::fs::read_to_string(common::spec_path(SPEC)).expect("spec");
    let out = text.replace("    region theta = -0.3 .. 0.3;", line);
    assert_ne!(out, text, "the spec's region line");
    out
}

#[test]
fn a_state_box_whose_premise_leaves_its_range_is_refused_at_the_setting() {
    // |theta| <= 2 > pi/2: sinc(2) = 0.4546 < 2/pi.
    let e = common::errors_of(SPEC, &with_region("    region theta = -2 .. 2;"));
    assert_eq!(e.len(), 1, "{e:?}");
    assert!(
        e[0].message.contains("outside its range") && e[0].message.contains("premise value s"),
        "{}",
        e[0].message
    );
    assert!(e[0]
        .help
        .as_deref()
        .is_some_and(|h| h.contains("shrink the state box")));
    // At the setting's line.
    let text = with_region("    region theta = -2 .. 2;");
    let line = text
        .lines()
        .position(|l| l.contains("region theta = -2"))
        .expect("line");
    let at = text[..e[0].span.start].lines().count();
    assert_eq!(at, line + 1, "{e:?}");
    // A name that is neither a premise nor a state is a check error.
    let e = common::errors_of(SPEC, &with_region("    region phi = -1 .. 1;"));
    assert!(
        e[0].message.contains("no premise variable or state `phi`"),
        "{e:?}"
    );
    // `auto` needs a premise variable.
    let e = common::errors_of(SPEC, &with_region("    region theta = auto;"));
    assert!(
        e.iter()
            .any(|d| d.message.contains("needs a premise variable")),
        "{e:?}"
    );
}
