//! Lowering of the language's matrix expressions into a tape's graph: every
//! value is a matrix of graph nodes ([`SymMat`], column-major like the
//! evaluator's). An operation whose operands are all constant is handed to
//! the language's evaluator (so constants such as `inv(J)` are the
//! interpreter's values to the bit); the others are expanded entry by entry in
//! the evaluator's order of operations. What cannot be expanded (an `inv` or
//! `det` of a state-dependent matrix, a state-dependent index or size, a
//! matrix power with a state-dependent exponent, anything the evaluator would
//! refuse) is [`Unsupported`]: the simulator then keeps the interpreter for
//! that run.

use super::{Binary, Builder, Id, Unary};
use std::collections::HashMap;
use tsf_lang::ast::{Arg, BinOp, Expr, ExprKind, IndexArg};
use tsf_lang::eval::{Env, FnDef, Mat, Mode};
use tsf_lang::limits::{MAX_EXPR_DEPTH, MAX_MATRIX_POWER};
use tsf_lang::spec::Signal;
use tsf_lang::Span;

/// Most graph nodes one tape may have (a larger expansion keeps the interpreter).
pub const MAX_NODES: usize = 1 << 20;

/// Nested user-function calls followed (the evaluator's limit).
const MAX_CALLS: usize = 64;

/// Why an expression is not compiled (the interpreter evaluates it instead).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Unsupported(pub String);

type Lowered = Result<SymMat, Unsupported>;

fn unsupported<T>(why: impl Into<String>) -> Result<T, Unsupported> {
    Err(Unsupported(why.into()))
}

/// A matrix of graph nodes, column-major.
#[derive(Debug, Clone, PartialEq)]
pub struct SymMat {
    /// Rows.
    pub rows: usize,
    /// Columns.
    pub cols: usize,
    /// Entries, column by column.
    pub data: Vec<Id>,
}

impl SymMat {
    /// The matrix with entries `f(i, j)`.
    pub fn from_fn(rows: usize, cols: usize, mut f: impl FnMut(usize, usize) -> Id) -> SymMat {
        let mut data = Vec::with_capacity(rows * cols);
        for j in 0..cols {
            for i in 0..rows {
                data.push(f(i, j));
            }
        }
        SymMat { rows, cols, data }
    }

    /// A column of nodes.
    pub fn column(data: Vec<Id>) -> SymMat {
        SymMat {
            rows: data.len(),
            cols: 1,
            data,
        }
    }

    /// Entry `(i, j)`.
    pub fn at(&self, i: usize, j: usize) -> Id {
        self.data[j * self.rows + i]
    }

    fn is_scalar(&self) -> bool {
        self.rows == 1 && self.cols == 1
    }

    fn is_vector(&self) -> bool {
        self.rows == 1 || self.cols == 1
    }
}

/// Names visible to an expression: later bindings shadow earlier ones, then
/// the spec's constants (the evaluator's rule).
pub type Scope = [(String, SymMat)];

/// Lowers expressions of one spec into one graph.
pub struct Lowerer<'a> {
    /// The graph being built.
    pub b: Builder,
    consts: &'a HashMap<String, Mat>,
    fns: &'a HashMap<String, FnDef>,
}

impl<'a> Lowerer<'a> {
    /// A lowerer adding to `b`, with the spec's constants and functions.
    pub fn new(
        b: Builder,
        consts: &'a HashMap<String, Mat>,
        fns: &'a HashMap<String, FnDef>,
    ) -> Self {
        Lowerer { b, consts, fns }
    }

    /// The inputs `at .. at + len` as a column.
    pub fn inputs(&self, at: usize, len: usize) -> SymMat {
        SymMat::column((at..at + len).map(|k| self.b.input(k)).collect())
    }

