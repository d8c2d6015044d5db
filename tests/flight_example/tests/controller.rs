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
