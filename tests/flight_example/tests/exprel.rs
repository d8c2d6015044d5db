//! The generated Rust of `tests/specs/cstr_exprel.tsf` (a premise
//! `exp(x2s) * exprel(e2)`) at e2 = 0 gives the limit of the control law,
//! computed here from the stored gains and the analytic memberships at
//! p = s = e (issue 33: the 0/0 quotient it replaces gave u = 0 there).

use flight_example::cstr::{Controller, TABLE};

/// u = sum_j h_j F_j x at e2 = 0: p = e^(1 + e2) = e in [1, e^2] and
/// s = e exprel(e2) = e in [e - 1, e (e - 1)]; a rule's centre says which
/// vertex (upper or lower) of each premise it is.
fn limit(x: &[f64; 2]) -> f64 {
    let e = std::f64::consts::E;
    let mp = (e - 1.0) / (e * e - 1.0);
    let ms = 1.0 / ((e - 1.0) * (e - 1.0));
    TABLE
        .centres
        .iter()
        .zip(&TABLE.gains)
        .map(|(c, f)| {
            let hp = if c[0] > 0.5 * (1.0 + e * e) {
                mp
            } else {
                1.0 - mp
            };
            let hs = if c[1] > 0.5 * e * e { ms } else { 1.0 - ms };
            hp * hs * (f[0][0] * x[0] + f[0][1] * x[1])
        })
        .sum()
}

#[test]
fn u_at_e2_zero_is_the_limit() {
    let x = [0.3, 0.0];
    let want = limit(&x);
    let mut c = Controller::new();
    let u = c.step(&x)[0];
    assert!(!c.fault() && !c.no_rule_fired(), "{:?}", c.flags());
    assert!(
        (u - want).abs() <= 1e-12 * want.abs().max(1.0),
        "u = {u}, limit {want}"
    );
    let near = c.step(&[0.3, 1e-9])[0];
    assert!((near - u).abs() <= 1e-6, "u(1e-9) = {near}, u(0) = {u}");
    let neg = c.step(&[0.3, -0.0])[0];
    assert_eq!(neg.to_bits(), u.to_bits());
    std::println!("Rust: u(e2 = 0) = {u:.17e}, limit {want:.17e}, u(e2 = 1e-9) = {near:.17e}");
}
