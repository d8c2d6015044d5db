//! Issue 36: the input bound and the saturation levels of the SAMPLED
//! observer loop (`synth/observer/sampled_bounds.rs`), on the shipped
//! `pendulum_observer_sampled_saturated.tsf` (saturate 200, 17 deg at rest:
//! the ACTIVE-saturation certificate, generalized sector condition), on its
//! 15-deg variant (the linear-region certificate) and on a variant with
//! `objective input_norm(u) minimize`.
//! Checked independently of tsfc's LMI code: (a) the conditions rebuilt
//! from the report in the P-form with nalgebra eigenvalues (P > 0,
//! [P, Kbar_l'; Kbar_l, mu^2 I] >= 0 with Kbar_l = [0, F_l], the linear
//! region per channel, xi0 = (x0, 0) in E(P, 1); with the saturation active
//! the paired looped-functional blocks with the dead-zone column and the
//! sector region), which fail tightened; (b)
//! the nonlinear pendulum (RK4 here) with the generated tables and the
//! runtime observer from points on the boundary of E(P, 1): |u_k| within the
//! level or mu, V(t_k) non-increasing, the actuator never saturating (linear
//! region) or saturating on some runs (active), the
//! state in the region; (c) `tsfc simulate` agrees; (d) the objectives the
//! sampled loop does not cover are refused at their line:col.

use crate::common;
use crate::common::looped::{mat, max_eig, report_gains, worst_paired, Looped};
use crate::common::observer::{pendulum, rk4_held, runtime_observer, runtime_terms, tsfc};
use crate::common::{errors_of, spec_path, Rng};
use nalgebra::{DMatrix, DVector};
use serde_json::Value;
use std::sync::OnceLock;
use tsf_runtime::Flags;
use tsfc::driver::prepare_run;
use tsfc::sim::Prepared;
use tsfc::synth::Settings;
use tsfc::tables::PremiseCode;

const SPEC: &str = "pendulum_observer_sampled_saturated.tsf";
/// The actuator level of the spec (N).
const LEVEL: f64 = 200.0;
/// The certified initial angle of the spec (17 deg, at rest: the saturation
/// certified active).
const TH0: f64 = 17.0 * std::f64::consts::PI / 180.0;
/// The angle of the linear-region variant (15 deg, at rest).
const TH_LINEAR: f64 = 15.0 * std::f64::consts::PI / 180.0;
/// The spec's initial-angle line.
const TH0_LINE: &str = "const th0 = 17 * pi() / 180;";

/// A compiled spec: its report and the tables generated code declares.
struct Loop {
    report: Value,
    prepared: Prepared,
}

fn compile_file(path: &std::path::Path) -> Loop {
    let run = tsfc::pipeline::read(path)
        .and_then(|f| f.compile(&Settings::default()))
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let report = serde_json::to_value(&run.compiled.report).expect("report json");
    let prepared = prepare_run(&run).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    Loop { report, prepared }
}

/// The shipped spec, compiled once per test binary.
fn shipped() -> &'static Loop {
    static L: OnceLock<Loop> = OnceLock::new();
    L.get_or_init(|| compile_file(&spec_path(SPEC)))
}

/// The shipped spec's saturation-region line.
const SATURATION: &str = "objective saturation region for x0 = [th0, 0];";

/// The shipped spec at 15 deg (its saturation-region line replaced by
/// `line` and the period by `period`), compiled from `tag`'s folder.
fn variant(tag: &str, line: &str, period: &str) -> Loop {
    let text = std::fs::read_to_string(spec_path(SPEC)).expect("spec");
    assert_eq!(text.matches(SATURATION).count(), 1, "the spec's line");
    assert_eq!(text.matches(TH0_LINE).count(), 1, "the spec's angle");
    let text = text
        .replace(SATURATION, line)
        .replace(TH0_LINE, "const th0 = 15 * pi() / 180;")
        .replace("every = 0.01;", &format!("every = {period};"));
    let dir = common::fresh_dir("observer_sampled_bounds", tag);
    let path = dir.join(format!("pendulum_observer_sampled_{tag}.tsf"));
    std::fs::write(&path, text).expect("write the variant");
    compile_file(&path)
}

