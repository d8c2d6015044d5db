//! Every shipped spec checks clean (no errors) and has the documented size.

use crate::common;

fn check(name: &str) -> tsfc::model::TsModel {
    common::shipped(name)
}

#[test]
fn zhang2013_checks_clean() {
    let m = check("zhang2013_multiobjective.tsf");
    assert_eq!((m.n, m.m, m.q, m.r()), (6, 3, 3, 9));
    assert!(m.coverage.covered);
}

#[test]
fn xu2020_checks_clean() {
    for name in [
        "xu2020_event_triggered.tsf",
        "xu2020_event_triggered_codesign.tsf",
        "xu2020_regional.tsf",
        "xu2020_few_transmissions.tsf",
    ] {
        let m = check(name);
        assert_eq!((m.n, m.m, m.r()), (6, 3, 7), "{name}");
        assert!(m.coverage.covered, "{name}");
    }
}

#[test]
fn inverted_pendulum_checks_clean() {
    let m = check("inverted_pendulum.tsf");
    assert_eq!((m.n, m.m, m.r()), (2, 1, 2));
    // The sector-nonlinearity vertices: A1(2,1) = g / (4l/3 - a m l) with
    // g = 9.8, m = 2, M = 8, l = 0.5, a = 1/(m+M): 9.8 / (2/3 - 0.1) = 17.294...
    let a21 = m.rules[0].a[(1, 0)];
    assert!(
        (a21 - 9.8 / (2.0 / 3.0 - 0.1)).abs() < 1e-9,
        "A1(2,1) = {a21}"
    );
}

#[test]
fn amrr2019_specs_check_clean() {
    for name in [
        "amrr2019_flexible_mixed_trigger.tsf",
        "amrr2019_tsfc_design.tsf",
    ] {
        let m = check(name);
        assert_eq!((m.n, m.m, m.q, m.r()), (6, 3, 3, 2), "{name}");
        assert!(m.coverage.covered, "{name}");
        // The radial factorization: at w = 0 the rules' local models carry
        // 1/4 (1 + p'p) I in the kinematic block, 1/4 I at p'p = 0, 1/2 I at p'p = 1.
        for (rule, g) in m.rules.iter().zip([0.25, 0.5]) {
            for i in 0..3 {
                assert_eq!(rule.a[(i, 3 + i)], g, "{name}: A({i}, {})", 3 + i);
            }
        }
    }
}

#[test]
fn xue2024_checks_clean() {
    let m = check("xue2024_markov_fault_tolerant.tsf");
    assert_eq!((m.n, m.m, m.r()), (6, 3, 3));
    assert!(m.coverage.covered);
    let modes = m.spec.modes.as_ref().expect("modes");
    assert_eq!(modes.len(), 3);
    // Rows of the restored rate matrix sum to 0.
    for a in 0..3 {
        assert!(modes.rates.row(a).sum().abs() < 1e-12);
    }
}

#[test]
fn wang2013_adaptive_checks_clean() {
    let m = check("wang2013_adaptive_mrac.tsf");
    assert_eq!((m.n, m.m, m.r()), (6, 3, 9));
    assert!(m.spec.adaptive.is_some() && m.spec.objectives.is_empty());
}

#[test]
fn every_shipped_spec_checks_clean() {
    // A new compatibility rule must not refuse a shipped spec.
    let dir = common::spec_path("");
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .expect("the specs folder")
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".tsf"))
        .collect();
    names.sort();
    for name in &names {
        check(name);
    }
    assert!(names.len() >= 12, "{names:?}");
}

/// The summary `tsfc compile` prints names what the SAMPLED loop (the loop
/// the generated code runs) certifies, apart from the continuous loop's
/// objectives: the spacecraft design's loop sampled every 4.5 s is certified
/// stable only, although its continuous loop has decay rate 0.05; the
/// observer pendulum's sampled loop has its own rate 0.5.
#[test]
fn summary_separates_the_sampled_loops_rate_from_the_continuous_one() {
    let line = |name: &str| {
        let (model, c) = common::compile_shipped(name);
        let s = tsfc::driver::summary::summary(&model, &c, std::path::Path::new("r.json"));
        let sampled: Vec<&str> = s
            .lines()
            .filter(|l| l.contains("sampled loop   "))
            .collect();
        assert_eq!(sampled.len(), 1, "{name}: {s}");
        (s.clone(), sampled[0].trim().to_string(), c)
    };
    let (s, sampled, c) = line("amrr2019_tsfc_design.tsf");
    assert!(s.contains("decay_rate           0.05"), "{s}");
    assert_eq!(
        sampled,
        "sampled loop         every 4.5 s: asymptotic stability only (a decay rate above is the continuous loop's)"
    );
    let report = c.report.sampled_loop.as_ref().expect("sampled loop");
    assert_eq!((report.decay_rate, report.sampling), (0.0, [4.5, 4.5]));
    let (_, sampled, c) = line("pendulum_observer.tsf");
    assert_eq!(
        sampled,
        "sampled loop         every 0.01 s: decay rate 0.5 certified"
    );
    assert_eq!(
        c.report.sampled_loop.as_ref().map(|l| l.decay_rate),
        Some(0.5)
    );
}
