//! Evaluation of expressions to real matrices, with shape checking.
//!
//! Every value is a `DMatrix<f64>`; scalars are 1x1 and vectors n x 1. Shape
//! errors, unknown names, bad indices and singular inverses are diagnostics
//! carrying the span of the offending sub-expression. In [`Mode::Shapes`]
//! only shapes are checked (a singular inverse is not an error there), which
//! is how state-dependent expressions are checked before any operating point
//! is known.

use crate::ast::{Arg, BinOp, Expr, ExprKind, IndexArg};
use crate::diag::Diagnostic;
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

/// Names of the built-in functions.
pub(crate) const BUILTINS: &[&str] = &[
    "eye",
    "zeros",
    "ones",
    "diag",
    "inv",
    "det",
    "trace",
    "transpose",
    "sqrt",
    "sin",
    "cos",
    "tan",
    "atan",
    "atan2",
    "exp",
    "log",
    "abs",
    "sign",
    "sinc",
    "norm",
    "dot",
    "cross",
    "skew",
    "min",
    "max",
    "sum",
    "mean",
    "blkdiag",
    "pi",
];

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

    /// Evaluates `e`.
    pub fn eval(&self, e: &Expr) -> R {
        self.eval_depth(e, 0)
    }

    fn eval_depth(&self, e: &Expr, depth: usize) -> R {
        let sp = e.span;
        match &e.kind {
            ExprKind::Number(v) => Ok(scalar(*v)),
            ExprKind::Name(n) => self.lookup(n).cloned().ok_or_else(|| self.unknown(n, sp)),
            ExprKind::Neg(a) => Ok(-self.eval_depth(a, depth)?),
            ExprKind::Transpose(a) => Ok(self.eval_depth(a, depth)?.transpose()),
            ExprKind::Matrix(rows) => self.matrix(rows, sp, depth),
            ExprKind::Binary(op, a, b) => {
                let (x, y) = (self.eval_depth(a, depth)?, self.eval_depth(b, depth)?);
                binary(*op, x, y, a.span, b.span, sp, self.mode)
            }
            ExprKind::Index(a, idx) => {
                let m = self.eval_depth(a, depth)?;
                self.index(m, idx, sp, depth)
            }
            ExprKind::Call(f, args) => self.call(&f.node, f.span, args, sp, depth),
        }
    }

    fn matrix(&self, rows: &[Vec<Expr>], sp: Span, depth: usize) -> R {
        let mut blocks: Vec<Mat> = Vec::new();
        for row in rows {
            let vals = row
                .iter()
                .map(|x| self.eval_depth(x, depth))
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

    fn int(&self, e: &Expr, depth: usize) -> Result<i64, Diagnostic> {
        let v = self.eval_depth(e, depth)?;
        if !is_scalar(&v) {
            return Err(Diagnostic::error(
                e.span,
                format!("expected an integer, found {}", shape(&v)),
            ));
        }
        let x = v[(0, 0)];
        if x.fract() != 0.0 || !x.is_finite() || x.abs() > 1e9 {
            return Err(
                Diagnostic::error(e.span, format!("expected an integer, found {x}"))
                    .with_label("not a whole number"),
            );
        }
        Ok(x as i64)
    }

    fn range(
        &self,
        a: &IndexArg,
        len: usize,
        sp: Span,
        depth: usize,
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
                let i = check(self.int(e, depth)?, e, false)?;
                Ok((i, i + 1))
            }
            IndexArg::Range(lo, hi) => {
                let l = check(self.int(lo, depth)?, lo, true)?;
                let h = check(self.int(hi, depth)?, hi, true)?;
                if h < l {
                    return Err(Diagnostic::error(sp, "empty or reversed index range")
                        .with_label(format!("{l}..{h} selects nothing")));
                }
                Ok((l, h))
            }
        }
    }

    fn index(&self, m: Mat, idx: &[IndexArg], sp: Span, depth: usize) -> R {
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
                let (l, h) = self.range(one, len, sp, depth)?;
                Ok(if col {
                    m.rows(l, h - l).into_owned()
                } else {
                    m.columns(l, h - l).into_owned()
                })
            }
            [r, c] => {
                let (r0, r1) = self.range(r, m.nrows(), sp, depth)?;
                let (c0, c1) = self.range(c, m.ncols(), sp, depth)?;
                Ok(m.view((r0, c0), (r1 - r0, c1 - c0)).into_owned())
            }
            _ => Err(Diagnostic::error(sp, "too many indices")),
        }
    }

    fn call(&self, name: &str, name_span: Span, args: &[Arg], sp: Span, depth: usize) -> R {
        if let Some(a) = args.iter().find(|a| a.name.is_some()) {
            let n = a.name.as_ref().map_or(sp, |n| n.span);
            return Err(
                Diagnostic::error(n, format!("`{name}` takes no named arguments"))
                    .with_help("pass the arguments by position"),
            );
        }
        if let Some(f) = self.fns.get(name) {
            if f.params.len() != args.len() {
                return Err(arity(name, name_span, f.params.len(), args.len()));
            }
            if depth > 64 {
                return Err(
                    Diagnostic::error(sp, format!("`{name}` calls itself too deeply"))
                        .with_help("functions may not be recursive"),
                );
            }
            let vals = args
                .iter()
                .map(|a| self.eval_depth(&a.value, depth))
                .collect::<Result<Vec<_>, _>>()?;
            let inner = Env {
                consts: self.consts,
                fns: self.fns,
                locals: f.params.iter().cloned().zip(vals).collect(),
                unavailable: Vec::new(),
                mode: self.mode,
            };
            return inner
                .eval_depth(&f.body, depth + 1)
                .map_err(|d| d.with_secondary(sp, format!("in this call of `{name}`")));
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
            .map(|a| self.eval_depth(&a.value, depth))
            .collect::<Result<Vec<_>, _>>()?;
        let spans: Vec<Span> = args.iter().map(|a| a.value.span).collect();
        builtin(name, name_span, &vals, &spans, sp, self.mode)
    }
}

