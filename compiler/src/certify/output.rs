//! The output-feedback part of the certificate. An observer-based design:
//! the observer LMIs rebuilt with N_i = P2 L_i from the shipped L_i, and the
//! augmented (x, e) conditions rebuilt with the shipped F_j and L_i at the
//! solved P1, Pe (and relaxation slacks), or the bounded certificate's
//! conditions (input bound, saturation region) at the solved X, S, Z_j; also
//! with the gains and levels as stored. A static output-feedback design:
//! the core conditions already hold at M_j = K_j C X (synth/observer/
//! static_output.rs); here the shipped state-feedback gains are checked to
//! be exactly K_j C.

use super::{margins_of, LmiMargin};
use crate::model::TsModel;
use crate::synth::loops::Rounding;
use crate::synth::observer::{
    augmented, bounded, gains, ObserverDesign, OutputFeedback, StaticOutputDesign,
};
use crate::synth::{Design, SynthError};
use nalgebra::DMatrix;

/// Margins of the output-feedback conditions of `design` (none for state
/// feedback). With `stored` (the gains F_j as stored and the rounding of
/// every stored value) the observer's conditions are rebuilt with the
/// stored F_j, L_i and saturation levels; Lyapunov matrices, multipliers and
/// sector gains keep their solved values.
pub(super) fn margins(
    model: &TsModel,
    design: &Design,
    stored: Option<(&[DMatrix<f64>], Rounding<'_>)>,
) -> Result<Vec<LmiMargin>, SynthError> {
    match &design.output {
        None => Ok(Vec::new()),
        Some(OutputFeedback::Observer(o)) => observer(model, design, o, stored),
        Some(OutputFeedback::StaticOutput(s)) => Ok(vec![static_output(design, s)]),
    }
}

fn internal(e: impl std::fmt::Display) -> SynthError {
    SynthError::Internal(format!("internal error: {e}"))
}

fn observer(
    model: &TsModel,
    design: &Design,
    o: &ObserverDesign,
    stored: Option<(&[DMatrix<f64>], Rounding<'_>)>,
) -> Result<Vec<LmiMargin>, SynthError> {
    let round = |m: &DMatrix<f64>| match stored {
        Some((_, r)) => m.map(r),
        None => m.clone(),
    };
    let f: &[DMatrix<f64>] = stored.map_or(&design.gains, |(g, _)| g);
    let l: Vec<DMatrix<f64>> = o.gains.iter().map(round).collect();
    let built = gains::problem(model, &o.c, o.decay, design.eps, false).map_err(internal)?;
    let mut values = vec![(gains::P2.to_string(), o.p2.clone())];
    values.extend(
        l.iter()
            .enumerate()
            .map(|(i, l)| (gains::product(i), &o.p2 * l)),
    );
    let mut lmis = margins_of(&built.problem, &built.nonstrict, &values, &[], &|_| {})?;
    let aug = &o.augmented;
    let (problem, nonstrict) = match &aug.bounded {
        None => {
            let b =
                augmented::problem(model, f, &l, &o.c, aug.alpha, design.eps).map_err(internal)?;
            (b.problem, b.nonstrict)
        }
        Some(b) => {
            let mut bounds = b.bounds.clone();
            if let (Some(s), Some((_, r))) = (&mut bounds.saturation, stored) {
                s.levels = s.levels.iter().map(|v| r(*v)).collect();
            }
            let b = bounded::problem(model, (f, &l), &o.c, aug.alpha, &bounds, design.eps)
                .map_err(internal)?;
            (b.problem, b.nonstrict)
        }
    };
    lmis.extend(margins_of(
        &problem,
        &nonstrict,
        &aug.values,
        &aug.reductions,
        &|_| {},
    )?);
    Ok(lmis)
}

/// The name of the entry that checks F_j = K_j C.
pub const STATIC_OUTPUT_GAINS: &str = "static output: F_j = K_j C bit for bit";

fn static_output(design: &Design, s: &StaticOutputDesign) -> LmiMargin {
    let same = s.gains.len() == design.gains.len()
        && s.gains.iter().zip(&design.gains).all(|(k, f)| {
            let kc: DMatrix<f64> = k * &s.c;
            kc.shape() == f.shape()
                && kc
                    .iter()
                    .zip(f.iter())
                    .all(|(a, b)| a.to_bits() == b.to_bits())
        });
    LmiMargin {
        name: STATIC_OUTPUT_GAINS.into(),
        margin: if same { 0.0 } else { -1.0 },
        error_bound: 0.0,
        strict: false,
        size: 1,
        ok: same,
    }
}
