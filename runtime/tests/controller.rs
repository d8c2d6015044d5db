//! Hand-checked controller and trigger behaviour.

mod common;

use common::*;
use tsf_runtime::trigger::{amrr_sigma, quad_form};
use tsf_runtime::*;

fn gains_id() -> [[[f64; N]; M]; R] {
    // F_i = (i + 1) * [1 0 0 0; 0 1 0 0]
    let mut g = [[[0.0; N]; M]; R];
    for (i, gi) in g.iter_mut().enumerate() {
        gi[0][0] = (i + 1) as f64;
        gi[1][1] = (i + 1) as f64;
    }
    g
}

#[test]
fn blend_by_hand() {
    let c = controller(gains_id(), [f64::INFINITY; M]);
    // z = (-0.5, 0): R0 = 0.5 * 1, R1 = 0.5 * 1, R2 = 0, R3 = exp(-0.5*(1+0.25)/0.09).
    let x = [-0.5, 0.0, 0.0, 0.0];
    let s = c.step(&x);
    let w3 = (-0.5f64 * 1.25 / 0.09).exp();
    let sum = 1.0 + w3;
    let h = [0.5 / sum, 0.5 / sum, 0.0, w3 / sum];
    for (a, b) in s.h.iter().zip(h) {
        assert!((a - b).abs() < 1e-15, "{:?} vs {:?}", s.h, h);
    }
    let u0 = -0.5 * (h[0] + 2.0 * h[1] + 4.0 * h[3]);
    assert!((s.u[0] - u0).abs() < 1e-15);
    assert_eq!(s.u[1], 0.0);
    assert_eq!(s.flags, Flags::NONE);
}

#[test]
fn nearest_rule_fallback() {
    let c = controller(gains_id(), [f64::INFINITY; M]);
    // z = (20, 20): no tri covers z0 = 20 and the about bump underflows.
    let s = c.step_with_premises(&[1.0, 1.0, 0.0, 0.0], &[20.0, 20.0]);
    assert!(s.flags.contains(Flags::NO_RULE_FIRED));
    assert!(!s.flags.is_fault());
    assert_eq!(s.h, [0.0, 0.0, 1.0, 0.0], "nearest centre is (1, 1)");
    assert_eq!(s.u, [3.0, 3.0]);
    // Huge premises: distances overflow and are recomputed scaled.
    let s = c.step_with_premises(&[1.0, 1.0, 0.0, 0.0], &[-1e300, 1e300]);
    assert_eq!(s.h, [1.0, 0.0, 0.0, 0.0], "nearest is (-1, 0)");
    // At this scale all centres are equidistant in floating point: tie -> 0.
    assert_eq!(nearest_rule(&CENTRES, &[f64::MAX, -f64::MAX]), 0);
    assert_eq!(nearest_rule(&CENTRES, &[f64::NAN, 0.0]), 0);
    assert_eq!(nearest_rule(&CENTRES, &[0.6, -0.4]), 3);
}

#[test]
fn faults_give_zero_command() {
    let c = controller(gains_id(), [1.0; M]);
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let s = c.step(&[0.1, bad, 0.0, 0.0]);
        assert_eq!(s.u, [0.0, 0.0]);
        assert_eq!(s.h, [0.0; R]);
        assert!(s.flags.contains(Flags::STATE_NONFINITE) && s.flags.is_fault());
    }
    // finite x whose linear premise overflows
    let s = c.step(&[f64::MAX, 0.0, f64::MAX, 0.0]);
    assert!(s.flags.contains(Flags::PREMISE_NONFINITE));
    assert_eq!(s.u, [0.0, 0.0]);
    let s = c.step_with_premises(&[0.0; N], &[f64::NAN, 0.0]);
    assert_eq!(s.flags, Flags::PREMISE_NONFINITE);
}

