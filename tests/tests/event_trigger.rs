//! Xu & Huang (2020) event-triggered co-design (issue 6): the shipped spec's
//! trigger weight and threshold are certified for every sampling interval in
//! [h_min, h_max]; the trigger conditions are re-derived here from their scalar
//! definition (independent of tsfc's LMI builder); the report carries the
//! trigger, region and L-inf fields; the closed loop converges from the paper's
//! x(0), and the paper's own Appendix A design is simulated in the same scenario
//! for comparison.

use crate::common;

use nalgebra::{DMatrix, DVector};
use std::sync::OnceLock;
use tsf_lang::spec::{Threshold, Trigger, Weight};
use tsfc::driver::compile::{compile, Compiled, Status};
use tsfc::model::TsModel;
use tsfc::report::SpecInfo;
use tsfc::sim::{simulate, Options, Outcome, Prepared};
use tsfc::synth::{Settings, TriggerDesign};

const SPEC: &str = "xu2020_event_triggered.tsf";

/// The spec compiled once per test binary (the trigger SDP takes ~25 s).
pub(crate) fn compiled() -> &'static (TsModel, Compiled) {
    static CELL: OnceLock<(TsModel, Compiled)> = OnceLock::new();
    CELL.get_or_init(|| common::compile_shipped(SPEC))
}

pub(crate) fn trigger() -> &'static TriggerDesign {
    let (_, c) = compiled();
    assert_eq!(c.status, Status::Certified, "{:?}", c.report.diagnosis);
    let (design, _) = c.outcome.as_ref().expect("certified");
    design.loop_design.event().expect("a synthesized trigger")
}

fn value<'a>(t: &'a TriggerDesign, name: &str) -> &'a DMatrix<f64> {
    t.values
        .iter()
        .find(|(n, _)| n == name)
        .map(|(_, v)| v)
        .unwrap_or_else(|| panic!("variable {name} missing"))
}

/// Lambda_{ij r}(h) assembled from the scalar quadratic form it represents
/// (polarization on basis vectors), with the Schur complement of r = 2 undone
/// (h L e^{phi h_max} Y^{-1} L'): an independent re-derivation of
/// docs/event_trigger.md, not of tsfc's block expressions.
fn lambda_by_polarization(
    model: &TsModel,
    t: &TriggerDesign,
    nu: f64,
    (i, j): (usize, usize),
    h: f64,
    r: u8,
) -> DMatrix<f64> {
    let plant = (&model.rules[i].a, &model.rules[i].b, &t.plan.d[i]);
    lambda_at(t, nu, plant, (&t.plan.gains[j], &t.plan.sector[j]), h, r)
}

/// [`lambda_by_polarization`] for a plant (A, B, D) and a controller (F, G)
/// given directly (a blended model of a regional certificate, say).
pub(crate) fn lambda_at(
    t: &TriggerDesign,
    nu: f64,
    (a, b, d): (&DMatrix<f64>, &DMatrix<f64>, &DMatrix<f64>),
    (f, g): (&DMatrix<f64>, &DMatrix<f64>),
    h: f64,
    r: u8,
) -> DMatrix<f64> {
    let (n, m) = (a.nrows(), b.ncols());
    let plan = &t.plan;
    let q = d.ncols();
    let k = 3 * n + m + q;
    let (p, y, w) = (value(t, "Ptr"), value(t, "Ytr"), value(t, "Upsilon"));
    let (l1, l2) = (value(t, "L1"), value(t, "L2"));
    let tm = value(t, "T");
    let xi = value(t, "xi_tr")[(0, 0)];
    let y_inv = y.clone().try_inverse().expect("Y > 0");
    let h_max = plan.sampling.1;
    // psi = [x; x(s); e; dz; tau]
    let form = |psi: &DVector<f64>| -> f64 {
        let x = psi.rows(0, n).into_owned();
        let xs = psi.rows(n, n).into_owned();
        let e = psi.rows(2 * n, n).into_owned();
        let dz = psi.rows(3 * n, m).into_owned();
        let tau = psi.rows(3 * n + m, q).into_owned();
        let xk = &xs - &e; // last transmitted state x(t_k)
        let xdot = a * &x + b * (f * &xk) - b * &dz + d * &tau;
        let mut v = 2.0 * x.dot(&(p * &xdot)) + plan.phi * x.dot(&(p * &x));
        // 2 eta' L (x - x(s)), eta = [x; x(s)]
        let lx = l1.transpose() * &x + l2.transpose() * &xs;
        v += 2.0 * lx.dot(&(&x - &xs));
        v += nu * xk.dot(&(w * &xk)) - e.dot(&(w * &e));
        v += 2.0 * dz.dot(&(tm * (g * &xk - &dz)));
        v -= xi * tau.dot(&tau);
        if r == 1 {
            v += h * xdot.dot(&(y * &xdot));
        } else {
            v += h * (plan.phi * h_max).exp() * lx.dot(&(&y_inv * &lx));
        }
        v
    };
    let basis = |a: usize| DVector::from_fn(k, |c, _| if c == a { 1.0 } else { 0.0 });
    let diag: Vec<f64> = (0..k).map(|a| form(&basis(a))).collect();
    DMatrix::from_fn(k, k, |a, c| {
        if a == c {
            diag[a]
        } else {
            0.5 * (form(&(basis(a) + basis(c))) - diag[a] - diag[c])
        }
    })
}

