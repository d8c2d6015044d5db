//! Issue 17: is Xu & Huang's printed gamma 0.1616 (and threshold nu = 0.2)
//! attainable? Lower bounds, computed independently of tsfc's LMIs, of the true
//! induced peak-to-peak gain sup ||y||_inf / ||tau||_inf (x(0) = 0, y = x, the
//! Euclidean norm in space and the sup in time, as in the paper's notation and
//! (14)) of two designs: the paper's Appendix A gains and trigger weight, and
//! tsfc's shipped two-step design.
//!
//! 1. The continuous-time linearization at the origin, u = K0 x with
//!    K0 = sum_j h_j(0) F_j (the spec's memberships): closed-form DC gain
//!    1 / sigma_min(K0_q) against sigma_max(-Acl^{-1} B); the exact induced
//!    norm of an LTI convolution y = g * tau in these norms,
//!    max_{|v| = 1} int_0^inf |g(t)' v| dt (reached by
//!    tau(t) = g(T - t)' v / |g(T - t)' v|), bracketed by an ascent from below
//!    and int sigma_max(g) dt from above.
//! 2. The nonlinear, sampled, event-triggered closed loop (quaternion truth
//!    plant (2)-(3), saturation, trigger (10), memberships at x(t_k)) simulated
//!    here, independently of `tsfc::sim`, under disturbances with
//!    max_t |tau(t)| = tau_bar: a constant along the worst DC direction, the
//!    bang-bang input above, and the paper's tau(t); with nu fixed and with the
//!    printed adaptive law (cross-checked by `tsfc::sim`).
//! 3. tsfc's trigger certificate on the paper's gains (ignored by default: one
//!    compile) and why it fails: unstable cross pairs A_i + B F_j.
//!
//! Numbers and findings: docs/event_trigger.md, "Is the paper's gamma 0.1616
//! attainable?".

use crate::common;

use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
use tsf_lang::spec::{Threshold, Trigger, Weight};
use tsfc::model::{premise_values, rule_weight, TsModel};

const SPEC: &str = "xu2020_event_triggered.tsf";
/// The paper's disturbance bound tau_bar (N m).
const TAU_BAR: f64 = 0.01;
/// The paper's printed L-inf gain.
const PAPER_GAMMA: f64 = 0.1616;
/// Impulse-response grid: step and horizon (s); the slowest closed-loop mode
/// of both designs decays by more than e^-20 over the horizon (asserted).
pub(crate) const DT: f64 = 0.01;
const T_IR: f64 = 200.0;
/// x(0) = 0: the L-inf gain (14) is defined from rest.
pub(crate) const REST: [f64; 6] = [0.0; 6];
/// The paper's initial state (Section 4): omega = 0, q = (-0.3802, 0.2124, 0.5013).
pub(crate) const PAPER_X0: [f64; 6] = [0.0, 0.0, 0.0, -0.3802, 0.2124, 0.5013];
/// The paper's decay rate phi (Section 4): V' <= -phi V + xi tau' tau, (29).
const PHI: f64 = 0.05;

/// The paper's Appendix A (gains read block-wise, and Upsilon), from the
/// reference file kept with the specs.
pub(crate) fn appendix_a() -> (Vec<DMatrix<f64>>, DMatrix<f64>) {
    let text = std::fs::read_to_string(common::spec_path("reference/xu2020_appendix_a.json"))
        .expect("reference file");
    let json: serde_json::Value = serde_json::from_str(&text).expect("json");
    let mat = |v: &serde_json::Value| -> DMatrix<f64> {
        let rows: Vec<Vec<f64>> = v
            .as_array()
            .expect("rows")
            .iter()
            .map(|row| {
                row.as_array()
                    .expect("row")
                    .iter()
                    .map(|x| x.as_f64().expect("number"))
                    .collect()
            })
            .collect();
        DMatrix::from_fn(rows.len(), rows[0].len(), |a, b| rows[a][b])
    };
    let gains = json["F"]
        .as_array()
        .expect("gains")
        .iter()
        .map(mat)
        .collect();
    (gains, mat(&json["Upsilon"]))
}

/// A design: PDC gains, trigger weight and the (fixed) threshold.
#[derive(Clone)]
pub(crate) struct Design {
    pub(crate) gains: Vec<DMatrix<f64>>,
    pub(crate) weight: DMatrix<f64>,
    pub(crate) nu: f64,
    /// The paper's adaptive law (mu1, mu2, mu3), unbounded; `None`: nu fixed.
    pub(crate) adaptive: Option<(f64, f64, f64)>,
    /// The certified region {x : x' U x <= 1} (tsfc's design), if any.
    pub(crate) region: Option<DMatrix<f64>>,
}

pub(crate) fn paper() -> Design {
    let (gains, weight) = appendix_a();
    Design {
        gains,
        weight,
        nu: 0.2,
        adaptive: None,
        region: None,
    }
}

/// tsfc's shipped design (compiled once per test binary, shared with
/// `event_trigger`), at its certified threshold.
fn tsfc_design() -> Design {
    let t = crate::event_trigger::trigger();
    Design {
        gains: t.plan.gains.clone(),
        weight: t.weight.clone(),
        nu: t.plan.nu,
        adaptive: None,
        region: Some(&t.p / t.plan.region_level()),
    }
}