#[test]
fn saturation_and_bad_gains() {
    let mut g = gains_id();
    g[1][0][0] = f64::NAN;
    g[1][1][1] = f64::INFINITY;
    g[2][0][0] = f64::NAN; // rule 2 does not fire at z0 < 0: must not leak
    let c = controller(g, [0.3, 2.0]);
    let s = c.step(&[-0.5, 1.0, 0.0, 0.0]);
    assert!(s.flags.contains(Flags::COMMAND_NONFINITE));
    assert_eq!(s.u[0], 0.0, "NaN channel -> 0");
    assert_eq!(s.u[1], 2.0, "+inf channel -> +u_bar");
    // Finite but large: clipped, flagged.
    let c = controller(gains_id(), [0.3, 0.5]);
    let s = c.step(&[-0.9, -0.9, 0.0, 0.0]);
    assert_eq!(s.u, [-0.3, -0.5]);
    assert_eq!(s.flags, Flags::SATURATED);
    // Negative / NaN bound pins the channel.
    let (u, _) = saturate(&[1.0, -1.0], &[-1.0, f64::NAN]);
    assert_eq!(u, [0.0, 0.0]);
    let (u, f) = saturate(&[f64::INFINITY, f64::NEG_INFINITY], &[f64::INFINITY, 1.0]);
    assert_eq!(u, [0.0, -1.0]);
    assert!(f.contains(Flags::COMMAND_NONFINITE) && f.contains(Flags::SATURATED));
}

#[test]
fn pipeline_functions() {
    let z = premises_linear(&MAP, &[1.0, 2.0, 3.0, 4.0]);
    assert_eq!(z, [2.5, 1.0]);
    assert_eq!(normalize(&[0.0, 0.0]), None);
    assert_eq!(normalize(&[f64::NAN, -1.0]), None);
    assert_eq!(normalize(&[1.0, 3.0]), Some([0.25, 0.75]));
    assert_eq!(normalize::<f64, 0>(&[]), None);
    let h = [0.25, 0.75];
    let g = [[[1.0, 2.0]], [[3.0, f64::NAN]]];
    assert!(blend(&h, &g, &[1.0, 1.0])[0].is_nan());
    assert_eq!(blend(&[1.0, 0.0], &g, &[1.0, 1.0]), [3.0]);
    // A rule without terms always fires.
    let empty: Rule<'_, f64> = Rule::new(&[]);
    assert_eq!(empty.weight(&[]), 1.0);
    // Out-of-range premise indices have degree 0 instead of panicking.
    let t = Term::Is {
        var: 7,
        set: Membership::tri(0.0, 0.0, 1.0),
    };
    assert_eq!(t.degree(&[0.0]), 0.0);
    let t = Term::About {
        first: usize::MAX,
        point: &[0.0, 0.0],
        sigma: 1.0,
    };
    assert_eq!(t.degree(&[0.0]), 0.0);
}

#[test]
fn zero_sized_controller_does_not_panic() {
    let c: Controller<'_, f64, 2, 1, 1, 0> = Controller {
        premise_map: [[1.0, 0.0]],
        rules: [],
        centres: [],
        gains: [],
        u_max: [1.0],
    };
    let s = c.step(&[1.0, 2.0]);
    assert_eq!(s.u, [0.0]);
    assert!(s.flags.contains(Flags::NO_RULE_FIRED));
}

#[test]
fn f32_controller() {
    static T: [Term<'static, f32>; 1] = [Term::Is {
        var: 0,
        set: Membership::tri(-1.0, 0.0, 1.0),
    }];
    let c: Controller<'_, f32, 1, 1, 1, 1> = Controller {
        premise_map: [[1.0]],
        rules: [Rule::new(&T)],
        centres: [[0.0]],
        gains: [[[-2.0]]],
        u_max: [1.5],
    };
    assert_eq!(c.step(&[0.5]).u, [-1.0]);
    assert_eq!(c.step(&[5.0]).u, [-1.5]);
    assert!(c.step(&[5.0]).flags.contains(Flags::NO_RULE_FIRED));
}