pub(crate) fn max_eig(m: &DMatrix<f64>) -> f64 {
    let s = 0.5 * (m + m.transpose());
    s.symmetric_eigen().eigenvalues.max()
}

#[test]
fn trigger_conditions_hold_for_every_rule_pair_and_sampling_interval() {
    let (model, _) = compiled();
    let t = trigger();
    conditions_hold(model, t);
    // The check can fail: four times the certified threshold is not certified
    // for these multipliers.
    assert!(
        violated_at(model, t, 4.0 * t.plan.nu),
        "nu = {} unexpectedly satisfies the conditions",
        4.0 * t.plan.nu
    );
}

/// Every Lambda_{ij r}(h), re-derived by polarization at the design's nu, is
/// negative definite for h in {h_min, (h_min + h_max)/2, h_max}.
fn conditions_hold(model: &TsModel, t: &TriggerDesign) {
    let (h_min, h_max) = t.plan.sampling;
    let r = model.r();
    let mut worst = f64::NEG_INFINITY;
    // h_min and h_max are imposed; the midpoint is implied (Lambda is affine in h).
    for h in [h_min, 0.5 * (h_min + h_max), h_max] {
        for rr in [1u8, 2] {
            for i in 0..r {
                for j in 0..r {
                    let l = lambda_by_polarization(model, t, t.plan.nu, (i, j), h, rr);
                    let e = max_eig(&l);
                    worst = worst.max(e / l.norm());
                    assert!(e < 0.0, "Lambda[{i},{j}] r={rr} h={h}: max eig {e:e}");
                }
            }
        }
    }
    eprintln!("trigger LMIs re-derived: worst max eig / ||Lambda|| = {worst:e}");
}

/// Whether some Lambda_{ij r}(h_max) is indefinite with the threshold `nu`
/// put in place of the certified one.
fn violated_at(model: &TsModel, t: &TriggerDesign, nu: f64) -> bool {
    let r = model.r();
    let h_max = t.plan.sampling.1;
    (0..r).flat_map(|i| (0..r).map(move |j| (i, j))).any(|ij| {
        [1u8, 2]
            .iter()
            .any(|&rr| max_eig(&lambda_by_polarization(model, t, nu, ij, h_max, rr)) > 0.0)
    })
}

#[test]
fn region_and_peak_conditions_hold() {
    region_and_peak_hold(trigger());
}

