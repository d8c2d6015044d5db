//! The objective families behind one trait: the problem a plan gives does not
//! depend on the order the spec lists its objectives, and the certificate
//! checks the unreduced conditions only through the reductions' inversion.

use crate::common;
use common::shipped;
use nalgebra::DVector;
use tsf_lang::spec::Spec;
use tsfc::model::TsModel;
use tsfc::synth::{self, plan, Quantity, Reduction, Settings};

/// (variable names, constraint names) of the problem built for `model`'s plan.
fn layout(model: &TsModel, reduce: bool) -> (Vec<String>, Vec<String>) {
    let (mut plan, _) = plan::initial_plan(&model.spec, 0.1);
    // As the xi search does when the spec leaves xi free.
    if let Some(l) = plan.linf_mut() {
        l.xi.get_or_insert(0.3);
    }
    let built = synth::build(model, &plan, model.spec.relaxation.node, 1e-7, reduce)
        .expect("the shipped spec builds");
    let vars = built.problem.vars().map(|(n, _)| n.to_string()).collect();
    let cons = built
        .problem
        .constraints()
        .map(|id| {
            built
                .problem
                .constraint_info(id)
                .expect("constraint of this problem")
                .0
                .to_string()
        })
        .collect();
    (vars, cons)
}

fn reversed_objectives(model: &TsModel) -> TsModel {
    let mut m = model.clone();
    let spec: &mut Spec = &mut m.spec;
    spec.objectives.reverse();
    m
}

#[test]
fn the_problem_does_not_depend_on_the_order_of_objectives() {
    for name in ["zhang2013_multiobjective.tsf", "xu2020_event_triggered.tsf"] {
        let model = shipped(name);
        assert!(
            model.spec.objectives.len() >= 2,
            "{name}: needs several objectives"
        );
        let (v1, c1) = layout(&model, true);
        let (v2, c2) = layout(&reversed_objectives(&model), true);
        assert_eq!(v1, v2, "{name}: variable order");
        assert_eq!(c1, c2, "{name}: constraint order");
        // Every family contributed: the variables of each objective are there.
        assert_eq!(v1.first().map(String::as_str), Some("X"), "{name}");
    }
}

#[test]
fn zhang_layout_has_every_family_once() {
    let model = shipped("zhang2013_multiobjective.tsf");
    let (vars, cons) = layout(&model, false);
    // hinf minimized: g; input norm fixed (<= 5): no mu2; Tanaka: one slack per family.
    assert!(vars.contains(&"g".to_string()));
    assert!(!vars.contains(&"mu2".to_string()));
    assert!(vars.contains(&"Y_decay".to_string()));
    assert!(vars.contains(&"Y_hinf".to_string()));
    let count = |prefix: &str| cons.iter().filter(|c| c.starts_with(prefix)).count();
    let r = model.r();
    assert_eq!(count("decay Q+(s-1)Y"), r);
    assert_eq!(count("hinf Q+(s-1)Y"), r);
    assert_eq!(count("input norm ["), r);
    assert_eq!(count("input norm: x0 in E(P,1)"), 1);
    // Decay is imposed, so plain stability is not.
    assert_eq!(count("stability"), 0);
}

#[test]
fn the_certificate_inverts_reductions_and_refuses_without_them() {
    let model = shipped("zhang2013_multiobjective.tsf");
    let design = synth::synthesize(&model, &Settings::default()).expect("certifiable");
    assert!(
        design
            .reductions
            .iter()
            .any(|r| matches!(r, Reduction::TanakaSlackZero { .. })),
        "every Zhang rule shares B: Tanaka's slack is reduced away"
    );
    let cert = tsfc::certify::certify(&model, &design).expect("certify");
    assert!(cert.ok, "worst: {}", cert.worst);
    // The Tanaka pair conditions are in the certificate although they were not solved.
    assert!(cert.lmis.iter().any(|l| l.name.contains("(Q+Q')/2-Y")));
    let mut stripped = design.clone();
    stripped.reductions.clear();
    let err = tsfc::certify::certify(&model, &stripped).expect_err("a slack has no value");
    assert!(err.to_string().contains("Y_"), "{err}");
}

/// A mass-spring-damper with a hardening spring k (1 + x1^2) and an input
/// limit of 0.7 (issue 11's case: `saturate` with H-inf alone compiled as
/// certified, and its saturated loop diverged).
fn msd(objective: &str) -> String {
    format!(
        "tsf 1;\ncontroller msd;\nstate x1, x2;\ninput u saturate 0.7;\ndisturbance w;\n\
         output z = [x1];\nA(x) = [0, 1; -(1 + x1 ^ 2), -0.5];\nB = [0; 1];\nD = [0; 1];\n\
         premise p = x1 ^ 2 range 0 .. 1 {{ small = trap(-1, -1, 0, 1); large = trap(0, 1, 2, 2); }}\n\
         rule R1: p is small => at(x1 = 0, x2 = 0);\nrule R2: p is large => at(x1 = 1, x2 = 0);\n\
         {objective}\nrelaxation basic;\n"
    )
}

