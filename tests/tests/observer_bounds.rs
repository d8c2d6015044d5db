//! Input bounds and the saturation region of an observer-based loop
//! (issue 36): certified on the augmented state xi = (x, e), e = x - x_hat,
//! re-derived here from the report alone in the P-form (the compiler solves
//! and checks the X = P^-1 form), failing when the bound is tightened or the
//! gains scaled; then the nonlinear pendulum (RK4 on the textbook equation,
//! the continuous fuzzy observer from x_hat(0) = 0, the saturated command fed
//! to plant and observer) from points on the boundary of the certified set.

use crate::common::looped::{certified, mat};
use crate::common::observer::{pendulum, tsfc};
use crate::common::{compile_shipped, compile_text, errors_of, spec_path};
use nalgebra::{DMatrix, DVector};
use serde_json::Value;

const SATURATED: &str = "pendulum_observer_saturated.tsf";

/// What the report says of the loop and its bounds.
struct Data {
    /// Per rule: A, B, F, L.
    rules: Vec<[DMatrix<f64>; 4]>,
    c: DMatrix<f64>,
    p: DMatrix<f64>,
    alpha: f64,
    x0: Vec<f64>,
    mu: Option<f64>,
    /// The output bound on theta.
    lambda: f64,
    /// Levels, T (diagonal), H_j.
    sector: Option<Sector>,
}

/// The sector condition's data: levels, T (diagonal), H_j.
type Sector = (Vec<f64>, DMatrix<f64>, Vec<DMatrix<f64>>);

fn data(report: &Value) -> Data {
    let locals = report["local_models"].as_array().expect("local_models");
    let gains = report["gains"].as_array().expect("gains");
    let obs = &report["observer"];
    let ls = obs["gains"].as_array().expect("observer gains");
    let aug = &obs["augmented"];
    let b = &aug["bounds"];
    assert_eq!(b["xhat0"], serde_json::json!([0.0, 0.0]), "x_hat(0) = 0");
    let sector = b["saturation"].as_object().map(|s| {
        let levels: Vec<f64> = serde_json::from_value(s["levels"].clone()).expect("levels");
        let t: Vec<f64> = serde_json::from_value(s["T"].clone()).expect("T");
        let h = s["H"].as_array().expect("H").iter().map(mat).collect();
        (levels, DMatrix::from_diagonal(&DVector::from_vec(t)), h)
    });
    Data {
        rules: (0..locals.len())
            .map(|i| {
                [
                    mat(&locals[i]["A"]),
                    mat(&locals[i]["B"]),
                    mat(&gains[i]["F"]),
                    mat(&ls[i]["L"]),
                ]
            })
            .collect(),
        c: mat(&obs["C"]),
        p: mat(&aug["P"]),
        alpha: aug["decay_rate"].as_f64().expect("decay rate"),
        x0: serde_json::from_value(b["initial_points"][0].clone()).expect("x0"),
        mu: b["input_norm_bound"].as_f64(),
        lambda: b["output_norm_bound"].as_f64().expect("the output bound"),
        sector,
    }
}

/// K_j = [F_j, -F_j] (u = K_j xi), with F scaled by `scale`.
fn k(d: &Data, j: usize, scale: f64) -> DMatrix<f64> {
    let f = &d.rules[j][2] * scale;
    let n = f.ncols();
    DMatrix::from_fn(f.nrows(), 2 * n, |r, c| {
        if c < n {
            f[(r, c)]
        } else {
            -f[(r, c - n)]
        }
    })
}

/// G_ij = [A_i + B_i F_j, -B_i F_j; 0, A_i - L_i C] with F scaled.
fn g(d: &Data, i: usize, j: usize, scale: f64) -> DMatrix<f64> {
    let [a, b, _, l] = &d.rules[i];
    let bf = b * &d.rules[j][2] * scale;
    let n = a.nrows();
    let mut g = DMatrix::zeros(2 * n, 2 * n);
    g.view_mut((0, 0), (n, n)).copy_from(&(a + &bf));
    g.view_mut((0, n), (n, n)).copy_from(&(-&bf));
    g.view_mut((n, n), (n, n)).copy_from(&(a - l * &d.c));
    g
}

