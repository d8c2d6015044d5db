//! H-inf gain (bounded-real lemma): ||y||_2 < gamma ||w||_2 with the block
//! [[Upsilon_ij, D_i, (C X + E M_j)'], [*, -gamma^2 I, G'], [*, *, -I]] < 0.

use crate::model::TsModel;
use crate::synth::achieved::{Achieved, Quantity};
use crate::synth::blocks::{scalar_times_identity, Channel};
use crate::synth::objective::{bound_value, scalar, Bound, BuildError, Ctx, Lmis, Objective};
use crate::synth::reduction::Values;
use crate::synth::relaxation::Family;
use tsf_lang::spec::ObjectiveKind;
use tsf_lmi::{Expr, Relation};

/// The variable gamma^2 when it is not fixed.
const G: &str = "g";

/// H-inf gain from a disturbance to an output.
#[derive(Debug, Clone, PartialEq)]
pub struct Hinf {
    /// Disturbance index.
    pub from: usize,
    /// Output index.
    pub to: usize,
    /// gamma (fixed) or minimized.
    pub target: Bound,
}

impl Objective for Hinf {
    fn kind(&self) -> ObjectiveKind {
        ObjectiveKind::Hinf
    }

    fn target(&self) -> Option<Bound> {
        Some(self.target)
    }

    fn set_target(&mut self, target: Bound) {
        self.target = target;
    }

    fn headline(&self) -> Option<Quantity> {
        Some(Quantity::HinfGamma)
    }

    fn implies_stability(&self) -> bool {
        true
    }

    fn supports_sector(&self) -> bool {
        false
    }

    fn declare(&self, _model: &TsModel, lmis: &mut Lmis<'_>) -> Result<(), BuildError> {
        if !matches!(self.target, Bound::Fixed(_)) {
            lmis.scalar(G)?;
        }
        Ok(())
    }

    fn impose(&self, ctx: &Ctx<'_>, lmis: &mut Lmis<'_>) -> Result<(), BuildError> {
        let model = ctx.model;
        let ch = Channel::new(model, self.from, self.to);
        let (q, p) = (ch.q(), ch.c.nrows());
        let g = lmis.var(G);
        let g_fixed = match self.target {
            Bound::Fixed(gamma) => gamma * gamma,
            _ => 0.0,
        };
        let fam = Family {
            name: "hinf".into(),
            q: Box::new(|i, j| {
                Expr::sym_blocks(vec![
                    vec![
                        Some(ctx.upsilon(i, j, 0.0)?),
                        Some(Expr::constant(&ch.d[i])?),
                        Some(ch.output_map(ctx.x, &ctx.m[j], model.n)?.transpose()),
                    ],
                    vec![
                        None,
                        Some(scalar_times_identity(g, g_fixed, q)?.scale(-1.0)?),
                        Some(Expr::constant(&ch.g.transpose())?),
                    ],
                    vec![None, None, Some(Expr::identity(p).scale(-1.0)?)],
                ])
            }),
        };
        lmis.impose(&fam)?;
        if let Some(g) = g {
            lmis.problem
                .add_scalar("g >= 0", Expr::var(g), Relation::Ge, 0.0)?;
            if self.target == Bound::Minimize {
                lmis.problem.minimize(Expr::var(g))?;
            }
        }
        Ok(())
    }

    fn achieved(&self, values: &Values, out: &mut Achieved) {
        let gamma = bound_value(self.target, || {
            scalar(values, G).unwrap_or(f64::NAN).max(0.0).sqrt()
        });
        out.set(Quantity::HinfGamma, gamma);
    }
}
