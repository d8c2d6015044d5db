//! `FactoredController` (distinct terms evaluated once) against
//! `Controller` (every rule evaluates its own terms): bit-identical
//! commands, strengths and flags for any state, premises and gains.

use proptest::prelude::*;
use proptest::test_runner::Config;
use tsf_runtime::*;

const N: usize = 3;
const M: usize = 2;
const P: usize = 2;
/// A 3 x 2 grid of rules plus one `about` rule and one rule with no terms
/// firing only through its index out of range.
const R: usize = 8;
const D: usize = 6;

static ABOUT: [f64; 2] = [0.5, -0.5];

const NEG: Term<'static, f64> = Term::Is {
    var: 0,
    set: Membership::trap(f64::NEG_INFINITY, f64::NEG_INFINITY, -1.0, 0.0),
};
const ZERO: Term<'static, f64> = Term::Is {
    var: 0,
    set: Membership::tri(-1.0, 0.0, 1.0),
};
const POS: Term<'static, f64> = Term::Is {
    var: 0,
    set: Membership::sigmoid(3.0, 0.5),
};
const LOW: Term<'static, f64> = Term::Is {
    var: 1,
    set: Membership::gauss(-0.5, 0.4),
};
const HIGH: Term<'static, f64> = Term::Is {
    var: 1,
    set: Membership::trap(-0.5, 0.5, 1.0, 1.0),
};
const NEAR: Term<'static, f64> = Term::About {
    first: 0,
    point: &ABOUT,
    sigma: 0.3,
};
/// A term on a premise component that does not exist: degree 0.
const NOWHERE: Term<'static, f64> = Term::Is {
    var: 7,
    set: Membership::tri(0.0, 0.0, 0.0),
};

static R0: [Term<'static, f64>; 2] = [NEG, LOW];
static R1: [Term<'static, f64>; 2] = [NEG, HIGH];
static R2: [Term<'static, f64>; 2] = [ZERO, LOW];
static R3: [Term<'static, f64>; 2] = [ZERO, HIGH];
static R4: [Term<'static, f64>; 2] = [POS, LOW];
static R5: [Term<'static, f64>; 2] = [HIGH, POS];
static R6: [Term<'static, f64>; 1] = [NEAR];
static R7: [Term<'static, f64>; 2] = [LOW, NOWHERE];

/// The same rules as indices into `[NEG, ZERO, POS, LOW, HIGH, NEAR]`;
/// index 9 is out of range (degree 0, like `NOWHERE`).
static INDICES: [&[usize]; R] = [
    &[0, 3],
    &[0, 4],
    &[1, 3],
    &[1, 4],
    &[2, 3],
    &[4, 2],
    &[5],
    &[3, 9],
];

const MAP: [[f64; N]; P] = [[1.0, 0.0, 0.5], [0.0, 1.0, -0.25]];
const CENTRES: [[f64; P]; R] = [
    [-1.0, -0.5],
    [-1.0, 1.0],
    [0.0, -0.5],
    [0.0, 1.0],
    [1.0, -0.5],
    [1.0, 1.0],
    [0.5, -0.5],
    [9.0, 9.0],
];

type Gains = [[[f64; N]; M]; R];

fn reference(gains: Gains, u_max: [f64; M]) -> Controller<'static, f64, N, M, P, R> {
    Controller {
        premise_map: MAP,
        rules: [&R0[..], &R1, &R2, &R3, &R4, &R5, &R6, &R7].map(Rule::new),
        centres: CENTRES,
        gains,
        u_max,
    }
}

fn factored(gains: Gains, u_max: [f64; M]) -> FactoredController<'static, f64, N, M, P, R, D> {
    FactoredController {
        premise_map: MAP,
        terms: [NEG, ZERO, POS, LOW, HIGH, NEAR],
        rules: INDICES,
        centres: CENTRES,
        gains,
        u_max,
    }
}

/// The bits of a step (so that -0 and NaN are compared exactly).
fn bits<const K: usize, const L: usize>(s: &Step<f64, K, L>) -> ([u64; K], [u64; L], u8) {
    (s.u.map(f64::to_bits), s.h.map(f64::to_bits), s.flags.0)
}

fn wild() -> impl Strategy<Value = f64> + Clone {
    prop_oneof![
        6 => -3.0..3.0f64,
        2 => proptest::num::f64::ANY,
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => prop_oneof![Just(f64::MAX), Just(-1e300), Just(0.0), Just(-0.0), Just(5e-324)],
    ]
}

fn gains() -> impl Strategy<Value = Gains> {
    let elem = prop_oneof![8 => -50.0..50.0f64, 1 => wild()];
    proptest::array::uniform8(proptest::array::uniform2(proptest::array::uniform3(elem)))
}

proptest! {
    #![proptest_config(Config { cases: 20_000, failure_persistence: None, ..Config::default() })]

    /// Bit for bit the reference controller's step, from the state or from
    /// premises given by the caller.
    #[test]
    fn factored_step_is_the_reference_step(
        x in proptest::array::uniform3(wild()),
        z in proptest::array::uniform2(wild()),
        g in gains(),
        u_max in proptest::array::uniform2(prop_oneof![0.0..10.0f64, Just(f64::INFINITY), wild()]),
    ) {
        let (a, b) = (reference(g, u_max), factored(g, u_max));
        prop_assert_eq!(bits(&b.step(&x)), bits(&a.step(&x)));
        prop_assert_eq!(bits(&b.step_with_premises(&x, &z)), bits(&a.step_with_premises(&x, &z)));
        let w = rule_weights(&a.rules, &z);
        prop_assert_eq!(b.weights(&z).map(f64::to_bits), w.map(f64::to_bits));
    }
}

#[test]
fn shared_terms_are_evaluated_once_and_multiplied_in_rule_order() {
    let z = [-0.25, 0.0];
    let d = term_degrees(&[NEG, ZERO, POS, LOW, HIGH, NEAR], &z);
    assert_eq!(d[0], 0.25, "neg edge (0 - z)/(0 - -1)");
    assert_eq!(d[1], 0.75);
    let w = factored_weights(&d, &INDICES);
    assert_eq!(w[0], d[0] * d[3]);
    assert_eq!(w[5], d[4] * d[2], "rule order kept");
    assert_eq!(w[7], 0.0, "index out of range is degree 0");
    let empty: [&[usize]; 1] = [&[]];
    assert_eq!(factored_weights(&d, &empty), [1.0], "no terms: weight 1");
}

#[test]
fn edge_cases_follow_the_reference() {
    let mut g = [[[1.0; N]; M]; R];
    g[7] = [[f64::NAN; N]; M]; // rule 7 never fires: its NaN gain must not leak
    let c = factored(g, [0.5, f64::INFINITY]);
    let s = c.step(&[0.1, 0.2, 2.0]);
    assert_eq!(s.flags, Flags::SATURATED);
    assert_eq!(s.u[0], 0.5);
    assert!((s.h.iter().sum::<f64>() - 1.0).abs() < 1e-15);
    let s = c.step_with_premises(&[0.0; N], &[40.0, -40.0]);
    assert_eq!(s.flags, Flags::NO_RULE_FIRED);
    assert_eq!(s.h, [0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]);
    let s = c.step(&[f64::NAN, 0.0, 0.0]);
    assert!(s.flags.is_fault());
    assert_eq!((s.u, s.h), ([0.0; M], [0.0; R]));
}