/// The P-form decay block of pair (i, j), with the sector column when the
/// loop saturates: [He(P G) + 2 a P, -P Bbar_i + H_j' T; *, -2 T].
fn decay_block(d: &Data, i: usize, j: usize, scale: f64) -> DMatrix<f64> {
    let gij = g(d, i, j, scale);
    let pg = &d.p * &gij;
    let top = &pg + pg.transpose() + &d.p * (2.0 * d.alpha);
    let Some((_, t, h)) = &d.sector else {
        return top;
    };
    let (s, m) = (top.nrows(), t.nrows());
    let b = &d.rules[i][1];
    let mut bbar = DMatrix::zeros(s, m);
    bbar.view_mut((0, 0), (b.nrows(), m)).copy_from(b);
    let col = -(&d.p * &bbar) + h[j].transpose() * t;
    let mut q = DMatrix::zeros(s + m, s + m);
    q.view_mut((0, 0), (s, s)).copy_from(&top);
    q.view_mut((0, s), (s, m)).copy_from(&col);
    q.view_mut((s, 0), (m, s)).copy_from(&col.transpose());
    q.view_mut((s, s), (m, m)).copy_from(&(t * -2.0));
    q
}

fn lmax(q: &DMatrix<f64>) -> f64 {
    q.clone().symmetric_eigen().eigenvalues.max() / q.norm()
}

fn lmin(q: &DMatrix<f64>) -> f64 {
    q.clone().symmetric_eigen().eigenvalues.min() / q.norm()
}

/// The worst decay condition of the basic relaxation (relative largest
/// eigenvalue of Q_ii and Q_ij + Q_ji): negative when all hold.
fn worst_decay(d: &Data, scale: f64) -> f64 {
    let r = d.rules.len();
    let mut worst = f64::NEG_INFINITY;
    for i in 0..r {
        for j in i..r {
            let q = if i == j {
                decay_block(d, i, i, scale)
            } else {
                decay_block(d, i, j, scale) + decay_block(d, j, i, scale)
            };
            worst = worst.max(lmax(&q));
        }
    }
    worst
}

/// [P, v'; v, level^2] for every controller rule's row v (relative smallest
/// eigenvalue): non-negative when E(P, 1) lies in |v xi| <= level.
fn worst_face(d: &Data, rows: &[DMatrix<f64>], level: f64) -> f64 {
    rows.iter()
        .map(|v| {
            let s = d.p.nrows();
            let mut q = DMatrix::zeros(s + 1, s + 1);
            q.view_mut((0, 0), (s, s)).copy_from(&d.p);
            q.view_mut((s, 0), (1, s)).copy_from(v);
            q.view_mut((0, s), (s, 1)).copy_from(&v.transpose());
            q[(s, s)] = level * level;
            lmin(&q)
        })
        .fold(f64::INFINITY, f64::min)
}

/// V = xi' P xi.
fn v(p: &DMatrix<f64>, xi: &[f64]) -> f64 {
    let xi = DVector::from_column_slice(xi);
    (xi.transpose() * p * &xi)[(0, 0)]
}

/// The level of x0 with x_hat(0) = 0: xi0 = (x0, x0).
fn x0_level(d: &Data, x0: &[f64]) -> f64 {
    v(&d.p, &[x0, x0].concat())
}

/// The sector rows (K_j - H_j)_s of channel 0 with F scaled.
fn sector_rows(d: &Data, scale: f64) -> Vec<DMatrix<f64>> {
    let (_, _, h) = d.sector.as_ref().expect("saturation data");
    (0..d.rules.len())
        .map(|j| (k(d, j, scale) - &h[j]).rows(0, 1).into_owned())
        .collect()
}