/// P, Upsilon > 0; E(P, c) inside the linear region of every gain; the output peak.
fn region_and_peak_hold(t: &TriggerDesign) {
    let p = value(t, "Ptr");
    let xi = value(t, "xi_tr")[(0, 0)];
    let gamma = value(t, "gamma_tr")[(0, 0)];
    assert!(p.clone().symmetric_eigen().eigenvalues.min() > 0.0);
    assert!(
        value(t, "Upsilon")
            .clone()
            .symmetric_eigen()
            .eigenvalues
            .min()
            > 0.0
    );
    // E(P, c) inside |(F_j - G_j)_s x| <= u_bar_s: max over the ellipsoid of
    // |k x| is sqrt(c k P^{-1} k'), c = xi_max tau_bar^2 / phi, the level
    // V' <= -phi V + xi tau'tau keeps V below from rest (xi <= xi_max).
    let plan = &t.plan;
    assert!(xi <= plan.xi_max);
    let c = plan.xi_max * plan.tau_bar * plan.tau_bar / plan.phi;
    let p_inv = p.clone().try_inverse().expect("P > 0");
    for (f, g) in plan.gains.iter().zip(&plan.sector) {
        for (s, ub) in plan.levels.iter().enumerate() {
            let kr = (f - g).row(s).into_owned();
            let peak = (c * (&kr * &p_inv * kr.transpose())[(0, 0)]).sqrt();
            assert!(peak <= ub * (1.0 + 1e-6), "channel {s}: {peak} > {ub}");
        }
    }
    // Output peak (C = I, no feedthrough): gamma >= xi and phi P - C'C / gamma >= 0.
    assert!(gamma >= xi - 1e-9);
    let id = DMatrix::<f64>::identity(p.nrows(), p.ncols());
    let s = p * plan.phi - id / gamma;
    assert!(s.symmetric_eigen().eigenvalues.min() > -1e-9);
}

#[test]
fn certificate_and_report_cover_the_trigger() {
    let (model, c) = compiled();
    let t = trigger();
    let (_, cert) = c.outcome.as_ref().expect("certified");
    assert!(cert.ok);
    let r = model.r();
    for prefix in [
        "trigger r=1 h=0.001",
        "trigger r=2 h=0.001",
        "trigger r=1 h=0.1",
        "trigger r=2 h=0.1",
    ] {
        let found: Vec<_> = cert
            .lmis
            .iter()
            .filter(|l| l.name.starts_with(prefix))
            .collect();
        assert_eq!(found.len(), r * r, "{prefix}");
        assert!(found.iter().all(|l| l.ok && l.margin > 0.0), "{prefix}");
    }
    let json = crate::common::schema::report_json(&c.report);
    let trig = &json["trigger"];
    let weight = trig["weight"].as_array().expect("weight rows");
    assert_eq!(weight.len(), model.n);
    for (a, row) in weight.iter().enumerate() {
        for (b, v) in row.as_array().expect("row").iter().enumerate() {
            assert_eq!(v.as_f64(), Some(t.weight[(a, b)]));
        }
    }
    assert_eq!(trig["nu"].as_f64(), Some(0.25));
    assert_eq!(trig["nu_min"].as_f64(), Some(0.2));
    assert_eq!(trig["sampling"][0].as_f64(), Some(0.001));
    assert_eq!(trig["sampling"][1].as_f64(), Some(0.1));
    let roa = &json["region_of_attraction"];
    assert_eq!(roa["U"].as_array().map(Vec::len), Some(model.n));
    // The certified ellipsoid does not contain the paper's x(0) (spec comment):
    // the scenario starts outside it; the objective asks no containment.
    assert_eq!(roa["contains_scenario_x0"].as_bool(), Some(false));
    assert!(roa["scenario_x0_level"].as_f64().expect("level") > 1.0);
    // U = P / c with c the certified level (xi_max tau_bar^2 / phi).
    let plan = &t.plan;
    let c = plan.xi_max * plan.tau_bar * plan.tau_bar / plan.phi;
    let u00 = roa["U"][0][0].as_f64().expect("U");
    assert!(
        (u00 * c / t.p[(0, 0)] - 1.0).abs() < 1e-12,
        "{u00} vs {}",
        t.p[(0, 0)] / c
    );
    assert!(roa["contains_x0"].is_null());
    let obj = &json["objectives"];
    assert_eq!(obj["linf_gamma_paper"].as_f64(), Some(0.1616));
    let g_ct = obj["linf_gamma"].as_f64().expect("linf_gamma");
    let g_et = obj["linf_gamma_event_triggered"]
        .as_f64()
        .expect("event-triggered gamma");
    assert_eq!(g_et, t.gamma);
    // Issue 17's goal: the paper's nu = 0.2 (here up to 0.25) with gamma at or
    // below its 0.1616. The continuous number is larger: the continuous design
    // keeps E(P, 1) inside the linear region (it bounds the designed gains),
    // the certificate of the fixed gains only the level reached from rest.
    assert!(
        t.plan.nu >= 0.2 && g_et <= 0.1616,
        "nu {}, gamma {g_et}",
        t.plan.nu
    );
    assert!(g_et < g_ct, "{g_et} vs {g_ct}");
    eprintln!(
        "linf gamma: continuous {g_ct:.4}, event-triggered {g_et:.4}, paper 0.1616; nu <= {}",
        t.plan.nu
    );
}

