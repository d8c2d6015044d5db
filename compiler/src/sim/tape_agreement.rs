//! The simulator's plants and signals compiled to the tape against the
//! language's evaluator: every built-in the lowering expands, on random
//! states; what it does not expand keeps the interpreter.

use crate::sim::plant::Plant;
use crate::sim::signal::Signals;
use crate::sim::source::SpecSource;
use crate::sim::trigger::SplitMix64;
use crate::sim::Evaluator;
use tsf_lang::spec::Spec;

const PENDULUM: &str = include_str!("../../../specs/inverted_pendulum.tsf");
const XU: &str = include_str!("../../../specs/xu2020_event_triggered.tsf");

/// The pendulum spec with `theta'` replaced by `theta_dot` (and `extra`
/// items added), checked.
fn pendulum_with(theta_dot: &str, extra: &str) -> Spec {
    let text = PENDULUM.replace("theta' = omega;", &format!("theta' = {theta_dot};"));
    let text = text.replace(
        "state theta, omega;",
        &format!("state theta, omega;\n{extra}"),
    );
    match tsf_lang::check_source(&text) {
        (Some(spec), _) => spec,
        (None, diags) => panic!("{diags:#?}"), // ok: unit test
    }
}

/// Largest relative difference of the two evaluators' right-hand sides over
/// random times, states and inputs.
fn worst_difference(spec: &Spec, compiled: bool) -> f64 {
    let source = SpecSource::default();
    let mut reference = Plant::new(spec, &source, Evaluator::Interpreter).expect("plant"); // ok: unit test
    let mut tape = Plant::new(spec, &source, Evaluator::Compiled).expect("plant"); // ok: unit test
    assert_eq!(tape.is_compiled(), compiled);
    let (dim, m, q) = (tape.dim(), spec.m(), spec.q());
    let mut rng = SplitMix64::new(3);
    let mut worst: f64 = 0.0;
    for _ in 0..200 {
        let mut draw =
            |len: usize| -> Vec<f64> { (0..len).map(|_| rng.next_f64() - 0.5).collect() };
        let (t, s, u, w) = (10.0 * draw(1)[0].abs(), draw(dim), draw(m), draw(q));
        let (mut a, mut b) = (vec![0.0; dim], vec![0.0; dim]);
        reference.rhs(t, &s, &u, &w, &mut a).expect("interpreter"); // ok: unit test
        tape.rhs(t, &s, &u, &w, &mut b).expect("tape"); // ok: unit test
        for (x, y) in a.iter().zip(&b) {
            assert!(x.is_finite() && y.is_finite(), "{a:?} {b:?}");
            worst = worst.max((x - y).abs() / x.abs().max(y.abs()).max(1e-300));
        }
    }
    worst
}

#[test]
fn every_expanded_builtin_agrees_with_the_interpreter() {
    let theta_dot = "omega + 1e-3 * (norm([theta, omega; u, t]) + sum([theta; omega]) \
        + mean([theta, omega]) + dot([theta; omega], [omega; theta]) \
        + trace([theta, omega; u, 1] ^ 3) + atan2(theta, 1 + omega ^ 2) \
        + min(theta, omega) + max(theta, 0.5) + sign(omega) + abs(theta) + exp(-theta ^ 2) \
        + log(2 + sin(t)) + tan(0.1 * theta) + atan(omega) + sqrt(1 + omega ^ 2) \
        + sinc(theta) + cross([theta; omega; u], [1; t; theta])[1] \
        + skew([theta; omega; 1])[0, 2] + diag([theta; omega])[1, 1] \
        + diag([theta, u; omega, 1])[0] + blkdiag(theta, [omega, u])[1, 2] \
        + f2(theta, omega)[0] + [theta; omega]' * [1; 2] + [theta; omega; u][1 .. 3][0] \
        + [theta, omega] .* [u, t] * [1; 1] + norm([theta; omega; u; t; 1; 2; 3; 4; 5]) \
        + (x' * x) / (1 + t) - inv([2, 1; 1, 3])[0, 1] * u + pi())";
    let spec = pendulum_with(theta_dot, "fn f2(p, r) = [p * r; p - r];");
    let worst = worst_difference(&spec, true);
    assert!(worst < 1e-14, "relative difference {worst:e}");
}

#[test]
fn a_state_dependent_inverse_keeps_the_interpreter() {
    let spec = pendulum_with("omega + inv([1 + theta ^ 2, 0; 0, 1])[0, 0]", "");
    assert_eq!(worst_difference(&spec, false), 0.0);
}

#[test]
fn the_shipped_plants_and_signals_compile() {
    let source = SpecSource::default();
    for text in [PENDULUM, XU] {
        let (Some(spec), _) = tsf_lang::check_source(text) else {
            panic!("shipped spec") // ok: unit test
        };
        let plant = Plant::new(&spec, &source, Evaluator::Compiled).expect("plant"); // ok: unit test
        assert!(plant.is_compiled());
        let mut reference = Signals::new(&spec, &source, Evaluator::Interpreter);
        let mut tape = Signals::new(&spec, &source, Evaluator::Compiled);
        assert!(tape.is_compiled());
        for k in 0..50 {
            let t = 0.37 * k as f64;
            let a = reference.at(t).expect("interpreter").to_vec(); // ok: unit test
            assert_eq!(a, tape.at(t).expect("tape"), "t = {t}"); // ok: unit test
        }
    }
    let worst = worst_difference(&tsf_lang::check_source(XU).0.expect("spec"), true); // ok: unit test
    assert!(worst < 1e-12, "relative difference {worst:e}");
}
