//! The generated controller in a flight crate: dimensions, the PDC law
//! against a blend computed here from the generated tables, edge cases.

use flight_example::attitude::{Controller, M, N, R, TABLE};

/// u = sum_j h_j F_j x with h from the controller itself (checked to be a
/// partition of unity) and F from the tables.
fn reference(x: &[f64; N], h: &[f64; R]) -> [f64; M] {
    let mut u = [0.0; M];
    for (j, hj) in h.iter().enumerate() {
        for (s, us) in u.iter_mut().enumerate() {
            *us += hj
                * TABLE.gains[j][s]
                    .iter()
                    .zip(x)
                    .map(|(f, xi)| f * xi)
                    .sum::<f64>();
        }
    }
    u
}

#[test]
fn dimensions_match_the_spec() {
    assert_eq!((Controller::N, Controller::M, Controller::R), (6, 3, 9));
}

#[test]
fn step_is_the_pdc_blend_of_the_certified_gains() {
    let mut c = Controller::new();
    let x0 = [0.08, -0.05, 0.1, 0.12, 0.06, -0.08];
    let u = c.step(&x0);
    let h = *c.strengths();
    assert!((h.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    assert!(!c.fault() && !c.no_rule_fired());
    let r = reference(&x0, &h);
    for s in 0..M {
        assert!(
            (u[s] - r[s]).abs() <= 1e-12 * (1.0 + r[s].abs()),
            "channel {s}: {} vs {}",
            u[s],
            r[s]
        );
    }
    // A stabilizing feedback opposes the rate: the torque on the fastest axis has the opposite sign.
    assert!(u[2] * x0[2] < 0.0, "u = {u:?}");
    assert_eq!(c.step(&[0.0; N]), [0.0; M]);
}

#[test]
fn non_finite_state_gives_zero_command_and_fault() {
    let mut c = Controller::new();
    let u = c.step(&[f64::NAN, 0.0, 0.0, 0.0, 0.0, 0.0]);
    assert_eq!(u, [0.0; M]);
    assert!(c.fault());
}

#[test]
fn event_triggered_controller_saturates_at_two_newton_metres() {
    use flight_example::event_triggered as xu;
    let mut c = xu::Controller::new();
    let u = c.step(&[1.0, -1.0, 1.0, 0.5, -0.5, 0.5]);
    assert!(u.iter().all(|v| v.abs() <= 2.0), "{u:?}");
    assert!(
        c.saturated(),
        "a large state must hit the 2 N m limit: {u:?}"
    );
}

#[test]
fn pendulum_premise_is_the_sector_function() {
    use flight_example::pendulum as p;
    // z = sinc(theta): the generated premise code uses the runtime's sin.
    let theta: f64 = 0.7;
    let z = p::premises(&[theta, 0.0]);
    assert!((z[0] - theta.sin() / theta).abs() < 1e-15, "{z:?}");
    let mut c = p::Controller::new();
    let u = c.step(&[theta, 0.0]);
    // Pushing the cart under the falling pole: u has the sign that reduces theta
    // (B = [0; -a cos(theta)/den] < 0, so a positive theta needs positive u).
    assert!(u[0] > 0.0, "u = {u:?}");
}

/// The generated tables list each distinct premise term once; expanded back
/// into one term list per rule they make a `tsf_runtime::Controller` whose
/// step is bit for bit the generated controller's, at random states.
fn agrees_with_per_rule_terms<
    const N: usize,
    const M: usize,
    const P: usize,
    const R: usize,
    const D: usize,
>(
    table: &tsf_runtime::FactoredController<'static, f64, N, M, P, R, D>,
    premises: impl Fn(&[f64; N]) -> [f64; P],
    step: impl Fn(&[f64; N]) -> ([f64; M], [f64; R]),
    scale: f64,
) {
    use tsf_runtime::{Controller, Rule, Term};
    let per_rule: Vec<Vec<Term<'static, f64>>> = table
        .rules
        .iter()
        .map(|rule| rule.iter().map(|&k| table.terms[k]).collect())
        .collect();
    let reference = Controller {
        premise_map: table.premise_map,
        rules: std::array::from_fn(|i| Rule::new(&per_rule[i])),
        centres: table.centres,
        gains: table.gains,
        u_max: table.u_max,
    };
    let mut seed = 0x2545_f491_4f6c_dd1d_u64;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    for _ in 0..2000 {
        let x: [f64; N] = std::array::from_fn(|_| scale * next());
        let want = reference.step_with_premises(&x, &premises(&x));
        let (u, h) = step(&x);
        assert_eq!(u.map(f64::to_bits), want.u.map(f64::to_bits), "u at {x:?}");
        assert_eq!(h.map(f64::to_bits), want.h.map(f64::to_bits), "h at {x:?}");
    }
}

#[test]
fn factored_tables_step_like_per_rule_terms() {
    use flight_example::{event_triggered as xu, pendulum};
    agrees_with_per_rule_terms(
        &TABLE,
        |x| tsf_runtime::premises_linear(&TABLE.premise_map, x),
        |x| {
            let mut c = Controller::new();
            (c.step(x), *c.strengths())
        },
        0.2,
    );
    agrees_with_per_rule_terms(
        &xu::TABLE,
        |x| tsf_runtime::premises_linear(&xu::TABLE.premise_map, x),
        |x| {
            let mut c = xu::Controller::new();
            (c.step(x), *c.strengths())
        },
        1.0,
    );
    agrees_with_per_rule_terms(
        &pendulum::TABLE,
        pendulum::premises,
        |x| {
            let mut c = pendulum::Controller::new();
            (c.step(x), *c.strengths())
        },
        1.5,
    );
}
