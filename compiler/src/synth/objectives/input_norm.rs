//! Input-norm bound: ||u(t)|| <= mu for every x0 in the initial set, from
//! [X, M_j'; M_j, mu^2 I] >= 0 and the initial set inside E(P, 1).

use crate::model::TsModel;
use crate::synth::achieved::{Achieved, Quantity};
use crate::synth::blocks::scalar_times_identity;
use crate::synth::objective::{bound_value, scalar, Bound, BuildError, Ctx, Lmis, Objective};
use crate::synth::reduction::Values;
use tsf_lang::spec::{InitialSet, ObjectiveKind};
use tsf_lmi::Expr;

/// The variable mu^2 when it is not fixed.
const MU2: &str = "mu2";

/// Input-norm bound ||u(t)|| <= mu.
#[derive(Debug, Clone, PartialEq)]
pub struct InputNorm {
    /// mu (fixed) or minimized.
    pub target: Bound,
    /// The initial set.
    pub initial: InitialSet,
}

impl Objective for InputNorm {
    fn kind(&self) -> ObjectiveKind {
        ObjectiveKind::InputNorm
    }

    fn target(&self) -> Option<Bound> {
        Some(self.target)
    }

    fn set_target(&mut self, target: Bound) {
        self.target = target;
    }

    fn headline(&self) -> Option<Quantity> {
        Some(Quantity::InputNormBound)
    }

    fn declare(&self, _model: &TsModel, lmis: &mut Lmis<'_>) -> Result<(), BuildError> {
        if !matches!(self.target, Bound::Fixed(_)) {
            lmis.scalar(MU2)?;
        }
        Ok(())
    }

    fn impose(&self, ctx: &Ctx<'_>, lmis: &mut Lmis<'_>) -> Result<(), BuildError> {
        lmis.contain(ctx.x, &self.initial, "input norm")?;
        let s = lmis.var(MU2);
        let fixed = match self.target {
            Bound::Fixed(mu) => mu * mu,
            _ => 0.0,
        };
        let (m, n) = (ctx.model.m, ctx.model.n);
        for (j, mj) in ctx.m.iter().enumerate() {
            let e = Expr::sym_blocks(vec![
                vec![
                    Some(Expr::var(ctx.x)),
                    Some(mj.expr(ctx.x, m, n)?.transpose()),
                ],
                vec![None, Some(scalar_times_identity(s, fixed, m)?)],
            ])?;
            lmis.nonstrict(&format!("input norm [{}]", j + 1), e)?;
        }
        if let (Some(s), Bound::Minimize) = (s, self.target) {
            lmis.problem.minimize(Expr::var(s))?;
        }
        Ok(())
    }

    fn achieved(&self, values: &Values, out: &mut Achieved) {
        let mu = bound_value(self.target, || {
            scalar(values, MU2).unwrap_or(f64::NAN).max(0.0).sqrt()
        });
        out.set(Quantity::InputNormBound, mu);
    }
}