/// The simulator's view of the design of [`compiled`] (no second compile).
pub(crate) fn prepared() -> &'static Prepared {
    static CELL: OnceLock<Prepared> = OnceLock::new();
    CELL.get_or_init(|| {
        let (model, c) = compiled();
        let (design, cert) = c.outcome.as_ref().expect("certified");
        let text = std::fs::read_to_string(common::spec_path(SPEC)).expect("spec");
        Prepared {
            model: model.clone(),
            tables: tsfc::tables::tables(model, design, cert, SPEC, "").expect("tables"),
            p: design.p.clone(),
            trigger_weight: design.loop_design.event().map(|t| t.weight.clone()),
            region: design.certified_region().map(|(p, c)| p / c),
            source: tsfc::sim::source::SpecSource {
                name: SPEC.into(),
                text,
            },
        }
    })
}

fn run(p: &Prepared, opts: &Options) -> Outcome {
    simulate(p, opts).unwrap_or_else(|e| panic!("{e}"))
}

fn summary(label: &str, o: &Outcome) -> String {
    let m = &o.metrics;
    format!(
        "{label}: converged {}, final ||x|| {:.2e}, settle {:?} s, max |u| {:?}, {} of {} samples transmitted ({:.1}%), saturated samples {}",
        m.converged,
        m.final_state_norm,
        m.settle_time_s,
        m.max_abs_u,
        m.transmissions,
        m.samples,
        100.0 * m.transmissions as f64 / m.samples as f64,
        m.saturated_samples
    )
}

/// The paper's Appendix A design (gains read block-wise, Upsilon, nu_ = 0.2
/// with the printed adaptive law) in the spec's scenario. The simulator caps
/// the law at its ceiling `max`, which defaults to nu: nu stays 0.2 (the
/// printed law is unbounded; xu_paper_evidence lifts the cap to f64::MAX).
pub(crate) fn paper_design(base: &Prepared) -> (Prepared, Options) {
    let (gains, ups) = crate::xu_paper_evidence::appendix_a();
    let mut p = base.clone();
    p.tables.gains = gains
        .iter()
        .map(|f| f.row_iter().map(|r| r.iter().copied().collect()).collect())
        .collect();
    p.trigger_weight = Some(ups);
    let opts = Options {
        trigger: Some(Trigger::Aperiodic {
            sampling: (0.001, 0.1),
            threshold: Some(Threshold {
                nu: 0.2,
                adaptive: Some((10.0, 1.0, 0.02)),
                max: None,
            }),
            weight: Weight::Synthesize,
        }),
        ..Options::default()
    };
    (p, opts)
}

#[test]
fn tsfc_design_and_paper_design_in_the_papers_scenario() {
    // Paper's x(0) and tau(t), 100 s, aperiodic sampling in [0.001, 0.1] s.
    let ours = run(prepared(), &Options::default());
    eprintln!("{}", summary("tsfc (nu in [0.2, 0.25])", &ours));
    assert!(ours.metrics.converged, "{:?}", ours.metrics);
    assert!(ours.metrics.nonfinite_at_s.is_none());
    for u in &ours.trace.u {
        assert!(u.iter().all(|v| v.abs() <= 2.0), "{u:?}");
    }
    assert!(
        ours.metrics.transmissions * 5 < ours.metrics.samples,
        "{} of {}",
        ours.metrics.transmissions,
        ours.metrics.samples
    );
    let final_nu = ours.metrics.final_nu.expect("adaptive nu");
    assert!((0.2..=0.25).contains(&final_nu), "nu = {final_nu}");

    let (paper, opts) = paper_design(prepared());
    let theirs = run(&paper, &opts);
    eprintln!(
        "{}",
        summary("paper Appendix A (nu = 0.2, law capped at 0.2)", &theirs)
    );
    assert!(theirs.metrics.nonfinite_at_s.is_none());
    for u in &theirs.trace.u {
        assert!(u.iter().all(|v| v.abs() <= 2.0), "{u:?}");
    }
}