#[test]
fn periodic() {
    let mut p = PeriodicTrigger::new(3);
    let got: Vec<bool> = (0..7).map(|_| p.decide()).collect();
    assert_eq!(got, [true, false, false, true, false, false, true]);
    let mut p = PeriodicTrigger::new(0);
    assert!((0..5).all(|_| p.decide()));
}

#[test]
fn relative_trigger() {
    let u = [[2.0, 0.0], [0.0, 1.0]];
    let mut t = RelativeTrigger::new(u, 0.25);
    assert!(t.decide(&[1.0, 0.0]), "first sample transmits");
    // x_k'Ux_k = 2, threshold 0.5; e = (0.4, 0): e'Ue = 0.32 < 0.5
    assert!(!t.decide(&[1.4, 0.0]));
    // e = (0.5, 0): 0.5 >= 0.5 transmits
    assert!(t.decide(&[1.5, 0.0]));
    assert_eq!(t.last(), Some(&[1.5, 0.0]));
    assert!(t.decide(&[f64::NAN, 0.0]), "NaN transmits");
    assert!(t.decide(&[1.0, 0.0]), "recovers: e = NaN transmits again");
    assert!(!t.decide(&[1.0, 0.1]));
    assert_eq!(quad_form(&u, &[1.0, 2.0]), 6.0);
}

#[test]
fn adaptive_trigger_law() {
    let (mu1, mu2, mu3, nu0) = (10.0, 1.0, 0.02, 0.2);
    let mut t = AdaptiveTrigger::new([[1.0, 0.0], [0.0, 1.0]], nu0, mu1, mu2, mu3);
    assert_eq!(t.nu(), nu0);
    assert!(t.decide(&[1.0, 0.0]));
    assert_eq!(t.nu(), nu0, "first transmission does not adapt");
    // Small jump ||dx|| = 0.01 < mu3: nu grows.
    let mut nu = nu0;
    let x1 = [1.0, 0.0];
    let x2 = [1.0, 0.01];
    // threshold nu * 1 = 0.2 > 1e-4: no transmission
    assert!(!t.decide(&x2));
    // Large jump transmits: ||dx|| = 0.6 -> atan(0.58) > 0, factor < 0 -> nu_min.
    let x3 = [1.0, 0.6];
    assert!(t.decide(&x3));
    let want =
        (nu * (1.0 - (2.0 * mu1 / std::f64::consts::PI) * (mu2 * (0.6f64 - mu3)).atan())).max(nu0);
    assert!((t.nu() - want).abs() < 1e-15);
    let _ = x1;
    // Now a jump just above the threshold but below mu3 in norm.
    let mut t = AdaptiveTrigger::new([[1.0]], 0.0001, mu1, mu2, mu3);
    assert!(t.decide(&[0.1]));
    assert!(t.decide(&[0.11]), "0.0001 >= 0.0001*0.01");
    nu = 0.0001;
    let want = nu * (1.0 - (2.0 * mu1 / std::f64::consts::PI) * (mu2 * (0.01f64 - mu3)).atan());
    assert!(
        (t.nu() - want).abs() <= 1e-15 * want,
        "{} vs {want}",
        t.nu()
    );
    assert!(t.nu() > nu);
    // Never NaN / infinite.
    let mut t = AdaptiveTrigger::new([[1.0]], 0.5, 1e300, 1.0, 1e10);
    for k in 0..50 {
        t.decide(&[k as f64]);
        assert!(t.nu().is_finite() && t.nu() >= 0.5);
    }
    t.decide(&[f64::NAN]);
    assert_eq!(t.nu(), 0.5, "NaN update resets to nu_min");
}

