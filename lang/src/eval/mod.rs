//! Evaluation of expressions to real matrices, with shape checking.
//!
//! Every value is a `DMatrix<f64>`; scalars are 1x1 and vectors n x 1. Shape
//! errors, unknown names, bad indices and singular inverses are diagnostics
//! carrying the span of the offending sub-expression. In [`Mode::Shapes`]
//! only shapes are checked (a singular inverse is not an error there), which
//! is how state-dependent expressions are checked before any operating point
//! is known.
//!
//! Evaluation is bounded: it never recurses deeper than
//! [`MAX_EXPR_DEPTH`] levels (through function calls too) and pays for its
//! work from a [`Budget`].

mod budget;
mod builtins;
mod ops;

pub use budget::Budget;
pub(crate) use builtins::BUILTINS;

use crate::ast::{Arg, Expr, ExprKind, IndexArg};
use crate::diag::Diagnostic;
use crate::limits::{MAX_EXPR_DEPTH, NODE_WORK};
use crate::num::Num;
use crate::span::Span;
use crate::suggest::suggest;
use nalgebra::DMatrix;
use std::collections::HashMap;

/// A value: a real matrix.
pub type Mat = DMatrix<f64>;

/// A user function `fn name(params) = body`.
#[derive(Debug, Clone)]
pub struct FnDef {
    /// Parameter names.
    pub params: Vec<String>,
    /// The body.
    pub body: Expr,
}

/// How strictly to evaluate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Full numeric evaluation.
    Exact,
    /// Shapes only: numeric failures (singular inverse) are not errors.
    Shapes,
}

/// The names visible to an expression.
#[derive(Debug, Clone)]
pub struct Env<'a> {
    /// Constants (evaluated).
    pub consts: &'a HashMap<String, Mat>,
    /// User functions.
    pub fns: &'a HashMap<String, FnDef>,
    /// Local bindings (states, `x`, `t`, parameters); later entries shadow earlier.
    pub locals: Vec<(String, Mat)>,
    /// Names that exist in the spec but may not be used here, with the reason.
    pub unavailable: Vec<(String, String)>,
    /// Evaluation mode.
    pub mode: Mode,
}

type R = Result<Mat, Diagnostic>;

fn shape(m: &Mat) -> String {
    if m.nrows() == 1 && m.ncols() == 1 {
        "a scalar".to_string()
    } else if m.ncols() == 1 {
        format!("a {}-vector", m.nrows())
    } else {
        format!("{}x{}", m.nrows(), m.ncols())
    }
}

fn is_scalar(m: &Mat) -> bool {
    m.nrows() == 1 && m.ncols() == 1
}

fn scalar(v: f64) -> Mat {
    DMatrix::from_element(1, 1, v)
}

/// How deep an evaluation is: expression levels (through function calls)
/// and nested user-function calls.
#[derive(Debug, Clone, Copy, Default)]
struct Depth {
    levels: usize,
    calls: usize,
}

/// Nested user-function calls allowed (deeper means a function calls itself).
const MAX_CALLS: usize = 64;

/// Secondary "in this call" labels kept on an error from deep inside functions
/// (the innermost ones and the outermost).
const MAX_CALL_LABELS: usize = 8;

/// One evaluation in progress: where it is, and what it may still spend.
#[derive(Clone, Copy)]
struct Run<'b> {
    depth: Depth,
    budget: &'b Budget,
}

impl Run<'_> {
    /// The run one level down, into the expression at `span`, paying for the visit.
    fn enter(self, span: Span) -> Result<Self, Diagnostic> {
        let levels = self.depth.levels + 1;
        if levels > MAX_EXPR_DEPTH {
            return Err(Diagnostic::error(
                span,
                format!("evaluation nested too deeply: more than {MAX_EXPR_DEPTH} levels"),
            )
            .with_label("this is evaluated too deep inside function calls")
            .with_help(format!(
                "at most {MAX_EXPR_DEPTH} levels, counted through function calls (MAX_EXPR_DEPTH): \
                 compute inner values in a `const`"
            )));
        }
        self.budget.pay(NODE_WORK, span)?;
        Ok(Run {
            depth: Depth {
                levels,
                ..self.depth
            },
            ..self
        })
    }
}