fn arity(name: &str, span: Span, want: usize, got: usize) -> Diagnostic {
    Diagnostic::error(
        span,
        format!(
            "`{name}` takes {want} argument{}, {got} given",
            if want == 1 { "" } else { "s" }
        ),
    )
    .with_label("wrong number of arguments")
}

fn binary(op: BinOp, x: Mat, y: Mat, xs: Span, ys: Span, sp: Span, mode: Mode) -> R {
    let mismatch = |what: &str, help: &str| {
        Diagnostic::error(
            sp,
            format!("shape mismatch in {what}: {} and {}", shape(&x), shape(&y)),
        )
        .with_secondary(xs, format!("this is {}", shape(&x)))
        .with_secondary(ys, format!("this is {}", shape(&y)))
        .with_help(help.to_string())
    };
    match op {
        BinOp::Add | BinOp::Sub => {
            let s = if op == BinOp::Add { 1.0 } else { -1.0 };
            if x.shape() == y.shape() {
                Ok(&x + &y * s)
            } else if is_scalar(&y) {
                Ok(x.map(|v| v + s * y[(0, 0)]))
            } else if is_scalar(&x) {
                Ok(y.map(|v| x[(0, 0)] + s * v))
            } else {
                Err(mismatch(
                    if op == BinOp::Add { "`+`" } else { "`-`" },
                    "both sides must have the same shape",
                ))
            }
        }
        BinOp::Mul => {
            if is_scalar(&x) {
                Ok(y * x[(0, 0)])
            } else if is_scalar(&y) {
                Ok(x * y[(0, 0)])
            } else if x.ncols() == y.nrows() {
                Ok(&x * &y)
            } else {
                Err(mismatch(
                    "`*`",
                    "the left side's columns must equal the right side's rows",
                ))
            }
        }
        BinOp::EMul => {
            if x.shape() == y.shape() {
                Ok(x.component_mul(&y))
            } else if is_scalar(&x) || is_scalar(&y) {
                binary(BinOp::Mul, x, y, xs, ys, sp, mode)
            } else {
                Err(mismatch("`.*`", "both sides must have the same shape"))
            }
        }
        BinOp::Div => {
            if !is_scalar(&y) {
                return Err(mismatch(
                    "`/`",
                    "divide by a scalar; for a matrix use `* inv(M)`",
                ));
            }
            if y[(0, 0)] == 0.0 && mode == Mode::Exact {
                return Err(Diagnostic::error(ys, "division by zero").with_label("this is 0"));
            }
            Ok(x / y[(0, 0)])
        }
        BinOp::Pow => {
            if is_scalar(&x) && is_scalar(&y) {
                return Ok(scalar(x[(0, 0)].powf(y[(0, 0)])));
            }
            let k = y[(0, 0)];
            if !is_scalar(&y) || x.nrows() != x.ncols() || k < 0.0 || k.fract() != 0.0 || k > 1e6 {
                return Err(mismatch(
                    "`^`",
                    "use scalar ^ scalar, or a square matrix ^ a non-negative integer",
                ));
            }
            let mut out = DMatrix::identity(x.nrows(), x.ncols());
            for _ in 0..k as usize {
                out = &out * &x;
            }
            Ok(out)
        }
    }
}

