//! The sampled loop of a design with Markov modes (`trigger periodic` or a
//! threshold-free `trigger aperiodic` with a `modes` block).
//!
//! Semantics: the state is sampled at s_l with s_{l+1} - s_l in [h_min,
//! h_max]; the mode r(t) is known continuously (fault detection), so the
//! command is u(t) = sum_j h_j(x(s_l)) F_{r(t) j} x(s_l): between samples the
//! held state x(s_l) is blended with the gains of the current mode, and a
//! mode jump changes the command at the jump.
//!
//! Certificate (input-delay Lyapunov-Krasovskii functional, with the mode in
//! the quadratic part only): with tau = t - s_l, h = s_{l+1} - s_l,
//!
//!   V = x' P_r x + (h - tau) int_{s_l}^t x'(a)' Y x'(a) da.
//!
//! The integral term does not depend on the mode, so a mode jump leaves V
//! continuous; it vanishes as t -> s_{l+1}, so a sample does too. With
//! psi = [x; x(s_l)], x' = Phi_aij psi in mode a (plant rule i at x(t),
//! controller rule j at x(s_l)), Phi_aij = A_i E_x + B_ai F_aj E_s, and the
//! bound -int x'' Y x' <= He(psi' N (x - x(s_l))) + tau psi' N Y^{-1} N' psi
//! (any N = E_x' L1_a + E_s' L2_a, Y > 0), the weak infinitesimal generator
//! (including sum_b pi_ab x' P_b x from the jumps of r) is at most
//! psi' [Xi_aij + (h - tau) Phi' Y Phi + tau N Y^{-1} N'] psi with
//!
//!   Xi_aij = He(E_x' P_a Phi_aij) + E_x' (sum_b pi_ab P_b) E_x + He(N (E_x - E_s)).
//!
//! That is affine in tau in [0, h] and, by convexity of Phi' Y Phi in the
//! memberships, holds for every blend if, for every mode a and every rule
//! pair (i, j) (plant and controller memberships differ):
//!
//!   r = 1: Xi_aij + h Phi_aij' Y Phi_aij < 0,
//!   r = 2: [[Xi_aij, sqrt(h) N], [*, -Y]] < 0.
//!
//! Both are Xi + h Pi with Pi >= 0, so h = h_max implies every h <= h_max:
//! the certificate covers every sampling sequence with intervals in (0,
//! h_max] (h_min is not used) and every mode path, provided the sampling
//! instants do not anticipate the mode process (deterministic, or chosen
//! independently of it). Dynkin's formula then gives E V(t) + eps E int |x|^2
//! <= V(0): mean-square (stochastic) stability of the sampled loop. The gains
//! are fixed here, so every term is linear in the unknowns P_a, Y, L1_a,
//! L2_a. The decay rate, H-inf or finite-time bounds are not claimed for the
//! sampled loop.
//!
//! Which gains: a mode-dependent design keeps its continuous gains (a
//! co-design would need one X_a per mode, and the coupling X_a' P_b X_a is
//! not linear). A fault-blind design co-designs its one gain set with the
//! sampled loop ([`add_codesign`]: descriptor form with a common X, in the
//! SDP of the continuous conditions); the analysis then certifies it.

use super::problem::input_matrices;
use super::ModesDesign;
use crate::model::TsModel;
use crate::synth::advice::{about, round_down};
use crate::synth::design::SynthError;
use crate::synth::sampling::{longest_scale_from_above, write_sampling};
use crate::synth::search::Runner;
use crate::synth::solved::Solved;
use nalgebra::DMatrix;
use tsf_lang::modes::Modes;
use tsf_lang::spec::Trigger;
use tsf_lmi::{Expr, LmiError, Problem, SolveStatus, Var};

/// The certified sampled loop of a mode design.
#[derive(Debug, Clone)]
pub struct ModesSampled {
    /// [h_min, h_max] the certificate was asked for (it covers (0, h_max]).
    pub sampling: (f64, f64),
    /// P_a of the functional, per mode.
    pub p: Vec<DMatrix<f64>>,
    /// Y of the functional's integral term (mode-independent).
    pub y: DMatrix<f64>,
    /// The free matrices L1_a, per mode.
    pub l1: Vec<DMatrix<f64>>,
    /// The free matrices L2_a, per mode.
    pub l2: Vec<DMatrix<f64>>,
    /// Values of every variable of the solved problem (by name).
    pub values: Vec<(String, DMatrix<f64>)>,
}