/// The spec at 15 deg at rest: the linear-region certificate holds there.
fn linear() -> &'static Loop {
    static L: OnceLock<Loop> = OnceLock::new();
    L.get_or_init(|| variant("linear", SATURATION, "0.01"))
}

/// The shipped spec at 15 deg with a minimized input bound from the same initial
/// state, at T = 0.005 s (the design's gains change with the bound; at
/// 0.01 s its sampled loop is not certified).
fn minimized() -> &'static Loop {
    static L: OnceLock<Loop> = OnceLock::new();
    L.get_or_init(|| {
        let line = format!("{SATURATION}\nobjective input_norm(u) minimize for x0 = [th0, 0];");
        variant("minimized", &line, "0.005")
    })
}

/// Kbar = [0, F] (the u-rows of the augmented gain, xi = (x, xhat)).
fn kbar(f: &DMatrix<f64>) -> DMatrix<f64> {
    let (m, n) = f.shape();
    let mut k = DMatrix::zeros(m, 2 * n);
    k.view_mut((0, n), (m, n)).copy_from(f);
    k
}

/// The least eigenvalue of [P, K'; K, level^2 I] (>= 0: ||K xi|| <= level
/// on E(P, 1)).
fn bound_block(p: &DMatrix<f64>, k: &DMatrix<f64>, level: f64) -> f64 {
    let (n, m) = (p.nrows(), k.nrows());
    let mut b = DMatrix::zeros(n + m, n + m);
    b.view_mut((0, 0), (n, n)).copy_from(p);
    b.view_mut((n, 0), (m, n)).copy_from(k);
    b.view_mut((0, n), (n, m)).copy_from(&k.transpose());
    b.view_mut((n, n), (m, m))
        .copy_from(&(DMatrix::identity(m, m) * level * level));
    b.symmetric_eigenvalues().min()
}

/// xi0 = (x0, 0) for theta(0) = `th` at rest.
fn initial(th: f64) -> DVector<f64> {
    DVector::from_vec(vec![th, 0.0, 0.0, 0.0])
}

fn quad(p: &DMatrix<f64>, v: &DVector<f64>) -> f64 {
    (v.transpose() * p * v)[(0, 0)]
}

/// The worst block over the rules of `f` (every channel: the blocks are 1-row
/// for m = 1).
fn worst_block(p: &DMatrix<f64>, f: &[DMatrix<f64>], level: f64) -> f64 {
    f.iter()
        .map(|fl| bound_block(p, &kbar(fl), level))
        .fold(f64::INFINITY, f64::min)
}

/// (a) The 15-deg variant: P > 0, E(P, 1) inside |F_l xhat| <= 200 N for
/// both rules, (x0, 0) in E(P, 1); the report says the saturation is inactive
/// on the certified set. Not vacuous: doubled gains leave the linear region,
/// and theta(0) 2 % beyond the set's edge in the same direction is outside.
#[test]
fn saturation_linear_region_rederived_from_the_report_and_fails_tightened() {
    let report = &linear().report;
    let s = &report["sampled_loop"];
    let covers = s["covers"].as_str().expect("covers");
    assert!(covers.contains("decays at rate 0.5"), "{covers}");
    assert!(covers.contains("saturation is inactive"), "{covers}");
    let b = &s["bounds"];
    assert_eq!(b["saturation"], "inactive_on_certified_set", "{b}");
    assert_eq!(b["saturation_levels"], serde_json::json!([LEVEL]), "{b}");
    let p = mat(&s["P"]);
    assert!(
        p.symmetric_eigenvalues().min() > 0.0,
        "P is not positive definite"
    );
    let f = report_gains(report);
    let worst = worst_block(&p, &f, LEVEL);
    assert!(worst >= -1e-9, "linear region violated: {worst:e}");
    let doubled: Vec<DMatrix<f64>> = f.iter().map(|g| g * 2.0).collect();
    let loose = worst_block(&p, &doubled, LEVEL);
    assert!(loose < 0.0, "doubled gains pass: {loose:e}");
    let v0 = quad(&p, &initial(TH_LINEAR));
    assert!(v0 <= 1.0, "(x0, 0) outside E(P, 1): {v0}");
    let edge = TH_LINEAR / v0.sqrt();
    assert!(quad(&p, &initial(1.02 * edge)) > 1.0);
    eprintln!(
        "(x0, 0)' P (x0, 0) = {v0:.4}: the set reaches {:.2} deg at rest; worst linear-region block {worst:e}",
        edge.to_degrees()
    );
}

