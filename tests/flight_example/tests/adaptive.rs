//! The generated adaptive controller in a flight crate: its initial state is
//! the design model's (b = diag J^-1, a of rule R1 = C A at the origin), its
//! step is `tsf_runtime::AdaptiveLaw::step` (runtime/src/adaptive.rs, called
//! here directly) at the rules' strengths computed here from the generated
//! tables, on seeded random sequences with NaN entries, and it steers the
//! spacecraft with the time-varying inertia to the spec's claims.

use flight_example::adaptive::{State, M, N, R, SAMPLE_PERIOD, TABLE};
use tsf_runtime::{
    factored_weights, nearest_rule, normalize, premises_linear, term_degrees, AdaptiveError,
    AdaptiveState,
};

/// The rules' normalised strengths at x (nearest rule when none fires).
fn strengths(x: &[f64; N]) -> [f64; R] {
    let z = premises_linear(&TABLE.premise_map, x);
    let w = factored_weights(&term_degrees(&TABLE.terms, &z), &TABLE.rules);
    normalize(&w).unwrap_or_else(|| {
        let mut h = [0.0; R];
        h[nearest_rule(&TABLE.centres, &z)] = 1.0;
        h
    })
}

/// One step of the runtime's law on the estimates of `s`.
fn reference_step(s: &mut State, x: &[f64; N], r: &[f64; M]) -> ([f64; M], bool) {
    let h = strengths(x);
    let mut u = [0.0; M];
    let mut st = AdaptiveState {
        a_hat: &mut s.a_hat,
        b_hat: &mut s.b_hat,
        d_hat: &mut s.d_hat,
        s_m: &mut s.s_m,
    };
    let ok = TABLE
        .law
        .step(&mut st, x, &h, r, SAMPLE_PERIOD, &mut u)
        .is_ok();
    (u, ok)
}

#[test]
fn initial_state_is_the_design_model() {
    let s = State::new();
    assert_eq!(s, State::INIT);
    let j = [2043.0, 3044.0, 1989.0];
    for (i, rule) in s.b_hat.chunks_exact(M).enumerate() {
        for (k, (b, jk)) in rule.iter().zip(j).enumerate() {
            assert!((b - 1.0 / jk).abs() <= 1e-15 / jk, "b[{i}][{k}] = {b}");
        }
    }
    // Rule R1 (the origin): e' = omega' + k1 rho' = 0.5 * 0.5 omega.
    for k in 0..M {
        let row = &s.a_hat[k * N..(k + 1) * N];
        let mut want = [0.0; N];
        want[k] = 0.25;
        assert_eq!(row, want, "a[R1][{k}]");
    }
    assert_eq!((s.d_hat, s.s_m), (0.01, [0.0; M]));
    assert_eq!(SAMPLE_PERIOD, 0.01);
}

/// SplitMix64 in [lo, hi).
fn uniform(seed: &mut u64, lo: f64, hi: f64) -> f64 {
    *seed = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *seed;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    lo + (hi - lo) * ((z >> 11) as f64 / (1u64 << 53) as f64)
}

#[test]
fn step_is_the_runtime_law_bit_for_bit() {
    let (mut refused, mut steps) = (0, 0);
    for seed in 0..50u64 {
        let mut rng = seed;
        let scale = [0.5, 2.0, 5.0, 400.0][(seed % 4) as usize];
        let (mut gen, mut reference) = (State::new(), State::new());
        for _ in 0..200 {
            let mut x: [f64; N] = core::array::from_fn(|_| uniform(&mut rng, -scale, scale));
            if uniform(&mut rng, 0.0, 1.0) < 0.03 {
                x[(seed % 6) as usize] = f64::NAN;
            }
            let r: [f64; M] = core::array::from_fn(|_| uniform(&mut rng, -1.0, 1.0));
            let u = gen.step(&x, &r);
            let (want, ok) = reference_step(&mut reference, &x, &r);
            assert_eq!(
                u.map(f64::to_bits),
                want.map(f64::to_bits),
                "seed {seed} x {x:?}"
            );
            assert_eq!(gen.fault(), !ok);
            if !ok {
                assert_eq!(gen.error(), Some(AdaptiveError::NonFinite));
                assert_eq!(u, [0.0; M]);
                refused += 1;
            } else {
                assert_eq!(*gen.strengths(), strengths(&x));
            }
            let bits = |s: &State| {
                let mut v: Vec<u64> = s.a_hat.iter().map(|a| a.to_bits()).collect();
                v.extend(s.b_hat.iter().map(|b| b.to_bits()));
                v.push(s.d_hat.to_bits());
                v.extend(s.s_m.iter().map(|v| v.to_bits()));
                v
            };
            assert_eq!(bits(&gen), bits(&reference), "seed {seed}: estimates");
            steps += 1;
        }
    }
    assert_eq!(steps, 10_000);
    assert!(refused > 100, "NaN steps exercised: {refused}");
}