/// The sampling intervals [h_min, h_max] of a spec with modes whose loop is
/// sampled (`trigger periodic`, or `trigger aperiodic` without a threshold;
/// the checker refuses the other triggers with modes).
pub fn wanted(spec: &tsf_lang::Spec) -> Option<(f64, f64)> {
    match spec.trigger.as_ref().map(|t| &t.node)? {
        Trigger::Periodic { every } => Some((*every, *every)),
        Trigger::Aperiodic {
            sampling,
            threshold: None,
            ..
        } => Some(*sampling),
        _ => None,
    }
}

/// Variable names of the sampled-loop problem.
pub mod names {
    /// P_a of mode `mode`.
    pub fn p(mode: &str) -> String {
        format!("Ps_{mode}")
    }
    /// L1_a of mode `mode`.
    pub fn l1(mode: &str) -> String {
        format!("L1s_{mode}")
    }
    /// L2_a of mode `mode`.
    pub fn l2(mode: &str) -> String {
        format!("L2s_{mode}")
    }
    /// The mode-independent Y.
    pub const Y: &str = "Ys";
}

/// The name of the condition r of mode `mode` for rule pair (i, j) at h.
pub fn condition_name(mode: &str, r: u8, i: usize, j: usize, h: f64) -> String {
    format!("mode {mode} sampled r={r} h={h} Q[{},{}]", i + 1, j + 1)
}

/// Names of the looped functional's unknowns: P_a and the two free matrices
/// per mode, the common Y, and the names of their positivity conditions.
struct UnknownNames {
    p: fn(&str) -> String,
    l: [fn(&str) -> String; 2],
    y: &'static str,
    p_psd: fn(&str) -> String,
    y_psd: &'static str,
}

/// P_a and [L1_a, L2_a] per mode, and the common Y.
type ModeVars = (Vec<Var>, Vec<[Var; 2]>, Var);

/// The unknowns P_a, [L1_a, L2_a] (one per mode) and Y, with P_a > 0 and Y > 0.
fn mode_unknowns(
    problem: &mut Problem,
    modes: &Modes,
    n: usize,
    eps: f64,
    names: &UnknownNames,
) -> Result<ModeVars, LmiError> {
    let mut p = Vec::new();
    let mut l = Vec::new();
    for mode in &modes.modes {
        p.push(problem.symmetric(&(names.p)(&mode.name), n)?);
        l.push([
            problem.full(&(names.l[0])(&mode.name), n, n)?,
            problem.full(&(names.l[1])(&mode.name), n, n)?,
        ]);
    }
    let y = problem.symmetric(names.y, n)?;
    for (a, mode) in modes.modes.iter().enumerate() {
        problem.psd(&(names.p_psd)(&mode.name), Expr::var(p[a]), eps)?;
    }
    problem.psd(names.y_psd, Expr::var(y), eps)?;
    Ok((p, l, y))
}

/// The sampled-loop LMIs for `gains` (per mode, per rule) and intervals
/// `sampling`: P_a > 0, Y > 0, and r = 1, 2 for every mode and rule pair at
/// h_max and (unless `reduce`, or h_min = h_max) at h_min, which h_max implies.
pub fn build(
    model: &TsModel,
    modes: &Modes,
    gains: &[Vec<DMatrix<f64>>],
    sampling: (f64, f64),
    eps: f64,
    reduce: bool,
) -> Result<Problem, LmiError> {
    let n = model.n;
    let k = 2 * n;
    let mut problem = Problem::new();
    let (p, l, y) = mode_unknowns(
        &mut problem,
        modes,
        n,
        eps,
        &UnknownNames {
            p: names::p,
            l: [names::l1, names::l2],
            y: names::Y,
            p_psd: |m| format!("sampled P_{m} > 0"),
            y_psd: "sampled Y > 0",
        },
    )?;
    let ex = DMatrix::identity(n, k);
    let es = DMatrix::from_fn(n, k, |row, col| if col == n + row { 1.0 } else { 0.0 });
    let exs = &ex - &es;
    let id = DMatrix::identity(n, n);
    let (h_min, h_max) = sampling;
    let hs: &[f64] = if reduce || h_min >= h_max {
        &[h_max]
    } else {
        &[h_min, h_max]
    };
    for (a, mode) in modes.modes.iter().enumerate() {
        let b = input_matrices(model, modes, a);
        // The part of Xi that does not depend on (i, j): coupling and N terms.
        let mut common = Expr::product(&ex.transpose(), l[a][0], &exs)?
            .add(Expr::product(&es.transpose(), l[a][1], &exs)?)?
            .he()?;
        for (c, pc) in p.iter().enumerate() {
            let pi = modes.rates[(a, c)];
            if pi != 0.0 {
                common = common.add(Expr::product(&ex.transpose(), *pc, &ex)?.scale(pi)?)?;
            }
        }
        let col = Expr::product(&ex.transpose(), l[a][0], &id)?.add(Expr::product(
            &es.transpose(),
            l[a][1],
            &id,
        )?)?;
        for (i, (rule, bi)) in model.rules.iter().zip(&b).enumerate() {
            for (j, fj) in gains[a].iter().enumerate() {
                let phi = &rule.a * &ex + bi * fj * &es;
                let xi = Expr::product(&ex.transpose(), p[a], &phi)?
                    .he()?
                    .add(common.clone())?;
                for &h in hs {
                    let r1 = xi
                        .clone()
                        .add(Expr::product(&phi.transpose(), y, &phi)?.scale(h)?)?;
                    problem.nsd(&condition_name(&mode.name, 1, i, j, h), r1, eps)?;
                    let r2 = Expr::sym_blocks(vec![
                        vec![Some(xi.clone()), Some(col.clone().scale(h.sqrt())?)],
                        vec![None, Some(Expr::var(y).scale(-1.0)?)],
                    ])?;
                    problem.nsd(&condition_name(&mode.name, 2, i, j, h), r2, eps)?;
                }
            }
        }
    }
    Ok(problem)
}