#[test]
fn saturation_region_of_the_observer_loop_holds_from_the_report_and_fails_tightened() {
    let report = certified(compile_shipped(SATURATED));
    let d = data(&report);
    let (levels, t, _) = d.sector.as_ref().expect("saturation data");
    assert_eq!(levels, &vec![200.0]);
    assert!(t[(0, 0)] > 0.0, "T > 0");
    assert_eq!(d.x0, vec![25f64.to_radians(), 0.0]);
    // Every condition with the reported data (relative rounding slack 1e-9).
    assert!(worst_decay(&d, 1.0) < 0.0, "{:e}", worst_decay(&d, 1.0));
    let face = worst_face(&d, &sector_rows(&d, 1.0), levels[0]);
    assert!(face > -1e-9, "linear region: {face:e}");
    let level = x0_level(&d, &d.x0);
    assert!(level <= 1.0 + 1e-9, "x0 level {level}");
    assert_eq!(d.lambda, 60f64.to_radians());
    let theta = DMatrix::from_row_slice(1, 4, &[1.0, 0.0, 0.0, 0.0]);
    let inside = worst_face(&d, std::slice::from_ref(&theta), d.lambda);
    assert!(inside > -1e-9, "|theta| <= 60 deg on E(P, 1): {inside:e}");
    assert!(worst_face(&d, &[theta], 0.9 * d.lambda) < 0.0, "not tight");
    // The report's region of attraction is the same augmented set.
    let roa = &report["region_of_attraction"];
    assert_eq!(mat(&roa["U"]), d.p);
    assert!((roa["x0_level"].as_f64().expect("level") - level).abs() < 1e-12);
    // Tightened: half the level, the gains doubled, x0 beyond the boundary.
    let half = worst_face(&d, &sector_rows(&d, 1.0), levels[0] / 2.0);
    assert!(half < 0.0, "half the level still holds: {half:e}");
    let doubled = worst_decay(&d, 2.0).max(-worst_face(&d, &sector_rows(&d, 2.0), levels[0]));
    assert!(doubled > 0.0, "doubled gains still hold: {doubled:e}");
    let out: Vec<f64> = d.x0.iter().map(|x| x * 1.01 / level.sqrt()).collect();
    assert!(x0_level(&d, &out) > 1.0);
}

/// The shipped spec with an input bound instead of the actuator limit,
/// from 15 deg (25 deg is infeasible with the output bound):
/// `objective input_norm(u) minimize for x0 = [15 deg, 0]`.
fn input_bound_spec() -> String {
    let text = std::fs::read_to_string(spec_path(SATURATED)).expect("the shipped spec");
    let out = text
        .replace("input u saturate 200;", "input u;")
        .replace(
            "objective saturation region for x0 = [25 * pi() / 180, 0];",
            "objective input_norm(u) minimize for x0 = [15 * pi() / 180, 0];",
        )
        .replace(
            "objective output_norm(th) <= thmax for x0 = [25 * pi() / 180, 0];",
            "objective output_norm(th) <= thmax for x0 = [15 * pi() / 180, 0];",
        );
    assert_eq!(
        out.matches("input_norm").count(),
        1,
        "the shipped spec's lines"
    );
    assert_eq!(out.matches("x0 = [15 * pi() / 180, 0]").count(), 2);
    assert!(!out.contains("u saturate"), "the actuator limit removed");
    out
}

#[test]
fn input_bound_of_the_observer_loop_holds_from_the_report_and_fails_tightened() {
    let report = certified(compile_text(
        "pendulum_observer_bounded",
        &input_bound_spec(),
    ));
    let d = data(&report);
    let mu = d.mu.expect("the certified bound");
    assert_eq!(
        report["objectives"]["input_norm_bound"].as_f64(),
        Some(mu),
        "the headline bound is the augmented one"
    );
    assert!(d.sector.is_none());
    let ks: Vec<DMatrix<f64>> = (0..d.rules.len()).map(|j| k(&d, j, 1.0)).collect();
    assert!(worst_decay(&d, 1.0) < 0.0);
    let face = worst_face(&d, &ks, mu);
    assert!(face > -1e-9, "input bound: {face:e}");
    assert!(x0_level(&d, &d.x0) <= 1.0 + 1e-9);
    // The minimized bound is tight (within the certified 0.1 % slack):
    // 0.98 mu fails at the reported P, and so do the doubled gains.
    assert!(worst_face(&d, &ks, 0.98 * mu) < 0.0, "0.98 mu holds");
    let k2: Vec<DMatrix<f64>> = (0..d.rules.len()).map(|j| k(&d, j, 2.0)).collect();
    assert!(worst_face(&d, &k2, mu) < 0.0, "doubled gains hold");
    // The state-feedback loop's bound is smaller: the observer's peaking
    // from x_hat(0) = 0 costs input.
    let sf = input_bound_spec()
        .replace("measure y = theta noise <= 0.001;", "")
        .replace("control observer_based(decay = 5);", "");
    let (_, c) = compile_text("pendulum_state_feedback_bounded", &sf);
    let sf_mu = serde_json::to_value(&c.report).expect("json")["objectives"]["input_norm_bound"]
        .as_f64()
        .expect("state-feedback bound");
    assert!(sf_mu < mu, "state feedback {sf_mu} vs observer {mu}");
}

