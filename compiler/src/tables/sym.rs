//! Scalar symbolic expressions of the state, for premise variables in
//! generated code. A `.tsf` expression (matrices of known shape) is expanded
//! entry by entry into scalar trees over `x[k]`, folded, and then either
//! recognized as linear (`z = L x`, evaluated by the runtime) or emitted as
//! straight-line code by the Rust and C generators.

use std::collections::HashMap;
use tsf_lang::ast::{BinOp, Expr, ExprKind, IndexArg};
use tsf_lang::spec::Spec;

/// Scalar functions generated code may call.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Func {
    /// sin
    Sin,
    /// cos
    Cos,
    /// exp
    Exp,
    /// sqrt
    Sqrt,
    /// atan
    Atan,
    /// |v|
    Abs,
    /// sin(v)/v with 1 at 0 (the runtime's `math::sinc`, with its
    /// small-argument branch)
    Sinc,
    /// (e^v - 1)/v with 1 at 0 (the runtime's `math::exprel`, with its
    /// series branch)
    Exprel,
}

impl Func {
    /// The name used in the language, the runtime and C's math.h (sinc and exprel are ours).
    pub fn name(self) -> &'static str {
        match self {
            Func::Sin => "sin",
            Func::Cos => "cos",
            Func::Exp => "exp",
            Func::Sqrt => "sqrt",
            Func::Atan => "atan",
            Func::Abs => "fabs",
            Func::Sinc => "sinc",
            Func::Exprel => "exprel",
        }
    }

    fn eval(self, v: f64) -> f64 {
        match self {
            Func::Sin => v.sin(),
            Func::Cos => v.cos(),
            Func::Exp => v.exp(),
            Func::Sqrt => v.sqrt(),
            Func::Atan => v.atan(),
            Func::Abs => v.abs(),
            Func::Sinc => tsf_runtime::math::sinc(v),
            Func::Exprel => tsf_runtime::math::exprel(v),
        }
    }
}

/// A scalar expression of the state.
#[derive(Debug, Clone, PartialEq)]
pub enum Sym {
    /// A constant.
    Const(f64),
    /// State component `x[k]`.
    X(usize),
    /// Sum.
    Add(Box<Sym>, Box<Sym>),
    /// Product.
    Mul(Box<Sym>, Box<Sym>),
    /// Quotient.
    Div(Box<Sym>, Box<Sym>),
    /// Negation.
    Neg(Box<Sym>),
    /// Function call.
    Call(Func, Box<Sym>),
}

fn c(v: f64) -> Sym {
    Sym::Const(v)
}

impl Sym {
    fn add(a: Sym, b: Sym) -> Sym {
        match (a, b) {
            (Sym::Const(x), Sym::Const(y)) => c(x + y),
            (Sym::Const(z), o) | (o, Sym::Const(z)) if z == 0.0 => o,
            (a, b) => Sym::Add(Box::new(a), Box::new(b)),
        }
    }

    fn mul(a: Sym, b: Sym) -> Sym {
        match (a, b) {
            (Sym::Const(x), Sym::Const(y)) => c(x * y),
            (Sym::Const(z), _) | (_, Sym::Const(z)) if z == 0.0 => c(0.0),
            (Sym::Const(o), e) | (e, Sym::Const(o)) if o == 1.0 => e,
            (a, b) => Sym::Mul(Box::new(a), Box::new(b)),
        }
    }

    fn neg(a: Sym) -> Sym {
        match a {
            Sym::Const(x) => c(-x),
            Sym::Neg(e) => *e,
            e => Sym::Neg(Box::new(e)),
        }
    }

    fn div(a: Sym, b: Sym) -> Sym {
        match (a, b) {
            (Sym::Const(x), Sym::Const(y)) => c(x / y),
            (e, Sym::Const(1.0)) => e,
            (Sym::Const(0.0), _) => c(0.0),
            (a, b) => Sym::Div(Box::new(a), Box::new(b)),
        }
    }

    fn call(f: Func, a: Sym) -> Sym {
        match a {
            Sym::Const(x) => c(f.eval(x)),
            a => Sym::Call(f, Box::new(a)),
        }
    }