    /// Each of `signals` bound by name to its slice of the inputs, which
    /// start at input `at` (the evaluator's bindings, in its order).
    pub fn bind(&self, signals: &[Signal], at: usize) -> Vec<(String, SymMat)> {
        signals
            .iter()
            .map(|s| (s.name.clone(), self.inputs(at + s.offset, s.len)))
            .collect()
    }

    /// The tape computing `outputs`.
    pub fn finish(self, outputs: &[Id]) -> Result<super::Tape, Unsupported> {
        self.b
            .finish(outputs)
            .ok_or_else(|| Unsupported("too many registers".into()))
    }

    /// The nodes of a constant matrix.
    pub fn constant(&mut self, m: &Mat) -> SymMat {
        SymMat {
            rows: m.nrows(),
            cols: m.ncols(),
            data: m.iter().map(|&v| self.b.constant(v)).collect(),
        }
    }

    fn as_const(&self, m: &SymMat) -> Option<Mat> {
        let v: Option<Vec<f64>> = m.data.iter().map(|&id| self.b.value(id)).collect();
        Some(Mat::from_vec(m.rows, m.cols, v?))
    }

    /// Lowers `e` with the names of `scope`.
    pub fn expr(&mut self, e: &Expr, scope: &Scope) -> Lowered {
        self.lower(e, scope, 0, 0)
    }

    fn lower(&mut self, e: &Expr, scope: &Scope, depth: usize, calls: usize) -> Lowered {
        if depth > MAX_EXPR_DEPTH || self.b.len() > MAX_NODES {
            return unsupported("too large to compile");
        }
        let d = depth + 1;
        match &e.kind {
            ExprKind::Number(v) => Ok(SymMat::column(vec![self.b.constant(*v)])),
            ExprKind::Name(n) => {
                if let Some((_, m)) = scope.iter().rev().find(|(k, _)| k == n) {
                    return Ok(m.clone());
                }
                match self.consts.get(n) {
                    Some(m) => Ok(self.constant(m)),
                    None => unsupported(format!("unknown name `{n}`")),
                }
            }
            ExprKind::Neg(a) => {
                let m = self.lower(a, scope, d, calls)?;
                Ok(self.map(&m, |b, v| b.un(Unary::Neg, v)))
            }
            ExprKind::Transpose(a) => {
                let m = self.lower(a, scope, d, calls)?;
                Ok(SymMat::from_fn(m.cols, m.rows, |i, j| m.at(j, i)))
            }
            ExprKind::Matrix(rows) => {
                let mut blocks = Vec::new();
                for row in rows {
                    let vals = row
                        .iter()
                        .map(|x| self.lower(x, scope, d, calls))
                        .collect::<Result<Vec<_>, _>>()?;
                    blocks.push(concat(&vals, true)?);
                }
                concat(&blocks, false)
            }
            ExprKind::Binary(op, a, b) => {
                let x = self.lower(a, scope, d, calls)?;
                let y = self.lower(b, scope, d, calls)?;
                if let (Some(cx), Some(cy)) = (self.as_const(&x), self.as_const(&y)) {
                    let kind = |args: Vec<Expr>| {
                        let mut it = args.into_iter();
                        match (it.next(), it.next()) {
                            (Some(l), Some(r)) => ExprKind::Binary(*op, Box::new(l), Box::new(r)),
                            _ => ExprKind::Number(f64::NAN),
                        }
                    };
                    return self.interpret(kind, vec![cx, cy], &[a.span, b.span], e.span);
                }
                self.binary(*op, &x, &y)
            }
            ExprKind::Index(a, idx) => {
                let m = self.lower(a, scope, d, calls)?;
                self.index(m, idx, scope, d, calls)
            }
            ExprKind::Call(f, args) => {
                if args.iter().any(|a| a.name.is_some()) {
                    return unsupported("named arguments");
                }
                let vals = args
                    .iter()
                    .map(|a| self.lower(&a.value, scope, d, calls))
                    .collect::<Result<Vec<_>, _>>()?;
                if let Some(def) = self.fns.get(&f.node) {
                    if def.params.len() != vals.len() || calls >= MAX_CALLS {
                        return unsupported("bad call");
                    }
                    let inner: Vec<(String, SymMat)> =
                        def.params.iter().cloned().zip(vals).collect();
                    return self.lower(&def.body, &inner, d, calls + 1);
                }
                let consts: Option<Vec<Mat>> = vals.iter().map(|v| self.as_const(v)).collect();
                if let Some(consts) = consts {
                    let name = f.clone();
                    let kind = move |args: Vec<Expr>| {
                        ExprKind::Call(
                            name,
                            args.into_iter()
                                .map(|value| Arg { name: None, value })
                                .collect(),
                        )
                    };
                    let spans: Vec<Span> = args.iter().map(|a| a.value.span).collect();
                    return self.interpret(kind, consts, &spans, e.span);
                }
                self.builtin(&f.node, &vals)
            }
        }
    }

