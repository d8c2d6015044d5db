//! Certificate of the mixed trigger on a named signal (Amrr et al., "Event-triggered
//! attitude control of flexible spacecraft using modified Rodrigues parameters", 2019):
//! transmit the state when ||s(x(t_i)) - s(x)|| >= beta ||s(x)|| + rho, u = PDC(x(t_i)).
//!
//! Route (PDC designs, given or synthesized gains):
//! 1. the signal is a constant linear image of the PDC command, s(x) = G u_pdc(x),
//!    u_pdc(x) = sum_j h_j(x) F_j x, checked on a grid of states of the premise
//!    region where rules fire (relative residual <= [`IMAGE_TOL`]); G has full column rank;
//! 2. with continuous monitoring u = u_pdc(x(t_i)) = u_pdc(x) + e and
//!    ||e|| <= ||G^+|| (beta ||G|| ||u_pdc|| + rho) = b1 ||u_pdc|| + b0;
//! 3. per plant/controller rule pair (i, j), with ||u_pdc||^2 <= sum_j h_j ||F_j x||^2,
//!    M_ij = [He(P(A_i + B_i F_j)) + lambda P + tau (1+eps) b1^2 F_j'F_j, P B_i; *, -tau I] < 0,
//!    P >= I, tau > 0 give V' <= -lambda V + tau (1 + 1/eps) b0^2 (S-procedure on
//!    ||e||^2 <= (1+eps) b1^2 ||u_pdc||^2 + (1+1/eps) b0^2): V(x(t)) tends to
//!    V_inf = tau (1 + 1/eps) b0^2 / lambda, ||x|| to sqrt(V_inf / lambda_min(P)).
//!
//! The certificate is for continuous monitoring of the T-S model without disturbance
//! and without input saturation (a spec with `saturate` is refused).

use super::design::SynthError;
use super::search::Runner;
use crate::model::TsModel;
use crate::model::{premise_values, rule_weight};
use nalgebra::DMatrix;
use serde::Serialize;
use tsf_lang::spec::{Monitor, NamedSignal, Trigger};
use tsf_lmi::{Expr, Problem};

/// Largest relative residual of s(x) - G u_pdc(x) on the grid.
pub const IMAGE_TOL: f64 = 1e-9;
/// Eigenvalue margin asked of each M_ij in the SDP.
const MARGIN: f64 = 1e-7;

/// The certified mixed-trigger loop.
#[derive(Debug, Clone, Serialize, PartialEq, schemars::JsonSchema)]
pub struct SignalTrigger {
    /// The monitored signal.
    pub signal: String,
    /// `continuous` or `step`.
    pub monitor: &'static str,
    /// beta, rho of the law.
    pub beta: f64,
    /// rho of the law.
    pub rho: f64,
    /// s(x) = G u_pdc(x) (K x m, rows in signal order).
    pub g: Vec<Vec<f64>>,
    /// Largest relative residual of that identity on the grid.
    pub image_residual: f64,
    /// Grid states where it was checked.
    pub image_points: usize,
    /// b1 = beta ||G|| ||G^+||.
    pub b1: f64,
    /// b0 = rho ||G^+||.
    pub b0: f64,
    /// Decay rate of V.
    pub lambda: f64,
    /// S-procedure multiplier.
    pub tau: f64,
    /// Young's inequality parameter.
    pub eps: f64,
    /// Lyapunov matrix (P >= I).
    pub p: Vec<Vec<f64>>,
    /// Ultimate level V_inf = tau (1 + 1/eps) b0^2 / lambda of x'Px.
    pub v_inf: f64,
    /// Ultimate bound on ||x||: sqrt(V_inf / lambda_min(P)).
    pub x_bound: f64,
    /// What is claimed, in words.
    pub claim: String,
}

/// Whether the spec's trigger is a mixed trigger monitored per step or continuously.
pub fn wanted(model: &TsModel) -> Option<(Option<&NamedSignal>, Monitor, f64, f64)> {
    match model.spec.trigger.as_ref().map(|t| &t.node)? {
        Trigger::Mixed {
            monitor,
            beta,
            rho,
            on,
        } if monitor.sampling().is_none() => Some((on.as_ref(), *monitor, *beta, *rho)),
        _ => None,
    }
}

fn to_rows(m: &DMatrix<f64>) -> Vec<Vec<f64>> {
    (0..m.nrows())
        .map(|i| (0..m.ncols()).map(|j| m[(i, j)]).collect())
        .collect()
}

