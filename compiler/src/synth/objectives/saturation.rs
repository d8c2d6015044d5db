//! Actuator saturation by the generalized sector condition (Tarbouriech,
//! Garcia, Gomes da Silva & Queinnec, *Stability and Stabilization of Linear
//! Systems with Saturating Actuators*, 2011): S = T^{-1} diagonal and
//! Z_j = G_j X add the dead-zone column to the decay and L-inf blocks; the
//! region E(P, c) lies where |(F_j - G_j)_k x| <= u_bar_k, so it is a
//! certified region of attraction (c from [`Saturation::level`]).

use crate::model::TsModel;
use crate::synth::blocks::{region_block, row_selector, var_row};
use crate::synth::objective::{BuildError, Ctx, Lmis, Objective, PlanView, Sector};
use crate::synth::solved::names;
use nalgebra::DMatrix;
use tsf_lang::spec::{InitialSet, ObjectiveKind};
use tsf_lmi::Expr;

/// Actuator saturation: levels and the disturbance bound that shrinks them.
#[derive(Debug, Clone, PartialEq)]
pub struct Saturation {
    /// u_bar_s per channel.
    pub levels: Vec<f64>,
    /// Bound on ||w(t)||, if declared.
    pub disturbance_bound: Option<f64>,
    /// Initial states the region E(P, 1) must contain.
    pub contain: Option<InitialSet>,
    /// Implied by declared `saturate` levels, not asked for by an objective.
    pub implied: bool,
}

impl Saturation {
    /// The level c of the certified region E(P, c) the linear region must
    /// hold: with a bounded disturbance and an objective that bounds the level
    /// reached from rest (L-inf: xi tau^2 / phi), the larger of that level and
    /// 1 (V <= max(V(0), reach) from V(0) <= 1: E(P, 1) is a region of
    /// attraction under the disturbance); otherwise 1 (a normalization of P).
    /// E(P, 1) also bounds the gains tsfc designs: with the reach level alone
    /// a matched disturbance's L-inf gain tends to 0 with unbounded gains
    /// (measured on Xu & Huang: gamma 0.001 after 20 SDPs). The sampled and
    /// event-triggered certificates of fixed gains use the reach level alone
    /// ([`crate::synth::TriggerPlan::region_level`]).
    pub fn level(&self, plan: &dyn PlanView) -> Result<f64, BuildError> {
        let reach = match self.disturbance_bound {
            Some(tau) => plan.reach_level(tau)?,
            None => None,
        };
        Ok(reach.map_or(1.0, |c| c.max(1.0)))
    }
}

impl Objective for Saturation {
    fn saturation_region(&self) -> Option<&Saturation> {
        Some(self)
    }

    fn saturation_region_mut(&mut self) -> Option<&mut Saturation> {
        Some(self)
    }

    fn kind(&self) -> ObjectiveKind {
        ObjectiveKind::SaturationRegion
    }

    fn declare(&self, model: &TsModel, lmis: &mut Lmis<'_>) -> Result<(), BuildError> {
        let (m, n) = (model.m, model.n);
        let s = lmis.problem.diagonal("S", m)?;
        let z = (0..model.r())
            .map(|j| lmis.problem.full(&names::sector_product(j), m, n))
            .collect::<Result<Vec<_>, _>>()?;
        lmis.sector = Some(Sector { s, z });
        Ok(())
    }

    fn impose(&self, ctx: &Ctx<'_>, lmis: &mut Lmis<'_>) -> Result<(), BuildError> {
        let (m, n) = (ctx.model.m, ctx.model.n);
        let Some(sector) = &ctx.sector else {
            return Err(BuildError::Unsupported(
                "internal error: saturation variables were not declared".into(),
            ));
        };
        if let Some(kind) = ctx.plan.without_sector() {
            let why = if self.implied {
                "the declared `saturate` levels must be inside the certificate, by the saturation region or an input bound below the levels; the saturation region"
            } else {
                "the saturation region"
            };
            return Err(BuildError::Unsupported(format!("{why} is supported with stability, decay rate, H-inf and L-inf objectives, not with {kind}: add `objective input_norm(u) <= <level> for x0 = ...` or remove {kind}")));
        }
        lmis.strict("S > 0", Expr::var(sector.s))?;
        if let Some(init) = &self.contain {
            lmis.contain(ctx.x, init, "region of attraction")?;
        }
        let shrink = self.level(ctx.plan)?;
        for (j, (mj, &zj)) in ctx.m.iter().zip(&sector.z).enumerate() {
            for (k, level) in self.levels.iter().enumerate() {
                let row = mj
                    .times(&row_selector(k, m), ctx.x, n)?
                    .sub(var_row(zj, k, m, n)?)?;
                let rhs = Expr::constant(&DMatrix::from_element(1, 1, level * level / shrink))?;
                lmis.nonstrict(
                    &format!("linear region [{},{}]", j + 1, k + 1),
                    region_block(Expr::var(ctx.x), row, rhs)?,
                )?;
            }
        }
        Ok(())
    }
}