/// The paper's inertia (also in the spec).
fn inertia() -> Matrix3<f64> {
    Matrix3::new(350.0, 3.0, 4.0, 3.0, 270.0, 10.0, 4.0, 10.0, 190.0)
}

/// Normalized memberships h_j(x) of the spec's rules.
pub(crate) fn memberships(model: &TsModel, x: &[f64]) -> Vec<f64> {
    let z = premise_values(&model.spec, x).expect("premise values");
    let w: Vec<f64> = model.terms.iter().map(|t| rule_weight(t, &z)).collect();
    let s: f64 = w.iter().sum();
    w.iter().map(|v| v / s).collect()
}

/// PDC command sum_j h_j(x) F_j x.
fn pdc(model: &TsModel, gains: &[DMatrix<f64>], x: &DVector<f64>) -> DVector<f64> {
    let h = memberships(model, x.as_slice());
    gains
        .iter()
        .zip(&h)
        .fold(DVector::zeros(gains[0].nrows()), |acc, (f, hj)| {
            acc + f * x * *hj
        })
}

/// The loop linearized at the origin (y = x).
struct Linearized {
    a_cl: DMatrix<f64>,
    b: DMatrix<f64>,
    k0: DMatrix<f64>,
}

fn linearize(model: &TsModel, gains: &[DMatrix<f64>]) -> Linearized {
    // Jacobian of (2)-(3) at x = 0 (q0 = 1): w' = J^-1 (u + tau), q' = w / 2.
    let j_inv = inertia().try_inverse().expect("J invertible");
    let mut a = DMatrix::zeros(6, 6);
    let mut b = DMatrix::zeros(6, 3);
    for k in 0..3 {
        a[(3 + k, k)] = 0.5;
        for c in 0..3 {
            b[(k, c)] = j_inv[(k, c)];
        }
    }
    // The spec's rule R1 is that Jacobian.
    let r1 = &model.rules[0];
    assert!((&r1.a - &a).norm() < 1e-12 && (&r1.b - &b).norm() < 1e-12);
    let h0 = memberships(model, &[0.0; 6]);
    let k0 = gains
        .iter()
        .zip(&h0)
        .fold(DMatrix::zeros(3, 6), |acc, (f, h)| acc + f * *h);
    Linearized {
        a_cl: &a + &b * &k0,
        b,
        k0,
    }
}

/// The T-S model's loop at the origin instead of the plant's Jacobian:
/// sum_i h_i(0) A_i (rules R2, R3 carry q0 = sqrt(1 - 3 0.56^2) = 0.24 in
/// their kinematics and fire at the origin with the spec's memberships).
fn linearize_ts(model: &TsModel, gains: &[DMatrix<f64>]) -> Linearized {
    let lin = linearize(model, gains);
    let h0 = memberships(model, &[0.0; 6]);
    let a_ts = model
        .rules
        .iter()
        .zip(&h0)
        .fold(DMatrix::zeros(6, 6), |acc, (r, h)| acc + &r.a * *h);
    Linearized {
        a_cl: a_ts + &lin.b * &lin.k0,
        ..lin
    }
}

/// Bounds on the peak-to-peak gain of the linearized loop.
struct LinearBounds {
    /// sigma_max(G(0)) by the closed form 1 / sigma_min(K0_q).
    dc_closed_form: f64,
    /// sigma_max(-Acl^{-1} B).
    dc_matrix: f64,
    /// The unit input direction of the DC gain.
    dc_input: DVector<f64>,
    /// max_t |s(t)|, s the step response along `dc_input`.
    step_peak: f64,
    /// int |g(t)' v| dt at the ascent's v: a lower bound (and the exact gain
    /// at the maximizing v).
    l1_lower: f64,
    /// The output direction v it uses.
    v: DVector<f64>,
    /// int sigma_max(g(t)) dt: an upper bound.
    l1_upper: f64,
    /// g(t_k) = e^{Acl t_k} B on the grid t_k = k DT.
    g: Vec<DMatrix<f64>>,
}