/// The spec's scenario with the generated controller: J(t) = J + 5 sin(t) I,
/// 0.05 sin t rad/s^2 on every axis, RK4 at the controller period with the
/// command held, 60 s: |rho| <= 1e-3 and |omega| <= 2e-3 after 40 s (the
/// spec's claims), every estimate inside its box.
#[test]
fn generated_controller_meets_the_spec_claims() {
    let j0 = [2043.0, 3044.0, 1989.0];
    let rhs = |t: f64, x: &[f64; N], u: &[f64; M]| -> [f64; N] {
        let (w, rho) = ([x[0], x[1], x[2]], [x[3], x[4], x[5]]);
        let j: [f64; 3] = core::array::from_fn(|k| j0[k] + 5.0 * t.sin());
        let jw = [j[0] * w[0], j[1] * w[1], j[2] * w[2]];
        let cross = [
            w[1] * jw[2] - w[2] * jw[1],
            w[2] * jw[0] - w[0] * jw[2],
            w[0] * jw[1] - w[1] * jw[0],
        ];
        let md = 0.05 * t.sin();
        let wd: [f64; 3] =
            core::array::from_fn(|k| (u[k] - cross[k] - 5.0 * t.cos() * w[k]) / j[k] + md);
        // rho' = 1/2 (I + skew(rho) + rho rho') omega.
        let rw = rho[0] * w[0] + rho[1] * w[1] + rho[2] * w[2];
        let sk = [
            rho[1] * w[2] - rho[2] * w[1],
            rho[2] * w[0] - rho[0] * w[2],
            rho[0] * w[1] - rho[1] * w[0],
        ];
        let rd: [f64; 3] = core::array::from_fn(|k| 0.5 * (w[k] + sk[k] + rho[k] * rw));
        [wd[0], wd[1], wd[2], rd[0], rd[1], rd[2]]
    };
    let mut x = [0.0, 0.0, 0.0, 1.23, 0.55, 2.17];
    let mut s = State::new();
    let h = SAMPLE_PERIOD;
    let (mut max_rho, mut max_omega) = (0.0_f64, 0.0_f64);
    let norm = |v: &[f64]| v.iter().map(|a| a * a).sum::<f64>().sqrt();
    for k in 0..6000 {
        let t = k as f64 * h;
        let u = s.step(&x, &[0.0; M]);
        assert!(!s.fault(), "step {k}");
        let add = |a: &[f64; N], b: &[f64; N], c: f64| -> [f64; N] {
            core::array::from_fn(|i| a[i] + c * b[i])
        };
        let k1 = rhs(t, &x, &u);
        let k2 = rhs(t + h / 2.0, &add(&x, &k1, h / 2.0), &u);
        let k3 = rhs(t + h / 2.0, &add(&x, &k2, h / 2.0), &u);
        let k4 = rhs(t + h, &add(&x, &k3, h), &u);
        x = core::array::from_fn(|i| x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
        if t + h >= 40.0 {
            max_rho = max_rho.max(norm(&x[3..]));
            max_omega = max_omega.max(norm(&x[..3]));
        }
        let law = &TABLE.law;
        assert!(s.a_hat.iter().all(|a| (law.a.lo..=law.a.hi).contains(a)));
        assert!(s.b_hat.iter().all(|b| (law.b.lo..=law.b.hi).contains(b)));
        assert!((law.d.lo..=law.d.hi).contains(&s.d_hat));
    }
    eprintln!("generated adaptive controller, 60 s: max |rho| {max_rho:.3e}, max |omega| {max_omega:.3e} after 40 s");
    assert!(max_rho <= 1e-3, "{max_rho:e}");
    assert!(max_omega <= 2e-3, "{max_omega:e}");
}