    /// Evaluates the operation `kind` on constant operands with the
    /// language's evaluator (operands bound to names no spec can use).
    fn interpret(
        &mut self,
        kind: impl FnOnce(Vec<Expr>) -> ExprKind,
        vals: Vec<Mat>,
        spans: &[Span],
        span: Span,
    ) -> Lowered {
        let names: Vec<String> = (0..vals.len()).map(|k| format!("#{k}")).collect();
        let args = names
            .iter()
            .zip(spans)
            .map(|(n, &span)| Expr {
                kind: ExprKind::Name(n.clone()),
                span,
            })
            .collect();
        let expr = Expr {
            kind: kind(args),
            span,
        };
        let env = Env {
            consts: self.consts,
            fns: self.fns,
            locals: names.into_iter().zip(vals).collect(),
            unavailable: Vec::new(),
            mode: Mode::Exact,
        };
        match env.eval(&expr) {
            Ok(m) => Ok(self.constant(&m)),
            Err(d) => unsupported(d.message),
        }
    }

    fn map(&mut self, m: &SymMat, mut f: impl FnMut(&mut Builder, Id) -> Id) -> SymMat {
        SymMat {
            rows: m.rows,
            cols: m.cols,
            data: m.data.iter().map(|&v| f(&mut self.b, v)).collect(),
        }
    }

    /// `f(x, y)` entry by entry, a scalar side broadcast (the evaluator's rule).
    fn zip(&mut self, f: Binary, x: &SymMat, y: &SymMat) -> Lowered {
        if (x.rows, x.cols) == (y.rows, y.cols) {
            let data = x
                .data
                .iter()
                .zip(&y.data)
                .map(|(&a, &b)| self.b.bin(f, a, b))
                .collect();
            Ok(SymMat { data, ..x.clone() })
        } else if y.is_scalar() {
            let s = y.data[0];
            Ok(self.map(x, |b, v| b.bin(f, v, s)))
        } else if x.is_scalar() {
            let s = x.data[0];
            Ok(self.map(y, |b, v| b.bin(f, s, v)))
        } else {
            unsupported("shape mismatch")
        }
    }

    /// `sum_k a_k` left to right, from the first term.
    fn sum(&mut self, terms: impl IntoIterator<Item = Id>) -> Id {
        let mut acc: Option<Id> = None;
        for t in terms {
            acc = Some(match acc {
                None => t,
                Some(a) => self.b.bin(Binary::Add, a, t),
            });
        }
        acc.unwrap_or_else(|| self.b.constant(0.0))
    }

    /// The matrix product `a * b` (`a.cols == b.rows`), each entry summed
    /// over k in order like nalgebra's small products.
    pub fn product(&mut self, a: &SymMat, b: &SymMat) -> SymMat {
        let mut data = Vec::with_capacity(a.rows * b.cols);
        for j in 0..b.cols {
            for i in 0..a.rows {
                let terms: Vec<Id> = (0..a.cols)
                    .map(|k| self.b.bin(Binary::Mul, a.at(i, k), b.at(k, j)))
                    .collect();
                data.push(self.sum(terms));
            }
        }
        SymMat {
            rows: a.rows,
            cols: b.cols,
            data,
        }
    }

