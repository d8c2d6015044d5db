//! Peak-to-peak (L-inf) gain for a fixed phi > 0:
//! [[Upsilon_ij + phi X, (sector), D_i], [*, (-2S), 0], [*, *, -xi I]] < 0 and
//! [[phi X, 0, (C X + E M_j)'], [*, (gamma - xi) I, G'], [*, *, gamma I]] > 0
//! give ||y||_inf < gamma ||w||_inf (Xu & Huang, *Event-triggered L-inf
//! control for T-S fuzzy systems with actuator saturation*, 2020, and
//! Abedor, Nagpal & Poolla, 1996).

use crate::model::TsModel;
use crate::synth::achieved::{Achieved, Quantity};
use crate::synth::blocks::{scalar_times_identity, Channel};
use crate::synth::objective::{
    bound_value, declare_model_error, model_error_multipliers, scalar, Bound, BuildError, Ctx,
    Lmis, Objective,
};
use crate::synth::reduction::Values;
use crate::synth::relaxation::Family;
use crate::synth::solved::names;
use tsf_lang::spec::ObjectiveKind;
use tsf_lmi::{Expr, Relation};

/// The variable gamma when it is not fixed.
const GAMMA: &str = "gamma";
/// The variable xi when the spec leaves it free.
const XI: &str = "xi";

/// Peak-to-peak gain.
#[derive(Debug, Clone, PartialEq)]
pub struct Linf {
    /// Disturbance index.
    pub from: usize,
    /// Output index.
    pub to: usize,
    /// gamma (fixed) or minimized.
    pub target: Bound,
    /// phi > 0 (a line search moves it unless the spec fixes it).
    pub phi: f64,
    /// Whether the spec fixes phi.
    pub phi_fixed: bool,
    /// xi fixed by the spec, or a variable.
    pub xi: Option<f64>,
    /// With a variable xi: the bound xi <= xi_bar the linear-region level is
    /// computed with (set by the level iteration of the search).
    pub xi_bound: Option<f64>,
    /// Minimize xi instead of gamma (the first stage of the xi-level search).
    pub minimize_xi: bool,
}

/// The level V = x'Px stays below from rest under ||w(t)|| <= tau when
/// V' <= -phi V + xi w'w: xi tau^2 / phi. From V(0) = v0 the bound is
/// e^{-phi t} v0 + (1 - e^{-phi t}) xi tau^2 / phi <= max(v0, xi tau^2 / phi),
/// so a region that must also hold the initial set E(P, 1) needs the larger of
/// 1 and this level (Xu & Huang (19)/(40) use the sum 1 + xi tau^2 / phi).
pub fn reach_level(xi: f64, tau: f64, phi: f64) -> f64 {
    xi * tau * tau / phi
}

impl Linf {
    /// The level the state reaches from rest under a disturbance bounded by
    /// `tau` ([`reach_level`]), with xi's bound when xi is a variable (the
    /// level grows with xi, so the bound's is sound); `None` when xi is free
    /// and unbounded.
    pub fn reach_level(&self, tau: f64) -> Option<f64> {
        self.xi
            .or(self.xi_bound)
            .map(|xi| reach_level(xi, tau, self.phi))
    }
}

impl Objective for Linf {
    fn peak_bound(&self) -> Option<&Linf> {
        Some(self)
    }

    fn peak_bound_mut(&mut self) -> Option<&mut Linf> {
        Some(self)
    }

    fn kind(&self) -> ObjectiveKind {
        ObjectiveKind::Linf
    }

    fn target(&self) -> Option<Bound> {
        Some(self.target)
    }

    fn set_target(&mut self, target: Bound) {
        self.target = target;
    }

    fn headline(&self) -> Option<Quantity> {
        Some(Quantity::LinfGamma)
    }

    fn implies_stability(&self) -> bool {
        true
    }

    /// From rest V stays below xi tau^2 / phi under ||w|| <= tau: a fixed xi
    /// (or a bound on it) is needed to know that level.
    fn reach_level(&self, tau: f64) -> Option<Result<f64, BuildError>> {
        Some(match Linf::reach_level(self, tau) {
            Some(f) => Ok(f),
            None => Err(BuildError::Unsupported("the saturation region with a bounded disturbance needs a fixed xi: write `objective linf(...) ... with xi = ...`".into())),
        })
    }