/// The xi search (L-inf with saturation and a bounded disturbance, issue 16):
/// two xi-minimizing SDPs and the design at the second minimum plus 0.5 %
/// with xi fixed, then one trigger SDP: 4 SDPs (the bisection took 10 + 1).
/// The certified numbers are those of the bisection or better (issue 16's
/// goal: continuous gamma <= 0.2906, event-triggered gamma <= 0.7639 at
/// nu_c >= 0.05; since issue 17 the spec certifies nu_c = 0.25).
#[test]
fn xi_search_and_trigger_take_four_sdps_with_the_same_or_better_gammas() {
    let (_, c) = compiled();
    let (design, _) = c.outcome.as_ref().expect("certified");
    let note = design
        .notes
        .iter()
        .find(|n| n.starts_with("xi minimized (the linear-region level"))
        .expect("the xi search's note");
    let (min, _) = note
        .split_once(" is ")
        .and_then(|(_, rest)| rest.split_once(' '))
        .expect("the minimum in the note");
    let min: f64 = min.parse().expect("a number");
    let xi = design
        .achieved
        .get(tsfc::synth::Quantity::LinfXi)
        .expect("xi");
    assert!((xi - min * 1.005).abs() <= 1e-5 * xi, "{xi} vs {note}");
    let gamma = design
        .achieved
        .get(tsfc::synth::Quantity::LinfGamma)
        .expect("gamma");
    assert!(gamma >= xi && gamma <= 0.2906, "continuous gamma {gamma}");
    let t = trigger();
    assert!(t.gamma <= 0.7639, "event-triggered gamma {}", t.gamma);
    assert!(t.plan.nu >= 0.2);
    assert_eq!(design.log.solves, 4, "SDPs");
}

/// The trigger step solves in scaled units (P = sigma P~, issue 16): every
/// condition of the unscaled plan at the design's values is D M~ D for the
/// scaled plan's condition M~ at the values over sigma (gamma, xi unchanged),
/// D diagonal with entries 1 or sqrt(sigma): congruences, so the scaled
/// problem is the same problem. Checked entry by entry on all 4 r^2 + 12
/// conditions of the unreduced problem.
#[test]
fn trigger_scaling_is_a_congruence_of_every_condition() {
    use tsfc::synth::trigger::{build, lyapunov_scale, scaled_plan};
    let (model, _) = compiled();
    let t = trigger();
    let sigma = lyapunov_scale(&t.plan);
    assert!(sigma > 10.0, "Xu & Huang's large gains: sigma = {sigma}");
    let eps = Settings::default().eps;
    let plain = build(model, &t.plan, eps, false).expect("builds");
    let scaled = build(model, &scaled_plan(&t.plan, sigma), eps, false).expect("builds");
    let assign = |b: &tsfc::synth::TriggerBuilt, over: f64| {
        let mut a = b.problem.assignment();
        for (name, v) in b.problem.vars() {
            let x = value(t, name);
            let f = if name == "gamma_tr" || name == "xi_tr" {
                1.0
            } else {
                over
            };
            a.set(v, x / f).expect("shape");
        }
        a
    };
    let (va, vb) = (assign(&plain, 1.0), assign(&scaled, sigma));
    let ids: Vec<_> = plain.problem.constraints().collect();
    let ids_scaled: Vec<_> = scaled.problem.constraints().collect();
    assert_eq!(ids.len(), ids_scaled.len());
    assert!(ids.len() >= 4 * model.r() * model.r());
    for (&a, &b) in ids.iter().zip(&ids_scaled) {
        let name = plain.problem.constraint_info(a).expect("info").0;
        let m = plain.problem.evaluate(a, &va).expect("evaluates");
        let ms = scaled.problem.evaluate(b, &vb).expect("evaluates");
        let k = m.nrows();
        let big = m.iter().fold(1e-300f64, |x, v| x.max(v.abs()));
        // D from the diagonal (every diagonal entry of these conditions is nonzero).
        let d: Vec<f64> = (0..k)
            .map(|i| {
                let r = m[(i, i)] / ms[(i, i)];
                assert!(
                    (r - 1.0).abs() < 1e-6 || (r / sigma - 1.0).abs() < 1e-6,
                    "{name}: ratio {r} at {i}"
                );
                if (r - 1.0).abs() < 1e-6 {
                    1.0
                } else {
                    sigma.sqrt()
                }
            })
            .collect();
        for i in 0..k {
            for j in 0..k {
                let diff = (m[(i, j)] - d[i] * d[j] * ms[(i, j)]).abs();
                assert!(diff <= 1e-9 * big, "{name} ({i}, {j}): {diff} of {big}");
            }
        }
    }
}

