//! The tables of a static-output-feedback design (`control static_output;`):
//! the PDC controller on the measured output, u = sat(sum_j h_j(z) K_j y).
//!
//! The certified loop is A_i + B_i K_j C (the state-feedback conditions hold
//! for F_j = K_j C, `synth/observer/static_output.rs`). Its generated step
//! is the runtime's PDC step with the state replaced by y: the "state" of
//! the tables is y (q components, named after the `measure` rows), the
//! gains are the K_j (m x q), and the premises, which the checker requires
//! to be functions of measured states, are rewritten on y through
//! S = C' (C C')^-1 (the measured components put back in their places:
//! x_k becomes sum_l S_kl y_l). So the generated code, the simulator and
//! the runtime share the controller step and its fault handling, and the
//! existing Rust/C conformance covers it.

use super::sym::Sym;
use super::{PremiseCode, Tables, TablesError};
use crate::synth::observer::{OutputFeedback, StaticOutputDesign};
use crate::synth::Design;
use crate::util::matrix::rows;
use nalgebra::DMatrix;

/// What generated code and the simulator need of a static-output design
/// beyond the controller on y.
#[derive(Debug, Clone, PartialEq)]
pub struct StaticOutputTables {
    /// The plant's state count n (the controller reads q = `c.len()` outputs).
    pub n: usize,
    /// The measured output y = C x (q rows of n).
    pub c: Vec<Vec<f64>>,
    /// The plant's state names (the tables' `state_names` are y's).
    pub state_names: Vec<String>,
}

/// `x_k` as a function of y: `sum_l S_kl y_l` (zero coefficients left out;
/// a coefficient 1 is the component itself).
fn state_of_y(s: &DMatrix<f64>, k: usize) -> Sym {
    let mut out: Option<Sym> = None;
    for l in 0..s.ncols() {
        let v = s[(k, l)];
        if v == 0.0 {
            continue;
        }
        let term = if v == 1.0 {
            Sym::X(l)
        } else {
            Sym::Mul(Box::new(Sym::Const(v)), Box::new(Sym::X(l)))
        };
        out = Some(match out {
            None => term,
            Some(acc) => Sym::Add(Box::new(acc), Box::new(term)),
        });
    }
    out.unwrap_or(Sym::Const(0.0))
}

/// `e` with every state component replaced by its expression in y.
fn on_y(e: &Sym, s: &DMatrix<f64>) -> Sym {
    let go = |a: &Sym| Box::new(on_y(a, s));
    match e {
        Sym::Const(v) => Sym::Const(*v),
        Sym::X(k) => state_of_y(s, *k),
        Sym::Add(a, b) => Sym::Add(go(a), go(b)),
        Sym::Mul(a, b) => Sym::Mul(go(a), go(b)),
        Sym::Div(a, b) => Sym::Div(go(a), go(b)),
        Sym::Neg(a) => Sym::Neg(go(a)),
        Sym::Call(f, a) => Sym::Call(*f, go(a)),
    }
}

/// The premise code on y: a linear map L becomes L S, expressions are
/// rewritten on y.
fn premises_on_y(premise: &PremiseCode, s: &DMatrix<f64>) -> PremiseCode {
    match premise {
        PremiseCode::Linear(l) => PremiseCode::Linear(
            l.iter()
                .map(|row| {
                    (0..s.ncols())
                        .map(|c| row.iter().enumerate().map(|(k, v)| v * s[(k, c)]).sum())
                        .collect()
                })
                .collect(),
        ),
        PremiseCode::Exprs(e) => PremiseCode::Exprs(e.iter().map(|x| on_y(x, s)).collect()),
    }
}

/// The design's static output feedback, if it is one.
fn design_of(design: &Design) -> Option<&StaticOutputDesign> {
    match &design.output {
        Some(OutputFeedback::StaticOutput(s)) => Some(s),
        _ => None,
    }
}

/// `t` (a static-output design's state-feedback tables) turned into the
/// controller on y; other designs' tables are returned as they are.
pub fn on_output(mut t: Tables, design: &Design) -> Result<Tables, TablesError> {
    let Some(sof) = design_of(design) else {
        return Ok(t);
    };
    let s = sof.premise_from_y.as_ref().ok_or_else(|| {
        TablesError::ObserverShape(
            "the premises of a static output-feedback controller must be read from y".into(),
        )
    })?;
    let q = sof.c.nrows();
    if sof.gains.len() != t.r || sof.gains.iter().any(|k| k.shape() != (t.m, q)) {
        return Err(TablesError::ObserverShape(format!(
            "{} gains K_j for {} rules, each {}x{q} expected",
            sof.gains.len(),
            t.r,
            t.m
        )));
    }
    t.static_output = Some(StaticOutputTables {
        n: t.n,
        c: rows(&sof.c),
        state_names: std::mem::take(&mut t.state_names),
    });
    t.premise = premises_on_y(&t.premise, s);
    t.gains = sof.gains.iter().map(rows).collect();
    t.state_names = sof.output_names.clone();
    t.n = q;
    t.header.reads = Some(format!(
        "Static output feedback: the step reads the measured output y = C x ({q} component{}: {}), not the state; u = sat(sum_j h_j K_j y), certified as the loop A_i + B_i K_j C.",
        if q == 1 { "" } else { "s" },
        sof.output_names.join(", ")
    ));
    Ok(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn premises_are_rewritten_on_y() {
        // x = S y with S = [1, 0; 0, 0; 0, 2]: x0 = y0, x1 = 0, x2 = 2 y1.
        let s = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 0.0, 0.0, 0.0, 2.0]);
        let lin = premises_on_y(&PremiseCode::Linear(vec![vec![1.0, 5.0, 3.0]]), &s);
        assert_eq!(lin, PremiseCode::Linear(vec![vec![1.0, 6.0]]));
        let e = Sym::Call(
            super::super::sym::Func::Sin,
            Box::new(Sym::Add(Box::new(Sym::X(0)), Box::new(Sym::X(2)))),
        );
        let PremiseCode::Exprs(on) = premises_on_y(&PremiseCode::Exprs(vec![e]), &s) else {
            panic!("expressions stay expressions") // ok: unit test
        };
        assert_eq!(on[0].eval(&[0.25, 0.5]), (0.25f64 + 1.0).sin());
    }
}