/// (a) The minimized input bound: the report's mu (also the objective's
/// `input_norm_bound`) satisfies [P, Kbar_l'; Kbar_l, mu^2] >= 0 for every
/// rule, with (x0, 0) in E(P, 1); 0.98 mu fails (mu is certified 0.1 %
/// above the least the solver finds over every P of the sampled
/// conditions, so no P of them certifies 0.98 mu).
#[test]
fn minimized_input_bound_rederived_from_the_report_and_fails_at_098_mu() {
    let report = &minimized().report;
    let s = &report["sampled_loop"];
    let mu = s["bounds"]["input_norm"].as_f64().expect("mu");
    assert_eq!(report["objectives"]["input_norm_bound"].as_f64(), Some(mu));
    let p = mat(&s["P"]);
    let f = report_gains(report);
    let worst = worst_block(&p, &f, mu);
    assert!(worst >= -1e-9, "input bound violated: {worst:e}");
    let tight = worst_block(&p, &f, 0.98 * mu);
    assert!(tight < 0.0, "0.98 mu passes: {tight:e}");
    assert!(quad(&p, &initial(TH_LINEAR)) <= 1.0 + 1e-9);
    // The bound is above what the command reaches at the start: |F_l x0|.
    let reach0 = f
        .iter()
        .map(|fl| (fl[(0, 0)] * TH_LINEAR).abs())
        .fold(0.0, f64::max);
    assert!(mu > reach0, "mu {mu} below |F x0| = {reach0}");
    eprintln!("minimized sampled input bound mu = {mu:.3} N (|F_l x0| <= {reach0:.3} N)");
}

/// What one run of the sampled loop saw.
struct Run {
    /// max |u_k|.
    u_max: f64,
    /// Whether any step saturated.
    saturated: bool,
    /// max V(t_{k+1}) / V(t_k).
    v_ratio: f64,
    /// max V(t_k) / (e^(-phi t_k) V(t_0)).
    v_decay: f64,
    /// max |theta(t)|, max |omega(t)|.
    reach: (f64, f64),
}