    /// `x + y` for matrices of one shape.
    pub fn add(&mut self, x: &SymMat, y: &SymMat) -> Lowered {
        self.zip(Binary::Add, x, y)
    }

    fn binary(&mut self, op: BinOp, x: &SymMat, y: &SymMat) -> Lowered {
        match op {
            BinOp::Add => self.zip(Binary::Add, x, y),
            BinOp::Sub => self.zip(Binary::Sub, x, y),
            BinOp::Mul if x.is_scalar() || y.is_scalar() => self.zip(Binary::Mul, x, y),
            BinOp::Mul if x.cols == y.rows => Ok(self.product(x, y)),
            BinOp::EMul if (x.rows, x.cols) == (y.rows, y.cols) => self.zip(Binary::Mul, x, y),
            BinOp::EMul if x.is_scalar() || y.is_scalar() => self.zip(Binary::Mul, x, y),
            BinOp::Div if y.is_scalar() => {
                if x.data.is_empty() {
                    // The evaluator checks the divisor even for an empty matrix.
                    let zero = self.b.constant(0.0);
                    self.b.bin(Binary::DivChecked, zero, y.data[0]);
                }
                self.zip(Binary::DivChecked, x, y)
            }
            BinOp::Pow if x.is_scalar() && y.is_scalar() => self.zip(Binary::Pow, x, y),
            BinOp::Pow if y.is_scalar() && x.rows == x.cols => {
                let k = match self.b.value(y.data[0]) {
                    Some(k) if (0.0..=MAX_MATRIX_POWER).contains(&k) && k.fract() == 0.0 => k,
                    _ => return unsupported("matrix power with a state-dependent exponent"),
                };
                Ok(self.power(x, k as u64))
            }
            _ => unsupported("shape mismatch"),
        }
    }

    /// `m ^ k` by repeated squaring, as the evaluator computes it.
    fn power(&mut self, m: &SymMat, mut k: u64) -> SymMat {
        let (one, zero) = (self.b.constant(1.0), self.b.constant(0.0));
        let mut out = SymMat::from_fn(m.rows, m.cols, |i, j| if i == j { one } else { zero });
        let mut base = m.clone();
        while k > 0 {
            if k & 1 == 1 {
                out = self.product(&out, &base);
            }
            k >>= 1;
            if k > 0 {
                base = self.product(&base, &base);
            }
        }
        out
    }

    fn index(
        &mut self,
        m: SymMat,
        idx: &[IndexArg],
        scope: &Scope,
        d: usize,
        calls: usize,
    ) -> Lowered {
        let bound = |this: &mut Self, e: &Expr, max: usize| -> Result<usize, Unsupported> {
            let v = this.lower(e, scope, d, calls)?;
            let value = v.data.first().filter(|_| v.is_scalar());
            match value.and_then(|&id| this.b.value(id)) {
                Some(x) if x.fract() == 0.0 && x >= 0.0 && x <= max as f64 => Ok(x as usize),
                _ => unsupported("state-dependent or invalid index"),
            }
        };
        let range = |this: &mut Self, a: &IndexArg, len: usize| match a {
            IndexArg::Full => Ok((0, len)),
            IndexArg::One(e) => {
                let i = bound(this, e, len.saturating_sub(1))?;
                if len == 0 {
                    return unsupported("index into an empty value");
                }
                Ok((i, i + 1))
            }
            IndexArg::Range(lo, hi) => {
                let (l, h) = (bound(this, lo, len)?, bound(this, hi, len)?);
                if h < l {
                    return unsupported("reversed range");
                }
                Ok((l, h))
            }
        };
        match idx {
            [one] if m.cols == 1 => {
                let (l, h) = range(self, one, m.rows)?;
                Ok(SymMat::column(m.data[l..h].to_vec()))
            }
            [one] if m.rows == 1 => {
                let (l, h) = range(self, one, m.cols)?;
                Ok(SymMat {
                    rows: 1,
                    cols: h - l,
                    data: m.data[l..h].to_vec(),
                })
            }
            [r, c] => {
                let (r0, r1) = range(self, r, m.rows)?;
                let (c0, c1) = range(self, c, m.cols)?;
                Ok(SymMat::from_fn(r1 - r0, c1 - c0, |i, j| {
                    m.at(r0 + i, c0 + j)
                }))
            }
            _ => unsupported("bad index"),
        }
    }

