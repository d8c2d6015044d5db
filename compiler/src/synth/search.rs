//! The searches around single SDPs: one attempt per plan, the decay-rate
//! bisection, the xi bisection and the L-inf line search over phi.

use super::achieved::Achieved;
use super::build::build;
use super::design::{Design, Settings, SolverLog, SynthError};
use super::lyapunov::fuzzy;
use super::objective::GainTerm;
use super::plan::{Bound, Goal, Plan};
use crate::model::TsModel;
use std::time::{Duration, Instant};
use tsf_lmi::{Problem, Solution, SolveStatus};

/// With `linf <= g`, the largest xi tried is g (1 - XI_CAP_REL).
const XI_CAP_REL: f64 = 1e-6;
/// The xi hint's first SDP bounds xi where the level reached from rest,
/// xi tau^2 / phi, is this minus 1 (the region level is then max(1, it) = 1).
const XI_HINT_LEVEL_FACTOR: f64 = 1.1;
/// After a feasible xi from the hint, xi times this is tried next.
const XI_PROBE: f64 = 0.9;
/// The design's fixed xi is the minimum of xi times 1 + this: at the minimum
/// itself the gains leave no room for sampling (the Xu & Huang trigger step is
/// infeasible for them) and fixed-xi solves within ~0.4 % of it stall.
const XI_MARGIN_REL: f64 = 5e-3;
/// With `linf ... minimize`, the xi grid above the smallest xi grows by this
/// factor (gamma >= xi, so it stops once xi passes the best gamma).
const XI_SCAN_FACTOR: f64 = 4.0;
/// Golden-section steps on log xi around the best grid point.
const XI_GOLDEN_STEPS: usize = 12;

/// (largest feasible, smallest infeasible) value found by a bisection.
pub(super) type Bracket = (f64, f64);

/// Outcome of one SDP.
pub(super) enum Attempt {
    Solved(Box<Design>),
    Infeasible,
    Trouble(SolveStatus),
}

/// Runs SDPs for one model and keeps the solver log (what loop laws design with).
pub struct Runner<'a> {
    /// The model.
    pub model: &'a TsModel,
    /// Synthesis settings.
    pub settings: &'a Settings,
    /// Solver bookkeeping of every SDP run.
    pub log: SolverLog,
    /// Accept `AlmostSolved` iterates (only while diagnosing).
    pub accept_almost: bool,
}