fn elementwise(v: &Mat, f: fn(f64) -> f64) -> Mat {
    v.map(f)
}

fn dim_arg(v: &Mat, s: Span) -> Result<usize, Diagnostic> {
    let x = if is_scalar(v) { v[(0, 0)] } else { f64::NAN };
    if x.fract() == 0.0 && (0.0..=10_000.0).contains(&x) {
        Ok(x as usize)
    } else {
        Err(
            Diagnostic::error(s, "expected a size (a whole number from 0 to 10000)").with_label(
                format!(
                    "this is {}",
                    if is_scalar(v) {
                        format!("{x}")
                    } else {
                        shape(v)
                    }
                ),
            ),
        )
    }
}

fn need_vec3(v: &Mat, s: Span, name: &str) -> Result<[f64; 3], Diagnostic> {
    if v.len() == 3 && (v.ncols() == 1 || v.nrows() == 1) {
        Ok([v[0], v[1], v[2]])
    } else {
        Err(Diagnostic::error(
            s,
            format!("`{name}` needs a 3-vector, found {}", shape(v)),
        ))
    }
}

fn builtin(name: &str, ns: Span, a: &[Mat], s: &[Span], sp: Span, mode: Mode) -> R {
    let want = |n: usize| {
        if a.len() == n {
            Ok(())
        } else {
            Err(arity(name, ns, n, a.len()))
        }
    };
    let sq = |m: &Mat, s: Span| {
        if m.nrows() == m.ncols() {
            Ok(())
        } else {
            Err(Diagnostic::error(
                s,
                format!("`{name}` needs a square matrix, found {}", shape(m)),
            ))
        }
    };
    match name {
        "pi" => want(0).map(|_| scalar(std::f64::consts::PI)),
        "eye" => {
            want(1)?;
            let n = dim_arg(&a[0], s[0])?;
            Ok(DMatrix::identity(n, n))
        }
        "zeros" | "ones" => {
            let v = if name == "zeros" { 0.0 } else { 1.0 };
            match a.len() {
                1 => Ok(DMatrix::from_element(dim_arg(&a[0], s[0])?, 1, v)),
                2 => Ok(DMatrix::from_element(
                    dim_arg(&a[0], s[0])?,
                    dim_arg(&a[1], s[1])?,
                    v,
                )),
                n => Err(arity(name, ns, 2, n).with_help(format!(
                    "`{name}(n)` is an n-vector, `{name}(r, c)` an r x c matrix"
                ))),
            }
        }
        "diag" => {
            want(1)?;
            let m = &a[0];
            if m.ncols() == 1 || m.nrows() == 1 {
                let v: Vec<f64> = m.iter().copied().collect();
                Ok(DMatrix::from_diagonal(&nalgebra::DVector::from_vec(v)))
            } else {
                sq(m, s[0])?;
                Ok(DMatrix::from_column_slice(
                    m.nrows(),
                    1,
                    m.diagonal().as_slice(),
                ))
            }
        }
        "inv" => {
            want(1)?;
            sq(&a[0], s[0])?;
            match a[0].clone().try_inverse() {
                Some(m) if m.iter().all(|v| v.is_finite()) => {
                    let cond = a[0].norm() * m.norm();
                    if cond > 1e14 && mode == Mode::Exact {
                        Err(singular(
                            sp,
                            s[0],
                            &format!("its condition number is about {cond:.1e}"),
                        ))
                    } else {
                        Ok(m)
                    }
                }
                _ if mode == Mode::Shapes => Ok(DMatrix::zeros(a[0].nrows(), a[0].ncols())),
                _ => Err(singular(sp, s[0], "its determinant is 0")),
            }
        }
        "det" => {
            want(1)?;
            sq(&a[0], s[0])?;
            Ok(scalar(a[0].determinant()))
        }
        "trace" => {
            want(1)?;
            sq(&a[0], s[0])?;
            Ok(scalar(a[0].trace()))
        }
        "transpose" => want(1).map(|_| a[0].transpose()),
        "sqrt" | "sin" | "cos" | "tan" | "atan" | "exp" | "log" | "abs" | "sign" | "sinc" => {
            want(1)?;
            let f: fn(f64) -> f64 = match name {
                "sqrt" => f64::sqrt,
                "sin" => f64::sin,
                "cos" => f64::cos,
                "tan" => f64::tan,
                "atan" => f64::atan,
                "exp" => f64::exp,
                "log" => f64::ln,
                "abs" => f64::abs,
                "sign" => |v: f64| {
                    if v > 0.0 {
                        1.0
                    } else if v < 0.0 {
                        -1.0
                    } else {
                        0.0
                    }
                },
                // The runtime's sinc, so that model and generated code agree.
                _ => tsf_runtime::math::sinc,
            };
            Ok(elementwise(&a[0], f))
        }
        "atan2" | "min" | "max" => {
            want(2)?;
            let f: fn(f64, f64) -> f64 = match name {
                "atan2" => f64::atan2,
                "min" => f64::min,
                _ => f64::max,
            };
            let (x, y) = (&a[0], &a[1]);
            if x.shape() == y.shape() {
                Ok(x.zip_map(y, f))
            } else if is_scalar(y) {
                Ok(x.map(|v| f(v, y[(0, 0)])))
            } else if is_scalar(x) {
                Ok(y.map(|v| f(x[(0, 0)], v)))
            } else {
                Err(Diagnostic::error(
                    sp,
                    format!(
                        "`{name}` needs arguments of the same shape, found {} and {}",
                        shape(x),
                        shape(y)
                    ),
                ))
            }
        }
        "norm" => want(1).map(|_| scalar(a[0].norm())),
        "sum" => want(1).map(|_| scalar(a[0].sum())),
        "mean" => {
            want(1)?;
            if a[0].is_empty() {
                return Err(Diagnostic::error(s[0], "`mean` of an empty value"));
            }
            Ok(scalar(a[0].mean()))
        }
        "dot" => {
            want(2)?;
            if a[0].len() != a[1].len()
                || !(a[0].ncols() == 1 || a[0].nrows() == 1)
                || !(a[1].ncols() == 1 || a[1].nrows() == 1)
            {
                return Err(Diagnostic::error(
                    sp,
                    format!(
                        "`dot` needs two vectors of the same length, found {} and {}",
                        shape(&a[0]),
                        shape(&a[1])
                    ),
                ));
            }
            Ok(scalar(
                a[0].iter().zip(a[1].iter()).map(|(p, q)| p * q).sum(),
            ))
        }
        "cross" => {
            want(2)?;
            let p = need_vec3(&a[0], s[0], name)?;
            let q = need_vec3(&a[1], s[1], name)?;
            Ok(DMatrix::from_column_slice(
                3,
                1,
                &[
                    p[1] * q[2] - p[2] * q[1],
                    p[2] * q[0] - p[0] * q[2],
                    p[0] * q[1] - p[1] * q[0],
                ],
            ))
        }
        "skew" => {
            want(1)?;
            let v = need_vec3(&a[0], s[0], name)?;
            Ok(DMatrix::from_row_slice(
                3,
                3,
                &[0.0, -v[2], v[1], v[2], 0.0, -v[0], -v[1], v[0], 0.0],
            ))
        }
        "blkdiag" => {
            let r: usize = a.iter().map(|m| m.nrows()).sum();
            let c: usize = a.iter().map(|m| m.ncols()).sum();
            let mut out = DMatrix::zeros(r, c);
            let (mut i, mut j) = (0, 0);
            for m in a {
                out.view_mut((i, j), (m.nrows(), m.ncols())).copy_from(m);
                i += m.nrows();
                j += m.ncols();
            }
            Ok(out)
        }
        _ => Err(Diagnostic::error(ns, format!("unknown function `{name}`"))),
    }
}

fn singular(sp: Span, arg: Span, why: &str) -> Diagnostic {
    Diagnostic::error(sp, "matrix is singular and cannot be inverted")
        .with_label("inverse of a singular matrix")
        .with_secondary(arg, why.to_string())
        .with_help("check the matrix entries (an inertia or mass matrix must be positive definite)")
}