/// Memberships of the shipped pendulum at theta (near, far): s = sinc(theta),
/// near = tri(s0, 1, 1), far = trap(-0.25, -0.25, s0, 1), s0 = sinc(60 deg).
fn memberships(theta: f64) -> [f64; 2] {
    let t = 60f64.to_radians();
    let s0 = t.sin() / t;
    let s = if theta == 0.0 {
        1.0
    } else {
        theta.sin() / theta
    };
    let near = ((s - s0) / (1.0 - s0)).clamp(0.0, 1.0);
    let far = if s <= s0 {
        1.0
    } else {
        ((1.0 - s) / (1.0 - s0)).clamp(0.0, 1.0)
    };
    let sum = near + far;
    [near / sum, far / sum]
}

/// One closed-loop derivative: the nonlinear pendulum and the continuous
/// fuzzy observer, both fed u = sat(sum_j h_j F_j x_hat) (`level` infinite
/// without an actuator limit). State: (theta, omega, theta_hat, omega_hat).
fn closed_loop(d: &Data, level: f64, s: [f64; 4]) -> ([f64; 4], f64) {
    let h = memberships(s[0]);
    let xh = DVector::from_column_slice(&s[2..]);
    let v: f64 = (0..2).map(|j| h[j] * (&d.rules[j][2] * &xh)[(0, 0)]).sum();
    let u = v.clamp(-level, level);
    let y = s[0];
    let mut dxh = DVector::zeros(2);
    for (i, [a, b, _, l]) in d.rules.iter().enumerate() {
        let innov = y - (&d.c * &xh)[(0, 0)];
        dxh += (a * &xh + b * u + l * innov) * h[i];
    }
    let dx = pendulum([s[0], s[1]], u);
    ([dx[0], dx[1], dxh[0], dxh[1]], v)
}

/// RK4 from `s0` for `time` s at step `dt`: the largest V over the run, V at
/// the end, the largest |v| (the unsaturated command) and the largest |theta|.
fn run(d: &Data, level: f64, s0: [f64; 4], time: f64, dt: f64) -> (f64, f64, f64, f64) {
    let vof = |s: &[f64; 4]| v(&d.p, &[s[0], s[1], s[0] - s[2], s[1] - s[3]]);
    let mut s = s0;
    let (mut vmax, mut umax, mut thmax) = (vof(&s), 0.0f64, s[0].abs());
    let add = |s: &[f64; 4], k: &[f64; 4], c: f64| std::array::from_fn(|r| s[r] + c * k[r]);
    for _ in 0..(time / dt).round() as usize {
        let (k1, u) = closed_loop(d, level, s);
        let (k2, _) = closed_loop(d, level, add(&s, &k1, dt / 2.0));
        let (k3, _) = closed_loop(d, level, add(&s, &k2, dt / 2.0));
        let (k4, _) = closed_loop(d, level, add(&s, &k3, dt));
        s = std::array::from_fn(|r| s[r] + dt / 6.0 * (k1[r] + 2.0 * k2[r] + 2.0 * k3[r] + k4[r]));
        vmax = vmax.max(vof(&s));
        umax = umax.max(u.abs());
        thmax = thmax.max(s[0].abs());
    }
    (vmax, vof(&s), umax, thmax)
}

/// Starts on the boundary of E(P, 1) (level 1 - 1e-6): the slice
/// x_hat(0) = 0 ((x0, x0) in 12 directions of the (theta, omega) plane), the
/// points where each rule's command K_j xi is largest (+-), and 16 seeded
/// directions of the whole augmented space. A start is (theta, omega,
/// theta_hat, omega_hat).
fn boundary_starts(d: &Data) -> Vec<[f64; 4]> {
    let on = |xi: [f64; 4]| -> [f64; 4] {
        let s = ((1.0 - 1e-6) / v(&d.p, &xi)).sqrt();
        // xi = (x, e), x_hat = x - e.
        [
            xi[0] * s,
            xi[1] * s,
            (xi[0] - xi[2]) * s,
            (xi[1] - xi[3]) * s,
        ]
    };
    let mut starts: Vec<[f64; 4]> = (0..12)
        .map(|k| {
            let phi = std::f64::consts::PI * f64::from(k) / 6.0;
            let (t, w) = (phi.cos(), 3.0 * phi.sin());
            on([t, w, t, w])
        })
        .collect();
    let x = d.p.clone().try_inverse().expect("P invertible");
    for j in 0..d.rules.len() {
        let dir = &x * k(d, j, 1.0).transpose();
        for sign in [1.0, -1.0] {
            starts.push(on(std::array::from_fn(|r| sign * dir[(r, 0)])));
        }
    }
    let mut rng = crate::common::Rng::new(36);
    for _ in 0..16 {
        starts.push(on(std::array::from_fn(|_| rng.uniform(-1.0, 1.0))));
    }
    starts
}