    /// nalgebra's dot product of two columns (eight partial sums from eight
    /// rows on), as its `norm` uses it.
    fn column_dot(&mut self, a: &[Id], b: &[Id]) -> Id {
        let mut acc = [None::<Id>; 8];
        let mut i = 0;
        while a.len() - i >= 8 {
            for (k, slot) in acc.iter_mut().enumerate() {
                let p = self.b.bin(Binary::Mul, a[i + k], b[i + k]);
                *slot = Some(match *slot {
                    None => p,
                    Some(s) => self.b.bin(Binary::Add, s, p),
                });
            }
            i += 8;
        }
        let zero = self.b.constant(0.0);
        let mut res = zero;
        for (p, q) in [(0, 4), (1, 5), (2, 6), (3, 7)] {
            let s = self
                .b
                .bin(Binary::Add, acc[p].unwrap_or(zero), acc[q].unwrap_or(zero));
            res = self.b.bin(Binary::Add, res, s);
        }
        for k in i..a.len() {
            let p = self.b.bin(Binary::Mul, a[k], b[k]);
            res = self.b.bin(Binary::Add, res, p);
        }
        res
    }

    /// A built-in function of operands not all constant.
    fn builtin(&mut self, name: &str, a: &[SymMat]) -> Lowered {
        if let Some(f) = Unary::builtin(name) {
            return match a {
                [m] => Ok(self.map(m, |b, v| b.un(f, v))),
                _ => unsupported("arity"),
            };
        }
        let f2 = match name {
            "atan2" => Some(Binary::Atan2),
            "min" => Some(Binary::Min),
            "max" => Some(Binary::Max),
            _ => None,
        };
        if let Some(f) = f2 {
            return match a {
                [x, y] => self.zip(f, x, y),
                _ => unsupported("arity"),
            };
        }
        match (name, a) {
            ("transpose", [m]) => Ok(SymMat::from_fn(m.cols, m.rows, |i, j| m.at(j, i))),
            ("norm", [m]) => {
                let mut total = self.b.constant(0.0);
                for col in m.data.chunks(m.rows.max(1)) {
                    let d = self.column_dot(col, col);
                    total = self.b.bin(Binary::Add, total, d);
                }
                Ok(scalar(self.b.un(Unary::Sqrt, total)))
            }
            ("sum", [m]) => {
                let zero = self.b.constant(0.0);
                let s = self.sum(std::iter::once(zero).chain(m.data.iter().copied()));
                Ok(scalar(s))
            }
            ("mean", [m]) if !m.data.is_empty() => {
                let zero = self.b.constant(0.0);
                let s = self.sum(std::iter::once(zero).chain(m.data.iter().copied()));
                let len = self.b.constant(m.data.len() as f64);
                Ok(scalar(self.b.bin(Binary::Div, s, len)))
            }
            ("dot", [p, q]) if p.is_vector() && q.is_vector() && p.data.len() == q.data.len() => {
                let terms: Vec<Id> = p
                    .data
                    .iter()
                    .zip(&q.data)
                    .map(|(&x, &y)| self.b.bin(Binary::Mul, x, y))
                    .collect();
                let s = self.sum(terms);
                Ok(scalar(s))
            }
            ("cross", [p, q]) if vec3(p) && vec3(q) => {
                let (p, q) = (&p.data, &q.data);
                let mut minus = |i: usize, j: usize| {
                    let l = self.b.bin(Binary::Mul, p[i], q[j]);
                    let r = self.b.bin(Binary::Mul, p[j], q[i]);
                    self.b.bin(Binary::Sub, l, r)
                };
                let c = vec![minus(1, 2), minus(2, 0), minus(0, 1)];
                Ok(SymMat::column(c))
            }
            ("skew", [v]) if vec3(v) => {
                let v = &v.data;
                let zero = self.b.constant(0.0);
                let n: Vec<Id> = v.iter().map(|&x| self.b.un(Unary::Neg, x)).collect();
                // Row-major [0, -v2, v1; v2, 0, -v0; -v1, v0, 0].
                let rows = [[zero, n[2], v[1]], [v[2], zero, n[0]], [n[1], v[0], zero]];
                Ok(SymMat::from_fn(3, 3, |i, j| rows[i][j]))
            }
            ("trace", [m]) if m.rows == m.cols => {
                let zero = self.b.constant(0.0);
                let s = self.sum(std::iter::once(zero).chain((0..m.rows).map(|i| m.at(i, i))));
                Ok(scalar(s))
            }
            ("diag", [m]) if m.is_vector() => {
                let zero = self.b.constant(0.0);
                let n = m.data.len();
                Ok(SymMat::from_fn(
                    n,
                    n,
                    |i, j| if i == j { m.data[i] } else { zero },
                ))
            }
            ("diag", [m]) if m.rows == m.cols => {
                Ok(SymMat::column((0..m.rows).map(|i| m.at(i, i)).collect()))
            }
            ("blkdiag", _) => {
                let zero = self.b.constant(0.0);
                let rows: usize = a.iter().map(|m| m.rows).sum();
                let cols: usize = a.iter().map(|m| m.cols).sum();
                let mut out = SymMat::from_fn(rows, cols, |_, _| zero);
                let (mut i0, mut j0) = (0, 0);
                for m in a {
                    for j in 0..m.cols {
                        for i in 0..m.rows {
                            out.data[(j0 + j) * rows + i0 + i] = m.at(i, j);
                        }
                    }
                    i0 += m.rows;
                    j0 += m.cols;
                }
                Ok(out)
            }
            _ => unsupported(format!("`{name}` of a state-dependent value")),
        }
    }
}

