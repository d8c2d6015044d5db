//! `objective finite_time minimize | <= c2 with c1 = .., T = .., alpha = .., R = ..;`
//! (finite-time boundedness); what it needs from the rest of the spec is
//! checked in `compat/finite_time.rs`.

use super::objectives::ObjectiveItem;
use super::Checker;
use crate::diag::Diagnostic;
use crate::eval::Mat;
use crate::num::Num;
use crate::spec::{FiniteTime, Target};

/// The `with` parameters of `finite_time`.
pub const PARAMETERS: [&str; 4] = ["c1", "T", "alpha", "R"];

/// The largest alpha * T: the certificate's factor e^{alpha T} stays below
/// e^50 (about 5e21), far past any useful bound.
pub const MAX_ALPHA_T: f64 = 50.0;

impl Checker<'_> {
    /// The numbers of a `finite_time` objective with goal `target`.
    pub(super) fn finite_time(
        &mut self,
        o: &ObjectiveItem,
        n: usize,
        target: Target,
    ) -> Option<FiniteTime> {
        let arg = |key: &str| o.with.iter().find(|a| a.name.node == key);
        let mut missing = Vec::new();
        for key in ["c1", "T"] {
            if arg(key).is_none() {
                missing.push(format!("`{key}`"));
            }
        }
        if !missing.is_empty() {
            self.err(
                Diagnostic::error(
                    o.span,
                    format!("objective `finite_time` needs {}", missing.join(" and ")),
                )
                .with_help("e.g. `objective finite_time minimize with c1 = 1, T = 10;`")
                .with_note("x(0)' R x(0) <= c1 implies x(t)' R x(t) < c2 for t in [0, T]"),
            );
            return None;
        }
        let c1 = self.with_param(o, "c1");
        let horizon = self.with_param(o, "T");
        let alpha = match arg("alpha") {
            Some(a) => Some(self.nonnegative(&a.value, "alpha")?),
            None => None,
        };
        let r = match arg("R") {
            Some(a) => Some(self.ftb_weight(&a.value, n)?),
            None => None,
        };
        let (c1, horizon) = (c1?, horizon?);
        if let (Some(a), Some(e)) = (alpha, arg("alpha")) {
            if a * horizon > MAX_ALPHA_T {
                self.err(
                    Diagnostic::error(e.value.span, "alpha * T is too large")
                        .with_label(format!("alpha * T = {}", Num(a * horizon)))
                        .with_note(format!(
                            "the bound grows like e^(alpha T); the limit is alpha * T <= {MAX_ALPHA_T} (docs/limits.md)"
                        )),
                );
                return None;
            }
        }
        if let (Target::Fixed(c2), Some(crate::ast::Goal::AtMost(e))) = (target, o.goal) {
            if c2 <= c1 {
                self.err(
                    Diagnostic::error(e.span, "the bound c2 must exceed c1")
                        .with_label(format!("c2 = {}, c1 = {}", Num(c2), Num(c1)))
                        .with_note("at t = 0, x' R x may already equal c1"),
                );
                return None;
            }
        }
        Some(FiniteTime {
            target,
            c1,
            horizon,
            alpha,
            r: r.unwrap_or_else(|| Mat::identity(n, n)),
        })
    }

    /// The weight `R`: a positive scalar (times the identity) or an n x n
    /// symmetric positive definite matrix.
    fn ftb_weight(&mut self, e: &crate::ast::Expr, n: usize) -> Option<Mat> {
        let v = self.eval_const(e)?;
        let r = if v.nrows() == 1 && v.ncols() == 1 && n != 1 {
            Mat::identity(n, n) * v[(0, 0)]
        } else {
            v
        };
        if r.nrows() != n || r.ncols() != n {
            self.err(
                Diagnostic::error(e.span, format!("`R` must be a scalar or {n}x{n}"))
                    .with_label(format!("this is {}x{}", r.nrows(), r.ncols())),
            );
            return None;
        }
        if (&r - r.transpose()).norm() > 1e-12 * (1.0 + r.norm()) || r.clone().cholesky().is_none()
        {
            self.err(Diagnostic::error(
                e.span,
                "`R` must be symmetric positive definite",
            ));
            return None;
        }
        Some(r)
    }
}

#[cfg(test)]
mod tests {
    use crate::check::testing::*;
    use crate::spec::{Objective, Target};

    const ONE_MODE: &str = "modes { mode nominal { } rates = [0]; }\n";

    #[test]
    fn finite_time_reads_its_parameters() {
        let spec = spec_with(&format!(
            "disturbance d energy 0.5; D = 1;\n{ONE_MODE}objective finite_time <= 4 with c1 = 1, T = 2, alpha = 0.3, R = 2;"
        ));
        assert_eq!(spec.disturbance_energy, Some(0.5));
        let Objective::FiniteTime(ft) = &spec.objectives[0].node else {
            panic!("not finite_time"); // ok: unit test
        };
        assert_eq!(ft.target, Target::Fixed(4.0));
        assert_eq!((ft.c1, ft.horizon, ft.alpha), (1.0, 2.0, Some(0.3)));
        assert_eq!(ft.r[(0, 0)], 2.0);
    }

    #[test]
    fn finite_time_refuses_what_it_cannot_certify() {
        let (m, _) = only_error(&format!(
            "{ONE_MODE}objective finite_time minimize with T = 2;"
        ));
        assert_eq!(m, "objective `finite_time` needs `c1`");
        let (m, at) = only_error(&format!(
            "{ONE_MODE}objective finite_time <= 1 with c1 = 2, T = 2;"
        ));
        assert_eq!(m, "the bound c2 must exceed c1");
        assert_eq!(at, "1");
        let (m, at) = only_error(&format!(
            "{ONE_MODE}objective finite_time minimize with c1 = 1, T = 100, alpha = 1;"
        ));
        assert_eq!(m, "alpha * T is too large");
        assert_eq!(at, "1");
        let (m, _) = only_error("objective finite_time minimize with c1 = 1, T = 2;");
        assert_eq!(m, "objective `finite_time` needs a `modes` block");
        let (m, _) = only_error(&format!(
            "disturbance d; D = 1;\n{ONE_MODE}objective finite_time minimize with c1 = 1, T = 2;"
        ));
        assert_eq!(
            m,
            "objective `finite_time` needs the disturbance energy bound"
        );
        let (m, at) = only_error("disturbance d energy -1; D = 1;");
        assert_eq!(m, "the disturbance energy bound must be positive");
        assert_eq!(at, "-1");
        let (m, at) = only_error(&format!(
            "{ONE_MODE}objective finite_time minimize with c1 = 1, T = 2, R = -1;"
        ));
        assert_eq!(m, "`R` must be symmetric positive definite");
        assert_eq!(at, "-1");
        let (m, at) = only_error(&format!(
            "{ONE_MODE}objective finite_time minimize with c1 = 1, T = 2;\nobjective decay_rate >= 1;"
        ));
        assert_eq!(
            m,
            "objective `decay_rate` together with `finite_time` is not supported with `modes`"
        );
        assert_eq!(at, "objective decay_rate >= 1;");
    }

    #[test]
    fn hinf_is_accepted_with_modes() {
        let spec = spec_with(&format!(
            "disturbance d; D = 1; output z = x1;\n{ONE_MODE}objective hinf(d -> z) minimize;\nobjective decay_rate >= 0.1;"
        ));
        assert!(spec.modes.is_some());
        assert_eq!(spec.objectives.len(), 2);
    }
}
