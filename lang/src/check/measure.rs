//! Output feedback items: `measure name = C * x [noise <= e];` (a measured
//! output, linear in the state, no feedthrough) and `control kind[(args)];`
//! (`state_feedback`, `observer_based(decay = a)`, `static_output`).

use super::{unknown_choice, Checker, Dims, Draft, Kind};
use crate::ast::{Expr, ExprKind, Ident, IndexArg, Item, NamedArg};
use crate::diag::Diagnostic;
use crate::eval::Mat;
use crate::spec::{Control, ControlKind, Measured, Signal};

/// The controller kinds `control` accepts.
const KINDS: [ControlKind; 3] = [
    ControlKind::StateFeedback,
    ControlKind::ObserverBased,
    ControlKind::StaticOutput,
];

/// Relative tolerance of the row-space tests on C (a state component is
/// measured when its distance to the row space of C is below this).
pub const ROW_SPACE_TOL: f64 = 1e-9;

impl Checker<'_> {
    /// `measure name = expr [noise <= e];`: declared, reduced to its rows of
    /// C (the expression must be linear in the state alone), stacked.
    pub(super) fn measure_item(
        &mut self,
        name: &Ident,
        value: &Expr,
        noise: Option<&Expr>,
        dims: Dims,
        draft: &mut Draft,
    ) {
        if !self.declare(name, Kind::Measured) {
            return;
        }
        let Some(out) = self.output(name, value, dims) else {
            self.poison(name.node.clone());
            return;
        };
        if out.e.iter().chain(out.g.iter()).any(|v| *v != 0.0) {
            self.err(
                Diagnostic::error(value.span, format!("measured output `{}` reads an input or a disturbance", name.node))
                    .with_label("a measurement is y = C x")
                    .with_help("measure states only; a noise bound is written `noise <= e` after the expression"),
            );
            return;
        }
        let noise = match noise {
            Some(e) => match self.positive(e, "the noise bound") {
                Some(v) => Some(v),
                None => return,
            },
            None => None,
        };
        let p = out.c.nrows();
        let names: Vec<String> = if p == 1 {
            vec![name.node.clone()]
        } else {
            (0..p).map(|k| format!("{}[{k}]", name.node)).collect()
        };
        match &mut draft.measure {
            Some(m) => {
                let rows = m.c.nrows();
                let mut c = Mat::zeros(rows + p, dims.n);
                c.rows_mut(0, rows).copy_from(&m.c);
                c.rows_mut(rows, p).copy_from(&out.c);
                m.c = c;
                m.names.extend(names);
                m.noise.extend(std::iter::repeat_n(noise, p));
            }
            None => {
                draft.measure = Some(Measured {
                    c: out.c,
                    names,
                    noise: vec![noise; p],
                    span: name.span,
                })
            }
        }
    }

    /// `control kind[(args)];`: once per spec; `decay = a > 0` only for `observer_based`.
    pub(super) fn control_item(
        &mut self,
        it: &Item,
        kind: &Ident,
        args: &[NamedArg],
        draft: &mut Draft,
    ) {
        let mut seen = draft.control.as_ref().map(|c| c.span);
        if !self.singleton(&mut seen, it.span, "the controller kind (`control`)") {
            return;
        }
        let Some(k) = KINDS.into_iter().find(|k| k.keyword() == kind.node) else {
            let words: Vec<&str> = KINDS.iter().map(|k| k.keyword()).collect();
            self.err(unknown_choice(
                kind.span,
                "controller kind",
                "controller kinds",
                &kind.node,
                &words,
            ));
            return;
        };
        let mut control = Control {
            kind: k,
            observer_decay: None,
            span: it.span,
        };
        for a in args {
            if a.name.node == "decay" && k == ControlKind::ObserverBased {
                match self.positive(&a.value, "the observer decay rate") {
                    Some(v) => control.observer_decay = Some(v),
                    None => return,
                }
            } else {
                let help = if k == ControlKind::ObserverBased {
                    "`observer_based` takes `decay = a` (the observer's decay rate)"
                } else {
                    "only `observer_based(decay = a)` takes an argument"
                };
                self.err(
                    Diagnostic::error(
                        a.name.span,
                        format!(
                            "unknown argument `{}` of `control {}`",
                            a.name.node,
                            k.keyword()
                        ),
                    )
                    .with_help(help),
                );
                return;
            }
        }
        draft.control = Some(control);
    }
}

/// Per state component: whether `e` may read it. A conservative syntactic
/// reading: a state's name (or `x`) reads all its components, `w[k]` with a
/// literal `k` only that one; function bodies see only their parameters and
/// constants, so the arguments of a call are all it reads.
pub(super) fn state_reads(e: &Expr, states: &[Signal], n: usize) -> Vec<bool> {
    let mut reads = vec![false; n];
    mark(e, states, &mut reads);
    reads
}