/// The co-designed spec (gains and trigger weight alternated, issue 17).
const CODESIGN_SPEC: &str = "xu2020_event_triggered_codesign.tsf";

/// The co-designed spec compiled once per test binary.
fn codesigned() -> &'static tsfc::pipeline::Run {
    static CELL: OnceLock<tsfc::pipeline::Run> = OnceLock::new();
    CELL.get_or_init(|| {
        tsfc::pipeline::read(&common::spec_path(CODESIGN_SPEC))
            .and_then(|front| front.compile(&Settings::default()))
            .unwrap_or_else(|e| panic!("{e}"))
    })
}

fn codesigned_trigger() -> &'static TriggerDesign {
    let run = codesigned();
    let (design, cert) = run.certified().unwrap_or_else(|e| panic!("{e}"));
    assert!(cert.ok);
    let t = design.loop_design.event().expect("a co-designed trigger");
    assert_eq!(t.method, "codesign");
    t
}

#[test]
fn codesign_is_certified_for_the_emitted_gains() {
    let run = codesigned();
    let t = codesigned_trigger();
    let (design, _) = run.certified().expect("certified");
    // The certificate speaks of the emitted gains: those of the trigger plan.
    assert_eq!(design.gains, t.plan.gains);
    // The spec's ceiling `max = 0.25` (the paper's nu_ = 0.2, law capped at 0.25).
    assert_eq!(t.plan.nu, 0.25);
    conditions_hold(&run.model, t);
    region_and_peak_hold(t);
    // The check can fail: a threshold well above the certified one breaks it.
    assert!(violated_at(&run.model, t, 4.0 * t.plan.nu));
    // Every pair (i, j) imposed: one gain serves every controller rule.
    assert!(t.plan.gains.iter().all(|f| *f == t.plan.gains[0]));
    assert!(t.plan.sector.iter().all(|g| *g == t.plan.sector[0]));
    let continuous = design
        .achieved
        .get(tsfc::synth::Quantity::LinfGamma)
        .expect("continuous gamma of the co-designed gains");
    // The continuous analysis keeps E(P, 1) inside the linear region, the
    // event-triggered certificate only the level reached from rest (docs): the
    // continuous number is the larger one here, and the issue-17 goal's gamma
    // (<= 0.1616) is the event-triggered one.
    assert!(t.gamma < continuous, "{continuous} vs {}", t.gamma);
    assert!(t.gamma <= 0.1616, "{}", t.gamma);
    eprintln!(
        "co-design: nu = {}, event-triggered gamma = {:.4} (continuous {continuous:.4}, paper 0.1616), rounds {:?}",
        t.plan.nu, t.gamma, t.rounds
    );
}

#[test]
fn codesign_gamma_does_not_increase_over_rounds_at_the_threshold() {
    let t = codesigned_trigger();
    assert!(t.rounds.len() >= 2, "{:?}", t.rounds);
    for w in t.rounds.windows(2) {
        // The threshold never decreases; at the final threshold gamma does not grow.
        assert!(w[1].nu >= w[0].nu, "{:?}", t.rounds);
        if w[0].nu == w[1].nu {
            assert!(w[1].gamma <= w[0].gamma * (1.0 + 1e-6), "{:?}", t.rounds);
        }
    }
    let last = t.rounds.last().expect("rounds");
    assert_eq!(last.gamma, t.gamma);
    assert_eq!(last.nu, t.plan.nu);
}