impl Runner<'_> {
    /// Builds and solves `plan` once.
    pub(super) fn attempt(&mut self, plan: &Plan) -> Result<Attempt, SynthError> {
        let relaxation = self.model.spec.relaxation.node;
        self.check_floor()?;
        let t0 = Instant::now();
        let mut built = build(self.model, plan, relaxation, self.settings.eps, true)?;
        let coupling = super::observer::static_output::coupled(self.model, &mut built)
            .map_err(super::BuildError::Lmi)?;
        self.log.build_time += t0.elapsed();
        let sol = self.solve(&built.problem, "gain problem")?;
        let approximate = sol.status == SolveStatus::AlmostSolved && self.accept_almost;
        match sol.status {
            SolveStatus::Solved => {}
            _ if approximate => {}
            s if s.is_primal_infeasible() => return Ok(Attempt::Infeasible),
            s => return Ok(Attempt::Trouble(s)),
        }
        self.log.status = Some(sol.status);
        self.log.iterations = sol.iterations;
        self.log.stats = Some(built.problem.stats());
        let iterate = sol.assignment_any_status();
        let values_of = |v| {
            iterate
                .value(v)
                .cloned()
                .map_err(|e| SynthError::Internal(format!("{e}")))
        };
        let x = values_of(built.x)?;
        let (p, gains, fuzzy) = match &built.fuzzy {
            Some(fv) => {
                let z = built
                    .m
                    .iter()
                    .map(|g| match g {
                        GainTerm::Free(v) => values_of(*v),
                        GainTerm::Given(_) => Err(SynthError::Internal(
                            "internal error: a fuzzy Lyapunov design with given gains".into(),
                        )),
                    })
                    .collect::<Result<Vec<_>, _>>()?;
                let pt =
                    fv.p.iter()
                        .map(|v| values_of(*v))
                        .collect::<Result<Vec<_>, _>>()?;
                let Some((gains, pk)) = fuzzy::recover(&x, &z, &pt) else {
                    return Ok(Attempt::Trouble(SolveStatus::NumericalError));
                };
                let design = fuzzy::FuzzyDesign {
                    phi: fuzzy::phi(self.model).unwrap_or_default().to_vec(),
                    mu: fv.mu,
                    p: pk.clone(),
                    region: None,
                };
                (pk[0].clone(), gains, Some(design))
            }
            None => {
                let Some(chol) = x.clone().cholesky() else {
                    return Ok(Attempt::Trouble(SolveStatus::NumericalError));
                };
                (chol.inverse(), built.gains(values_of, &chol)?, None)
            }
        };
        let mut values = built
            .problem
            .vars()
            .map(|(name, v)| values_of(v).map(|m| (name.to_string(), m)))
            .collect::<Result<Vec<_>, _>>()?;
        let (gains, output) = match &coupling {
            None => (gains, None),
            Some(cp) => {
                let value = |v| iterate.value(v).ok().cloned();
                let finished =
                    super::observer::static_output::finish(self.model, cp, &x, value, &mut values);
                let Some((f, sof)) = finished else {
                    return Ok(Attempt::Trouble(SolveStatus::NumericalError));
                };
                (f, Some(super::observer::OutputFeedback::StaticOutput(sof)))
            }
        };
        let mut achieved = Achieved::default();
        for o in plan.objectives() {
            o.achieved(&values, &mut achieved);
        }
        Ok(Attempt::Solved(Box::new(Design {
            plan: plan.clone(),
            gains,
            x,
            p,
            values,
            achieved,
            eps: self.settings.eps,
            reductions: built.reductions,
            notes: Vec::new(),
            log: SolverLog::default(),
            certify_time: Duration::ZERO,
            approximate,
            loop_design: Default::default(),
            verdicts: Vec::new(),
            modes: None,
            fuzzy,
            output,
        })))
    }

    /// Refuses, before building anything, a model whose gain problem cannot
    /// fit the memory budget: X > 0 and one vertex condition per rule are
    /// LMIs of at least n x n, whatever the objectives.
    pub fn check_floor(&self) -> Result<(), SynthError> {
        let n = self.model.n;
        let floor = tsf_lmi::ClarabelSolver::memory_floor(vec![n; 1 + self.model.r()]);
        if floor > self.settings.memory_limit {
            return Err(SynthError::TooLarge {
                what: "gain problem".into(),
                estimate: floor,
                limit: self.settings.memory_limit,
                largest_lmi: n,
                floor: true,
            });
        }
        Ok(())
    }

    /// Solves one SDP within the memory budget and logs it.
    pub fn solve(&mut self, problem: &Problem, what: &str) -> Result<Solution, SynthError> {
        let settings = self.settings.solver.clone();
        self.solve_with(problem, what, &settings)
    }

    /// [`Runner::solve`] with other solver settings.
    pub fn solve_with(
        &mut self,
        problem: &Problem,
        what: &str,
        settings: &tsf_lmi::SolveSettings,
    ) -> Result<Solution, SynthError> {
        let estimate = problem.memory_estimate();
        if estimate > self.settings.memory_limit {
            return Err(SynthError::TooLarge {
                what: what.to_string(),
                estimate,
                limit: self.settings.memory_limit,
                largest_lmi: problem.stats().psd_cones.iter().copied().max().unwrap_or(0),
                floor: false,
            });
        }
        self.log.memory_estimate = self.log.memory_estimate.max(estimate);
        let sol = problem
            .solve(settings)
            .map_err(|e| SynthError::Internal(format!("solver refused the {what}: {e}")))?;
        self.log.solves += 1;
        self.log.unscaled_retries += usize::from(sol.unscaled_retry);
        self.log.last_status = Some(sol.status);
        self.log.solve_time += Duration::from_secs_f64(sol.solve_time.max(0.0));
        Ok(sol)
    }

    /// Largest decay rate for which `plan` is feasible: (design, bracket).
    fn max_decay(&mut self, plan: &Plan) -> Result<Option<(Design, Bracket)>, SynthError> {
        let mut best = match self.attempt(&plan.with_decay(0.0))? {
            Attempt::Solved(d) => *d,
            Attempt::Infeasible => return Ok(None),
            Attempt::Trouble(s) => {
                return Err(SynthError::Solver {
                    status: s,
                    message: "the solver failed at decay rate 0".into(),
                    achievable: Vec::new(),
                })
            }
        };
        let (mut lo, mut hi) = (0.0, 0.5);
        // Grow the bracket until infeasible.
        while let Attempt::Solved(d) = self.attempt(&plan.with_decay(hi))? {
            best = *d;
            lo = hi;
            hi *= 2.0;
            if hi > 1e6 {
                return Ok(Some((best, (lo, f64::INFINITY))));
            }
        }
        while hi - lo > self.settings.bisection_rel_tol * hi.max(1e-9) {
            let mid = 0.5 * (lo + hi);
            match self.attempt(&plan.with_decay(mid))? {
                Attempt::Solved(d) => {
                    best = *d;
                    lo = mid;
                }
                // Near the supremum the solver may stall instead of proving
                // infeasibility: both count as "not achieved".
                Attempt::Infeasible | Attempt::Trouble(_) => hi = mid,
            }
        }
        Ok(Some((best, (lo, hi))))
    }

    /// Smallest fixed xi for which `plan` is feasible, to a margin (L-inf with
    /// saturation and a bounded disturbance, where xi enters the linear-region
    /// level). Two SDPs minimize xi with xi an unknown and the level computed
    /// at a bound ([`Runner::xi_hint`]): first at the loose bound of level factor
    /// [`XI_HINT_LEVEL_FACTOR`], then at that minimum times 1 + tol; the design
    /// is solved with xi fixed at the second minimum times 1 + [`XI_MARGIN_REL`]
    /// (three SDPs instead of a bisection). When that does not solve, xi is
    /// bisected with xi fixed: the bracket grows from 1e-3 (or from the first
    /// minimum with a probe of [`XI_PROBE`] below it) and halves to
    /// `bisection_rel_tol`. Every design returned is solved at a fixed xi.
    /// (design, note).
    fn min_xi(&mut self, plan: &Plan, tau: f64) -> Result<Option<(Design, String)>, SynthError> {
        let with = |xi: f64| {
            let mut p = plan.clone();
            if let Some(l) = p.linf_mut() {
                l.xi = Some(xi);
            }
            p
        };
        // gamma >= xi ((gamma - xi) I > 0): with a fixed bound gamma <= g the
        // search must stay below g, else the growing bracket can jump over the
        // feasible window [xi_min, g).
        let cap = match plan.linf().map(|l| l.target) {
            Some(Bound::Fixed(g)) => g * (1.0 - XI_CAP_REL),
            _ => 1e8,
        };
        let tol = self.settings.bisection_rel_tol;
        let Some(linf) = plan.linf() else {
            return Ok(None);
        };
        let first_bound = ((XI_HINT_LEVEL_FACTOR - 1.0) * linf.phi / (tau * tau)).min(cap);
        let hint = self.xi_hint(plan, first_bound, tau)?;
        if let Some(h1) = hint {
            let bound = (h1 * (1.0 + tol)).min(cap);
            if let Some(h2) = self.xi_hint(plan, bound, tau)? {
                let xi = (h2 * (1.0 + XI_MARGIN_REL)).min(cap);
                if let Attempt::Solved(d) = self.attempt(&with(xi))? {
                    let note = format!("xi minimized (the linear-region level depends on it): the smallest xi with the level computed at xi <= {bound:.6} is {h2:.6} (at xi <= {first_bound:.6}: {h1:.6}); designed with xi fixed at {xi:.6} (margin {XI_MARGIN_REL})");
                    return Ok(Some((*d, note)));
                }
            }
        }
        let mut candidates: Vec<f64> = hint
            .map(|h| (h * (1.0 + tol)).min(cap))
            .into_iter()
            .collect();
        let mut grow = 1e-3f64.min(cap);
        loop {
            candidates.push(grow);
            if grow >= cap {
                break;
            }
            grow = (grow * 4.0).min(cap);
        }
        let (mut lo, mut found) = (0.0f64, None);
        for (k, xi) in candidates.into_iter().enumerate() {
            match self.attempt(&with(xi))? {
                Attempt::Solved(d) => {
                    found = Some((*d, xi, k == 0 && hint.is_some()));
                    break;
                }
                _ if found.is_none() && xi > lo && k > 0 => lo = xi,
                _ => {}
            }
        }
        let Some((mut best, mut hi, hinted)) = found else {
            return Ok(None);
        };
        if lo >= hi {
            lo = 0.0;
        }
        if hinted {
            let probe = hi * XI_PROBE;
            match self.attempt(&with(probe))? {
                Attempt::Solved(d) => {
                    best = *d;
                    hi = probe;
                }
                _ => lo = lo.max(probe),
            }
        }
        while hi - lo > tol * hi {
            let mid = 0.5 * (lo + hi);
            match self.attempt(&with(mid))? {
                Attempt::Solved(d) => {
                    best = *d;
                    hi = mid;
                }
                Attempt::Infeasible | Attempt::Trouble(_) => lo = mid,
            }
        }
        // The design at the bisection's edge has margins at the solver's
        // tolerance; one more at xi + XI_MARGIN_REL (as for the hinted route)
        // is strictly inside and is the one kept when it solves.
        let backed = (hi * (1.0 + XI_MARGIN_REL)).min(cap);
        if backed > hi {
            if let Attempt::Solved(d) = self.attempt(&with(backed))? {
                let note = format!("xi minimized by bisection (the linear-region level depends on it): feasible at {hi:.6}, not at {lo:.6}; designed with xi fixed at {backed:.6} (margin {XI_MARGIN_REL})");
                return Ok(Some((*d, note)));
            }
        }
        let note = format!("xi minimized by bisection (the linear-region level depends on it): feasible at {hi:.6}, not at {lo:.6}");
        Ok(Some((best, note)))
    }

    /// With gamma minimized: the smallest xi leaves the saturation region no
    /// room and can inflate gamma (gamma(xi) falls, then rises with xi since
    /// gamma >= xi). From the design `at_min` (solved at the smallest xi, to a
    /// margin), xi grows by [`XI_SCAN_FACTOR`] while it is below the best gamma
    /// found and the design solves, then [`XI_GOLDEN_STEPS`] golden-section
    /// steps on log xi around the best grid point. Every design is solved at a
    /// fixed xi; the one with the smallest gamma is kept, with a note when it
    /// is not `at_min`.
    fn xi_for_gamma(
        &mut self,
        plan: &Plan,
        at_min: Design,
    ) -> Result<(Design, Option<String>), SynthError> {
        use super::achieved::Quantity::{LinfGamma, LinfXi};
        let gamma = |d: &Design| d.achieved.get(LinfGamma).unwrap_or(f64::INFINITY);
        let (Some(xi0), g0) = (at_min.achieved.get(LinfXi), gamma(&at_min)) else {
            return Ok((at_min, None));
        };
        let solve = |runner: &mut Self, xi: f64| -> Result<Option<Design>, SynthError> {
            let mut p = plan.clone();
            if let Some(l) = p.linf_mut() {
                l.xi = Some(xi);
            }
            Ok(match runner.attempt(&p)? {
                Attempt::Solved(d) => Some(*d),
                _ => None,
            })
        };
        let mut grid: Vec<(f64, f64)> = vec![(xi0, g0)];
        let mut best = (at_min, xi0, g0);
        let mut xi = xi0 * XI_SCAN_FACTOR;
        while xi < best.2 && xi <= 1e8 {
            let Some(d) = solve(self, xi)? else { break };
            let g = gamma(&d);
            grid.push((xi, g));
            if g < best.2 {
                best = (d, xi, g);
            }
            xi *= XI_SCAN_FACTOR;
        }
        if grid.len() == 1 {
            return Ok((best.0, None));
        }
        // Golden section on log xi between the neighbours of the best point.
        let k = grid.iter().position(|(x, _)| *x == best.1).unwrap_or(0);
        let (mut a, mut b) = (
            grid[k.saturating_sub(1)].0.ln(),
            grid[(k + 1).min(grid.len() - 1)].0.ln(),
        );
        let gr = 0.5 * (5f64.sqrt() - 1.0);
        let eval = |runner: &mut Self, t: f64, best: &mut (Design, f64, f64)| {
            let xi = t.exp();
            let g = solve(runner, xi)?.map_or(f64::INFINITY, |d| {
                let g = gamma(&d);
                if g < best.2 {
                    *best = (d, xi, g);
                }
                g
            });
            Ok::<f64, SynthError>(g)
        };
        for _ in 0..XI_GOLDEN_STEPS {
            if b - a < 1e-3 {
                break;
            }
            let c = b - gr * (b - a);
            let d = a + gr * (b - a);
            if eval(self, c, &mut best)? < eval(self, d, &mut best)? {
                b = d;
            } else {
                a = c;
            }
        }
        let (design, xi, g) = best;
        let note = (xi != xi0).then(|| {
            format!("gamma minimized over xi: at the smallest xi ({xi0:.6e}) gamma is {g0:.6e}; xi scanned upward by {XI_SCAN_FACTOR}x and refined by golden section on log xi: gamma = {g:.6e} at xi = {xi:.6e}")
        });
        Ok((design, note))
    }

    /// One SDP that minimizes xi with the linear-region level computed at the
    /// bound xi <= `bound`; its xi places the search, so an `AlmostSolved`
    /// iterate is taken.
    fn xi_hint(&mut self, plan: &Plan, bound: f64, tau: f64) -> Result<Option<f64>, SynthError> {
        if plan.linf().is_none() || tau <= 0.0 {
            return Ok(None);
        }
        let mut p = plan.clone();
        if let Some(l) = p.linf_mut() {
            l.xi_bound = Some(bound);
            l.minimize_xi = true;
        }
        let keep = std::mem::replace(&mut self.accept_almost, true);
        let attempt = self.attempt(&p);
        self.accept_almost = keep;
        Ok(match attempt? {
            Attempt::Solved(d) => d
                .achieved
                .get(super::achieved::Quantity::LinfXi)
                .filter(|x| x.is_finite() && *x > 0.0),
            _ => None,
        })
    }

    /// Solves `plan` as the goal says (no diagnosis).
    pub fn run(&mut self, plan: &Plan, goal: Goal) -> Result<Option<Design>, SynthError> {
        if goal == Goal::MaxDecay {
            return Ok(self.max_decay(plan)?.map(|(mut d, bracket)| {
                d.achieved.decay_bracket = Some(bracket);
                d.notes.push(format!(
                    "decay rate maximized by bisection: feasible at {:.6}, not at {:.6}",
                    bracket.0, bracket.1
                ));
                d
            }));
        }
        let linf = plan.linf();
        let phi_free = linf.is_some_and(|l| !l.phi_fixed);
        let disturbed_saturation = plan
            .saturation()
            .is_some_and(|s| s.disturbance_bound.is_some());
        if linf.is_some_and(|l| l.xi.is_none()) && disturbed_saturation {
            if phi_free {
                return Err(SynthError::Unsupported("L-inf with saturation and a bounded disturbance needs a fixed phi (`with phi = ...`): the linear-region level depends on xi / phi".into()));
            }
            let tau = plan
                .saturation()
                .and_then(|s| s.disturbance_bound)
                .unwrap_or(0.0);
            let Some((d, note)) = self.min_xi(plan, tau)? else {
                return Ok(None);
            };
            let minimize = plan
                .linf()
                .is_some_and(|l| matches!(l.target, Bound::Minimize));
            let (mut d, scan) = if minimize {
                self.xi_for_gamma(plan, d)?
            } else {
                (d, None)
            };
            d.notes.push(note);
            d.notes.extend(scan);
            return Ok(Some(d));
        }
        if phi_free {
            return self.linf_line_search(plan);
        }
        match self.attempt(plan)? {
            Attempt::Solved(d) => Ok(Some(*d)),
            Attempt::Infeasible => Ok(None),
            Attempt::Trouble(s) => Err(SynthError::Solver {
                status: s,
                message: "the solver stopped without a verdict".into(),
                achievable: Vec::new(),
            }),
        }
    }

    /// Line search over phi (log grid, then golden section) for the smallest L-inf gamma.
    fn linf_line_search(&mut self, plan: &Plan) -> Result<Option<Design>, SynthError> {
        let eval = |runner: &mut Self, phi: f64| -> Result<Option<Design>, SynthError> {
            let mut p = plan.clone();
            if let Some(l) = p.linf_mut() {
                l.phi = phi;
            }
            Ok(match runner.attempt(&p)? {
                Attempt::Solved(d) => Some(*d),
                _ => None,
            })
        };
        let key = |d: &Design| {
            d.achieved
                .get(super::achieved::Quantity::LinfGamma)
                .unwrap_or(f64::INFINITY)
        };
        let grid: Vec<f64> = (0..13).map(|k| 10f64.powf(-4.0 + 0.4 * k as f64)).collect();
        let mut results: Vec<(f64, Option<Design>)> = Vec::new();
        for &phi in &grid {
            let d = eval(self, phi)?;
            results.push((phi, d));
        }
        let best_k = results
            .iter()
            .enumerate()
            .filter_map(|(k, (_, d))| d.as_ref().map(|d| (k, key(d))))
            .min_by(|x, y| x.1.total_cmp(&y.1))
            .map(|(k, _)| k);
        let Some(best_k) = best_k else {
            return Ok(None);
        };
        let (mut a, mut b) = (
            grid[best_k.saturating_sub(1)].ln(),
            grid[(best_k + 1).min(grid.len() - 1)].ln(),
        );
        let mut best = results.swap_remove(best_k).1;
        let gr = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..12 {
            let c = b - gr * (b - a);
            let d = a + gr * (b - a);
            let fc = eval(self, c.exp())?;
            let fd = eval(self, d.exp())?;
            let (kc, kd) = (
                fc.as_ref().map_or(f64::INFINITY, key),
                fd.as_ref().map_or(f64::INFINITY, key),
            );
            for cand in [fc, fd].into_iter().flatten() {
                if best.as_ref().is_none_or(|bd| key(&cand) < key(bd)) {
                    best = Some(cand);
                }
            }
            if kc < kd {
                b = d;
            } else {
                a = c;
            }
        }
        Ok(best.map(|mut d| {
            d.notes.push(format!(
                "L-inf phi chosen by line search over [1e-4, 1e1]: phi = {:.6}",
                d.achieved
                    .get(super::achieved::Quantity::LinfPhi)
                    .unwrap_or(f64::NAN)
            ));
            d
        }))
    }
}