#[test]
fn declared_saturation_is_always_inside_the_certificate() {
    // H-inf alone: the saturation region is implied and the H-inf block
    // carries the dead zone, so the certified gamma is regional (noted) and
    // the gains are not those of the unsaturated design (6.2e6, issue 11).
    let model = common::model_of("msd.tsf", &msd("objective hinf(w -> z) minimize;"));
    let d = synth::synthesize(&model, &Settings::default()).expect("certified with the region");
    assert!(d.plan.saturation().is_some_and(|s| s.implied));
    assert!(d
        .notes
        .iter()
        .any(|n| n.contains("H-inf under saturation is regional")));
    let biggest = d.gains.iter().map(|f| f.norm()).fold(0.0, f64::max);
    assert!(biggest < 1e3, "gains {biggest}");
    // Stability: the region is implied, certified and noted.
    let model = common::model_of("msd.tsf", &msd("objective stability;"));
    let d = synth::synthesize(&model, &Settings::default()).expect("certifiable");
    let sat = d.plan.saturation().expect("implied saturation objective");
    assert!(sat.implied && sat.levels == vec![0.7]);
    assert!(d.notes.iter().any(|n| n.contains("implied")));
    let cert = tsfc::certify::certify(&model, &d).expect("certify");
    assert!(
        cert.ok
            && cert
                .lmis
                .iter()
                .any(|l| l.name.starts_with("linear region"))
    );
    // Independent check of the linear region: on E(P, 1) the largest
    // |(F_j - G_j) x| is sqrt((F_j - G_j) P^{-1} (F_j - G_j)') <= 0.7.
    let z = |j: usize| {
        d.values
            .iter()
            .find(|(n, _)| *n == format!("Z{}", j + 1))
            .map(|(_, v)| v.clone())
            .expect("Z_j")
    };
    for (j, f) in d.gains.iter().enumerate() {
        let g = z(j) * &d.p;
        let k = f - g;
        let peak = (&k * &d.x * k.transpose())[(0, 0)].sqrt();
        assert!(peak <= 0.7 * (1.0 + 1e-6), "rule {}: {peak}", j + 1);
    }
    // An input bound within the level covers it instead (no region implied).
    let model = common::model_of(
        "msd.tsf",
        &msd("objective stability;\nobjective input_norm(u) <= 0.5 for x0 = [0.3, 0];"),
    );
    let d = synth::synthesize(&model, &Settings::default()).expect("certifiable");
    assert!(d.plan.saturation().is_none());
    assert!(d.notes.iter().any(|n| n.contains("does not saturate")));
    // An input bound above the level is a spec error at check time.
    let e = common::errors_of(
        "msd.tsf",
        &msd("objective stability;\nobjective input_norm(u) <= 5 for x0 = [0.3, 0];"),
    );
    assert!(e[0].message.contains("outside the certificate"), "{e:?}");
}

/// The mass-spring-damper without an input limit, with `objectives`.
fn msd_free(objectives: &str) -> String {
    msd(objectives).replace("input u saturate 0.7;", "input u;")
}

/// The value a diagnosis line advises (`write <kind> <= v`).
fn advised(line: &str) -> f64 {
    let at = line.rfind("<= ").expect("an advised bound") + 3;
    let number: String = line[at..]
        .chars()
        .take_while(|c| c.is_ascii_digit() || matches!(c, '.' | 'e' | '-' | '+'))
        .collect();
    number.parse().expect("a number")
}

#[test]
fn a_conflict_through_the_shared_p_is_named_and_the_advice_certifies() {
    let text = msd_free(
        "objective hinf(w -> z) <= 0.05;\nobjective input_norm(u) <= 0.05 for x0 = [1, 0];",
    );
    let model = common::model_of("msd.tsf", &text);
    // Each alone is feasible ...
    for alone in [
        "objective hinf(w -> z) <= 0.05;",
        "objective input_norm(u) <= 0.05 for x0 = [1, 0];",
    ] {
        let m = common::model_of("msd.tsf", &msd_free(alone));
        synth::synthesize(&m, &Settings::default()).expect(alone);
    }
    // ... together they are not, and the diagnosis says why.
    let Err(synth::SynthError::Infeasible { achievable, .. }) =
        synth::synthesize(&model, &Settings::default())
    else {
        panic!("infeasible together");
    };
    assert!(
        achievable
            .iter()
            .any(|l| l.contains("feasible on its own") && l.contains("x0' P x0 <= 1")),
        "{achievable:?}"
    );
    assert!(
        !achievable
            .iter()
            .any(|l| l.contains("conflict on their own")),
        "{achievable:?}"
    );
    // The advised input bound certifies when written.
    let line = achievable
        .iter()
        .find(|l| l.contains("smallest feasible bound") && l.contains("input_norm"))
        .expect("advice for input_norm");
    let v = advised(line);
    let fixed = text.replace("input_norm(u) <= 0.05", &format!("input_norm(u) <= {v}"));
    let model = common::model_of("msd.tsf", &fixed);
    let d = synth::synthesize(&model, &Settings::default()).expect("the advice certifies");
    assert!(tsfc::certify::certify(&model, &d).expect("certify").ok);
}