#[test]
fn nonlinear_pendulum_stays_in_the_certified_sets_from_their_boundary() {
    let sat = data(&certified(compile_shipped(SATURATED)));
    let level = sat.sector.as_ref().expect("sector").0[0];
    let mut saturated = false;
    for s0 in boundary_starts(&sat) {
        let (vmax, vend, umax, thmax) = run(&sat, level, s0, 8.0, 1e-3);
        assert!(vmax <= 1.0 + 1e-6, "{s0:?}: V reaches {vmax}");
        assert!(vend < 0.05, "{s0:?}: V(8 s) = {vend}");
        assert!(thmax < 60f64.to_radians(), "{s0:?}: theta {thmax}");
        saturated |= umax > level;
    }
    assert!(
        saturated,
        "no run saturates: the test does not exercise the sector"
    );
    let inp = data(&certified(compile_text(
        "pendulum_observer_bounded",
        &input_bound_spec(),
    )));
    let mu = inp.mu.expect("mu");
    let mut peak = 0.0f64;
    for s0 in boundary_starts(&inp) {
        let (vmax, vend, umax, thmax) = run(&inp, f64::INFINITY, s0, 8.0, 1e-3);
        assert!(thmax < 60f64.to_radians(), "{s0:?}: theta {thmax}");
        assert!(vmax <= 1.0 + 1e-6, "{s0:?}: V reaches {vmax}");
        assert!(vend < 0.05, "{s0:?}: V(8 s) = {vend}");
        assert!(umax <= mu, "{s0:?}: |u| = {umax} > mu = {mu}");
        peak = peak.max(umax);
    }
    assert!(
        peak > 0.2 * mu,
        "peak |u| {peak} of mu {mu}: a trivial bound"
    );
    // The continuous observer loop has no simulation to compare with: `tsfc
    // simulate` refuses it, naming the missing trigger (docs/limits.md).
    let dir = crate::common::fresh_dir("observer_bounds", "simulate");
    let out = tsfc(&["simulate"], &spec_path(SATURATED), &dir);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("trigger periodic"), "{err}");
}

/// (line, column) of byte offset `at` in `text`, both from 1.
fn line_col(text: &str, at: usize) -> (usize, usize) {
    let before = &text[..at];
    let line = before.matches('\n').count() + 1;
    let col = at - before.rfind('\n').map_or(0, |k| k + 1) + 1;
    (line, col)
}

#[test]
fn uncovered_observer_bound_combinations_are_refused_at_the_objective() {
    let spec = input_bound_spec();
    let objective = "objective output_norm(th)";
    // The sampled loop covers the input bound (observer_sampled_bounds.rs),
    // not the output bound: one error, at the output bound.
    let sampled = spec.replace(
        "control observer_based(decay = 5);",
        "control observer_based(decay = 5);\ntrigger periodic { every = 0.01; }",
    );
    let errors = errors_of("sampled.tsf", &sampled);
    assert_eq!(errors.len(), 1, "{errors:?}");
    let e = &errors[0];
    assert_eq!(
        e.message,
        "`objective output_norm` is not covered for the sampled `control observer_based` loop"
    );
    let at = sampled.find(objective).expect("the objective");
    assert_eq!(line_col(&sampled, e.span.start), line_col(&sampled, at));
    // H-inf together with the bounds.
    let hinf = spec.replace(
        "objective stability;",
        "objective stability;\ndisturbance d;\nD = [0; 1];\noutput z = theta;\nobjective hinf(d -> z) minimize;",
    );
    let errors = errors_of("hinf.tsf", &hinf);
    let e = errors.first().expect("an error");
    assert!(
        e.message
            .contains("`objective hinf` is not combined with an input bound"),
        "{}",
        e.message
    );
    let at = hinf.find("objective hinf").expect("the objective");
    assert_eq!(line_col(&hinf, e.span.start), line_col(&hinf, at));
}