fn mark(e: &Expr, states: &[Signal], reads: &mut [bool]) {
    let whole = |name: &str, reads: &mut [bool]| {
        if name == "x" {
            reads.iter_mut().for_each(|r| *r = true);
        } else if let Some(s) = states.iter().find(|s| s.name == name) {
            for r in reads.iter_mut().skip(s.offset).take(s.len) {
                *r = true;
            }
        }
    };
    match &e.kind {
        ExprKind::Number(_) => {}
        ExprKind::Name(name) => whole(name, reads),
        ExprKind::Matrix(rows) => rows.iter().flatten().for_each(|x| mark(x, states, reads)),
        ExprKind::Neg(a) | ExprKind::Transpose(a) => mark(a, states, reads),
        ExprKind::Binary(_, a, b) => {
            mark(a, states, reads);
            mark(b, states, reads);
        }
        ExprKind::Index(base, args) => {
            let literal = match (&base.kind, args.as_slice()) {
                (ExprKind::Name(name), [IndexArg::One(i)]) => match i.kind {
                    ExprKind::Number(k) if k >= 0.0 && k.fract() == 0.0 => {
                        let offset = if name == "x" {
                            Some(0)
                        } else {
                            states.iter().find(|s| s.name == *name).map(|s| s.offset)
                        };
                        offset.map(|o| o + k as usize)
                    }
                    _ => None,
                },
                _ => None,
            };
            match literal {
                Some(k) if k < reads.len() => reads[k] = true,
                _ => {
                    mark(base, states, reads);
                    for a in args {
                        match a {
                            IndexArg::Full => {}
                            IndexArg::One(i) => mark(i, states, reads),
                            IndexArg::Range(a, b) => {
                                mark(a, states, reads);
                                mark(b, states, reads);
                            }
                        }
                    }
                }
            }
        }
        ExprKind::Call(_, args) => args.iter().for_each(|a| mark(&a.value, states, reads)),
    }
}

/// Whether the unit vector of state component `k` lies in the row space of
/// `c` (then x_k = (C^+ y)_k for every x): its distance to the row space,
/// relative to 1, is below [`ROW_SPACE_TOL`].
pub(super) fn recovered(c: &Mat, k: usize) -> bool {
    let n = c.ncols();
    let Ok(pinv) = c.clone().pseudo_inverse(ROW_SPACE_TOL * c.norm().max(1.0)) else {
        return false;
    };
    let projector = pinv * c;
    let mut e = Mat::zeros(n, 1);
    e[(k, 0)] = 1.0;
    (&projector * &e - &e).norm() <= 1e3 * ROW_SPACE_TOL
}

/// The numerical rank of `c` (singular values above [`ROW_SPACE_TOL`] times the largest).
pub(super) fn rank(c: &Mat) -> usize {
    let sv = c.clone().svd(false, false).singular_values;
    let top = sv.iter().copied().fold(0.0, f64::max);
    sv.iter()
        .filter(|s| **s > ROW_SPACE_TOL * top.max(1.0))
        .count()
}

#[cfg(test)]
mod tests {
    use crate::check::testing::*;
    use crate::spec::ControlKind;

    const TWO: &str =
        "tsf 1; controller c; state x1, x2; input u; A = [0, 1; -1, 0]; B = [0; 1];\n\
        premise x1 range -1 .. 1 { all = trap(-1, -1, 1, 1); }\n\
        rule R: x1 is all => A = [0, 1; -2, 0];\n";

    #[test]
    fn measurements_stack_into_c_with_names_and_noise() {
        let spec = valid(&format!(
            "{TWO}measure th = x1 noise <= 0.01;\nmeasure v = [x2; x1 + x2];\ncontrol observer_based(decay = 3);\n"
        ));
        let m = spec.measure.expect("measured"); // ok: unit test
        assert_eq!(m.c.nrows(), 3);
        assert_eq!(
            m.c.row(2).iter().copied().collect::<Vec<_>>(),
            vec![1.0, 1.0]
        );
        assert_eq!(m.names, vec!["th", "v[0]", "v[1]"]);
        assert_eq!(m.noise, vec![Some(0.01), None, None]);
        assert_eq!(spec.control.kind, ControlKind::ObserverBased);
        assert_eq!(spec.control.observer_decay, Some(3.0));
    }

    #[test]
    fn the_default_is_state_feedback() {
        let spec = valid(TWO);
        assert_eq!(spec.control.kind, ControlKind::StateFeedback);
        assert!(spec.measure.is_none());
    }

    #[test]
    fn measure_and_control_errors_name_the_cause() {
        let (m, at) = only_error_of(&format!("{TWO}measure y = x1 + u;\n"));
        assert_eq!(m, "measured output `y` reads an input or a disturbance");
        assert_eq!(at, "x1 + u");
        let (m, at) = only_error_of(&format!("{TWO}measure y = x1 * x2;\n"));
        assert!(m.contains("not linear"), "{m}");
        assert_eq!(at, "x1 * x2");
        let (m, at) = only_error_of(&format!("{TWO}measure y = x1;\ncontrol observer;\n"));
        assert_eq!(m, "unknown controller kind `observer`");
        assert_eq!(at, "observer");
        let (m, at) = only_error_of(&format!("{TWO}measure y = x1 noise <= 0;\n"));
        assert_eq!(m, "the noise bound must be positive");
        assert_eq!(at, "0");
    }
}
