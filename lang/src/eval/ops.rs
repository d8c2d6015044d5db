//! The binary operators: `+ - * .* / ^` with scalar broadcasting.

use super::{is_scalar, scalar, shape, Mat, Mode, R};
use crate::ast::BinOp;
use crate::diag::Diagnostic;
use crate::limits::MAX_MATRIX_POWER;
use crate::num::Num;
use crate::span::Span;
use nalgebra::DMatrix;

pub(super) fn binary(op: BinOp, x: Mat, y: Mat, xs: Span, ys: Span, sp: Span, mode: Mode) -> R {
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
            if !is_scalar(&y) || x.nrows() != x.ncols() {
                return Err(mismatch(
                    "`^`",
                    "use scalar ^ scalar, or a square matrix ^ a non-negative integer",
                ));
            }
            let k = y[(0, 0)];
            if !(0.0..=MAX_MATRIX_POWER).contains(&k) || k.fract() != 0.0 {
                return Err(Diagnostic::error(
                    ys,
                    format!("matrix power exponent {} is not allowed", Num(k)),
                )
                .with_label(format!(
                    "the exponent of a matrix power must be a whole number from 0 to {}",
                    Num(MAX_MATRIX_POWER)
                ))
                .with_secondary(xs, format!("this is {}", shape(&x)))
                .with_help(format!(
                    "at most {} (MAX_MATRIX_POWER); for a real power of a scalar, both sides must be scalars",
                    Num(MAX_MATRIX_POWER)
                )));
            }
            Ok(power(&x, k as u64))
        }
    }
}

/// `m ^ k` by repeated squaring: about 2 log2(k) products.
fn power(m: &Mat, mut k: u64) -> Mat {
    let mut out = DMatrix::identity(m.nrows(), m.ncols());
    let mut base = m.clone();
    while k > 0 {
        if k & 1 == 1 {
            out = &out * &base;
        }
        k >>= 1;
        if k > 0 {
            base = &base * &base;
        }
    }
    out
}

/// The work of `x op y` beyond visiting the node: the multiply-adds of a
/// product or power (sums and element-wise operations cost what their
/// operands did to build).
pub(super) fn work(op: BinOp, x: &Mat, y: &Mat) -> u64 {
    let product = |a: &Mat, b: &Mat| (a.nrows() as u64) * (a.ncols() as u64) * (b.ncols() as u64);
    match op {
        BinOp::Mul if !is_scalar(x) && !is_scalar(y) => product(x, y),
        BinOp::Pow if !is_scalar(x) && is_scalar(y) && y[(0, 0)].is_finite() => {
            let k = y[(0, 0)].clamp(1.0, MAX_MATRIX_POWER);
            let steps = 2 * (64 - (k as u64).leading_zeros()) as u64;
            steps.saturating_mul(product(x, x))
        }
        _ => (x.len() + y.len()) as u64,
    }
}