/// Deterministic grid states: the rules' operating points, the origin's
/// neighbours and pseudo-random states in the box spanned by them (at least [-1, 1]).
fn grid(model: &TsModel) -> Vec<Vec<f64>> {
    let n = model.n;
    let mut scale = vec![1.0f64; n];
    for r in &model.rules {
        for (k, v) in r.at.iter().flatten().enumerate().take(n) {
            scale[k] = scale[k].max(v.abs());
        }
    }
    let mut out: Vec<Vec<f64>> = model.rules.iter().filter_map(|r| r.at.clone()).collect();
    let mut rng = crate::util::rng::SplitMix64::new(0x5157_4d41);
    for _ in 0..2000 {
        out.push(
            (0..n)
                .map(|k| scale[k] * (2.0 * rng.next_f64() - 1.0))
                .collect(),
        );
    }
    out.retain(|x| x.len() == n);
    out
}

/// u_pdc(x) with the normalized rule weights at x, or `None` where no rule
/// fires or x is outside the premise region (a premise outside its range).
fn pdc(model: &TsModel, gains: &[DMatrix<f64>], x: &[f64]) -> Option<DMatrix<f64>> {
    let z = premise_values(&model.spec, x).ok()?;
    // The premise region only: the certificate (like the others) covers it.
    let inside = model.premises.slots.iter().all(|slot| {
        let (lo, hi) = slot.range;
        z.get(slot.first..slot.first + slot.dim)
            .is_some_and(|c| c.iter().all(|v| *v >= lo && *v <= hi))
    });
    if !inside {
        return None;
    }
    let w: Vec<f64> = model.terms.iter().map(|t| rule_weight(t, &z)).collect();
    let total: f64 = w.iter().sum();
    if !(total > 1e-6 && total.is_finite()) {
        return None;
    }
    let xv = DMatrix::from_column_slice(x.len(), 1, x);
    let mut u = DMatrix::zeros(model.m, 1);
    for (wj, f) in w.iter().zip(gains) {
        u += f * &xv * (*wj / total);
    }
    Some(u)
}

/// G with s(x) = G u_pdc(x) on the grid, its largest relative residual and the
/// number of grid states; an error names why the signal is not such an image.
pub fn image(
    model: &TsModel,
    signal: Option<&NamedSignal>,
    gains: &[DMatrix<f64>],
) -> Result<(DMatrix<f64>, f64, usize), String> {
    let name = signal.map_or("the state", |s| s.name.as_str());
    let mut us = Vec::new();
    let mut ss = Vec::new();
    for x in grid(model) {
        let Some(u) = pdc(model, gains, &x) else {
            continue;
        };
        let s = match signal {
            Some(sig) => sig.eval(&model.spec, &x),
            None => Some(x.clone()),
        };
        let Some(s) = s.filter(|s| s.iter().all(|v| v.is_finite())) else {
            return Err(format!("the signal `{name}` is not finite at x = {x:?}"));
        };
        us.push(u);
        ss.push(DMatrix::from_column_slice(s.len(), 1, &s));
    }
    let (Some(u0), Some(s0)) = (us.first(), ss.first()) else {
        return Err("no rule fires on the grid of states: the signal cannot be compared with the PDC command".into());
    };
    let (m, k) = (u0.nrows(), s0.nrows());
    let cols = us.len();
    let mut umat = DMatrix::zeros(m, cols);
    let mut smat = DMatrix::zeros(k, cols);
    for (c, (u, s)) in us.iter().zip(&ss).enumerate() {
        umat.set_column(c, &u.column(0));
        smat.set_column(c, &s.column(0));
    }
    // G = S U^+ (least squares), then the residual of every column.
    let pinv = umat
        .clone()
        .pseudo_inverse(1e-12)
        .map_err(|e| format!("internal error: {e}"))?;
    let g = &smat * pinv;
    let mut worst = 0.0f64;
    for (u, s) in us.iter().zip(&ss) {
        let gu = &g * u;
        let scale = s.norm().max(gu.norm()).max(1e-300);
        worst = worst.max((s - gu).norm() / scale);
    }
    let why = |what: String| {
        format!(
            "the mixed trigger on `{name}` is certified only when the signal is a constant linear image of the PDC command, s(x) = G sum_j h_j(x) F_j x ({what}); \
             write the signal as that image (for Amrr et al.: sigma = -(1/k) u with F1 = -k [alpha I, I], F2 = -k [2 alpha I, I], premise p'p, h1 = 1 - p'p, h2 = p'p), \
             or use `trigger aperiodic {{ sampling = ..; threshold nu = ..; weight = synthesize; }}`"
        )
    };
    if worst.is_nan() || worst > IMAGE_TOL {
        return Err(why(format!(
            "the best G leaves a relative residual {worst:.3e} > {IMAGE_TOL:e} on {cols} states"
        )));
    }
    let sv = g.clone().svd(false, false).singular_values;
    let smin = sv.iter().copied().fold(f64::INFINITY, f64::min);
    let smax = sv.iter().copied().fold(0.0, f64::max);
    if k < m || smin.is_nan() || smin <= 1e-9 * smax.max(1e-300) {
        return Err(why(format!(
            "G is {k}x{m} without full column rank: the command cannot be recovered from the signal"
        )));
    }
    Ok((g, worst, cols))
}