/// The nonlinear pendulum (RK4 at T / 10) under the generated tables and the
/// runtime observer from xi0 = (x0, xhat0), for `samples` periods; V
/// compared with the decay e^(-phi t).
fn run(l: &Loop, xi0: &DVector<f64>, samples: usize, phi: f64) -> Run {
    let tables = &l.prepared.tables;
    let PremiseCode::Exprs(exprs) = &tables.premise else {
        panic!("sinc premise")
    };
    let t = l.report["sampled_loop"]["sampling"][0].as_f64().expect("T");
    let p = mat(&l.report["sampled_loop"]["P"]);
    let terms = runtime_terms(tables);
    let obs = runtime_observer::<2, 1, 1, 1, 2, 2>(tables, &terms);
    let (mut x, mut xhat) = ([xi0[0], xi0[1]], [xi0[2], xi0[3]]);
    let mut out = Run {
        u_max: 0.0,
        saturated: false,
        v_ratio: 0.0,
        v_decay: 0.0,
        reach: (0.0, 0.0),
    };
    let (v0, mut v_prev) = (quad(&p, xi0), f64::NAN);
    for k in 0..samples {
        let v = quad(&p, &nalgebra::dvector![x[0], x[1], xhat[0], xhat[1]]);
        if v_prev > 1e-12 {
            out.v_ratio = out.v_ratio.max(v / v_prev);
        }
        v_prev = v;
        let envelope = (-phi * t * k as f64).exp() * v0;
        out.v_decay = out.v_decay.max(v / envelope);
        let y = [x[0]];
        let pv = obs.premise_state(&xhat, &y);
        let step = obs.step_with_premises(&mut xhat, &y, &[exprs[0].eval(&pv)]);
        out.saturated |= step.flags.contains(Flags::SATURATED);
        out.u_max = out.u_max.max(step.u[0].abs());
        for _ in 0..10 {
            rk4_held(&mut x, step.u[0], t / 10.0, 1, pendulum);
            out.reach = (out.reach.0.max(x[0].abs()), out.reach.1.max(x[1].abs()));
        }
    }
    out
}

/// Starts on the boundary of E(P, 1): 30 random directions of xi = (x,
/// xhat) and the initial-set direction (theta, 0, 0, 0).
fn boundary_starts(p: &DMatrix<f64>, seed: u64) -> Vec<DVector<f64>> {
    let mut rng = Rng::new(seed);
    let mut dirs: Vec<DVector<f64>> = (0..30)
        .map(|_| DVector::from_fn(4, |_, _| rng.uniform(-1.0, 1.0)))
        .collect();
    dirs.push(initial(1.0));
    dirs.into_iter().map(|v| &v / quad(p, &v).sqrt()).collect()
}

/// (b) The shipped spec's loop from the boundary of E(P, 1): the actuator
/// never saturates (|u_k| <= 200 N, no SATURATED flag), V(t_k) does not
/// increase and stays below the certified envelope e^(-2 alpha t_k) V(0)
/// (alpha = 0.5 when the report covers the decay rate, else 0), the state
/// stays in the region |theta| <= 50 deg, |omega| <= 5. The peak command
/// uses a fair part of the level (the bound is not trivial). With the
/// minimized variant: |u_k| <= mu.
#[test]
fn sampled_bounds_hold_along_nonlinear_runs_from_the_set_boundary() {
    let cases = [(linear(), LEVEL, 36), (minimized(), f64::NAN, 37)];
    for (l, level, seed) in cases {
        let level = if level.is_nan() {
            l.report["sampled_loop"]["bounds"]["input_norm"]
                .as_f64()
                .expect("mu")
        } else {
            level
        };
        let runs = boundary_runs(l, level, seed);
        assert!(runs.iter().all(|r| !r.saturated), "the actuator saturated");
        let peak = runs.iter().map(|r| r.u_max).fold(0.0, f64::max);
        assert!(peak > 0.3 * level, "peak |u| {peak} of {level}: trivial");
        eprintln!("peak |u_k| = {peak:.3} of {level:.3} from the boundary of E(P, 1)");
    }
}

