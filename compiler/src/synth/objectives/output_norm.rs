//! Output-norm bound: ||y(t)|| <= lambda for every x0 in the initial set, from
//! [X, X C'; C X, lambda^2 I] >= 0 and the initial set inside E(P, 1).

use crate::model::TsModel;
use crate::synth::achieved::{Achieved, Quantity};
use crate::synth::blocks::scalar_times_identity;
use crate::synth::objective::{bound_value, scalar, Bound, BuildError, Ctx, Lmis, Objective};
use crate::synth::reduction::Values;
use nalgebra::DMatrix;
use tsf_lang::spec::{InitialSet, ObjectiveKind};
use tsf_lmi::Expr;

/// The variable lambda^2 when it is not fixed.
const LAMBDA2: &str = "lambda2";

/// Output-norm bound ||y(t)|| <= lambda.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputNorm {
    /// Output index.
    pub output: usize,
    /// lambda (fixed) or minimized.
    pub target: Bound,
    /// The initial set.
    pub initial: InitialSet,
}

impl Objective for OutputNorm {
    fn kind(&self) -> ObjectiveKind {
        ObjectiveKind::OutputNorm
    }

    fn target(&self) -> Option<Bound> {
        Some(self.target)
    }

    fn set_target(&mut self, target: Bound) {
        self.target = target;
    }

    fn headline(&self) -> Option<Quantity> {
        Some(Quantity::OutputNormBound)
    }

    fn declare(&self, _model: &TsModel, lmis: &mut Lmis<'_>) -> Result<(), BuildError> {
        if !matches!(self.target, Bound::Fixed(_)) {
            lmis.scalar(LAMBDA2)?;
        }
        Ok(())
    }

    fn impose(&self, ctx: &Ctx<'_>, lmis: &mut Lmis<'_>) -> Result<(), BuildError> {
        let n = ctx.model.n;
        let out = &ctx.model.spec.outputs[self.output];
        lmis.contain(ctx.x, &self.initial, "output norm")?;
        let s = lmis.var(LAMBDA2);
        let fixed = match self.target {
            Bound::Fixed(l) => l * l,
            _ => 0.0,
        };
        let cx = Expr::product(&out.c, ctx.x, &DMatrix::identity(n, n))?;
        let e = Expr::sym_blocks(vec![
            vec![Some(Expr::var(ctx.x)), Some(cx.transpose())],
            vec![None, Some(scalar_times_identity(s, fixed, out.c.nrows())?)],
        ])?;
        lmis.nonstrict("output norm", e)?;
        if let (Some(s), Bound::Minimize) = (s, self.target) {
            lmis.problem.minimize(Expr::var(s))?;
        }
        Ok(())
    }

    fn achieved(&self, values: &Values, out: &mut Achieved) {
        let lambda = bound_value(self.target, || {
            scalar(values, LAMBDA2).unwrap_or(f64::NAN).max(0.0).sqrt()
        });
        out.set(Quantity::OutputNormBound, lambda);
    }
}