/// The descriptor multiplier ratios delta (P3 = delta P2) the fault-blind
/// co-design tries, in order, until its SDP is solved.
pub const CODESIGN_DELTAS: [f64; 3] = [1.0, 0.1, 10.0];

/// Variable names of the fault-blind co-design's sampled-loop part.
pub mod codesign_names {
    /// X' P_a X of mode `mode`.
    pub fn p(mode: &str) -> String {
        format!("Pc_{mode}")
    }
    /// X' L1_a X of mode `mode`.
    pub fn n1(mode: &str) -> String {
        format!("N1c_{mode}")
    }
    /// X' L2_a X of mode `mode`.
    pub fn n3(mode: &str) -> String {
        format!("N3c_{mode}")
    }
    /// X' Y X.
    pub const Y: &str = "Yc";
}

/// The name of the co-design condition r of mode `mode` for rule pair (i, j).
pub fn codesign_condition_name(mode: &str, r: u8, i: usize, j: usize) -> String {
    format!("mode {mode} sampled co-design r={r} Q[{},{}]", i + 1, j + 1)
}

/// Adds to `problem` (the continuous fault-blind design, with the common X
/// and gain variables M_j = F_j X) the sampled-loop conditions at h_max in
/// descriptor form, so that the gains are designed for the sampled loop.
///
/// With zeta = [x; x'; x(s_l)] and the descriptor identity 0 = 2 (x' P2' +
/// x'' delta P2') (-x' + A_i x + B_ai F_j x(s_l)), the generator bound of the
/// module's functional (free matrix N_a = E_x' L1_a + E_s' L2_a, no x'
/// component) is zeta' [Xi + (h - tau) E_d' Y E_d + tau N_a Y^{-1} N_a'] zeta.
/// Congruence with diag(X, X, X), X = P2^{-1} common to every mode (the
/// gains are), makes every term linear: X' P_a X, X' Y X, X' L_a X, M_j =
/// F_j X, and the coupling X' (sum_b pi_ab P_b) X = sum_b pi_ab X' P_b X.
/// Substituting x' = Phi_aij psi (the descriptor term vanishes) gives back
/// the analysis conditions of [`build`] with P_a, Y, L1_a, L2_a: the
/// co-design is feasible only if the analysis is, which then certifies.
#[allow(clippy::too_many_arguments)]
pub fn add_codesign(
    problem: &mut Problem,
    model: &TsModel,
    modes: &Modes,
    x: tsf_lmi::Var,
    m: &[tsf_lmi::Var],
    h: f64,
    delta: f64,
    eps: f64,
) -> Result<(), LmiError> {
    let n = model.n;
    let k = 3 * n;
    let sel =
        |block: usize| DMatrix::from_fn(n, k, |r, c| if c == block * n + r { 1.0 } else { 0.0 });
    let (ex, ed, es) = (sel(0), sel(1), sel(2));
    let exs = &ex - &es;
    let id = DMatrix::identity(n, n);
    let (p, l, y) = mode_unknowns(
        problem,
        modes,
        n,
        eps,
        &UnknownNames {
            p: codesign_names::p,
            l: [codesign_names::n1, codesign_names::n3],
            y: codesign_names::Y,
            p_psd: |m| format!("sampled co-design X'P_{m}X > 0"),
            y_psd: "sampled co-design X'YX > 0",
        },
    )?;
    // (E_x' + delta E_d'): where the descriptor multiplier enters.
    let mult = ex.transpose() + ed.transpose() * delta;
    let dy = Expr::product(&ed.transpose(), y, &ed)?.scale(h)?;
    for (a, mode) in modes.modes.iter().enumerate() {
        let b = input_matrices(model, modes, a);
        let mut common = Expr::product(&ex.transpose(), p[a], &ed)?
            .he()?
            .add(
                Expr::product(&ex.transpose(), l[a][0], &exs)?
                    .add(Expr::product(&es.transpose(), l[a][1], &exs)?)?
                    .he()?,
            )?
            .add(Expr::product(&mult, x, &(-&ed))?.he()?)?;
        for (c, pc) in p.iter().enumerate() {
            let pi = modes.rates[(a, c)];
            if pi != 0.0 {
                common = common.add(Expr::product(&ex.transpose(), *pc, &ex)?.scale(pi)?)?;
            }
        }
        let col = Expr::product(&ex.transpose(), l[a][0], &id)?
            .add(Expr::product(&es.transpose(), l[a][1], &id)?)?
            .scale(h.sqrt())?;
        for (i, (rule, bi)) in model.rules.iter().zip(&b).enumerate() {
            let ax = Expr::product(&(&mult * &rule.a), x, &ex)?;
            for (j, mj) in m.iter().enumerate() {
                let xi = ax
                    .clone()
                    .add(Expr::product(&(&mult * bi), *mj, &es)?)?
                    .he()?
                    .add(common.clone())?;
                let r1 = xi.clone().add(dy.clone())?;
                problem.nsd(&codesign_condition_name(&mode.name, 1, i, j), r1, eps)?;
                let r2 = Expr::sym_blocks(vec![
                    vec![Some(xi), Some(col.clone())],
                    vec![None, Some(Expr::var(y).scale(-1.0)?)],
                ])?;
                problem.nsd(&codesign_condition_name(&mode.name, 2, i, j), r2, eps)?;
            }
        }
    }
    Ok(())
}