/// The runs of [`run`] from [`boundary_starts`] of `l`'s E(P, 1) for 4 s,
/// each checked: |u_k| <= `level`, V(t_k) non-increasing and below the
/// certified envelope e^(-phi t_k) V(0) (phi = 1 when the report covers the
/// decay rate 0.5, else 0), the state in the region |theta| <= 50 deg,
/// |omega| <= 5.
fn boundary_runs(l: &Loop, level: f64, seed: u64) -> Vec<Run> {
    let s = &l.report["sampled_loop"];
    let t = s["sampling"][0].as_f64().expect("T");
    let covers = s["covers"].as_str().expect("covers");
    let phi = if covers.contains("decays at rate 0.5") {
        1.0
    } else {
        0.0
    };
    let p = mat(&s["P"]);
    let mut runs = Vec::new();
    for xi0 in boundary_starts(&p, seed) {
        let r = run(l, &xi0, (4.0 / t) as usize, phi);
        assert!(r.u_max <= level, "{xi0}: |u| = {} > {level}", r.u_max);
        assert!(
            r.v_ratio <= 1.0 + 1e-9,
            "{xi0}: V(t_k+1) / V(t_k) = {}",
            r.v_ratio
        );
        assert!(
            r.v_decay <= 1.0 + 1e-9,
            "{xi0}: V(t_k) above e^(-{phi} t_k) V(0) by {}",
            r.v_decay
        );
        assert!(
            r.reach.0 <= 50f64.to_radians() && r.reach.1 <= 5.0,
            "{xi0}: left the region {:?}",
            r.reach
        );
        runs.push(r);
    }
    runs
}

/// The report's sector multiplier T (diagonal) and sector gains G_q (one per
/// pair q = (observer rule j, controller rule l), j outer).
fn sector(report: &Value) -> (DMatrix<f64>, Vec<DMatrix<f64>>) {
    let b = &report["sampled_loop"]["bounds"];
    let t: Vec<f64> = serde_json::from_value(b["sector_multiplier"].clone()).expect("T");
    let g = b["sector_gains"].as_array().expect("G");
    (
        DMatrix::from_diagonal(&DVector::from_vec(t)),
        g.iter().map(mat).collect(),
    )
}

/// The worst paired block (drift `delta` of h_2) with the dead-zone column,
/// multiplier `t` and sector gains `g` (pair q = j r + l), at `phi`.
fn worst_paired_sat(
    report: &Value,
    t: &DMatrix<f64>,
    g: &[DMatrix<f64>],
    delta: f64,
    phi: f64,
) -> f64 {
    let lp = Looped::of(report);
    let f = report_gains(report);
    let r = lp.rules();
    worst_paired(&lp, delta, |plant, j, l| {
        lp.blocks_sat(plant, (j, &f[l]), phi, (t, &g[j * r + l]))
    })
}

/// The largest |(row xi)| on E(P, 1): sqrt(row P^-1 row').
fn reach(p_inv: &DMatrix<f64>, row: &DMatrix<f64>) -> f64 {
    (row * p_inv * row.transpose())[(0, 0)].sqrt()
}