fn linear_bounds(lin: &Linearized) -> LinearBounds {
    let kq = lin.k0.columns(3, 3).into_owned();
    let sv = kq.clone().svd(false, false).singular_values;
    let dc_closed_form = 1.0 / sv.min();
    let g0 = -lin.a_cl.clone().try_inverse().expect("Hurwitz") * &lin.b;
    let svd = g0.clone().svd(false, true);
    let (imax, dc_matrix) = svd.singular_values.argmax();
    let dc_input = svd.v_t.expect("v_t").row(imax).transpose();
    // Impulse response on the grid; the step response by the trapezoid rule.
    let phi = (&lin.a_cl * DT).exp();
    let steps = (T_IR / DT).round() as usize;
    let mut g = Vec::with_capacity(steps + 1);
    let mut e = lin.b.clone();
    for _ in 0..=steps {
        g.push(e.clone());
        e = &phi * e;
    }
    assert!(
        g[steps].norm() < 1e-9 * g[0].norm(),
        "impulse response not decayed over {T_IR} s"
    );
    let trap = |f: &dyn Fn(usize) -> f64| -> f64 {
        DT * ((1..steps).map(f).sum::<f64>() + 0.5 * (f(0) + f(steps)))
    };
    let mut s = DVector::zeros(6);
    let mut step_peak: f64 = 0.0;
    for k in 1..=steps {
        s += (&g[k - 1] * &dc_input + &g[k] * &dc_input) * (0.5 * DT);
        step_peak = step_peak.max(s.norm());
    }
    let l1_upper = trap(&|k| g[k].clone().svd(false, false).singular_values.max());
    // The exact gain is max over unit v of the convex f(v) = int |g' v|:
    // ascent from the DC output direction and from each unit axis.
    let dc_out = &g0 * &dc_input;
    let starts = std::iter::once(&dc_out / dc_out.norm())
        .chain((0..6).map(|a| DVector::from_fn(6, |i, _| if i == a { 1.0 } else { 0.0 })));
    let (l1_lower, v) = starts
        .map(|v0| ascend(&g, v0))
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .expect("starts");
    LinearBounds {
        dc_closed_form,
        dc_matrix,
        dc_input,
        step_peak,
        l1_lower,
        v,
        l1_upper,
        g,
    }
}

/// int_0^T |g(t)' v| dt by the trapezoid rule on the grid.
fn l1_along(g: &[DMatrix<f64>], v: &DVector<f64>) -> f64 {
    let last = g.len() - 1;
    let norms: Vec<f64> = g.iter().map(|gk| (gk.transpose() * v).norm()).collect();
    DT * (norms.iter().sum::<f64>() - 0.5 * (norms[0] + norms[last]))
}

/// Ascent on the convex f(v) = int |g' v| over the unit sphere:
/// v <- grad f(v) / |grad f(v)| never decreases f (convexity). Returns the
/// final (f(v), v).
fn ascend(g: &[DMatrix<f64>], mut v: DVector<f64>) -> (f64, DVector<f64>) {
    let last = g.len() - 1;
    let mut value = l1_along(g, &v);
    for _ in 0..100 {
        let mut grad = DVector::zeros(v.len());
        for (k, gk) in g.iter().enumerate() {
            let w = gk.transpose() * &v;
            let n = w.norm();
            if n > 0.0 {
                let c = if k == 0 || k == last { 0.5 } else { 1.0 };
                grad += gk * w * (c * DT / n);
            }
        }
        let next = &grad / grad.norm();
        let next_value = l1_along(g, &next);
        assert!(next_value >= value * (1.0 - 1e-9), "ascent decreased");
        let done = next_value - value < 1e-10 * next_value;
        (v, value) = (next, next_value);
        if done {
            break;
        }
    }
    (value, v)
}

/// max over a log grid of omega in [1e-4, 10] rad/s of sigma_max((j omega I - Acl)^{-1} B),
/// with the maximizing omega.
fn frequency_peak(lin: &Linearized) -> (f64, f64) {
    use nalgebra::Complex;
    let a = lin.a_cl.map(|v| Complex::new(v, 0.0));
    let b = lin.b.map(|v| Complex::new(v, 0.0));
    (0..=250)
        .map(|k| {
            let w = 10f64.powf(-4.0 + 5.0 * k as f64 / 250.0);
            let m = DMatrix::<Complex<f64>>::identity(6, 6) * Complex::new(0.0, w) - &a;
            let h = m.try_inverse().expect("no eigenvalue on the axis") * &b;
            (h.svd(false, false).singular_values.max(), w)
        })
        .max_by(|x, y| x.0.total_cmp(&y.0))
        .expect("grid")
}

/// What one closed-loop run measured.
pub(crate) struct Run {
    /// max_t |y(t)| (y = x), on the integration grid.
    pub(crate) peak: f64,
    /// |y| at the end.
    pub(crate) last: f64,
    pub(crate) transmissions: usize,
    pub(crate) samples: usize,
    /// The threshold at the end (grows under the paper's law).
    final_nu: f64,
    /// max_t x' U x for the design's region (0 without one).
    pub(crate) region_peak: f64,
}

