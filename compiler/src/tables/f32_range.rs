//! The last line of defence of `precision f32`: every number the tables
//! store must be a finite f32 (infinite saturation levels, "no limit", are
//! written as the type's infinity and pass). The checker refuses the numbers a
//! spec gives with their spans (`tsf_lang::check::precision`); this catches
//! the derived ones (premise maps and constants, rule centres, synthesized
//! gains and weights) before a generator would print infinity or panic.

use super::sym::Sym;
use super::{PremiseCode, Tables, TablesError};
use crate::model::TermSpec;
use tsf_lang::spec::{Precision, SetShape};

/// `t` if every stored number fits its precision.
pub(super) fn checked(t: Tables) -> Result<Tables, TablesError> {
    if t.precision == Precision::F32 {
        if let Some((what, value)) = first_outside(&t) {
            return Err(TablesError::F32Range { what, value });
        }
    }
    Ok(t)
}

/// Whether `v` is stored as a finite f32 (or is infinite on purpose).
fn fits(v: f64) -> bool {
    v.is_infinite() || (v as f32).is_finite()
}

/// The constants of a premise expression.
fn sym_consts(s: &Sym, out: &mut Vec<f64>) {
    match s {
        Sym::Const(v) => out.push(*v),
        Sym::X(_) => {}
        Sym::Add(a, b) | Sym::Mul(a, b) | Sym::Div(a, b) => {
            sym_consts(a, out);
            sym_consts(b, out);
        }
        Sym::Neg(a) | Sym::Call(_, a) => sym_consts(a, out),
    }
}

/// The first table entry that does not fit an f32: what it is, its value.
fn first_outside(t: &Tables) -> Option<(String, f64)> {
    let mut groups: Vec<(&str, Vec<f64>)> = Vec::new();
    let mut premise = Vec::new();
    match &t.premise {
        PremiseCode::Linear(rows) => premise.extend(rows.iter().flatten()),
        PremiseCode::Exprs(e) => e.iter().for_each(|s| sym_consts(s, &mut premise)),
    }
    groups.push(("a coefficient of the premise map", premise));
    let terms = t.terms.iter().flatten().flat_map(|term| match term {
        TermSpec::Is { set, .. } => match *set {
            SetShape::Tri(a, b, c) => vec![a, b, c],
            SetShape::Trap(a, b, c, d) => vec![a, b, c, d],
            SetShape::Gauss(a, b) | SetShape::Sigmoid(a, b) => vec![a, b],
        },
        TermSpec::About { point, sigma, .. } => [point.as_slice(), &[*sigma]].concat(),
    });
    groups.push(("a membership parameter", terms.collect()));
    groups.push((
        "a rule centre",
        t.centres.iter().flatten().copied().collect(),
    ));
    groups.push((
        "a gain entry",
        t.gains.iter().flatten().flatten().copied().collect(),
    ));
    let modes = t
        .modes
        .iter()
        .flat_map(|m| m.gains.iter().flatten().flatten());
    groups.push(("a mode's gain entry", modes.flatten().copied().collect()));
    groups.push(("a saturation level", t.u_max.clone()));
    if let Some(s) = t.sensor.aperiodic() {
        let mut v = vec![s.h_min, s.h_max, s.nu_min, s.nu_max];
        v.extend(s.weight.iter().flatten());
        if let super::SensorLaw::Adaptive(a, b, c) = s.law {
            v.extend([a, b, c]);
        }
        groups.push(("a value of the sensor's trigger", v));
    }
    if let Some(s) = t.sensor.mixed() {
        let mut v = vec![s.beta, s.rho];
        s.exprs.iter().for_each(|e| sym_consts(e, &mut v));
        groups.push(("a value of the mixed trigger", v));
    }
    groups.into_iter().find_map(|(what, v)| {
        v.into_iter()
            .find(|x| !fits(*x))
            .map(|x| (what.to_string(), x))
    })
}