    fn declare(&self, model: &TsModel, lmis: &mut Lmis<'_>) -> Result<(), BuildError> {
        if !matches!(self.target, Bound::Fixed(_)) {
            lmis.scalar(GAMMA)?;
        }
        if self.xi.is_none() {
            lmis.scalar(XI)?;
        }
        declare_model_error(model, lmis, names::MODEL_ERROR_LINF, true)?;
        Ok(())
    }

    fn impose(&self, ctx: &Ctx<'_>, lmis: &mut Lmis<'_>) -> Result<(), BuildError> {
        let (model, n) = (ctx.model, ctx.model.n);
        let ch = Channel::new(model, self.from, self.to);
        let (q, p) = (ch.q(), ch.c.nrows());
        let (gamma, xi) = (lmis.var(GAMMA), lmis.var(XI));
        let xi_fixed = self.xi.unwrap_or(0.0);
        let gamma_fixed = match self.target {
            Bound::Fixed(g) => g,
            _ => 0.0,
        };
        let phi = self.phi;
        // With a model error: one Petersen multiplier for the decrease block
        // (the output-peak block has no A, B), the disturbance rows after
        // the state's (and the dead zone's).
        let robust = model_error_multipliers(lmis, names::MODEL_ERROR_LINF);
        let w_rows = n + ctx.sector.as_ref().map_or(0, |_| model.m);
        let fam = Family {
            name: if ctx.model_error.is_some() {
                "robust linf".into()
            } else {
                "linf".into()
            },
            q: Box::new(|i, j| {
                let w = (
                    Expr::constant(&ch.d[i])?,
                    scalar_times_identity(xi, xi_fixed, q)?.scale(-1.0)?,
                );
                let block = ctx.with_sector(i, j, ctx.upsilon(i, j, phi)?, Some(w))?;
                ctx.with_model_error_by(&robust, j, block, Some(w_rows))
            }),
        };
        lmis.impose(&fam)?;
        // Output peak, for every controller rule j.
        let gi = |k| scalar_times_identity(gamma, gamma_fixed, k);
        for j in 0..model.r() {
            let e = Expr::sym_blocks(vec![
                vec![
                    Some(Expr::var(ctx.x).scale(phi)?),
                    None,
                    Some(ch.output_map(ctx.x, &ctx.m[j], n)?.transpose()),
                ],
                vec![
                    None,
                    Some(gi(q)?.sub(scalar_times_identity(xi, xi_fixed, q)?)?),
                    Some(Expr::constant(&ch.g.transpose())?),
                ],
                vec![None, None, Some(gi(p)?)],
            ])?;
            lmis.strict(&format!("linf peak [{}]", j + 1), e)?;
        }
        if let Some(xi) = xi {
            let eps = lmis.eps;
            lmis.problem
                .add_scalar("xi > 0", Expr::var(xi), Relation::Ge, eps)?;
            if let Some(bound) = self.xi_bound {
                lmis.problem.add_scalar(
                    "xi < xi_bar (linear-region level)",
                    Expr::var(xi),
                    Relation::Le,
                    bound - eps,
                )?;
            }
        }
        match (gamma, xi, self.target) {
            (_, Some(xi), _) if self.minimize_xi => lmis.problem.minimize(Expr::var(xi))?,
            (Some(g), _, Bound::Minimize) => lmis.problem.minimize(Expr::var(g))?,
            _ => {}
        }
        Ok(())
    }

    fn achieved(&self, values: &Values, out: &mut Achieved) {
        let gamma = bound_value(self.target, || scalar(values, GAMMA).unwrap_or(f64::NAN));
        out.set(Quantity::LinfGamma, gamma);
        out.set(Quantity::LinfPhi, self.phi);
        if let Some(xi) = self.xi.or_else(|| scalar(values, XI)) {
            out.set(Quantity::LinfXi, xi);
        }
    }
}