/// ||G|| and ||G^+|| (spectral norms).
fn norms(g: &DMatrix<f64>) -> (f64, f64) {
    let sv = g.clone().svd(false, false).singular_values;
    let smin = sv.iter().copied().fold(f64::INFINITY, f64::min);
    let smax = sv.iter().copied().fold(0.0, f64::max);
    (smax, 1.0 / smin)
}

/// M_ij of the module doc for given P, tau (constant matrices).
#[allow(clippy::too_many_arguments)]
pub fn lmi_matrix(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    f: &DMatrix<f64>,
    p: &DMatrix<f64>,
    tau: f64,
    lambda: f64,
    eps: f64,
    b1: f64,
) -> DMatrix<f64> {
    let (n, m) = (a.nrows(), b.ncols());
    let pa = p * (a + b * f);
    let top = &pa + pa.transpose() + p * lambda + f.transpose() * f * (tau * (1.0 + eps) * b1 * b1);
    let mut out = DMatrix::zeros(n + m, n + m);
    out.view_mut((0, 0), (n, n)).copy_from(&top);
    let pb = p * b;
    out.view_mut((0, n), (n, m)).copy_from(&pb);
    out.view_mut((n, 0), (m, n)).copy_from(&pb.transpose());
    out.view_mut((n, n), (m, m))
        .copy_from(&(DMatrix::identity(m, m) * -tau));
    out
}

/// One re-checked condition: name, margin (positive: holds), a bound on its
/// rounding error, and the matrix size.
pub type Checked = (String, f64, f64, usize);

/// Every condition of `cert` rebuilt with `gains` and the model's A_i, B_i:
/// the image identity (margin IMAGE_TOL - residual), -lambda_max(M_ij),
/// lambda_min(P) - 1 and tau. `beta_scale` multiplies b1 (stored beta / beta).
pub fn margins(
    model: &TsModel,
    gains: &[DMatrix<f64>],
    cert: &SignalTrigger,
    beta_scale: f64,
) -> Vec<Checked> {
    let n = model.n;
    let p = DMatrix::from_fn(n, n, |i, j| {
        cert.p
            .get(i)
            .and_then(|r| r.get(j))
            .copied()
            .unwrap_or(f64::NAN)
    });
    let signal = match model.spec.trigger.as_ref().map(|t| &t.node) {
        Some(Trigger::Mixed { on, .. }) => on.as_ref(),
        _ => None,
    };
    let residual = image(model, signal, gains).map_or(f64::INFINITY, |(_, r, _)| r);
    let mut out = vec![(
        "signal trigger image s = G u_pdc".to_string(),
        IMAGE_TOL - residual,
        0.0,
        1,
    )];
    let b1 = cert.b1 * beta_scale;
    for (i, rule) in model.rules.iter().enumerate() {
        for (j, f) in gains.iter().enumerate() {
            let mij = lmi_matrix(&rule.a, &rule.b, f, &p, cert.tau, cert.lambda, cert.eps, b1);
            let size = mij.nrows();
            let sym = (&mij + mij.transpose()) * 0.5;
            let top = sym.clone().symmetric_eigen().eigenvalues.max();
            // Rounding of forming M and of the eigen-solver: a few ulps of ||M||_F per entry.
            let bound = 16.0 * f64::EPSILON * (size as f64) * sym.norm();
            out.push((
                format!("signal trigger M[{},{}]", i + 1, j + 1),
                -top,
                bound,
                size,
            ));
        }
    }
    let sym = (&p + p.transpose()) * 0.5;
    let pmin = sym.clone().symmetric_eigen().eigenvalues.min();
    let bound = 16.0 * f64::EPSILON * (n as f64) * sym.norm();
    out.push((
        "signal trigger P >= I".into(),
        pmin - 1.0 + MARGIN,
        bound,
        n,
    ));
    out.push(("signal trigger tau > 0".into(), cert.tau, 0.0, 1));
    out
}