    /// The coefficients `l` with `self == l . x` if the expression is linear
    /// (and has no constant term), else `None`.
    pub fn linear(&self, n: usize) -> Option<Vec<f64>> {
        fn go(s: &Sym, scale: f64, out: &mut [f64]) -> Option<f64> {
            // Returns the constant term.
            match s {
                Sym::Const(v) => Some(scale * v),
                Sym::X(k) => {
                    *out.get_mut(*k)? += scale;
                    Some(0.0)
                }
                Sym::Add(a, b) => Some(go(a, scale, out)? + go(b, scale, out)?),
                Sym::Neg(a) => go(a, -scale, out),
                Sym::Mul(a, b) => match (&**a, &**b) {
                    (Sym::Const(k), e) | (e, Sym::Const(k)) => go(e, scale * k, out),
                    _ => None,
                },
                Sym::Div(a, b) => match &**b {
                    Sym::Const(k) => go(a, scale / k, out),
                    _ => None,
                },
                Sym::Call(..) => None,
            }
        }
        let mut l = vec![0.0; n];
        let k = go(self, 1.0, &mut l)?;
        (k == 0.0).then_some(l)
    }

    /// Evaluates at state `x` (with the same scalar functions as the language).
    pub fn eval(&self, x: &[f64]) -> f64 {
        match self {
            Sym::Const(v) => *v,
            Sym::X(k) => x.get(*k).copied().unwrap_or(f64::NAN),
            Sym::Add(a, b) => a.eval(x) + b.eval(x),
            Sym::Mul(a, b) => a.eval(x) * b.eval(x),
            Sym::Div(a, b) => a.eval(x) / b.eval(x),
            Sym::Neg(a) => -a.eval(x),
            Sym::Call(f, a) => f.eval(a.eval(x)),
        }
    }

    /// The functions this expression calls (to import or declare them).
    pub fn functions(&self, out: &mut Vec<Func>) {
        match self {
            Sym::Const(_) | Sym::X(_) => {}
            Sym::Add(a, b) | Sym::Mul(a, b) | Sym::Div(a, b) => {
                a.functions(out);
                b.functions(out);
            }
            Sym::Neg(a) => a.functions(out),
            Sym::Call(f, a) => {
                if !out.contains(f) {
                    out.push(*f);
                }
                a.functions(out);
            }
        }
    }
}

/// A matrix of scalar expressions (column-major like the language's values).
#[derive(Debug, Clone)]
struct SymMat {
    rows: usize,
    cols: usize,
    data: Vec<Sym>,
}

impl SymMat {
    fn at(&self, i: usize, j: usize) -> Sym {
        self.data
            .get(j * self.rows + i)
            .cloned()
            .unwrap_or(c(f64::NAN))
    }

    fn from_fn(rows: usize, cols: usize, f: impl Fn(usize, usize) -> Sym) -> SymMat {
        let mut data = Vec::with_capacity(rows * cols);
        for j in 0..cols {
            for i in 0..rows {
                data.push(f(i, j));
            }
        }
        SymMat { rows, cols, data }
    }

    fn scalar(s: Sym) -> SymMat {
        SymMat {
            rows: 1,
            cols: 1,
            data: vec![s],
        }
    }

    fn is_scalar(&self) -> bool {
        self.rows == 1 && self.cols == 1
    }

    fn as_const(&self) -> Option<f64> {
        match (self.is_scalar(), self.data.first()) {
            (true, Some(Sym::Const(v))) => Some(*v),
            _ => None,
        }
    }
}

/// Why an expression cannot be generated (a sentence for the user).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SymError(String);

impl std::fmt::Display for SymError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for SymError {}

impl From<String> for SymError {
    fn from(s: String) -> Self {
        SymError(s)
    }
}

impl From<&str> for SymError {
    fn from(s: &str) -> Self {
        SymError(s.to_string())
    }
}

struct Ctx<'a> {
    spec: &'a Spec,
    locals: HashMap<String, SymMat>,
    depth: usize,
}

/// Expands a premise expression of the state into scalar expressions (its entries).
pub fn premise_entries(spec: &Spec, e: &Expr) -> Result<Vec<Sym>, SymError> {
    let n = spec.n();
    let mut locals = HashMap::new();
    locals.insert("x".to_string(), SymMat::from_fn(n, 1, |i, _| Sym::X(i)));
    for s in &spec.states {
        locals.insert(
            s.name.clone(),
            SymMat::from_fn(s.len, 1, |i, _| Sym::X(s.offset + i)),
        );
    }
    let cx = Ctx {
        spec,
        locals,
        depth: 0,
    };
    Ok(cx.eval(e)?.data)
}