#[test]
fn adaptive_trigger_ceiling() {
    // States alternate between 0 and 0.01: every sample transmits while nu <= 1
    // (e^2 = 1e-4 >= nu * x_k^2 with x_k in {0, 0.01}) and every jump
    // ||dx|| = 0.01 < mu3 makes the law grow nu by 1 + (20/pi) atan(0.01) = 1.064.
    let (mu1, mu2, mu3) = (10.0, 1.0, 0.02);
    let mut free = AdaptiveTrigger::new([[1.0]], 0.01, mu1, mu2, mu3);
    let mut capped = free.with_max(0.05);
    for k in 0..60 {
        let x = [if k % 2 == 0 { 0.0 } else { 0.01 }];
        assert!(free.decide(&x) && capped.decide(&x), "sample {k} transmits");
        assert!((0.01..=0.05).contains(&capped.nu()), "{}", capped.nu());
    }
    // The law itself leaves the ceiling (so the assertion above can fail).
    assert!(free.nu() > 0.2, "unbounded law: {}", free.nu());
    assert_eq!(capped.nu(), 0.05);
    // A ceiling below nu_min keeps nu_min.
    let mut low = AdaptiveTrigger::new([[1.0]], 0.2, mu1, mu2, mu3).with_max(0.1);
    for x in [0.0, 0.01, 0.0, 0.01] {
        low.decide(&[x]);
    }
    assert_eq!(low.nu(), 0.2);
}

#[test]
fn mixed_trigger() {
    let mut t = MixedTrigger::new(0.5, 0.01);
    assert!(t.decide(&[1.0, 0.0, 0.0]));
    // ||Xi|| = 0.5, threshold 0.5 * ||sigma|| + 0.01 = 0.5*1.5 + 0.01 = 0.76
    assert!(!t.decide(&[1.5, 0.0, 0.0]));
    // ||Xi|| = 1.0, threshold 0.5*2 + 0.01 = 1.01
    assert!(!t.decide(&[2.0, 0.0, 0.0]));
    // ||Xi|| = 0.0 vs 0.01 near the origin: no; ||Xi|| = 1 vs 0.01 at sigma = 0: yes
    assert!(t.decide(&[0.0, 0.0, 0.0]));
    assert_eq!(t.last(), Some(&[0.0, 0.0, 0.0]));
    assert!(!t.decide(&[0.005, 0.0, 0.0]));
    assert!(t.decide(&[0.0, 0.0, f64::NAN]));
    let s = amrr_sigma(&[0.1, 0.0, 0.0], &[0.1, 0.2, 0.0], 2.0);
    let pp = 0.05;
    assert!((s[0] - (0.1 + 0.2 + 2.0 * pp * 0.1)).abs() < 1e-16);
    assert!((s[1] - (0.4 + 2.0 * pp * 0.2)).abs() < 1e-16);
}

#[test]
fn signal_trigger_holds_the_state_and_decides_on_the_signal() {
    let mut t = SignalTrigger::<f64, 2, 1>::new(0.5, 0.01);
    assert_eq!(t.last(), None);
    // First call transmits; the held value is the state, not the signal.
    assert_eq!(t.decide(&[1.0, 2.0], &[3.0]), Some([1.0, 2.0]));
    assert_eq!(t.last(), Some(&[1.0, 2.0]));
    // ||3 - 4|| = 1 < 0.5 * 4 + 0.01: held.
    assert!(!t.law.would_transmit(&[4.0]));
    assert_eq!(t.decide(&[9.0, 9.0], &[4.0]), None);
    assert_eq!(t.last(), Some(&[1.0, 2.0]));
    // ||3 - 0|| = 3 >= 0.01: transmits, and would_transmit changed nothing before.
    assert!(t.law.would_transmit(&[0.0]));
    assert_eq!(t.decide(&[0.5, 0.5], &[0.0]), Some([0.5, 0.5]));
    // A NaN signal transmits (the NaN policy of the other triggers).
    assert!(t.decide(&[0.5, 0.5], &[f64::NAN]).is_some());
}