/// Solves the (P, tau) SDP for lambda, eps: minimize tau s.t. P >= I, M_ij <= -margin I.
fn solve(
    runner: &mut Runner<'_>,
    model: &TsModel,
    gains: &[DMatrix<f64>],
    lambda: f64,
    eps: f64,
    b1: f64,
) -> Result<Option<(DMatrix<f64>, f64)>, SynthError> {
    let lmi = |e: tsf_lmi::LmiError| SynthError::Internal(format!("internal error: {e}"));
    let (n, m) = (model.n, model.m);
    let mut pr = Problem::new();
    let p = pr.symmetric("P", n).map_err(lmi)?;
    let tau = pr.scalar("tau").map_err(lmi)?;
    pr.psd(
        "P >= I",
        Expr::var(p)
            .add_constant(&(DMatrix::identity(n, n) * -1.0))
            .map_err(lmi)?,
        0.0,
    )
    .map_err(lmi)?;
    let c = (1.0 + eps) * b1 * b1;
    for (i, rule) in model.rules.iter().enumerate() {
        for (j, f) in gains.iter().enumerate() {
            let acl = &rule.a + &rule.b * f;
            let in_n = DMatrix::identity(n, n);
            let top = Expr::product(&in_n, p, &acl)
                .and_then(|e| e.he())
                .and_then(|e| e.add(Expr::var(p).scale(lambda)?))
                .and_then(|e| e.add(Expr::scaled(tau, &(f.transpose() * f * c))?))
                .map_err(lmi)?;
            let pb = Expr::product(&in_n, p, &rule.b).map_err(lmi)?;
            let br = Expr::scaled(tau, &(DMatrix::identity(m, m) * -1.0)).map_err(lmi)?;
            let e = Expr::sym_blocks(vec![vec![Some(top), Some(pb)], vec![None, Some(br)]])
                .map_err(lmi)?;
            pr.nsd(&format!("M[{},{}]", i + 1, j + 1), e, MARGIN)
                .map_err(lmi)?;
        }
    }
    pr.minimize(Expr::var(tau)).map_err(lmi)?;
    let sol = runner.solve(&pr, "mixed-trigger problem")?;
    let Ok(values) = sol.assignment() else {
        return Ok(None);
    };
    let pv = values.value(p).map_err(lmi)?.clone();
    let tv = values.value(tau).map_err(lmi)?[(0, 0)];
    Ok(Some((pv, tv)))
}

/// Young's-inequality weights tried for the ultimate bound (the first one also
/// brackets the decay rate).
const EPS_GRID: [f64; 5] = [0.01, 0.05, 0.25, 1.0, 4.0];

/// The smallest decay rate a certificate may claim.
const LAMBDA_MIN: f64 = 1e-3;

