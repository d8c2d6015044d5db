//! Constant values: evaluation in the constant environment, and the scalar,
//! vector, named-argument and setting forms items ask for.

use super::Checker;
use crate::ast::{Expr, NamedArg, Setting, Value};
use crate::diag::Diagnostic;
use crate::eval::Mat;
use crate::num::Num;
use std::collections::HashMap;

impl Checker<'_> {
    /// The value of a constant expression (finite), or None with the error reported.
    pub(super) fn eval_const(&mut self, e: &Expr) -> Option<Mat> {
        if self.poisoned(e) {
            return None;
        }
        let r = self.evaluate(&self.const_env(), e);
        match r {
            Ok(v) if v.iter().all(|x| x.is_finite()) => Some(v),
            Ok(_) => {
                self.err(
                    Diagnostic::error(e.span, "value is not finite")
                        .with_label("evaluates to NaN or infinity"),
                );
                None
            }
            Err(d) => {
                self.err(d);
                None
            }
        }
    }

    /// A constant 1x1 value; `what` names it in the error.
    pub(super) fn scalar(&mut self, e: &Expr, what: &str) -> Option<f64> {
        let v = self.eval_const(e)?;
        if v.nrows() == 1 && v.ncols() == 1 {
            Some(v[(0, 0)])
        } else {
            self.err(
                Diagnostic::error(e.span, format!("{what} must be a scalar")).with_label(format!(
                    "this is {}x{}",
                    v.nrows(),
                    v.ncols()
                )),
            );
            None
        }
    }

    /// A constant scalar > 0.
    pub(super) fn positive(&mut self, e: &Expr, what: &str) -> Option<f64> {
        let v = self.scalar(e, what)?;
        if v > 0.0 {
            Some(v)
        } else {
            self.err(
                Diagnostic::error(e.span, format!("{what} must be positive"))
                    .with_label(format!("this is {}", Num(v))),
            );
            None
        }
    }

    /// A constant scalar >= 0.
    pub(super) fn nonnegative(&mut self, e: &Expr, what: &str) -> Option<f64> {
        let v = self.scalar(e, what)?;
        if v >= 0.0 {
            Some(v)
        } else {
            self.err(
                Diagnostic::error(e.span, format!("{what} must not be negative"))
                    .with_label(format!("this is {}", Num(v))),
            );
            None
        }
    }

    /// A constant row or column with `len` components.
    pub(super) fn vector(&mut self, e: &Expr, len: usize, what: &str) -> Option<Vec<f64>> {
        let v = self.eval_const(e)?;
        if v.len() == len && (v.ncols() == 1 || v.nrows() == 1) {
            Some(v.iter().copied().collect())
        } else {
            self.shape_err(
                Diagnostic::error(
                    e.span,
                    format!(
                        "{what} must have {len} component{}",
                        if len == 1 { "" } else { "s" }
                    ),
                )
                .with_label(format!("this is {}x{}", v.nrows(), v.ncols())),
            );
            None
        }
    }

    /// Scalar named arguments, each one of `allowed`; `what` names their owner.
    pub(super) fn named(
        &mut self,
        args: &[NamedArg],
        allowed: &[&str],
        what: &str,
    ) -> Option<HashMap<String, f64>> {
        let mut out = HashMap::new();
        for a in args {
            if !allowed.contains(&a.name.node.as_str()) {
                self.err(
                    Diagnostic::error(
                        a.name.span,
                        format!("{what} has no parameter `{}`", a.name.node),
                    )
                    .with_label(if allowed.is_empty() {
                        "no parameters".to_string()
                    } else {
                        format!("parameters: {}", allowed.join(", "))
                    }),
                );
                return None;
            }
            out.insert(a.name.node.clone(), self.scalar(&a.value, &a.name.node)?);
        }
        Some(out)
    }

    /// A setting `key = lo .. hi [step h]` with 0 <= lo < hi.
    pub(super) fn range_setting(&mut self, s: &Setting) -> Option<(f64, f64, Option<f64>)> {
        match &s.value {
            Value::Range(lo, hi, step) => {
                let l = self.scalar(lo, "a range bound")?;
                let h = self.scalar(hi, "a range bound")?;
                if l >= h || l.is_nan() || h.is_nan() || l < 0.0 {
                    self.err(Diagnostic::error(
                        s.span,
                        format!(
                            "`{}` needs 0 <= lo < hi, found {} .. {}",
                            s.key.node,
                            Num(l),
                            Num(h)
                        ),
                    ));
                    return None;
                }
                let st = match step {
                    Some(e) => Some(self.positive(e, "the step")?),
                    None => None,
                };
                Some((l, h, st))
            }
            Value::Expr(e) => {
                self.err(Diagnostic::error(
                    e.span,
                    format!("`{}` needs a range `lo .. hi`", s.key.node),
                ));
                None
            }
        }
    }

    /// A setting with one scalar value.
    pub(super) fn setting_scalar(&mut self, s: &Setting) -> Option<f64> {
        self.setting_value(s, Self::scalar)
    }

    /// A setting with one scalar value >= 0.
    pub(super) fn setting_nonnegative(&mut self, s: &Setting) -> Option<f64> {
        self.setting_value(s, Self::nonnegative)
    }

    /// A setting with one value, read by `read`.
    fn setting_value(
        &mut self,
        s: &Setting,
        read: fn(&mut Self, &Expr, &str) -> Option<f64>,
    ) -> Option<f64> {
        match &s.value {
            Value::Expr(e) => read(self, e, &format!("`{}`", s.key.node)),
            Value::Range(..) => {
                self.err(Diagnostic::error(
                    s.span,
                    format!("`{}` needs a single value, not a range", s.key.node),
                ));
                None
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::check::testing::*;

    #[test]
    fn scalars_positives_and_vectors() {
        let (m, at) = only_error("trigger periodic { every = [1, 2]; }");
        assert_eq!(m, "`every` must be a scalar");
        assert_eq!(at, "[1, 2]");
        let (m, at) = only_error("premise p = x1 sigma -0.5;");
        assert_eq!(m, "sigma must be positive");
        assert_eq!(at, "-0.5");
        let (m, at) = only_error("simulate { x0 = [1; 2]; time = 0 .. 1; }");
        assert_eq!(m, "x0 must have 1 component");
        assert_eq!(at, "[1; 2]");
        let (m, at) = only_error("const k = 2 * log(0);");
        assert_eq!(m, "value is not finite");
        assert_eq!(at, "2 * log(0)");
    }

    #[test]
    fn named_arguments_and_ranges() {
        let (m, at) = only_error("relaxation tanaka(s = 1, t = 2);");
        assert_eq!(m, "relaxation `tanaka` has no parameter `t`");
        assert_eq!(at, "t");
        let (m, at) = only_error("trigger mixed { sampling = 0.2 .. 0.1; beta = 1; rho = 1; }");
        assert_eq!(m, "`sampling` needs 0 <= lo < hi, found 0.2 .. 0.1");
        assert_eq!(at, "sampling = 0.2 .. 0.1;");
        let (m, at) = only_error("trigger periodic { every = 0 .. 1; }");
        assert_eq!(m, "`every` needs a single value, not a range");
        assert_eq!(at, "every = 0 .. 1;");
        let (m, at) = only_error("trigger mixed { sampling = 0.1; beta = 1; rho = 1; }");
        assert_eq!(m, "`sampling` needs a range `lo .. hi`");
        assert_eq!(at, "0.1");
    }
}
