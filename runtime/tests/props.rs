//! Property tests (proptest), 100_000 cases per property.

mod common;

use common::*;
use proptest::prelude::*;
use proptest::test_runner::Config;
use tsf_runtime::*;

const CASES: u32 = 100_000;

fn config() -> Config {
    Config {
        cases: CASES,
        failure_persistence: None,
        ..Config::with_cases(CASES)
    }
}

/// Any f64 at all, weighted towards the nasty ones.
fn wild() -> impl Strategy<Value = f64> + Clone {
    prop_oneof![
        4 => -10.0..10.0f64,
        2 => proptest::num::f64::ANY,
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(f64::NEG_INFINITY),
        1 => prop_oneof![Just(f64::MAX), Just(-f64::MAX), Just(1e300), Just(-1e300), Just(0.0)],
    ]
}

fn gains(elem: impl Strategy<Value = f64> + Clone) -> impl Strategy<Value = [[[f64; N]; M]; R]> {
    let row = proptest::array::uniform4(elem);
    let mat = proptest::array::uniform2(row);
    proptest::array::uniform4(mat)
}

fn bound() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => 0.0..100.0f64,
        1 => Just(0.0),
        1 => Just(f64::INFINITY),
        1 => Just(f64::MAX),
        1 => 0.0..1e-300f64,
    ]
}