/// (a) The shipped spec (17 deg at rest, the saturation ACTIVE): the paired
/// looped-functional blocks WITH the dead-zone column (plant and observer
/// fed the clipped command: -Bbar [I; Gu_j / T] dz; the sector term
/// He(dz' T G_q xi_k) - 2 dz' T dz) rebuilt from the report (P, Y, L, T,
/// G_q, the drift delta, the local models, F_l, L_j) are negative at the
/// decay rate 0.5; E(P, 1) lies inside the sector region
/// |((Kbar_l - G_q) xi)| <= 200 N and the sample box, and contains (x0, 0).
/// Not vacuous: with T = 0 the blocks fail; with G = 0 (no sector) the
/// region fails: the actuator DOES saturate on E(P, 1), by the factor
/// reported; (x0, 0) 2 % beyond the set's edge is outside.
#[test]
fn active_saturation_blocks_rederived_from_the_report_and_fail_without_the_sector() {
    let report = &shipped().report;
    let s = &report["sampled_loop"];
    let covers = s["covers"].as_str().expect("covers");
    assert!(covers.contains("decays at rate 0.5"), "{covers}");
    assert!(covers.contains("ACTIVE"), "{covers}");
    assert_eq!(
        s["bounds"]["saturation"], "active_sector",
        "{}",
        s["bounds"]
    );
    let (t, g) = sector(report);
    let delta = s["drift"]["delta"][1].as_f64().expect("delta");
    assert_eq!(
        s["drift"]["input_bound"].as_f64(),
        Some(LEVEL),
        "U by the actuator"
    );
    let worst = worst_paired_sat(report, &t, &g, delta, 1.0);
    assert!(worst < 0.0, "a paired block is not negative: {worst:e}");
    let none = worst_paired_sat(report, &(&t * 0.0), &g, delta, 1.0);
    assert!(none > 0.0, "T = 0 passes: {none:e}");
    let p = mat(&s["P"]);
    let p_inv = p.clone().try_inverse().expect("P invertible");
    let (f, r) = (report_gains(report), g.len() / 2);
    for (q, gq) in g.iter().enumerate() {
        let inside = reach(&p_inv, &(kbar(&f[q % r]) - gq));
        assert!(
            inside <= LEVEL * (1.0 + 1e-9),
            "pair {q}: {inside} > {LEVEL}"
        );
    }
    let command = f
        .iter()
        .map(|fl| reach(&p_inv, &kbar(fl)))
        .fold(0.0, f64::max);
    assert!(
        command > LEVEL,
        "|F_l xhat| <= {command} on E(P, 1): nothing saturates"
    );
    for (k, b) in s["drift"]["samples"]
        .as_array()
        .expect("box")
        .iter()
        .enumerate()
    {
        let half = b[1]
            .as_f64()
            .expect("box")
            .min(-b[0].as_f64().expect("box"));
        assert!(
            p_inv[(k, k)].sqrt() <= half,
            "state {k} leaves the sample box"
        );
    }
    let v0 = quad(&p, &initial(TH0));
    assert!(v0 <= 1.0, "(x0, 0) outside E(P, 1): {v0}");
    assert!(quad(&p, &initial(1.02 * TH0 / v0.sqrt())) > 1.0);
    eprintln!(
        "active: worst block {worst:e} (T = 0: {none:e}); |F_l xhat| reaches {command:.1} N on E(P, 1); the set reaches {:.2} deg at rest",
        (TH0 / v0.sqrt()).to_degrees()
    );
}

/// (b) The shipped spec (saturation active) from the boundary of E(P, 1)
/// with the runtime observer and a REAL saturating actuator: the actuator
/// saturates on some runs, and on every run V(t_k) stays below
/// e^(-t_k) V(0) and the state in the region ([`boundary_runs`]).
#[test]
fn active_saturation_holds_along_saturating_nonlinear_runs() {
    let runs = boundary_runs(shipped(), LEVEL, 38);
    let saturated = runs.iter().filter(|r| r.saturated).count();
    assert!(
        saturated > 0,
        "no run saturated: the test proves nothing new"
    );
    eprintln!("{saturated} of {} runs saturated the actuator", runs.len());
}

/// (c) `tsfc simulate` of the shipped spec (17 deg at rest, x_hat(0) = 0,
/// the measurement noise of the spec): exit 0, converged, max |u| within the
/// level, and within 5 % of the noise-free run here.
#[test]
fn tsfc_simulate_agrees_with_the_sampled_bounds() {
    let dir = common::fresh_dir("observer_sampled_bounds", "simulate");
    let out = tsfc(&["simulate"], &spec_path(SPEC), &dir);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    let metrics: Value = serde_json::from_slice(
        &std::fs::read(dir.join("pendulum_observer_sampled_saturated.metrics.json"))
            .expect("metrics"),
    )
    .expect("json");
    assert_eq!(metrics["converged"], Value::Bool(true), "{metrics}");
    let umax = metrics["max_abs_u"][0].as_f64().expect("max |u|");
    assert!(umax <= LEVEL, "{umax}");
    let here = run(shipped(), &initial(TH0), 500, 0.0);
    assert!(
        (umax - here.u_max).abs() <= 0.05 * here.u_max,
        "tsfc simulate max |u| {umax} vs {} here",
        here.u_max
    );
}

