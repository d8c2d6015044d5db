//! The built-in functions (`eye`, `inv`, `sin`, `blkdiag`, ...) and what each costs.

use super::{is_scalar, scalar, shape, Mat, Mode, R};
use crate::diag::Diagnostic;
use crate::num::Num;
use crate::span::Span;
use nalgebra::DMatrix;

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
    "exprel",
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

pub(super) fn arity(name: &str, span: Span, want: usize, got: usize) -> Diagnostic {
    Diagnostic::error(
        span,
        format!(
            "`{name}` takes {want} argument{}, {got} given",
            if want == 1 { "" } else { "s" }
        ),
    )
    .with_label("wrong number of arguments")
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
                        Num(x).to_string()
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

/// One call of a built-in: its name, its arguments and their spans.
struct Call<'a> {
    name: &'a str,
    /// The span of the name.
    ns: Span,
    a: &'a [Mat],
    s: &'a [Span],
    /// The span of the whole call.
    sp: Span,
    mode: Mode,
}

impl Call<'_> {
    /// `Ok` if the call has `n` arguments.
    fn want(&self, n: usize) -> Result<(), Diagnostic> {
        if self.a.len() == n {
            Ok(())
        } else {
            Err(arity(self.name, self.ns, n, self.a.len()))
        }
    }

    /// `Ok` if `m` (the argument at span `s`) is square.
    fn square(&self, m: &Mat, s: Span) -> Result<(), Diagnostic> {
        if m.nrows() == m.ncols() {
            Ok(())
        } else {
            Err(Diagnostic::error(
                s,
                format!("`{}` needs a square matrix, found {}", self.name, shape(m)),
            ))
        }
    }

    /// `zeros(n)`, `ones(n)`, `zeros(r, c)`, `ones(r, c)`.
    fn filled(&self) -> R {
        let (name, a, s) = (self.name, self.a, self.s);
        let v = if name == "zeros" { 0.0 } else { 1.0 };
        match a.len() {
            1 => Ok(DMatrix::from_element(dim_arg(&a[0], s[0])?, 1, v)),
            2 => Ok(DMatrix::from_element(
                dim_arg(&a[0], s[0])?,
                dim_arg(&a[1], s[1])?,
                v,
            )),
            n => Err(arity(name, self.ns, 2, n).with_help(format!(
                "`{name}(n)` is an n-vector, `{name}(r, c)` an r x c matrix"
            ))),
        }
    }

    /// `diag(v)` of a vector (a diagonal matrix) or of a square matrix (its diagonal).
    fn diag(&self) -> R {
        self.want(1)?;
        let m = &self.a[0];
        if m.ncols() == 1 || m.nrows() == 1 {
            let v: Vec<f64> = m.iter().copied().collect();
            Ok(DMatrix::from_diagonal(&nalgebra::DVector::from_vec(v)))
        } else {
            self.square(m, self.s[0])?;
            Ok(DMatrix::from_column_slice(
                m.nrows(),
                1,
                m.diagonal().as_slice(),
            ))
        }
    }

    /// `inv(m)`: refused when singular or (exact mode) badly conditioned.
    fn inv(&self) -> R {
        let (a, s) = (self.a, self.s);
        self.want(1)?;
        self.square(&a[0], s[0])?;
        match a[0].clone().try_inverse() {
            Some(m) if m.iter().all(|v| v.is_finite()) => {
                let cond = a[0].norm() * m.norm();
                if cond > 1e14 && self.mode == Mode::Exact {
                    Err(singular(
                        self.sp,
                        s[0],
                        &format!("its condition number is about {cond:.1e}"),
                    ))
                } else {
                    Ok(m)
                }
            }
            _ if self.mode == Mode::Shapes => Ok(DMatrix::zeros(a[0].nrows(), a[0].ncols())),
            _ => Err(singular(self.sp, s[0], "its determinant is 0")),
        }
    }

    /// A function of one scalar, applied element by element.
    fn unary(&self) -> R {
        self.want(1)?;
        let f: fn(f64) -> f64 = match self.name {
            "sqrt" => f64::sqrt,
            "sin" => f64::sin,
            "cos" => f64::cos,
            "tan" => f64::tan,
            "atan" => f64::atan,
            "exp" => f64::exp,
            "log" => f64::ln,
            "abs" => f64::abs,
            "sign" => tsf_runtime::math::sign,
            // The runtime's exprel and sinc, so that model and generated code agree.
            "exprel" => tsf_runtime::math::exprel,
            _ => tsf_runtime::math::sinc,
        };
        Ok(elementwise(&self.a[0], f))
    }

    /// `atan2`, `min`, `max`: element by element, a scalar broadcast.
    fn binary(&self) -> R {
        let name = self.name;
        self.want(2)?;
        let f: fn(f64, f64) -> f64 = match name {
            "atan2" => f64::atan2,
            "min" => f64::min,
            _ => f64::max,
        };
        let (x, y) = (&self.a[0], &self.a[1]);
        if x.shape() == y.shape() {
            Ok(x.zip_map(y, f))
        } else if is_scalar(y) {
            Ok(x.map(|v| f(v, y[(0, 0)])))
        } else if is_scalar(x) {
            Ok(y.map(|v| f(x[(0, 0)], v)))
        } else {
            Err(Diagnostic::error(
                self.sp,
                format!(
                    "`{name}` needs arguments of the same shape, found {} and {}",
                    shape(x),
                    shape(y)
                ),
            ))
        }
    }

    /// `mean(v)`, refused for an empty value.
    fn mean(&self) -> R {
        self.want(1)?;
        if self.a[0].is_empty() {
            return Err(Diagnostic::error(self.s[0], "`mean` of an empty value"));
        }
        Ok(scalar(self.a[0].mean()))
    }

    /// `dot(p, q)` of two vectors of one length.
    fn dot(&self) -> R {
        let a = self.a;
        self.want(2)?;
        if a[0].len() != a[1].len()
            || !(a[0].ncols() == 1 || a[0].nrows() == 1)
            || !(a[1].ncols() == 1 || a[1].nrows() == 1)
        {
            return Err(Diagnostic::error(
                self.sp,
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

    /// `cross(p, q)` of two 3-vectors.
    fn cross(&self) -> R {
        self.want(2)?;
        let p = need_vec3(&self.a[0], self.s[0], self.name)?;
        let q = need_vec3(&self.a[1], self.s[1], self.name)?;
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

    /// `skew(v)`: the cross-product matrix of a 3-vector.
    fn skew(&self) -> R {
        self.want(1)?;
        let v = need_vec3(&self.a[0], self.s[0], self.name)?;
        Ok(DMatrix::from_row_slice(
            3,
            3,
            &[0.0, -v[2], v[1], v[2], 0.0, -v[0], -v[1], v[0], 0.0],
        ))
    }

    /// `blkdiag(m1, m2, ...)`: the block-diagonal matrix of any number of blocks.
    fn blkdiag(&self) -> R {
        let r: usize = self.a.iter().map(|m| m.nrows()).sum();
        let c: usize = self.a.iter().map(|m| m.ncols()).sum();
        let mut out = DMatrix::zeros(r, c);
        let (mut i, mut j) = (0, 0);
        for m in self.a {
            out.view_mut((i, j), (m.nrows(), m.ncols())).copy_from(m);
            i += m.nrows();
            j += m.ncols();
        }
        Ok(out)
    }
}

pub(super) fn builtin(name: &str, ns: Span, a: &[Mat], s: &[Span], sp: Span, mode: Mode) -> R {
    let call = Call {
        name,
        ns,
        a,
        s,
        sp,
        mode,
    };
    let want = |n: usize| call.want(n);
    match name {
        "pi" => want(0).map(|_| scalar(std::f64::consts::PI)),
        "eye" => {
            want(1)?;
            let n = dim_arg(&a[0], s[0])?;
            Ok(DMatrix::identity(n, n))
        }
        "zeros" | "ones" => call.filled(),
        "diag" => call.diag(),
        "inv" => call.inv(),
        "det" => {
            want(1)?;
            call.square(&a[0], s[0])?;
            Ok(scalar(a[0].determinant()))
        }
        "trace" => {
            want(1)?;
            call.square(&a[0], s[0])?;
            Ok(scalar(a[0].trace()))
        }
        "transpose" => want(1).map(|_| a[0].transpose()),
        "sqrt" | "sin" | "cos" | "tan" | "atan" | "exp" | "log" | "abs" | "sign" | "sinc"
        | "exprel" => call.unary(),
        "atan2" | "min" | "max" => call.binary(),
        "norm" => want(1).map(|_| scalar(a[0].norm())),
        "sum" => want(1).map(|_| scalar(a[0].sum())),
        "mean" => call.mean(),
        "dot" => call.dot(),
        "cross" => call.cross(),
        "skew" => call.skew(),
        "blkdiag" => call.blkdiag(),
        _ => Err(Diagnostic::error(ns, format!("unknown function `{name}`"))),
    }
}

fn singular(sp: Span, arg: Span, why: &str) -> Diagnostic {
    Diagnostic::error(sp, "matrix is singular and cannot be inverted")
        .with_label("inverse of a singular matrix")
        .with_secondary(arg, why.to_string())
        .with_help("check the matrix entries (an inertia or mass matrix must be positive definite)")
}

/// The work of calling built-in `name` on `a` beyond visiting the node: the
/// elements it creates, or the multiply-adds of an inverse or determinant.
/// Paid before the call, so a huge matrix is refused before it is allocated.
pub(super) fn work(name: &str, a: &[Mat]) -> u64 {
    let dim = |m: &Mat| {
        if is_scalar(m) && m[(0, 0)] >= 0.0 {
            m[(0, 0)].min(1e9) as u64
        } else {
            0
        }
    };
    let cube = |m: &Mat| (m.nrows() as u64).pow(3);
    let inputs = a.iter().map(|m| m.len() as u64).sum::<u64>();
    match (name, a) {
        ("eye", [n]) => dim(n).saturating_mul(dim(n)),
        ("zeros" | "ones", [n]) => dim(n),
        ("zeros" | "ones", [r, c]) => dim(r).saturating_mul(dim(c)),
        ("diag", [v]) if v.ncols() == 1 || v.nrows() == 1 => (v.len() as u64).pow(2),
        ("inv" | "det", [m]) => cube(m),
        ("blkdiag", _) => {
            let r: u64 = a.iter().map(|m| m.nrows() as u64).sum();
            let c: u64 = a.iter().map(|m| m.ncols() as u64).sum();
            r.saturating_mul(c)
        }
        _ => inputs,
    }
}