/// The largest beta (rounded down to 3 significant digits) for which the LMIs
/// hold at `LAMBDA_MIN`, by bisection of `b1 = beta ||G|| ||G^+||` (feasibility is
/// monotone in b1: a (P, tau) for b1 serves every smaller one); `None` if even
/// beta -> 0 fails.
fn largest_beta(
    runner: &mut Runner<'_>,
    model: &TsModel,
    gains: &[DMatrix<f64>],
    (beta, eps, gain): (f64, f64, f64),
) -> Result<Option<f64>, SynthError> {
    let (mut lo, mut hi) = (0.0, beta);
    if solve(runner, model, gains, LAMBDA_MIN, eps, 1e-6 * beta * gain)?.is_none() {
        return Ok(None);
    }
    for _ in 0..12 {
        let mid = 0.5 * (lo + hi);
        if solve(runner, model, gains, LAMBDA_MIN, eps, mid * gain)?.is_some() {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    if lo <= 0.0 {
        return Ok(None);
    }
    let scale = 10f64.powi(2 - lo.log10().floor() as i32);
    Ok(Some((lo * scale).floor() / scale))
}

/// Directions sampled on the boundary of the ultimate set when a premise is
/// not linear in the state (each also at half the radius).
const ULTIMATE_SAMPLES: usize = 2000;

/// Why the ultimate set {x : x'Px <= v_inf} is no certified bound, or `None`:
/// it must be finite and inside the premise region, where the T-S model (and
/// so the certificate) holds. Premises linear in x (z = C x) are checked
/// exactly, max over the set of |c_k x| = sqrt(v_inf c_k P^-1 c_k'); others at
/// [`ULTIMATE_SAMPLES`] states of its boundary and as many at half radius.
fn ultimate_set_outside(model: &TsModel, p: &DMatrix<f64>, v_inf: f64, rho: f64) -> Option<String> {
    if !(v_inf.is_finite() && v_inf >= 0.0) {
        return Some(format!(
            "the ultimate bound V_inf = tau (1 + 1/eps) b0^2 / lambda is not finite (rho = {rho:e}): lower rho"
        ));
    }
    let advice = |reach: f64, room: f64| {
        format!(
            "lower rho: V_inf grows as rho^2, so about rho <= {:.3e} keeps the set inside for these gains",
            rho * room / reach
        )
    };
    let Some(chol) = p.clone().cholesky() else {
        return Some("the Lyapunov matrix P is not positive definite".into());
    };
    let slots = &model.premises.slots;
    let component = |k: usize| {
        slots
            .iter()
            .find(|s| (s.first..s.first + s.dim).contains(&k))
    };
    if let Ok(c) = crate::model::region::premise_matrix(model) {
        let pinv = chol.inverse();
        for k in 0..c.nrows() {
            let Some(slot) = component(k) else { continue };
            let row = c.row(k);
            let reach = (v_inf * (row * &pinv * row.transpose())[(0, 0)]).sqrt();
            let (lo, hi) = slot.range;
            if !(lo <= -reach && reach <= hi) {
                return Some(format!(
                    "its ultimate set x'Px <= V_inf = {v_inf:.4e} reaches |{}| = {reach:.4e}, outside the premise range {lo} .. {hi} where the T-S model holds; {}",
                    model.premises.component_name(k),
                    advice(reach, (-lo).min(hi).max(0.0))
                ));
            }
        }
        return None;
    }
    let n = model.n;
    let mut rng = crate::util::rng::SplitMix64::new(0x0017_5e75);
    let lt = chol.l().transpose();
    for _ in 0..ULTIMATE_SAMPLES {
        let u = DMatrix::from_fn(n, 1, |_, _| 2.0 * rng.next_f64() - 1.0);
        let norm = u.norm();
        if norm == 0.0 {
            continue;
        }
        let Some(x) = lt.solve_upper_triangular(&(u * (v_inf.sqrt() / norm))) else {
            continue;
        };
        for scale in [1.0, 0.5] {
            let xs: Vec<f64> = x.iter().map(|v| v * scale).collect();
            let Ok(z) = crate::model::premise_values(&model.spec, &xs) else {
                return Some("a premise cannot be evaluated on its ultimate set".into());
            };
            for slot in slots {
                let (lo, hi) = slot.range;
                for k in slot.first..slot.first + slot.dim {
                    let v = z.get(k).copied().unwrap_or(f64::NAN);
                    if !(lo <= v && v <= hi) {
                        return Some(format!(
                            "its ultimate set x'Px <= V_inf = {v_inf:.4e} leaves the premise range {lo} .. {hi} of `{}` (value {v:.4e} at a sampled state), where the T-S model holds: lower rho",
                            model.premises.component_name(k)
                        ));
                    }
                }
            }
        }
    }
    None
}

/// Certifies the mixed-trigger loop for `gains`, or refuses naming why.
pub(super) fn certify_loop(
    runner: &mut Runner<'_>,
    model: &TsModel,
    gains: &[DMatrix<f64>],
) -> Result<SignalTrigger, SynthError> {
    let Some((signal, monitor, beta, rho)) = wanted(model) else {
        return Err(SynthError::Internal(
            "internal error: no mixed trigger".into(),
        ));
    };
    if model.spec.saturation.is_some() {
        return Err(SynthError::Unsupported(
            "the mixed-trigger certificate does not cover input saturation: remove `saturate` from the input (the certificate assumes u is applied unsaturated), or use `trigger aperiodic { ..; weight = synthesize; }` with the saturation region".into(),
        ));
    }
    let (g, residual, points) = image(model, signal, gains).map_err(SynthError::Unsupported)?;
    let (gn, ginv) = norms(&g);
    let (b1, b0) = (beta * gn * ginv, rho * ginv);
    let bound = |tau: f64, lambda: f64, eps: f64| {
        if b0 == 0.0 {
            0.0
        } else {
            tau * (1.0 + 1.0 / eps) * b0 * b0 / lambda
        }
    };
    // rho = 0 (b0 = 0): Young's inequality is not needed, eps = 0 is exact.
    // Otherwise the bracket uses a small eps, so that (1 + eps) b1^2 is nearly
    // b1^2 and feasibility is nearly that of rho = 0 (a large eps shrinks the
    // certified beta: eps = 1 asks for beta * sqrt(2)); the grid below then trades
    // lambda and eps for the smallest ultimate bound.
    let eps0 = if b0 == 0.0 { 0.0 } else { EPS_GRID[0] };
    // The largest lambda certified at eps0 (bracket grown, then bisected).
    let mut best: Option<(f64, f64, f64, DMatrix<f64>)> = None; // (lambda, eps, tau, P)
    let (mut lo, mut hi) = (0.0, LAMBDA_MIN);
    let mut at_lo = None;
    while let Some(sol) = solve(runner, model, gains, hi, eps0, b1)? {
        at_lo = Some(sol);
        lo = hi;
        hi *= 4.0;
        if hi > 1e4 {
            break;
        }
    }
    if let Some((p, tau)) = at_lo.clone() {
        best = Some((lo, eps0, tau, p));
    }
    for _ in 0..12 {
        if lo == 0.0 {
            break;
        }
        let mid = 0.5 * (lo + hi);
        if let Some((p, tau)) = solve(runner, model, gains, mid, eps0, b1)? {
            lo = mid;
            best = Some((mid, eps0, tau, p));
        } else {
            hi = mid;
        }
    }
    let Some(mut pick) = best else {
        let name = signal.map_or("the state", |s| s.name.as_str());
        let advice = match largest_beta(runner, model, gains, (beta, eps0, gn * ginv))? {
            Some(b) => format!("the largest beta certified is {b} (write `beta = {b};`)"),
            None => "no beta > 0 is certified: the gains themselves need a margin".into(),
        };
        return Err(SynthError::Unsupported(format!(
            "the mixed-trigger loop on `{name}` is not certified for these gains: no decay rate lambda >= {LAMBDA_MIN:e} satisfies the LMIs with b1 = beta ||G|| ||G^+|| = {b1:.4} (beta = {beta}); {advice}"
        )));
    };
    if b0 > 0.0 {
        let lmax = pick.0;
        let mut score = bound(pick.2, pick.0, pick.1);
        for frac in [0.25, 0.5, 0.75] {
            for eps in EPS_GRID {
                if let Some((p, tau)) = solve(runner, model, gains, frac * lmax, eps, b1)? {
                    let s = bound(tau, frac * lmax, eps);
                    if s < score {
                        score = s;
                        pick = (frac * lmax, eps, tau, p);
                    }
                }
            }
        }
    }
    let (lambda, eps, tau, p) = pick;
    let v_inf = bound(tau, lambda, eps);
    let pmin = p.clone().symmetric_eigen().eigenvalues.min();
    let x_bound = (v_inf / pmin).sqrt();
    let name = signal.map_or("the state", |s| s.name.as_str());
    if let Some(why) = ultimate_set_outside(model, &p, v_inf, rho) {
        return Err(SynthError::Unsupported(format!(
            "the mixed-trigger loop on `{name}` is not certified: {why}"
        )));
    }
    let monitor_word = match monitor {
        Monitor::Step => "step",
        _ => "continuous",
    };
    let claim = format!(
        "for continuous monitoring of the law (u = PDC(x(t_i)), the T-S model, w = 0, no saturation): V = x'Px satisfies V' <= -lambda V + tau (1 + 1/eps) b0^2, so x'Px tends to V_inf = {v_inf:.4e} and ||x|| to {x_bound:.4e}{}{}",
        if b0 == 0.0 { " (rho = 0: exponentially stable with rate lambda/2 in x)" } else { "" },
        if monitor == Monitor::Step { "; `monitor = step` checks the law at every integration step: between checks ||e|| may exceed the bound, so the certificate is for continuous monitoring and per-step checking approximates it" } else { "" }
    );
    Ok(SignalTrigger {
        signal: signal.map_or("x".into(), |s| s.name.clone()),
        monitor: monitor_word,
        beta,
        rho,
        g: to_rows(&g),
        image_residual: residual,
        image_points: points,
        b1,
        b0,
        lambda,
        tau,
        eps,
        p: to_rows(&p),
        v_inf,
        x_bound,
        claim,
    })
}