/// (d) The sampled loop does not cover the output bound or H-inf: refused at
/// the objective (file:line:col), with a hint naming what it covers.
#[test]
fn uncovered_sampled_objectives_are_refused_at_their_line_and_column() {
    let text = std::fs::read_to_string(spec_path(SPEC)).expect("spec");
    let anchor = "relaxation basic;";
    let cases = [
        (
            "output th = theta;\nobjective output_norm(th) <= thmax for x0 = [th0, 0];",
            "objective output_norm",
        ),
        (
            "disturbance d;\nD = [0; 1];\noutput z = theta;\nobjective hinf(d -> z) minimize;",
            "objective hinf",
        ),
    ];
    for (added, at) in cases {
        let spec = text.replace(anchor, &format!("{anchor}\n{added}"));
        let errors = errors_of(SPEC, &spec);
        assert_eq!(errors.len(), 1, "{errors:?}");
        let e = &errors[0];
        let word = at.trim_start_matches("objective ");
        assert_eq!(
            e.message,
            format!(
                "`objective {word}` is not covered for the sampled `control observer_based` loop"
            )
        );
        let help = e.help.as_deref().unwrap_or_default();
        assert!(
            help.contains("an input bound and saturation levels"),
            "{help}"
        );
        let want = spec.find(at).expect("the objective");
        assert_eq!(e.span.start, want, "{at}: not at its line:col");
    }
}

/// An ellipsoidal initial set {x0' R x0 <= 1} with x_hat(0) = 0: the x-block
/// of P satisfies P11 <= R (eigenvalues of R - P11), so every such x0 with
/// x_hat(0) = 0 lies in E(P, 1); the linear region holds as for a point.
#[test]
fn ellipsoidal_initial_set_gives_p11_below_r() {
    let line = "const R = [25, 0; 0, 25];\nobjective saturation region for x0 in ellipsoid(R);";
    let l = variant("ellipsoid", line, "0.01");
    let s = &l.report["sampled_loop"];
    assert_eq!(s["bounds"]["saturation"], "inactive_on_certified_set");
    let p = mat(&s["P"]);
    let gap = DMatrix::from_diagonal_element(2, 2, 25.0) - p.view((0, 0), (2, 2));
    let least = gap.symmetric_eigenvalues().min();
    assert!(least >= -1e-9, "P11 above R: {least:e}");
    let worst = worst_block(&p, &report_gains(&l.report), LEVEL);
    assert!(worst >= -1e-9, "linear region violated: {worst:e}");
}

/// (a) The free-vertex route (no `region`: every plant rule i with every
/// pair (j, l)) with the saturation active: the test oscillator of
/// `common::observer` with `saturate 5` from x1(0) = 0.9 at rest (the
/// linear-region certificate stops between 0.5 and 0.7). The blocks with the
/// dead-zone column, rebuilt from the report at every vertex (i, j, l), are
/// negative at the decay rate 0.5 and fail with T = 0; E(P, 1) lies in the
/// sector region and the command leaves the level on it.
#[test]
fn active_saturation_on_free_vertices_rederived_from_the_report() {
    let text = common::observer::OSC_SPEC
        .replace("PERIOD", "0.01")
        .replace("input u;", "input u saturate 5;")
        .replace(
            "relaxation basic;",
            "relaxation basic;\nobjective saturation region for x0 = [0.9, 0];",
        );
    let dir = common::fresh_dir("observer_sampled_bounds", "osc_active");
    let path = dir.join("osc_active.tsf");
    std::fs::write(&path, text).expect("write the spec");
    let report = &compile_file(&path).report;
    let s = &report["sampled_loop"];
    assert_eq!(
        s["bounds"]["saturation"], "active_sector",
        "{}",
        s["bounds"]
    );
    assert!(s["drift"].is_null(), "free vertices");
    assert!(s["covers"]
        .as_str()
        .expect("covers")
        .contains("decays at rate 0.5"));
    let (t, g) = sector(report);
    let (lp, f) = (Looped::of(report), report_gains(report));
    let r = lp.rules();
    let worst = |t: &DMatrix<f64>| {
        let mut worst = f64::NEG_INFINITY;
        for (a, b) in &lp.models {
            for (q, gq) in g.iter().enumerate() {
                let plant = lp.plant(a, b);
                let (r1, r2) = lp.blocks_sat(&plant, (q / r, &f[q % r]), 1.0, (t, gq));
                worst = worst.max(max_eig(&r1)).max(max_eig(&r2));
            }
        }
        worst
    };
    let (held, none) = (worst(&t), worst(&(&t * 0.0)));
    assert!(held < 0.0, "a vertex block is not negative: {held:e}");
    assert!(none > 0.0, "T = 0 passes: {none:e}");
    let p_inv = mat(&s["P"]).try_inverse().expect("P invertible");
    for (q, gq) in g.iter().enumerate() {
        let inside = reach(&p_inv, &(kbar(&f[q % r]) - gq));
        assert!(inside <= 5.0 * (1.0 + 1e-9), "pair {q}: {inside} > 5");
    }
    let command = f
        .iter()
        .map(|fl| reach(&p_inv, &kbar(fl)))
        .fold(0.0, f64::max);
    assert!(
        command > 5.0,
        "|F_l xhat| <= {command} on E(P, 1): nothing saturates"
    );
    eprintln!("free vertices, active: worst block {held:e} (T = 0: {none:e}); |F_l xhat| reaches {command:.2} on E(P, 1)");
}