fn scalar(id: Id) -> SymMat {
    SymMat::column(vec![id])
}

fn vec3(m: &SymMat) -> bool {
    m.data.len() == 3 && m.is_vector()
}

/// Side by side (`across`) or stacked, with the evaluator's shape checks.
fn concat(parts: &[SymMat], across: bool) -> Lowered {
    let Some(first) = parts.first() else {
        return Ok(SymMat {
            rows: 0,
            cols: 0,
            data: Vec::new(),
        });
    };
    let (h, w) = (first.rows, first.cols);
    if across {
        if parts.iter().any(|p| p.rows != h) {
            return unsupported("matrix row mixes heights");
        }
        let data = parts.iter().flat_map(|p| p.data.iter().copied()).collect();
        let cols = parts.iter().map(|p| p.cols).sum();
        Ok(SymMat {
            rows: h,
            cols,
            data,
        })
    } else {
        if parts.iter().any(|p| p.cols != w) {
            return unsupported("matrix rows have different widths");
        }
        let rows: usize = parts.iter().map(|p| p.rows).sum();
        let mut starts = Vec::with_capacity(parts.len());
        let mut r0 = 0;
        for p in parts {
            starts.push(r0);
            r0 += p.rows;
        }
        Ok(SymMat::from_fn(rows, w, |i, j| {
            let k = starts.iter().rposition(|&s| s <= i).unwrap_or(0);
            parts[k].at(i - starts[k], j)
        }))
    }
}