proptest! {
    #![proptest_config(config())]

    /// |u_s| <= u_bar_s and never NaN, for any state, premises and gains.
    #[test]
    fn saturation_always_holds(
        x in proptest::array::uniform4(wild()),
        g in gains(wild()),
        u_max in proptest::array::uniform2(bound()),
        z in proptest::option::of(proptest::array::uniform2(wild())),
    ) {
        let c = controller(g, u_max);
        let s = match z {
            Some(z) => c.step_with_premises(&x, &z),
            None => c.step(&x),
        };
        for (u, b) in s.u.iter().zip(u_max) {
            prop_assert!(!u.is_nan());
            prop_assert!(u.abs() <= b, "u = {u}, bound {b}");
        }
        for h in s.h {
            prop_assert!((0.0..=1.0).contains(&h));
        }
    }

    /// h_i in [0, 1], sum h = 1 (1e-12) whenever a rule fires; one-hot and
    /// flagged otherwise.
    #[test]
    fn strengths_are_a_partition_of_unity(
        z in proptest::array::uniform2(prop_oneof![4 => -3.0..3.0f64, 1 => -40.0..40.0f64, 1 => wild()]),
    ) {
        let c = controller([[[0.0; N]; M]; R], [1.0; M]);
        let (h, flags) = c.strengths(&z);
        for hi in h {
            prop_assert!((0.0..=1.0).contains(&hi), "{h:?}");
        }
        let sum: f64 = h.iter().sum();
        prop_assert!((sum - 1.0).abs() <= 1e-12, "sum {sum}");
        if flags.contains(Flags::NO_RULE_FIRED) {
            prop_assert_eq!(h.iter().filter(|&&v| v == 1.0).count(), 1);
        } else {
            prop_assert_eq!(flags, Flags::NONE);
        }
    }

    /// The runtime equals a straightforward std implementation (different
    /// operation order: K = sum h_j F_j first, then K x).
    #[test]
    fn blend_matches_reference(
        x in proptest::array::uniform4(-5.0..5.0f64),
        g in gains(-100.0..100.0f64),
        u_max in proptest::array::uniform2(prop_oneof![0.0..50.0f64, Just(f64::INFINITY)]),
    ) {
        let c = controller(g, u_max);
        let s = c.step(&x);
        let z = [x[0] + 0.5 * x[2], x[1] - 0.25 * x[3]];
        let (h_ref, fired) = reference::strengths(z);
        prop_assert_eq!(fired, !s.flags.contains(Flags::NO_RULE_FIRED));
        for (a, b) in s.h.iter().zip(h_ref) {
            prop_assert!((a - b).abs() <= 1e-12, "h {:?} vs {:?}", s.h, h_ref);
        }
        for m in 0..M {
            let mut k = [0.0; N];
            let mut scale = 0.0;
            for j in 0..R {
                for n in 0..N {
                    k[n] += h_ref[j] * g[j][m][n];
                    scale += (h_ref[j] * g[j][m][n] * x[n]).abs();
                }
            }
            let u_raw: f64 = k.iter().zip(x).map(|(a, b)| a * b).sum();
            let u_ref = u_raw.clamp(-u_max[m], u_max[m]);
            let tol = 1e-12 * scale.max(1e-300);
            prop_assert!((s.u[m] - u_ref).abs() <= tol, "u {} vs {u_ref} (tol {tol})", s.u[m]);
        }
    }

    /// Every membership degree is in [0, 1] and never NaN, for any
    /// parameters (even invalid ones) and any argument.
    #[test]
    fn memberships_in_unit_interval(
        p in proptest::array::uniform4(wild()),
        z in wild(),
        zs in proptest::array::uniform3(wild()),
    ) {
        let sets = [
            Membership::tri(p[0], p[1], p[2]),
            Membership::trap(p[0], p[1], p[2], p[3]),
            Membership::gauss(p[0], p[1]),
            Membership::sigmoid(p[0], p[1]),
        ];
        for m in sets {
            let d = m.degree(z);
            prop_assert!((0.0..=1.0).contains(&d), "{m:?}({z}) = {d}");
        }
        let d = about_degree(&zs, &p[..3], p[3]);
        prop_assert!((0.0..=1.0).contains(&d));
        // Well-formed tri: matches the reference semantics.
        let mut q = [p[0], p[1], p[2]];
        if q.iter().all(|v| v.is_finite() && v.abs() < 1e100) {
            q.sort_by(f64::total_cmp);
            let d = Membership::tri(q[0], q[1], q[2]).degree(z);
            let r = reference::trap(z, q[0], q[1], q[1], q[2]);
            prop_assert!((d - r).abs() <= 1e-15, "tri{q:?}({z}) = {d} vs {r}");
        }
    }

    /// f32 controllers saturate too.
    #[test]
    fn saturation_holds_f32(
        x in proptest::array::uniform2(wild()),
        g in proptest::array::uniform2(wild()),
        b in bound(),
    ) {
        static T0: [Term<'static, f32>; 1] = [Term::Is { var: 0, set: Membership::gauss(0.0, 1.0) }];
        static T1: [Term<'static, f32>; 1] = [Term::Is { var: 0, set: Membership::tri(-1.0, 0.0, 1.0) }];
        let c: Controller<'_, f32, 2, 1, 1, 2> = Controller {
            premise_map: [[1.0, 0.0]],
            rules: [Rule::new(&T0), Rule::new(&T1)],
            centres: [[0.0], [0.0]],
            gains: [[[g[0] as f32, g[1] as f32]], [[g[1] as f32, g[0] as f32]]],
            u_max: [b as f32],
        };
        let s = c.step(&[x[0] as f32, x[1] as f32]);
        prop_assert!(!s.u[0].is_nan() && s.u[0].abs() <= b as f32);
    }

    /// Triggers never panic; the adaptive threshold stays in [nu_min, MAX].
    #[test]
    fn triggers_are_total(
        xs in proptest::collection::vec(proptest::array::uniform2(wild()), 1..8),
        mu in proptest::array::uniform3(prop_oneof![0.0..20.0f64, Just(1e300)]),
        nu_min in 0.0..1.0f64,
    ) {
        let u = [[2.0, 0.5], [0.5, 1.0]];
        let mut a = AdaptiveTrigger::new(u, nu_min, mu[0], mu[1], mu[2]);
        let mut r = RelativeTrigger::new(u, nu_min);
        let mut m = MixedTrigger::new(nu_min, mu[2]);
        for (k, x) in xs.iter().enumerate() {
            let sent = a.decide(x);
            prop_assert!(a.nu() >= nu_min && a.nu().is_finite());
            if k == 0 {
                prop_assert!(sent);
            }
            if sent {
                prop_assert_eq!(a.last().map(|l| l.map(f64::to_bits)), Some(x.map(f64::to_bits)));
            }
            r.decide(x);
            m.decide(x);
        }
    }
}