impl Env<'_> {
    fn lookup(&self, name: &str) -> Option<&Mat> {
        self.locals
            .iter()
            .rev()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v)
            .or_else(|| self.consts.get(name))
    }

    fn unknown(&self, name: &str, span: Span) -> Diagnostic {
        if let Some((_, why)) = self.unavailable.iter().find(|(n, _)| n == name) {
            return Diagnostic::error(span, format!("`{name}` cannot be used here"))
                .with_label(why.clone());
        }
        if self.fns.contains_key(name) || BUILTINS.contains(&name) {
            return Diagnostic::error(span, format!("`{name}` is a function, not a value"))
                .with_label("call it with arguments")
                .with_help(format!("write `{name}(...)`"));
        }
        let mut d =
            Diagnostic::error(span, format!("unknown name `{name}`")).with_label("not declared");
        let cands = self
            .locals
            .iter()
            .map(|(n, _)| n.as_str())
            .chain(self.consts.keys().map(String::as_str));
        if let Some(s) = suggest(name, cands) {
            d = d.with_help(format!("did you mean `{s}`?"));
        }
        d
    }

    /// Evaluates `e` within one evaluation's work ([`MAX_EVAL_WORK`](crate::limits::MAX_EVAL_WORK)).
    pub fn eval(&self, e: &Expr) -> R {
        self.eval_with(e, &Budget::evaluation())
    }

    /// Evaluates `e`, paying its work from `budget`.
    pub fn eval_with(&self, e: &Expr, budget: &Budget) -> R {
        let run = Run {
            depth: Depth::default(),
            budget,
        };
        self.eval_in(e, run)
    }

    fn eval_in(&self, e: &Expr, run: Run) -> R {
        let sp = e.span;
        let run = run.enter(sp)?;
        match &e.kind {
            ExprKind::Number(v) => Ok(scalar(*v)),
            ExprKind::Name(n) => self.lookup(n).cloned().ok_or_else(|| self.unknown(n, sp)),
            ExprKind::Neg(a) => Ok(-self.eval_in(a, run)?),
            ExprKind::Transpose(a) => Ok(self.eval_in(a, run)?.transpose()),
            ExprKind::Matrix(rows) => self.matrix(rows, sp, run),
            ExprKind::Binary(op, a, b) => {
                let (x, y) = (self.eval_in(a, run)?, self.eval_in(b, run)?);
                run.budget.pay(ops::work(*op, &x, &y), sp)?;
                ops::binary(*op, x, y, a.span, b.span, sp, self.mode)
            }
            ExprKind::Index(a, idx) => {
                let m = self.eval_in(a, run)?;
                self.index(m, idx, sp, run)
            }
            ExprKind::Call(f, args) => self.call(&f.node, f.span, args, sp, run),
        }
    }

    fn matrix(&self, rows: &[Vec<Expr>], sp: Span, run: Run) -> R {
        let mut blocks: Vec<Mat> = Vec::new();
        for row in rows {
            let vals = row
                .iter()
                .map(|x| self.eval_in(x, run))
                .collect::<Result<Vec<_>, _>>()?;
            let h = vals.first().map_or(0, |m| m.nrows());
            for (v, x) in vals.iter().zip(row) {
                if v.nrows() != h {
                    return Err(Diagnostic::error(
                        x.span,
                        format!(
                            "matrix row mixes heights: this element has {} rows, the first has {h}",
                            v.nrows()
                        ),
                    )
                    .with_label(format!("this is {}", shape(v)))
                    .with_help("elements separated by `,` must have the same number of rows"));
                }
            }
            let w: usize = vals.iter().map(|m| m.ncols()).sum();
            let mut out = DMatrix::zeros(h, w);
            let mut c = 0;
            for v in &vals {
                out.view_mut((0, c), (h, v.ncols())).copy_from(v);
                c += v.ncols();
            }
            blocks.push(out);
        }
        let w = blocks.first().map_or(0, |m| m.ncols());
        for (b, row) in blocks.iter().zip(rows) {
            if b.ncols() != w {
                let s = row
                    .first()
                    .map_or(sp, |f| row.iter().fold(f.span, |acc, x| acc.join(x.span)));
                return Err(Diagnostic::error(
                    s,
                    format!("matrix rows have different widths: this row has {} columns, the first has {w}", b.ncols()),
                )
                .with_label("this row")
                .with_help("rows separated by `;` must have the same number of columns"));
            }
        }
        let h: usize = blocks.iter().map(|m| m.nrows()).sum();
        let mut out = DMatrix::zeros(h, w);
        let mut r = 0;
        for b in &blocks {
            out.view_mut((r, 0), (b.nrows(), w)).copy_from(b);
            r += b.nrows();
        }
        Ok(out)
    }

    fn int(&self, e: &Expr, run: Run) -> Result<i64, Diagnostic> {
        let v = self.eval_in(e, run)?;
        if !is_scalar(&v) {
            return Err(Diagnostic::error(
                e.span,
                format!("expected an integer, found {}", shape(&v)),
            ));
        }
        let x = v[(0, 0)];
        if x.fract() != 0.0 || !x.is_finite() || x.abs() > 1e9 {
            return Err(Diagnostic::error(
                e.span,
                format!("expected an integer, found {}", Num(x)),
            )
            .with_label("not a whole number"));
        }
        Ok(x as i64)
    }

    fn range(
        &self,
        a: &IndexArg,
        len: usize,
        sp: Span,
        run: Run,
    ) -> Result<(usize, usize), Diagnostic> {
        let check = |v: i64, e: &Expr, allow_end: bool| -> Result<usize, Diagnostic> {
            let max = if allow_end {
                len as i64
            } else {
                len as i64 - 1
            };
            if v < 0 || v > max {
                Err(
                    Diagnostic::error(e.span, format!("index {v} is out of bounds")).with_label(
                        format!("valid indices are 0..{len} (0-based, end excluded)"),
                    ),
                )
            } else {
                Ok(v as usize)
            }
        };
        match a {
            IndexArg::Full => Ok((0, len)),
            IndexArg::One(e) => {
                let i = check(self.int(e, run)?, e, false)?;
                Ok((i, i + 1))
            }
            IndexArg::Range(lo, hi) => {
                let l = check(self.int(lo, run)?, lo, true)?;
                let h = check(self.int(hi, run)?, hi, true)?;
                if h < l {
                    return Err(Diagnostic::error(sp, "empty or reversed index range")
                        .with_label(format!("{l}..{h} selects nothing")));
                }
                Ok((l, h))
            }
        }
    }

    fn index(&self, m: Mat, idx: &[IndexArg], sp: Span, run: Run) -> R {
        match idx {
            [one] => {
                let (len, col) = if m.ncols() == 1 {
                    (m.nrows(), true)
                } else if m.nrows() == 1 {
                    (m.ncols(), false)
                } else {
                    return Err(Diagnostic::error(
                        sp,
                        format!("a single index needs a vector, found {}", shape(&m)),
                    )
                    .with_help("index a matrix as `M[i, j]`"));
                };
                let (l, h) = self.range(one, len, sp, run)?;
                Ok(if col {
                    m.rows(l, h - l).into_owned()
                } else {
                    m.columns(l, h - l).into_owned()
                })
            }
            [r, c] => {
                let (r0, r1) = self.range(r, m.nrows(), sp, run)?;
                let (c0, c1) = self.range(c, m.ncols(), sp, run)?;
                Ok(m.view((r0, c0), (r1 - r0, c1 - c0)).into_owned())
            }
            _ => Err(Diagnostic::error(sp, "too many indices")),
        }
    }

    fn call(&self, name: &str, name_span: Span, args: &[Arg], sp: Span, run: Run) -> R {
        if let Some(a) = args.iter().find(|a| a.name.is_some()) {
            let n = a.name.as_ref().map_or(sp, |n| n.span);
            return Err(
                Diagnostic::error(n, format!("`{name}` takes no named arguments"))
                    .with_help("pass the arguments by position"),
            );
        }
        if let Some(f) = self.fns.get(name) {
            if f.params.len() != args.len() {
                return Err(builtins::arity(name, name_span, f.params.len(), args.len()));
            }
            if run.depth.calls > MAX_CALLS {
                return Err(
                    Diagnostic::error(sp, format!("`{name}` calls itself too deeply"))
                        .with_help("functions may not be recursive"),
                );
            }
            let vals = args
                .iter()
                .map(|a| self.eval_in(&a.value, run))
                .collect::<Result<Vec<_>, _>>()?;
            let inner = Env {
                consts: self.consts,
                fns: self.fns,
                locals: f.params.iter().cloned().zip(vals).collect(),
                unavailable: Vec::new(),
                mode: self.mode,
            };
            let deeper = Run {
                depth: Depth {
                    calls: run.depth.calls + 1,
                    ..run.depth
                },
                ..run
            };
            return inner.eval_in(&f.body, deeper).map_err(|mut d| {
                // Deep inside calls, keep the innermost calls and the outermost one.
                if d.secondary.len() >= MAX_CALL_LABELS {
                    d.secondary.pop();
                }
                d.with_secondary(sp, format!("in this call of `{name}`"))
            });
        }
        if !BUILTINS.contains(&name) {
            let mut d = Diagnostic::error(name_span, format!("unknown function `{name}`"))
                .with_label("not defined");
            let cands = BUILTINS
                .iter()
                .copied()
                .chain(self.fns.keys().map(String::as_str));
            if let Some(s) = suggest(name, cands) {
                d = d.with_help(format!("did you mean `{s}`?"));
            } else {
                d = d.with_help("define it with `fn name(args) = ...;`");
            }
            return Err(d);
        }
        let vals = args
            .iter()
            .map(|a| self.eval_in(&a.value, run))
            .collect::<Result<Vec<_>, _>>()?;
        let spans: Vec<Span> = args.iter().map(|a| a.value.span).collect();
        run.budget.pay(builtins::work(name, &vals), sp)?;
        builtins::builtin(name, name_span, &vals, &spans, sp, self.mode)
    }
}