/// With saturation the report's `region_of_attraction` is the sampled loop's
/// E(P, 1) written on (x, e): U = S' P S, S = [I, 0; I, -I], re-derived here
/// from `sampled_loop.P`. The objective's x0 at rest with x_hat(0) = 0 lies
/// in it at the level xi0' P xi0 (<= 1), 20 % further out it does not, and a
/// scenario started there gets the summary's outside-the-region warning.
#[test]
fn region_of_attraction_is_the_sampled_set_on_x_and_e() {
    let report = &shipped().report;
    let p = mat(&report["sampled_loop"]["P"]);
    let roa = &report["region_of_attraction"];
    let u = mat(&roa["U"]);
    let n = p.nrows() / 2;
    let mut s = DMatrix::<f64>::zeros(2 * n, 2 * n);
    for i in 0..n {
        s[(i, i)] = 1.0;
        s[(n + i, i)] = 1.0;
        s[(n + i, n + i)] = -1.0;
    }
    let want = s.transpose() * &p * &s;
    assert!(
        (&u - &want).amax() <= 1e-12 * want.amax(),
        "{u} against {want}"
    );
    let level = quad(&p, &initial(TH0));
    let reported = roa["x0_level"].as_f64().expect("x0_level");
    assert!(
        (reported - level).abs() <= 1e-12,
        "{reported} against {level}"
    );
    assert!(level <= 1.0 && roa["contains_x0"] == true, "{level}");
    assert!(quad(&p, &initial(1.2 * TH0)) > 1.0);

    let text = std::fs::read_to_string(spec_path(SPEC)).expect("spec");
    let line = "    x0 = [th0, 0];";
    assert_eq!(text.matches(line).count(), 1, "the scenario's x0");
    let dir = common::fresh_dir("observer_sampled_bounds", "outside");
    let path = dir.join("pendulum_observer_sampled_outside.tsf");
    std::fs::write(&path, text.replace(line, "    x0 = [1.2 * th0, 0];")).expect("write");
    let run = tsfc::pipeline::read(&path)
        .and_then(|f| f.compile(&Settings::default()))
        .unwrap_or_else(|e| panic!("{e}"));
    let roa = run
        .compiled
        .report
        .region_of_attraction
        .as_ref()
        .expect("region");
    assert_eq!(roa.contains_scenario_x0, Some(false));
    let summary =
        tsfc::driver::summary::summary(&run.model, &run.compiled, std::path::Path::new("r.json"));
    assert!(
        summary.contains("the scenario starts outside the certified region of attraction"),
        "{summary}"
    );
}
