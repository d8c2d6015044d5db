//! H-inf gain (bounded-real lemma): ||y||_2 < gamma ||w||_2 with the block
//! [[Upsilon_ij, D_i, (C X + E M_j)'], [*, -gamma^2 I, G'], [*, *, -I]] < 0.
//!
//! Under actuator saturation (the generalized sector condition of
//! [`super::saturation`], dead zone psi = u - sat(u), S = T^{-1}, Z_j = G_j X)
//! the block gains the dead-zone row and column:
//!
//!   [[Upsilon_ij, -B_i S + Z_j', D_i, (C X + E M_j)'],
//!    [*,          -2 S,         0,   -(E S)'        ],
//!    [*,          *,  -gamma^2 I,    G'             ],
//!    [*,          *,           *,    -I             ]] < 0,
//!
//! so V' + y'y - gamma^2 w'w < 0 wherever the sector condition holds (the
//! linear region, which contains E(P, 1)). Hence, with x(0)'P x(0) + gamma^2
//! ||w||_2^2 <= 1, the state stays in E(P, 1) and ||y||_2^2 is below
//! gamma^2 ||w||_2^2 + x(0)'P x(0): a regional L2 gain, for disturbance energies up to
//! (1 - x(0)'P x(0)) / gamma^2 (Tarbouriech, Garcia, Gomes da Silva &
//! Queinnec, *Stability and Stabilization of Linear Systems with Saturating
//! Actuators*, 2011, ch. 6).

use crate::model::TsModel;
use crate::synth::achieved::{Achieved, Quantity};
use crate::synth::blocks::{scalar_times_identity, Channel};
use crate::synth::objective::{
    bound_value, declare_model_error, model_error_multipliers, scalar, Bound, BuildError, Ctx,
    Lmis, Objective, Sector,
};
use crate::synth::reduction::Values;
use crate::synth::relaxation::Family;
use crate::synth::solved::names;
use nalgebra::DMatrix;
use tsf_lang::spec::ObjectiveKind;
use tsf_lmi::LmiError;
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
        true
    }

    fn declare(&self, model: &TsModel, lmis: &mut Lmis<'_>) -> Result<(), BuildError> {
        if !matches!(self.target, Bound::Fixed(_)) {
            lmis.scalar(G)?;
        }
        declare_model_error(model, lmis, names::MODEL_ERROR_HINF, true)?;
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
        // With a model error: one Petersen multiplier for this block, the
        // disturbance rows after the state's (and the dead zone's).
        let robust = model_error_multipliers(lmis, names::MODEL_ERROR_HINF);
        let w_rows = model.n + ctx.sector.as_ref().map_or(0, |_| model.m);
        let fam = Family {
            name: if ctx.model_error.is_some() {
                "robust hinf".into()
            } else {
                "hinf".into()
            },
            q: Box::new(|i, j| {
                let mut rows = vec![
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
                ];
                if let Some(sector) = &ctx.sector {
                    dead_zone(ctx, &ch, sector, (i, j), &mut rows)?;
                }
                ctx.with_model_error_by(&robust, j, Expr::sym_blocks(rows)?, Some(w_rows))
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

/// Inserts the dead-zone row and column (second block row) into the H-inf
/// block of rule pair `(i, j)`: -B_i S + Z_j' against the state, -2 S on the
/// diagonal, 0 against the disturbance and -(E S)' against the output.
fn dead_zone(
    ctx: &Ctx<'_>,
    ch: &Channel,
    sector: &Sector,
    (i, j): (usize, usize),
    rows: &mut Vec<Vec<Option<Expr>>>,
) -> Result<(), LmiError> {
    let m = ctx.model.m;
    let id = DMatrix::identity(m, m);
    let cross = Expr::product(&ctx.model.rules[i].b, sector.s, &id)?
        .scale(-1.0)?
        .add(Expr::var(sector.z[j]).transpose())?;
    let to_output = if ch.e.iter().all(|v| *v == 0.0) {
        None
    } else {
        Some(
            Expr::product(&ch.e, sector.s, &id)?
                .scale(-1.0)?
                .transpose(),
        )
    };
    rows[0].insert(1, Some(cross));
    rows[1].insert(0, None);
    rows[2].insert(0, None);
    rows.insert(
        1,
        vec![
            None,
            Some(Expr::var(sector.s).scale(-2.0)?),
            None,
            to_output,
        ],
    );
    Ok(())
}

/// What an H-inf bound certifies under saturation, as a note: the largest
/// disturbance energy ||w||_2^2 for which the state provably stays in
/// E(P, 1), from x(0) = 0 and from the saturation objective's x0 (if a
/// point). `None` without both objectives.
pub fn regional_note(d: &crate::synth::Design) -> Option<String> {
    let sat = d.plan.saturation()?;
    d.plan.find(ObjectiveKind::Hinf)?;
    let gamma = d.achieved.get(Quantity::HinfGamma)?;
    let g2 = gamma * gamma;
    let from_x0 = match &sat.contain {
        Some(tsf_lang::spec::InitialSet::Point(x0)) => {
            let x = nalgebra::DVector::from_column_slice(x0);
            let v = (x.transpose() * &d.p * &x)[(0, 0)];
            format!(
                ", from x0 (x0'Px0 = {v:.6}): {:.6e}",
                ((1.0 - v) / g2).max(0.0)
            )
        }
        _ => String::new(),
    };
    Some(format!(
        "H-inf under saturation is regional: gamma = {gamma:.6} holds while x'Px <= 1 (inside the linear region of the sector condition), i.e. for disturbance energies ||w||_2^2 <= (1 - x(0)'Px(0)) / gamma^2: from x(0) = 0: {:.6e}{from_x0}",
        1.0 / g2
    ))
}