/// The nonlinear event-triggered loop: truth plant (2)-(3) with q0 =
/// sqrt(1 - |q|^2), sat at 2 N m, sampling intervals drawn from
/// {0.01, 0.02, .., 0.1} s (inside [h_min, h_max]), transmit when
/// e' Upsilon e >= nu x(t_k)' Upsilon x(t_k), u = sum_j h_j(x(t_k)) F_j x(t_k)
/// held between transmissions; RK4 with step DT, tau held on each step.
/// `tau(k)` is the disturbance on step k (t in [k DT, (k + 1) DT)).
pub(crate) fn closed_loop(
    model: &TsModel,
    d: &Design,
    x0: &[f64; 6],
    tau: &dyn Fn(usize) -> Vector3<f64>,
    steps: usize,
) -> Run {
    let jm = inertia();
    let j_inv = jm.try_inverse().expect("J invertible");
    let f = |x: &[f64; 6], u: &Vector3<f64>, ta: &Vector3<f64>| -> [f64; 6] {
        let w = Vector3::new(x[0], x[1], x[2]);
        let q = Vector3::new(x[3], x[4], x[5]);
        let wd = j_inv * (-w.cross(&(jm * w)) + u + ta);
        let q0 = (1.0 - q.norm_squared()).sqrt();
        let qd = 0.5 * (q0 * w + q.cross(&w));
        [wd[0], wd[1], wd[2], qd[0], qd[1], qd[2]]
    };
    let axpy = |x: &[f64; 6], k: &[f64; 6], c: f64| -> [f64; 6] {
        std::array::from_fn(|i| x[i] + c * k[i])
    };
    let mut x = *x0;
    let mut xk = DVector::<f64>::zeros(6);
    let mut u = Vector3::zeros();
    let mut nu = d.nu;
    let mut rng: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut next_sample = 0usize;
    let (mut peak, mut transmissions, mut samples) = (0.0f64, 0usize, 0usize);
    let mut region_peak = 0.0f64;
    for k in 0..steps {
        if k == next_sample {
            samples += 1;
            let xs = DVector::from_column_slice(&x);
            let e = &xs - &xk;
            let lhs = (e.transpose() * &d.weight * &e)[(0, 0)];
            let rhs = nu * (xk.transpose() * &d.weight * &xk)[(0, 0)];
            if transmissions == 0 || lhs >= rhs {
                transmissions += 1;
                // nu(t_0) = nu_; the law updates nu at every later transmission.
                if let (Some((mu1, mu2, mu3)), true) = (d.adaptive, transmissions > 1) {
                    let jump = (&xs - &xk).norm();
                    let factor =
                        1.0 - 2.0 * mu1 / std::f64::consts::PI * (mu2 * (jump - mu3)).atan();
                    nu = (nu * factor).max(d.nu);
                }
                xk = xs;
                let c = pdc(model, &d.gains, &xk);
                u = Vector3::from_fn(|i, _| c[i].clamp(-2.0, 2.0));
            }
            rng = rng
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            next_sample = k + 1 + ((rng >> 33) % 10) as usize;
        }
        let ta = tau(k);
        let k1 = f(&x, &u, &ta);
        let k2 = f(&axpy(&x, &k1, 0.5 * DT), &u, &ta);
        let k3 = f(&axpy(&x, &k2, 0.5 * DT), &u, &ta);
        let k4 = f(&axpy(&x, &k3, DT), &u, &ta);
        x = std::array::from_fn(|i| x[i] + DT / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
        peak = peak.max(norm(&x));
        if let Some(u) = &d.region {
            let xs = DVector::from_column_slice(&x);
            region_peak = region_peak.max((xs.transpose() * u * &xs)[(0, 0)]);
        }
    }
    Run {
        region_peak,
        peak,
        final_nu: nu,
        last: norm(&x),
        transmissions,
        samples,
    }
}

/// Every bound and run of one design.
struct Evidence {
    lb: LinearBounds,
    /// (sigma_max of the frequency response at its peak, omega).
    freq_peak: (f64, f64),
    /// Constant tau along the DC input direction, |tau| = tau_bar.
    constant: Run,
    /// Bang-bang tau(t) = tau_bar g(T - t)' v / |g(T - t)' v|.
    bang: Run,
    /// The same two with every sample transmitted (nu = 0): the sampled loop
    /// without the trigger, a second method for the linear numbers.
    constant_all: Run,
    bang_all: Run,
}

fn evidence(name: &str, model: &TsModel, d: &Design) -> Evidence {
    let lin = linearize(model, &d.gains);
    let slowest = lin
        .a_cl
        .clone()
        .complex_eigenvalues()
        .iter()
        .map(|c| c.re)
        .fold(f64::NEG_INFINITY, f64::max);
    let lb = linear_bounds(&lin);
    let freq_peak = frequency_peak(&lin);
    eprintln!(
        "{name}: linearization: slowest Re eig {slowest:.4}; DC gain {:.5} (closed form {:.5}); peak of sigma_max(G(jw)) {:.5} at w = {:.2e}; step peak {:.5}; exact LTI gain in [{:.5}, {:.5}]",
        lb.dc_matrix, lb.dc_closed_form, freq_peak.0, freq_peak.1, lb.step_peak, lb.l1_lower, lb.l1_upper
    );
    let steps = lb.g.len() - 1;
    let c = lb.dc_input.clone() * TAU_BAR;
    let constant_tau = Vector3::new(c[0], c[1], c[2]);
    let bang_tau = |k: usize| -> Vector3<f64> {
        let w = lb.g[steps - k].transpose() * &lb.v;
        let w = &w * (TAU_BAR / w.norm());
        Vector3::new(w[0], w[1], w[2])
    };
    let every = Design {
        nu: 0.0,
        adaptive: None,
        gains: d.gains.clone(),
        weight: d.weight.clone(),
        region: d.region.clone(),
    };
    let ev = Evidence {
        constant: closed_loop(model, d, &REST, &|_| constant_tau, steps),
        bang: closed_loop(model, d, &REST, &bang_tau, steps),
        constant_all: closed_loop(model, &every, &REST, &|_| constant_tau, steps),
        bang_all: closed_loop(model, &every, &REST, &bang_tau, steps),
        lb,
        freq_peak,
    };
    for (what, r) in [
        ("constant tau", &ev.constant),
        ("bang-bang tau", &ev.bang),
        ("constant tau, nu = 0", &ev.constant_all),
        ("bang-bang tau, nu = 0", &ev.bang_all),
    ] {
        eprintln!(
            "{name}: event-triggered loop, {what}: max |y| / tau_bar = {:.5}, final {:.5}; {} of {} samples transmitted; final nu {:.3e}",
            r.peak / TAU_BAR,
            r.last / TAU_BAR,
            r.transmissions,
            r.samples,
            r.final_nu
        );
    }
    ev
}

/// The checks common to both designs: two methods agree, the bounds are
/// ordered, and the nonlinear loop reproduces the linear numbers.
fn check_consistent(ev: &Evidence) {
    let lb = &ev.lb;
    // DC gain: closed form 1 / sigma_min(K0_q) against the matrix inverse.
    assert!((lb.dc_matrix - lb.dc_closed_form).abs() < 1e-9 * lb.dc_matrix);
    // DC <= step peak <= max sigma(G(jw)) <= exact gain <= int sigma_max(g).
    assert!(lb.step_peak >= lb.dc_matrix * (1.0 - 1e-3));
    assert!(ev.freq_peak.0 >= lb.dc_matrix * (1.0 - 1e-6));
    assert!(lb.l1_lower >= ev.freq_peak.0 * (1.0 - 1e-3));
    assert!(lb.l1_upper >= lb.l1_lower);
    // Simulation, every sample transmitted: the constant disturbance reaches
    // the DC equilibrium, the bang-bang input the L1 value at t = T.
    let rel = |a: f64, b: f64| (a - b).abs() / b;
    assert!(rel(ev.constant_all.last / TAU_BAR, lb.dc_matrix) < 0.01);
    assert!(rel(ev.bang_all.last / TAU_BAR, lb.l1_lower) < 0.03);
    // With the trigger the loop stays within the paper's region (|x| small).
    for r in [&ev.constant, &ev.bang] {
        assert!(r.peak.is_finite() && r.peak < 1.0);
    }
}

/// max_t |y(t)| / max_t |tau(t)| of the paper's Appendix A design under the
/// paper's own disturbance (Section 4) from x(0) = 0 for 300 s, by the
/// independent simulation here.
fn papers_scenario_ratio(model: &TsModel, d: &Design) -> (f64, Run) {
    let steps = (300.0 / DT).round() as usize;
    let tau = |k: usize| paper_tau(k as f64 * DT);
    let tau_peak = (0..steps).map(|k| tau(k).norm()).fold(0.0, f64::max);
    let r = closed_loop(model, d, &REST, &tau, steps);
    (r.peak / tau_peak, r)
}

/// The printed adaptive law (mu = 10, 1, 0.02), unbounded above.
const PRINTED_LAW: (f64, f64, f64) = (10.0, 1.0, 0.02);

#[test]
fn papers_design_with_fixed_nu_stays_far_below_its_printed_gamma() {
    let model = common::shipped(SPEC);
    let ev = evidence("paper Appendix A (nu = 0.2)", &model, &paper());
    check_consistent(&ev);
    let lb = &ev.lb;
    // Measured (docs/event_trigger.md): DC 0.03038, exact LTI gain in
    // [0.03386, 0.04474], event-triggered bang-bang 0.0347.
    assert!((lb.dc_matrix - 0.03038).abs() < 5e-5, "{}", lb.dc_matrix);
    assert!((lb.l1_lower - 0.03386).abs() < 5e-4, "{}", lb.l1_lower);
    assert!((lb.l1_upper - 0.04474).abs() < 5e-4, "{}", lb.l1_upper);
    let bang = ev.bang.peak / TAU_BAR;
    assert!((0.0339..0.040).contains(&bang), "{bang}");
    // The T-S model's loop at the origin (the paper's (13)): same DC gain.
    let ts = linear_bounds(&linearize_ts(&model, &paper().gains));
    eprintln!(
        "paper Appendix A, T-S model at the origin: DC gain {:.5}; exact LTI gain in [{:.5}, {:.5}]",
        ts.dc_matrix, ts.l1_lower, ts.l1_upper
    );
    assert!((ts.dc_matrix - lb.dc_matrix).abs() < 1e-9 * lb.dc_matrix);
    let (scenario, run) = papers_scenario_ratio(&model, &paper());
    eprintln!(
        "paper Appendix A (nu = 0.2), paper's tau from x(0) = 0, 300 s: max |y| / max |tau| = {scenario:.4}; {} of {} samples transmitted",
        run.transmissions, run.samples
    );
    // The finding: no disturbance tried brings the paper's design (at its
    // constant threshold) near its printed gamma; the bounds lie 3.6 to 5 times below.
    for v in [
        lb.l1_upper,
        ts.l1_upper,
        bang,
        scenario,
        ev.constant.peak / TAU_BAR,
    ] {
        assert!(v < PAPER_GAMMA / 3.5, "{v} vs {PAPER_GAMMA}");
    }
}

#[test]
fn papers_adaptive_law_breaks_its_printed_gamma() {
    let model = common::shipped(SPEC);
    let law = Design {
        adaptive: Some(PRINTED_LAW),
        ..paper()
    };
    let (ratio, run) = papers_scenario_ratio(&model, &law);
    eprintln!(
        "paper Appendix A (printed law), paper's tau from x(0) = 0, 300 s: max |y| / max |tau| = {ratio:.3}; {} of {} samples transmitted; final nu {:.3}",
        run.transmissions, run.samples, run.final_nu
    );
    assert!(ratio > 50.0 * PAPER_GAMMA, "{ratio}");
    // A second method: tsfc's simulator with the same design and law; the law's
    // ceiling `max` defaults to nu, so it must be lifted to f64::MAX.
    let (p, opts) = crate::event_trigger::paper_design(crate::event_trigger::prepared());
    let tsfc_sim = |max: Option<f64>, x0: Option<Vec<f64>>| -> (f64, u64) {
        let o = tsfc::sim::simulate(
            &p,
            &tsfc::sim::Options {
                horizon: Some(300.0),
                x0,
                trigger: Some(Trigger::Aperiodic {
                    sampling: (0.001, 0.1),
                    threshold: Some(Threshold {
                        nu: 0.2,
                        adaptive: Some(PRINTED_LAW),
                        max,
                    }),
                    weight: Weight::Synthesize,
                }),
                ..opts.clone()
            },
        )
        .expect("simulation");
        // The trace is thinned: its peak is a lower bound of the run's.
        let peak = o.trace.x.iter().map(|x| norm(x)).fold(0.0, f64::max);
        let tau_peak = o
            .trace
            .t
            .iter()
            .map(|&t| paper_tau(t).norm())
            .fold(0.0, f64::max);
        (peak / tau_peak, o.metrics.transmissions)
    };
    let zero = Some(vec![0.0; 6]);
    let (unbounded, sent) = tsfc_sim(Some(f64::MAX), zero.clone());
    let (clamped, sent_clamped) = tsfc_sim(None, zero);
    // The spec's scenario (the paper's x(0)) with the printed law: the
    // transmission count the existing comparison (clamped law) does not show.
    let (_, sent_x0) = tsfc_sim(Some(f64::MAX), None);
    eprintln!("tsfc simulator, paper's scenario (paper's x(0)), printed law unbounded: {sent_x0} transmissions in 300 s");
    eprintln!(
        "tsfc simulator, paper's tau from x(0) = 0, 300 s: printed law {unbounded:.3} ({sent} transmissions), law clamped at nu = 0.2 {clamped:.4} ({sent_clamped} transmissions)"
    );
    assert!(unbounded > 50.0 * PAPER_GAMMA, "{unbounded}");
    assert!(clamped < PAPER_GAMMA / 3.5, "{clamped}");
}

#[test]
fn tsfc_design_true_gain_lies_below_its_certificates() {
    let model = common::shipped(SPEC);
    let ev = evidence("tsfc shipped (nu = nu_c)", &model, &tsfc_design());
    check_consistent(&ev);
    let (design, _) = crate::event_trigger::compiled()
        .1
        .outcome
        .as_ref()
        .expect("certified");
    let continuous = design
        .achieved
        .get(tsfc::synth::Quantity::LinfGamma)
        .expect("continuous gamma");
    let event_triggered = crate::event_trigger::trigger().gamma;
    let bang = ev.bang.peak / TAU_BAR;
    eprintln!(
        "tsfc shipped: certified gamma continuous {continuous:.4} ({:.0} x the exact LTI gain's upper bound), event-triggered {event_triggered:.4} ({:.0} x the largest simulated ratio)",
        continuous / ev.lb.l1_upper,
        event_triggered / bang
    );
    // Consistent with the certificates: every measured ratio lies below the
    // certified bounds (one above would refute them; today they are 23 and 12
    // times larger, docs/event_trigger.md).
    assert!(
        ev.lb.l1_lower < continuous,
        "{} vs {continuous}",
        ev.lb.l1_lower
    );
    let measured = bang.max(ev.constant.peak / TAU_BAR);
    assert!(
        measured < event_triggered,
        "{measured} vs {event_triggered}"
    );
    // From rest the state stays in the certified E(P, c), c = xi_max
    // tau_bar^2 / phi (issue 17: only this level lies in the linear region):
    // x' U x <= 1 along both worst-case disturbances (x' P x <= V <= c).
    for (what, r) in [("constant", &ev.constant), ("bang-bang", &ev.bang)] {
        eprintln!(
            "tsfc shipped, {what} tau: max x' U x = {:.4}",
            r.region_peak
        );
        assert!(
            r.region_peak > 0.0 && r.region_peak <= 1.0,
            "{what}: {}",
            r.region_peak
        );
    }
    // Transmissions against threshold and gains (paper's tau from x(0) = 0,
    // 300 s): each design at both thresholds (tsfc's gains are certified up to
    // 0.25; the paper's gains are not certified by tsfc at any threshold).
    for (who, d) in [("tsfc", tsfc_design()), ("paper", paper())] {
        for nu in [0.05, 0.2] {
            let (ratio, run) = papers_scenario_ratio(&model, &Design { nu, ..d.clone() });
            eprintln!(
                "{who} gains, nu = {nu}: {} of {} samples transmitted, max |y| / max |tau| = {ratio:.4}",
                run.transmissions, run.samples
            );
        }
    }
    // tsfc's gains give a smaller true gain than the paper's (2.7 times since
    // issue 17's region level: the continuous design's level is max(1, reach)).
    let paper_bound = linear_bounds(&linearize(&model, &paper().gains)).l1_lower;
    assert!(
        ev.lb.l1_upper < paper_bound / 2.0,
        "tsfc's LTI gain {} vs the paper's {paper_bound}: the shipped gains changed; update docs/event_trigger.md",
        ev.lb.l1_upper
    );
}

/// tsfc's trigger certificate applied to the paper's gains (the given-gains
/// route with `weight = synthesize`: any Upsilon, P, Y, ... may certify them).
/// Not run by default (one compile, ~50 s): `cargo test --release -p
/// tsfc-tests --test suite xu_paper_evidence:: -- --ignored`.
#[test]
#[ignore]
fn papers_gains_fail_tsfc_trigger_certificate_even_at_nu_zero() {
    let text = std::fs::read_to_string(common::spec_path(SPEC)).expect("spec");
    let (gains, _) = appendix_a();
    let mut rule = 0;
    let spec: String = text
        .lines()
        .map(|l| {
            if l.starts_with("rule R") {
                let f = &gains[rule];
                rule += 1;
                let rows: Vec<String> = f
                    .row_iter()
                    .map(|r| {
                        r.iter()
                            .map(|v| format!("{v}"))
                            .collect::<Vec<_>>()
                            .join(", ")
                    })
                    .collect();
                format!(
                    "{}, F = [{}];",
                    l.trim_end().trim_end_matches(';'),
                    rows.join("; ")
                )
            } else if l.trim_start().starts_with("threshold nu") {
                "    threshold nu = 0.2;".to_string()
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    assert_eq!(rule, 7);
    let path = std::env::temp_dir().join(format!("xu_paper_gains_{}.tsf", std::process::id()));
    std::fs::write(&path, spec).expect("temp spec");
    let run = tsfc::pipeline::read(&path)
        .and_then(|front| front.compile(&tsfc::synth::Settings::default()))
        .unwrap_or_else(|e| panic!("{e}"));
    let _ = std::fs::remove_file(&path);
    let json = crate::common::schema::report_json(&run.compiled.report);
    eprintln!(
        "paper's gains, nu = 0.2: status {:?}; diagnosis {}",
        run.compiled.status, json["diagnosis"]
    );
    assert!(run.certified().is_err());
    assert!(json["diagnosis"].to_string().contains("even with nu = 0"));
}

/// Euclidean norm of a slice.
fn norm(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

/// The paper's disturbance (Section 4), N m.
pub(crate) fn paper_tau(t: f64) -> Vector3<f64> {
    1e-3 * Vector3::new(
        -1.5 + 2.0 * (0.06 * t).cos() - 0.5 * (0.2 * t).cos(),
        2.0 + 1.5 * (0.06 * t).sin() - (0.2 * t).cos(),
        -1.5 + 2.0 * (0.06 * t).sin() - 1.5 * (0.2 * t).sin(),
    )
}

/// Why tsfc's certificate cannot take the paper's gains: it imposes every
/// (plant rule i, controller rule j) pair (memberships at x(t_k) against those
/// at t), so A_i + B F_j must at least be Hurwitz for every pair.
#[test]
fn papers_gains_cross_pairs() {
    let model = common::shipped(SPEC);
    let gains = paper().gains;
    let worst: Vec<Vec<f64>> = model
        .rules
        .iter()
        .map(|r| {
            gains
                .iter()
                .map(|f| {
                    (&r.a + &r.b * f)
                        .complex_eigenvalues()
                        .iter()
                        .map(|c| c.re)
                        .fold(f64::NEG_INFINITY, f64::max)
                })
                .collect()
        })
        .collect();
    for (i, row) in worst.iter().enumerate() {
        eprintln!(
            "plant R{}: max Re eig(A_i + B F_j), j = 1..7: {row:.4?}",
            i + 1
        );
    }
    // The paper's own pairs are stable (spec comment: max -0.0147, at R6) ...
    assert!((0..7).all(|i| worst[i][i] < -0.014));
    // ... but four cross pairs are not: (R4, F7), (R5, F6), (R6, F7), (R7, F6)
    // (plant and controller rules at opposite rates, which a bound kappa on
    // the mismatch rules out and an every-pair condition cannot).
    let unstable: Vec<(usize, usize)> = (0..7)
        .flat_map(|i| (0..7).map(move |j| (i, j)))
        .filter(|&(i, j)| worst[i][j] > 0.0)
        .collect();
    assert_eq!(unstable, vec![(3, 6), (4, 5), (5, 6), (6, 5)]);
    assert!((worst[4][5] - 0.0199).abs() < 5e-4, "{}", worst[4][5]);
}

/// The paper's local models (7) at its printed operating points, built
/// from the formula (not from the spec).
fn paper_local_models() -> (Vec<DMatrix<f64>>, DMatrix<f64>) {
    let points: [(f64, f64); 7] = [
        (0.0, 0.0),
        (0.0, 0.56),
        (0.0, -0.56),
        (0.5, 0.0),
        (-0.5, 0.0),
        (1.0, 0.56),
        (-1.0, -0.56),
    ];
    let a = points
        .iter()
        .map(|&(w, q)| common::spacecraft_local_model(w, q).0)
        .collect();
    (a, common::spacecraft_local_model(0.0, 0.0).1)
}

/// The paper's gains violate a necessary condition of its own Theorem 2.
/// Every LMI Lambda_iir(h) < 0 (the mismatch relaxation (37)-(39) covers
/// h(x(t)) = h(x(t_k)) = e_i, so it implies the matched vertex condition),
/// evaluated at psi = (x, (A_i + B F_i) x, x, 0, 0, 0) (descriptor terms,
/// L-terms, sector and disturbance rows vanish; the Y-terms, h-terms and
/// the trigger's nu x'Upsilon x are >= 0), gives
/// 2 x'U (A_i + B F_i) x + phi x'U x < 0, so A_i + B F_i + (phi / 2) I must be
/// Hurwitz: max Re eig(A_i + B F_i) < -phi / 2 = -0.025. Four printed vertex
/// loops miss it. tsfc's certified gains meet it for every pair (its
/// certificate imposes every pair). Scaling the attitude (q) columns of the
/// four failing gains by the smallest factor (steps of 0.1) that meets it
/// leaves the transmissions of the paper's scenario unchanged (83 and 83).
#[test]
fn papers_gains_violate_the_decay_condition_of_their_theorem() {
    let model = common::shipped(SPEC);
    let (a, b) = paper_local_models();
    // The spec's rules are the same local models (a second construction).
    for (i, r) in model.rules.iter().enumerate() {
        assert!((&r.a - &a[i]).amax() < 1e-12, "rule R{}", i + 1);
        assert!((&r.b - &b).amax() < 1e-12, "rule R{}", i + 1);
    }
    let own = |gains: &[DMatrix<f64>]| -> Vec<f64> {
        (0..7)
            .map(|i| common::abscissa(&(&a[i] + &b * &gains[i])))
            .collect()
    };
    let printed = paper().gains;
    let alpha = own(&printed);
    eprintln!(
        "paper's own pairs, max Re eig(A_i + B F_i): {alpha:.4?}; needed < {:.4}",
        -PHI / 2.0
    );
    let violated: Vec<usize> = (0..7).filter(|&i| alpha[i] >= -PHI / 2.0).collect();
    assert_eq!(violated, vec![1, 2, 5, 6], "{alpha:?}");
    assert!((alpha[5] + 0.0147).abs() < 5e-4, "{}", alpha[5]);
    assert!((alpha[1] + 0.0174).abs() < 5e-4, "{}", alpha[1]);

    // tsfc's shipped gains: every (plant, controller) pair meets it.
    let shipped = tsfc_design().gains;
    let worst = (0..7)
        .flat_map(|i| (0..shipped.len()).map(move |j| (i, j)))
        .map(|(i, j)| common::abscissa(&(&a[i] + &b * &shipped[j])))
        .fold(f64::NEG_INFINITY, f64::max);
    eprintln!("tsfc's shipped gains, worst pair: {worst:.4}");
    assert!(worst < -PHI / 2.0, "{worst}");

    // The smallest scaling of the failing rules' attitude columns that meets it.
    let scaled = |s: f64| -> Vec<DMatrix<f64>> {
        printed
            .iter()
            .enumerate()
            .map(|(i, f)| {
                let mut f = f.clone();
                if violated.contains(&i) {
                    f.columns_mut(3, 3).scale_mut(s);
                }
                f
            })
            .collect()
    };
    let s_min = (10..=40)
        .map(|k| k as f64 / 10.0)
        .find(|&s| own(&scaled(s)).iter().all(|&v| v < -PHI / 2.0))
        .expect("a scaling up to 4 meets the condition");
    eprintln!("smallest q-column scaling meeting it: {s_min}");
    assert!((1.5..=2.5).contains(&s_min), "{s_min}");

    // Transmissions in the paper's scenario (x(0), tau(t), 300 s, nu = 0.2,
    // the paper's Upsilon): the condition does not cost transmissions.
    let steps = (300.0 / DT).round() as usize;
    let tau = |k: usize| paper_tau(k as f64 * DT);
    let run = |gains: Vec<DMatrix<f64>>| {
        let d = Design { gains, ..paper() };
        closed_loop(&model, &d, &PAPER_X0, &tau, steps)
    };
    let (p, r) = (run(printed.clone()), run(scaled(s_min)));
    eprintln!(
        "paper's scenario, 300 s: printed gains {} of {} samples transmitted (final |x| {:.2e}); failing rules' q columns x {s_min}: {} of {} (final |x| {:.2e})",
        p.transmissions, p.samples, p.last, r.transmissions, r.samples, r.last
    );
    assert!(p.last < 1e-3 && r.last < 1e-3, "{} {}", p.last, r.last);
    let (p, r) = (p.transmissions as f64, r.transmissions as f64);
    assert!((r - p).abs() <= 0.1 * p, "{r} vs {p}");
}