/// How often the fault-blind co-design's refusal halves h_max looking for
/// an interval it solves (down to h_max / 2^6).
pub const CODESIGN_HALVINGS: u32 = 6;

/// The refusal of a fault-blind sampled design whose co-design was not
/// solved at `sampling` (the search's `message`), with advice: the halved
/// h_max at which it was (`found`), checked by the analysis of [`build`].
pub(super) fn codesign_refusal(
    runner: &mut Runner<'_>,
    modes: &Modes,
    sampling: (f64, f64),
    message: &str,
    found: Option<(f64, super::Solved)>,
) -> SynthError {
    let deltas = CODESIGN_DELTAS.map(|d| d.to_string()).join(", ");
    let message = format!(
        "no fault-blind gains were found for the sampled loop at h_max = {} s: the continuous conditions with the sampled-loop conditions in descriptor form (one X, delta in [{deltas}]) were infeasible or the solver stopped ({message})",
        sampling.1
    );
    let advice = match found {
        None => format!(
            "no co-design solved down to h_max = {} s either: use `design = mode_dependent;`, weaken the objectives, or shorten the sampling further",
            sampling.1 / f64::from(1u32 << CODESIGN_HALVINGS)
        ),
        Some((h, s)) => {
            let at = (sampling.0.min(h), h);
            let write = write_sampling(sampling, h);
            match certify_loop(runner, modes, &s.modes, at) {
                Ok(_) => format!("the co-design is solved and certified at h_max = {h} s: write {write} (certified)"),
                Err(_) => format!("the co-design is solved at h_max = {h} s but its analysis did not certify: shorten the sampling below {h} s"),
            }
        }
    };
    SynthError::Infeasible {
        message,
        achievable: vec![advice],
    }
}

