//! Premises and state-dependent model matrices must be finite wherever the
//! controller runs: at the origin x = 0 (the usual equilibrium) when it lies
//! in the state region, and at the states of the consistency grid. A premise
//! like `(exp(a + v) - exp(a)) / v` is 0/0 at v = 0: the generated code
//! would return u = 0 with the premise-non-finite flag there, so the model
//! stage refuses it at check time and names the removable-singularity
//! built-ins (`exprel`, `sinc`).

use nalgebra::DMatrix;
use tsf_lang::ast::{BinOp, Expr, ExprKind, IndexArg};
use tsf_lang::eval::Mode;
use tsf_lang::span::Span;
use tsf_lang::spec::{ModelMatrix, Spec};
use tsf_lang::Diagnostic;

/// The help of a 0/0: the removable singularities the language has built in.
const REMOVABLE: &str = "a removable singularity: write it with `exprel` (exprel(v) = (e^v - 1)/v, 1 at 0), e.g. `exp(a) * exprel(v)` for `(exp(a + v) - exp(a)) / v`, or `sinc` for sin(v)/v";

/// What the state box says about the origin: `true` when every component's
/// grid bounds `(lo, hi)` contain 0 (unknown, infinite bounds count as
/// containing it).
pub(super) fn origin_in_box(bounds: &[(f64, f64)]) -> bool {
    bounds
        .iter()
        .all(|&(lo, hi)| !(lo.is_finite() && hi.is_finite()) || (lo <= 0.0 && 0.0 <= hi))
}

/// The first premise or state-dependent matrix (A, B, D) that is not finite
/// (or fails to evaluate) at `x`, as an error; `None` when all are finite or
/// `x` lies outside the premise region (a premise finite there but outside
/// its declared range).
pub(super) fn diagnose_at(spec: &Spec, x: &[f64]) -> Option<Diagnostic> {
    let exact = spec.state_env(x, Mode::Exact);
    let mut bad: Option<(Subject<'_>, Result<DMatrix<f64>, Diagnostic>)> = None;
    for p in &spec.premises {
        let v = exact.eval(&p.expr);
        let comp = |m: &DMatrix<f64>| match p.component {
            Some(k) => m.get(k).copied().into_iter().collect::<Vec<_>>(),
            None => m.iter().copied().collect(),
        };
        match &v {
            Ok(m) if comp(m).iter().all(|z| z.is_finite()) => {
                if let Some((lo, hi)) = p.range {
                    if comp(m).iter().any(|z| *z < lo || *z > hi) {
                        // Outside the premise region: the controller never runs here.
                        return None;
                    }
                }
            }
            _ => {
                if bad.is_none() {
                    bad = Some((Subject::Premise(&p.name, &p.expr), v));
                }
            }
        }
    }
    if bad.is_none() {
        let mats = [("A", &spec.a), ("B", &spec.b), ("D", &spec.d)];
        for (name, m) in mats {
            let Some(m) = m.as_ref().filter(|m| m.state_dependent) else {
                continue;
            };
            let v = exact.eval(&m.expr);
            if !v.as_ref().is_ok_and(|v| v.iter().all(|e| e.is_finite())) {
                bad = Some((Subject::Matrix(name, m), v));
                break;
            }
        }
    }
    let (subject, v) = bad?;
    Some(describe(spec, x, subject, v))
}

/// What is not finite.
#[derive(Clone, Copy)]
enum Subject<'s> {
    /// A premise: its name and expression.
    Premise(&'s str, &'s Expr),
    /// `A`, `B` or `D` and its definition.
    Matrix(&'static str, &'s ModelMatrix),
}

impl Subject<'_> {
    fn expr(&self) -> &Expr {
        match self {
            Subject::Premise(_, e) => e,
            Subject::Matrix(_, m) => &m.expr,
        }
    }
}

/// `x = 0`, or `x = [..]` with four decimals.
fn point(x: &[f64]) -> String {
    if x.iter().all(|v| *v == 0.0) {
        "x = 0".into()
    } else {
        let v: Vec<String> = x.iter().map(|v| format!("{v:.4}")).collect();
        format!("x = [{}]", v.join(", "))
    }
}