#[test]
fn gains_far_above_the_input_limit_are_warned_about() {
    let warned = |d: &synth::Design| d.notes.iter().any(|n| n.starts_with("warning: the gain"));
    // Operating points at ||x|| <= 1 and a 0.7 limit: the warning needs a
    // gain norm above 100 * 0.7 / 1 = 70 (the Euclidean norm of the 1 x 2 row).
    for (alpha, expect) in [(0.5, false), (5.0, true)] {
        let model = common::model_of(
            "msd.tsf",
            &msd(&format!("objective decay_rate >= {alpha};")),
        );
        let d = synth::synthesize(&model, &Settings::default()).expect("certifiable");
        let largest = d.gains.iter().map(|f| f.norm()).fold(0.0, f64::max);
        assert_eq!(largest > 70.0, expect, "alpha {alpha}: ||F|| = {largest}");
        assert_eq!(warned(&d), expect, "alpha {alpha}: {:?}", d.notes);
    }
}

/// The saturated loop x' = (A_i) x + B_i sat(F_i x) + D_i w, y = C x of rule
/// `i` (memberships frozen at a vertex: one of the loops the T-S certificate
/// covers), integrated by RK4 from x(0) = 0 under w(t) = a sin(t) for
/// t < 2 pi, then w = 0 until 40 s: (max x'Px, int y'y, int w'w).
fn frozen_saturated_run(
    model: &tsfc::model::TsModel,
    d: &tsfc::synth::Design,
    i: usize,
    a: f64,
) -> (f64, f64, f64) {
    let rule = &model.rules[i];
    let f = &d.gains[i];
    let w = |t: f64| {
        if t < 2.0 * std::f64::consts::PI {
            a * t.sin()
        } else {
            0.0
        }
    };
    let rhs = |t: f64, x: &DVector<f64>| {
        let u = (f * x)[0].clamp(-0.7, 0.7);
        &rule.a * x + &rule.b * u + rule.d.column(0) * w(t)
    };
    let (dt, steps) = (1e-3, 40_000);
    let mut x = DVector::zeros(2);
    let (mut peak, mut yy, mut ww) = (0.0f64, 0.0, 0.0);
    for k in 0..steps {
        let t = k as f64 * dt;
        let k1 = rhs(t, &x);
        let k2 = rhs(t + dt / 2.0, &(&x + &k1 * (dt / 2.0)));
        let k3 = rhs(t + dt / 2.0, &(&x + &k2 * (dt / 2.0)));
        let k4 = rhs(t + dt, &(&x + &k3 * dt));
        let y0 = x[0];
        x += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (dt / 6.0);
        // Trapezoid rule on y = x1 and on w.
        yy += 0.5 * dt * (y0 * y0 + x[0] * x[0]);
        ww += 0.5 * dt * (w(t).powi(2) + w(t + dt).powi(2));
        peak = peak.max((x.transpose() * &d.p * &x)[(0, 0)]);
    }
    (peak, yy, ww)
}

#[test]
fn hinf_with_the_saturation_region_holds_for_the_admissible_disturbance_energy() {
    let model = common::model_of(
        "msd.tsf",
        &msd("objective hinf(w -> z) minimize;\nobjective saturation region;"),
    );
    let d = synth::synthesize(&model, &Settings::default()).expect("certified");
    let cert = tsfc::certify::certify(&model, &d).expect("certify");
    assert!(cert.ok, "{}", cert.worst);
    assert!(cert.lmis.iter().any(|l| l.name.starts_with("hinf")));
    let gamma = d.achieved.get(Quantity::HinfGamma).expect("gamma");
    // Energy of a sin(t) over one period is a^2 pi: take 90 % of 1/gamma^2.
    let a = (0.9 / (gamma * gamma * std::f64::consts::PI)).sqrt();
    for i in 0..model.rules.len() {
        let (peak, yy, ww) = frozen_saturated_run(&model, &d, i, a);
        // Independent of the LMIs: the state stays in E(P, 1) (V <= gamma^2 E)
        // and the output energy is below gamma^2 times the disturbance energy.
        assert!(
            peak <= gamma * gamma * ww * (1.0 + 1e-6),
            "rule {}: V peaked at {peak}",
            i + 1
        );
        assert!(
            yy <= gamma * gamma * ww * (1.0 + 1e-6),
            "rule {}: {yy} > gamma^2 {ww}",
            i + 1
        );
        assert!(peak <= 1.0);
    }
}