/// What the certificate covers, in words (report and notes).
pub fn covers(sampling: (f64, f64)) -> String {
    let (lo, hi) = sampling;
    let asked = if lo == hi {
        format!("sampled every {hi} s")
    } else {
        format!("sampled at any intervals in [{lo}, {hi}] s")
    };
    format!(
        "the loop {asked} (zero-order hold of the state; the command re-blended with the current mode's gains at each mode jump) is mean-square stable under the Markov chain, for every sampling sequence with intervals in (0, {hi}] s chosen independently of the mode process; decay, H-inf and finite-time bounds are certified for the continuous loop only"
    )
}

/// What solver messages call this problem.
const SOLVE_WHAT: &str = "sampled mode-loop problem";

/// One solve at `sampling` for the gains of `md`: the certificate's data,
/// or None when not solved.
fn attempt(
    runner: &mut Runner<'_>,
    modes: &Modes,
    md: &ModesDesign,
    sampling: (f64, f64),
) -> Result<Option<ModesSampled>, SynthError> {
    let internal = |e: LmiError| SynthError::Internal(format!("internal error: {e}"));
    let problem = build(
        runner.model,
        modes,
        &md.gains,
        sampling,
        runner.settings.eps,
        true,
    )
    .map_err(internal)?;
    let sol = runner.solve(&problem, SOLVE_WHAT)?;
    if sol.status != SolveStatus::Solved {
        return Ok(None);
    }
    let iterate = sol.assignment().map_err(internal)?;
    let values = problem
        .vars()
        .map(|(name, v)| {
            iterate
                .value(v)
                .cloned()
                .map(|m| (name.to_string(), m))
                .map_err(internal)
        })
        .collect::<Result<Vec<_>, _>>()?;
    let get = |name: &str| values.required(name);
    let per_mode = |f: fn(&str) -> String| {
        modes
            .modes
            .iter()
            .map(|m| get(&f(&m.name)))
            .collect::<Result<Vec<_>, _>>()
    };
    Ok(Some(ModesSampled {
        sampling,
        p: per_mode(names::p)?,
        l1: per_mode(names::l1)?,
        l2: per_mode(names::l2)?,
        y: get(names::Y)?,
        values,
    }))
}

/// The sampled-loop certificate of the mode design `md` at `sampling`, or
/// the refusal with the longest certified interval (halving, then bisection
/// on h_max; the advised value re-solved before it is advised).
pub(in crate::synth) fn certify_loop(
    runner: &mut Runner<'_>,
    modes: &Modes,
    md: &ModesDesign,
    sampling: (f64, f64),
) -> Result<(ModesSampled, String), SynthError> {
    if let Some(s) = attempt(runner, modes, md, sampling)? {
        return Ok((s, format!("sampled loop certified: {}", covers(sampling))));
    }
    // The certificate does not depend on h_min: only h_max is scaled.
    let at = |s: f64| (sampling.0.min(sampling.1 * s), sampling.1 * s);
    let what = if sampling.0 == sampling.1 {
        format!("sampling every {} s", sampling.1)
    } else {
        format!("sampling intervals in [{}, {}] s", sampling.0, sampling.1)
    };
    let gains = match md.design {
        tsf_lang::modes::ModeDesign::Dependent => "the gains of the continuous mode design",
        tsf_lang::modes::ModeDesign::Independent => "the co-designed fault-blind gains",
    };
    let reach = longest_scale_from_above(|s| Ok(attempt(runner, modes, md, at(s))?.is_some()))?;
    let Some(reach) = reach else {
        return Err(SynthError::Infeasible {
            message: format!("the sampled loop is not certified: {gains} are not certified for {what}, nor for any interval down to 1/1024 of it (halved from 1/2)"),
            achievable: vec!["weaken the objectives that set the gains (large gains need fast sampling), or declare a faster trigger".into()],
        });
    };
    let mut advice = round_down(sampling.1 * reach);
    let mut verified = false;
    for _ in 0..4 {
        if attempt(runner, modes, md, at(advice / sampling.1))?.is_some() {
            verified = true;
            break;
        }
        advice = round_down(advice * 0.95);
    }
    let write = if verified && sampling.0 == sampling.1 {
        format!("write {} (certified)", write_sampling(sampling, advice))
    } else if verified {
        format!(
            "write `sampling = {} .. {advice};` (certified)",
            sampling.0.min(advice)
        )
    } else {
        "no short value re-solved as certified: shorten the sampling further".into()
    };
    Err(SynthError::Infeasible {
        message: format!("the sampled loop is not certified: {gains} are not certified for {what} under the Markov chain"),
        achievable: vec![format!(
            "the longest certified sampling interval is about {} s: {write}, or weaken the objectives that set the gains",
            about(sampling.1 * reach)
        )],
    })
}