fn describe(
    spec: &Spec,
    x: &[f64],
    subject: Subject<'_>,
    exact: Result<DMatrix<f64>, Diagnostic>,
) -> Diagnostic {
    // IEEE values (0/0 = NaN, c/0 = inf) from the shape-mode evaluator, which
    // does not stop at a division by zero.
    let ieee = spec.state_env(x, Mode::Shapes).eval(subject.expr()).ok();
    let nan = ieee.as_ref().is_some_and(|m| m.iter().any(|v| v.is_nan()));
    let at = point(x);
    let (what, entry) = match subject {
        Subject::Premise(name, _) => (format!("premise `{name}`"), None),
        Subject::Matrix(name, m) => {
            let bad = ieee.as_ref().and_then(|v| {
                v.iter()
                    .position(|e| !e.is_finite())
                    .map(|k| (v.nrows(), k))
            });
            let entry = bad.map(|(rows, k)| (k % rows, k / rows));
            let what = match entry {
                Some((i, j)) => format!("`{name}(x)[{i}, {j}]`"),
                None => format!("`{name}(x)`"),
            };
            (what, entry.and_then(|e| entry_span(&m.expr, e)))
        }
    };
    let whole = entry.unwrap_or(subject.expr().span);
    let division = match &exact {
        Err(d) if d.message == "division by zero" => {
            Some(division_at(spec, subject.expr(), d.span))
        }
        _ => None,
    };
    let d = match (division, exact) {
        (Some(div), _) => {
            let (kind, label) = if nan {
                ("0/0", "0/0 here")
            } else {
                ("a division by zero", "division by zero here")
            };
            let span = div.unwrap_or(whole);
            let mut d = Diagnostic::error(span, format!("{what} is not finite at {at} ({kind})"))
                .with_label(format!("{label}, at {at}"));
            if span != whole && !(whole.start <= span.start && span.end <= whole.end) {
                d = d.with_secondary(whole, format!("{what} evaluated here"));
            }
            if nan {
                d.with_help(REMOVABLE)
            } else {
                d.with_help(help(&at))
            }
        }
        (None, Err(e)) => e.with_secondary(whole, format!("while evaluating {what} at {at}")),
        (None, Ok(v)) => {
            let kind = if v.iter().any(|e| e.is_nan()) {
                "NaN"
            } else {
                "infinite"
            };
            Diagnostic::error(whole, format!("{what} is not finite at {at} ({kind})"))
                .with_label(format!("{kind} at {at}"))
                .with_help(help(&at))
        }
    };
    d.with_note(
        "premises and A(x), B(x) are evaluated at the origin (when the state region holds it) and on the model-consistency grid",
    )
}

fn help(at: &str) -> String {
    format!("the controller evaluates it at {at}, inside the state region: rewrite it so that it is finite there, or narrow the premise ranges so the region excludes this state")
}

/// The span of entry `(i, j)` of a matrix literal of scalar entries (`None`
/// for any other expression).
fn entry_span(e: &Expr, (i, j): (usize, usize)) -> Option<Span> {
    match &e.kind {
        ExprKind::Matrix(rows) => rows.get(i)?.get(j).map(|e| e.span),
        _ => None,
    }
}

/// The division whose divisor has span `divisor`, searched in `e` and in
/// every user function's body (`None` if there is none: the error came from
/// elsewhere).
fn division_at(spec: &Spec, e: &Expr, divisor: Span) -> Option<Span> {
    find_division(e, divisor).or_else(|| {
        spec.fns
            .values()
            .find_map(|f| find_division(&f.body, divisor))
    })
}

fn find_division(e: &Expr, divisor: Span) -> Option<Span> {
    // An explicit stack: expressions may nest deeply.
    let mut stack = vec![e];
    while let Some(e) = stack.pop() {
        match &e.kind {
            ExprKind::Binary(op, a, b) => {
                if *op == BinOp::Div && b.span == divisor {
                    return Some(e.span);
                }
                stack.push(a);
                stack.push(b);
            }
            ExprKind::Neg(a) | ExprKind::Transpose(a) => stack.push(a),
            ExprKind::Matrix(rows) => stack.extend(rows.iter().flatten()),
            ExprKind::Index(a, args) => {
                stack.push(a);
                for arg in args {
                    match arg {
                        IndexArg::One(i) => stack.push(i),
                        IndexArg::Range(i, j) => {
                            stack.push(i);
                            stack.push(j);
                        }
                        IndexArg::Full => {}
                    }
                }
            }
            ExprKind::Call(_, args) => stack.extend(args.iter().map(|a| &a.value)),
            ExprKind::Number(_) | ExprKind::Name(_) => {}
        }
    }
    None
}