impl Ctx<'_> {
    fn eval(&self, e: &Expr) -> Result<SymMat, SymError> {
        match &e.kind {
            ExprKind::Number(v) => Ok(SymMat::scalar(c(*v))),
            ExprKind::Name(n) => {
                if let Some(m) = self.locals.get(n) {
                    return Ok(m.clone());
                }
                let v =
                    self.spec.consts.get(n).ok_or_else(|| {
                        format!("`{n}` is not available in generated premise code")
                    })?;
                Ok(SymMat::from_fn(v.nrows(), v.ncols(), |i, j| c(v[(i, j)])))
            }
            ExprKind::Neg(a) => {
                let m = self.eval(a)?;
                Ok(SymMat {
                    data: m.data.into_iter().map(Sym::neg).collect(),
                    ..m
                })
            }
            ExprKind::Transpose(a) => {
                let m = self.eval(a)?;
                Ok(SymMat::from_fn(m.cols, m.rows, |i, j| m.at(j, i)))
            }
            ExprKind::Matrix(rows) => self.matrix(rows),
            ExprKind::Binary(op, a, b) => self.binary(*op, self.eval(a)?, self.eval(b)?),
            ExprKind::Index(a, idx) => self.index(self.eval(a)?, idx),
            ExprKind::Call(f, args) => {
                let vals = args
                    .iter()
                    .map(|a| self.eval(&a.value))
                    .collect::<Result<Vec<_>, _>>()?;
                self.call(&f.node, vals)
            }
        }
    }

    fn matrix(&self, rows: &[Vec<Expr>]) -> Result<SymMat, SymError> {
        let mut blocks = Vec::new();
        for row in rows {
            let vals = row
                .iter()
                .map(|x| self.eval(x))
                .collect::<Result<Vec<_>, _>>()?;
            let h = vals.first().map_or(0, |m| m.rows);
            let w: usize = vals.iter().map(|m| m.cols).sum();
            let mut cells = vec![c(0.0); h * w];
            let mut col = 0;
            for v in &vals {
                for j in 0..v.cols {
                    for i in 0..v.rows.min(h) {
                        cells[(col + j) * h + i] = v.at(i, j);
                    }
                }
                col += v.cols;
            }
            blocks.push(SymMat {
                rows: h,
                cols: w,
                data: cells,
            });
        }
        let w = blocks.first().map_or(0, |b| b.cols);
        let h: usize = blocks.iter().map(|b| b.rows).sum();
        let mut starts = Vec::new();
        let mut r0 = 0;
        for b in &blocks {
            starts.push(r0);
            r0 += b.rows;
        }
        Ok(SymMat::from_fn(h, w, |i, j| {
            let k = starts.iter().rposition(|s| *s <= i).unwrap_or(0);
            blocks[k].at(i - starts[k], j)
        }))
    }

    fn binary(&self, op: BinOp, a: SymMat, b: SymMat) -> Result<SymMat, SymError> {
        let elementwise = |f: fn(Sym, Sym) -> Sym| -> Result<SymMat, SymError> {
            if a.rows == b.rows && a.cols == b.cols {
                Ok(SymMat::from_fn(a.rows, a.cols, |i, j| {
                    f(a.at(i, j), b.at(i, j))
                }))
            } else if b.is_scalar() {
                Ok(SymMat::from_fn(a.rows, a.cols, |i, j| {
                    f(a.at(i, j), b.at(0, 0))
                }))
            } else if a.is_scalar() {
                Ok(SymMat::from_fn(b.rows, b.cols, |i, j| {
                    f(a.at(0, 0), b.at(i, j))
                }))
            } else {
                Err("shape mismatch".into())
            }
        };
        match op {
            BinOp::Add => elementwise(Sym::add),
            BinOp::Sub => elementwise(|x, y| Sym::add(x, Sym::neg(y))),
            BinOp::EMul => elementwise(Sym::mul),
            BinOp::Div if b.is_scalar() => elementwise(Sym::div),
            BinOp::Mul if a.is_scalar() || b.is_scalar() => elementwise(Sym::mul),
            BinOp::Mul if a.cols == b.rows => Ok(SymMat::from_fn(a.rows, b.cols, |i, j| {
                (0..a.cols).fold(c(0.0), |acc, k| Sym::add(acc, Sym::mul(a.at(i, k), b.at(k, j))))
            })),
            BinOp::Pow if a.is_scalar() => match b.as_const() {
                Some(k) if k.fract() == 0.0 && (0.0..=16.0).contains(&k) => {
                    Ok(SymMat::scalar((0..k as usize).fold(c(1.0), |acc, _| Sym::mul(acc, a.at(0, 0)))))
                }
                _ => match (a.as_const(), b.as_const()) {
                    (Some(x), Some(y)) => Ok(SymMat::scalar(c(x.powf(y)))),
                    _ => Err("only constant whole powers (0 to 16) are supported in generated premise code".into()),
                },
            },
            _ => Err("this operation is not supported in generated premise code".into()),
        }
    }

    fn index(&self, m: SymMat, idx: &[IndexArg]) -> Result<SymMat, SymError> {
        let range = |a: &IndexArg, len: usize| -> Result<(usize, usize), SymError> {
            let int = |e: &Expr| -> Result<usize, SymError> {
                match self.eval(e)?.as_const() {
                    Some(v) if v.fract() == 0.0 && v >= 0.0 && (v as usize) <= len => {
                        Ok(v as usize)
                    }
                    _ => Err("indices must be constant".into()),
                }
            };
            match a {
                IndexArg::Full => Ok((0, len)),
                IndexArg::One(e) => {
                    let i = int(e)?;
                    Ok((i, i + 1))
                }
                IndexArg::Range(a, b) => Ok((int(a)?, int(b)?)),
            }
        };
        match idx {
            [one] if m.cols == 1 => {
                let (a, b) = range(one, m.rows)?;
                Ok(SymMat::from_fn(b.saturating_sub(a), 1, |i, _| {
                    m.at(a + i, 0)
                }))
            }
            [one] if m.rows == 1 => {
                let (a, b) = range(one, m.cols)?;
                Ok(SymMat::from_fn(1, b.saturating_sub(a), |_, j| {
                    m.at(0, a + j)
                }))
            }
            [r, cc] => {
                let (r0, r1) = range(r, m.rows)?;
                let (c0, c1) = range(cc, m.cols)?;
                Ok(SymMat::from_fn(
                    r1.saturating_sub(r0),
                    c1.saturating_sub(c0),
                    |i, j| m.at(r0 + i, c0 + j),
                ))
            }
            _ => Err("unsupported indexing".into()),
        }
    }

    fn call(&self, name: &str, a: Vec<SymMat>) -> Result<SymMat, SymError> {
        let one = |a: &[SymMat]| -> Result<SymMat, SymError> {
            a.first()
                .cloned()
                .ok_or_else(|| format!("`{name}` needs an argument").into())
        };
        let func = match name {
            "sin" => Some(Func::Sin),
            "cos" => Some(Func::Cos),
            "exp" => Some(Func::Exp),
            "sqrt" => Some(Func::Sqrt),
            "atan" => Some(Func::Atan),
            "abs" => Some(Func::Abs),
            "sinc" => Some(Func::Sinc),
            "exprel" => Some(Func::Exprel),
            _ => None,
        };
        if let Some(f) = func {
            let m = one(&a)?;
            return Ok(SymMat {
                data: m.data.into_iter().map(|s| Sym::call(f, s)).collect(),
                ..m
            });
        }
        match name {
            "sum" | "mean" => {
                let m = one(&a)?;
                let len = m.data.len().max(1) as f64;
                let s = m.data.into_iter().fold(c(0.0), Sym::add);
                Ok(SymMat::scalar(if name == "mean" {
                    Sym::div(s, c(len))
                } else {
                    s
                }))
            }
            "dot" => match a.as_slice() {
                [p, q] if p.data.len() == q.data.len() => Ok(SymMat::scalar(
                    p.data.iter().zip(&q.data).fold(c(0.0), |acc, (x, y)| {
                        Sym::add(acc, Sym::mul(x.clone(), y.clone()))
                    }),
                )),
                _ => Err("`dot` needs two vectors of one length".into()),
            },
            "norm" => {
                let m = one(&a)?;
                let s = m.data.iter().fold(c(0.0), |acc, x| {
                    Sym::add(acc, Sym::mul(x.clone(), x.clone()))
                });
                Ok(SymMat::scalar(Sym::call(Func::Sqrt, s)))
            }
            "transpose" => {
                let m = one(&a)?;
                Ok(SymMat::from_fn(m.cols, m.rows, |i, j| m.at(j, i)))
            }
            _ if self.depth < 32 => {
                let f = self.spec.fns.get(name).ok_or_else(|| {
                    format!("`{name}` is not supported in generated premise code")
                })?;
                let mut locals = HashMap::new();
                for (p, v) in f.params.iter().zip(a) {
                    locals.insert(p.clone(), v);
                }
                Ctx {
                    spec: self.spec,
                    locals,
                    depth: self.depth + 1,
                }
                .eval(&f.body)
            }
            _ => Err(format!("`{name}` nests too deeply").into()),
        }
    }
}
