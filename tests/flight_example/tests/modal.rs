//! The generated mode-dependent controller in a flight crate: the step in
//! each mode is the PDC blend of that mode's certified gains; an out-of-range
//! mode uses mode 0's gains and raises `MODE_OUT_OF_RANGE`.

use flight_example::markov::{Controller, K, M, MODE_NAMES, N, R, TABLE};
use tsf_runtime::Flags;

/// u = sum_j h_j F_aj x with h from the controller and F from the tables.
fn reference(a: usize, x: &[f64; N], h: &[f64; R]) -> [f64; M] {
    let mut u = [0.0; M];
    for (j, hj) in h.iter().enumerate() {
        for (s, us) in u.iter_mut().enumerate() {
            *us += hj
                * TABLE.gains[a][j][s]
                    .iter()
                    .zip(x)
                    .map(|(f, xi)| f * xi)
                    .sum::<f64>();
        }
    }
    u
}

#[test]
fn three_named_modes() {
    assert_eq!(K, 3);
    assert_eq!(MODE_NAMES, ["normal", "degraded", "bias"]);
}

#[test]
fn each_mode_blends_its_own_gains_and_a_bad_mode_falls_back_to_mode_0() {
    let x = [0.5, 0.3, 0.1, 0.1, 0.3, 0.5];
    let mut c = Controller::new();
    let mut commands = Vec::new();
    for a in 0..K {
        let u = c.step(a as u8, &x);
        let h = *c.strengths();
        assert!((h.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert!(!c.mode_out_of_range() && !c.fault());
        let r = reference(a, &x, &h);
        for s in 0..M {
            assert!(
                (u[s] - r[s]).abs() <= 1e-12 * (1.0 + r[s].abs()),
                "mode {a} channel {s}"
            );
        }
        assert_eq!(u, TABLE.step(a as u8, &x).u);
        commands.push(u);
    }
    assert_ne!(commands[0], commands[1], "mode-dependent gains");
    for bad in [3u8, 4, 200, 255] {
        let u = c.step(bad, &x);
        assert_eq!(u, commands[0]);
        assert!(c.mode_out_of_range());
        assert!(c.flags().contains(Flags::MODE_OUT_OF_RANGE));
    }
    let u = c.step(1, &[f64::NAN, 0.0, 0.0, 0.0, 0.0, 0.0]);
    assert_eq!(u, [0.0; M]);
    assert!(c.fault() && !c.mode_out_of_range());
}