/// The paper's scenario for 300 s: the co-designed loop and the paper's
/// Appendix A design (nu = 0.2, law capped at 0.2). The goal of issue 17 (fewer
/// transmissions than the paper's design) is not met: the assertion records
/// the measured order and fails when a design changes it.
#[test]
fn codesign_and_papers_design_transmissions_in_300_s() {
    let run = codesigned();
    let ours = tsfc::driver::prepare_run(run).unwrap_or_else(|e| panic!("{e}"));
    let long = Options {
        horizon: Some(300.0),
        ..Options::default()
    };
    let mine = simulate(&ours, &long).unwrap_or_else(|e| panic!("{e}"));
    eprintln!("{}", summary("tsfc co-design, 300 s", &mine));
    let (paper, opts) = paper_design(&ours);
    let theirs = simulate(
        &paper,
        &Options {
            horizon: Some(300.0),
            ..opts
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    eprintln!("{}", summary("paper Appendix A, 300 s", &theirs));
    for o in [&mine, &theirs] {
        assert!(o.metrics.converged, "{:?}", o.metrics);
        assert!(o.metrics.nonfinite_at_s.is_none());
    }
    assert!(
        theirs.metrics.transmissions < mine.metrics.transmissions,
        "co-design {} vs paper {}: the co-design now transmits less than the paper's design; update docs/event_trigger.md and this test",
        mine.metrics.transmissions,
        theirs.metrics.transmissions
    );
}

/// An inverted single-link arm (sector model of sinc(theta), torque limit 20,
/// matched disturbance bounded by 0.5), written as a new user would: its
/// continuous design is unbalanced (L-inf gamma far above xi, set by
/// 1 / (phi lambda_min(P))), and with the trigger step's xi capped at 4 times
/// step 1's xi the certificate refused the threshold the bisection advised.
/// The cap now follows the larger of step 1's xi and gamma.
/// xi is fixed at the smallest feasible value (0.0165): the minimize search
/// now moves xi to where gamma is least (step 1 balanced: gamma 0.108 at xi
/// 0.108, whose stiffer gains certify nu <= 0.00546 only), so the unbalanced
/// step 1 this test is about (gamma 8.76 at xi 0.0165) is asked for explicitly.
const ARM: &str = "tsf 1;
controller arm_et;
const gl = 9.8;
const c  = 0.2;
state th, om;
input u saturate 20.0;
disturbance tau bound 0.5;
output y = x;
A(x) = [0, 1; gl * sinc(th), -c];
B = [0; 1];
D = B;
premise z = sinc(th) range sinc(pi() / 3) .. 1;
rules sector;
objective linf(tau -> y) minimize with phi = 0.5, xi = 0.0165;
objective saturation region;
trigger aperiodic {
    sampling = 0.001 .. 0.005;
    threshold nu = 0.0125;
    weight = synthesize;
}
";

#[test]
fn unbalanced_step_one_still_certifies_the_trigger() {
    let model = common::model_of("arm.tsf", ARM);
    let info = SpecInfo {
        path: "arm.tsf".into(),
        sha256: String::new(),
    };
    let c = compile(&model, info, &Settings::default(), Default::default());
    let (design, cert) = c.outcome.as_ref().unwrap_or_else(|e| panic!("{e}"));
    assert!(cert.ok);
    let q = |k| design.achieved.get(k).expect("step-1 L-inf");
    let (xi1, gamma1) = (
        q(tsfc::synth::Quantity::LinfXi),
        q(tsfc::synth::Quantity::LinfGamma),
    );
    assert!(
        gamma1 > 10.0 * xi1,
        "step 1 balanced: xi {xi1}, gamma {gamma1}"
    );
    let t = design.loop_design.event().expect("a trigger design");
    // The certified point needs xi above the old cap 4 xi1.
    let xi = value(t, "xi_tr")[(0, 0)];
    assert!(xi > 4.0 * xi1, "xi {xi} vs step 1 {xi1}");
    assert!(t.gamma < gamma1, "{} vs {gamma1}", t.gamma);
    conditions_hold(&model, t);
    region_and_peak_hold(t);
}
