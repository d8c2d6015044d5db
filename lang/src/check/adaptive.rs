//! The `adaptive { ... }` block (docs/adaptive.md): the error signal (linear
//! in the state, one component per input), the reference model A_m and Q,
//! the estimates `a`, `b` and the robust term `d` with rates, projection
//! bounds, initial values and boundary layer, the reference input r(t), the
//! convergence claims (the items an adaptive controller cannot have are
//! refused in `compat/adaptive.rs`).
//! Conditions that need eigenvalues or the local models (A_m Hurwitz, P > 0,
//! C B_i diagonal with the declared sign) are the compiler's.

use super::{unknown_choice, Checker, Dims, Draft};
use crate::adaptive::{Adaptive, Estimate, Robust};
use crate::ast::{AdaptiveStmt, Expr, Ident, Item, ItemKind, Setting, Value};
use crate::diag::Diagnostic;
use crate::eval::Mat;
use crate::num::Num;
use crate::span::Span;
use crate::spec::{Convergence, RuleSpec, SpannedObjective};

/// Most inputs (error components) an adaptive controller may have (the
/// runtime keeps its per-step work on the stack).
pub const MAX_ADAPTIVE_INPUTS: usize = 8;
/// Most adapted numbers (rules x inputs x (states + 1) + 1).
pub const MAX_ADAPTIVE_PARAMETERS: usize = 20_000;

/// The settings of the block.
const SETTINGS: [&str; 3] = ["error", "reference", "Q"];

/// The parts of an `adaptive` block, as its statements are checked.
#[derive(Default)]
struct Parts {
    error: Option<Mat>,
    reference: Option<Mat>,
    q: Option<Mat>,
    a: Option<Estimate>,
    b: Option<Estimate>,
    robust: Option<Robust>,
    r: Option<Expr>,
    /// Where each setting, estimate and the reference input was given first.
    seen: [Option<Span>; 7],
    converged: Vec<Convergence>,
}

impl<'a> Checker<'a> {
    /// The `adaptive` block of the file, if any (given once), checked.
    pub(super) fn adaptive_block(
        &mut self,
        items: &'a [Item],
        draft: &Draft,
        dims: Dims,
        objectives: &[SpannedObjective],
        rules: &[RuleSpec],
    ) -> Option<Adaptive> {
        let mut seen = None;
        let mut block = None;
        for it in items {
            if let ItemKind::Adaptive(stmts) = &it.kind {
                if self.singleton(&mut seen, it.span, "the `adaptive` block") {
                    block = Some((it.span, stmts));
                }
            }
        }
        let (span, stmts) = block?;
        let supported = self.adaptive_alone(span, items, draft, objectives, rules);
        let adaptive = self.adaptive(span, stmts, dims)?;
        supported.then_some(adaptive)
    }

    fn adaptive(&mut self, span: Span, stmts: &[AdaptiveStmt], dims: Dims) -> Option<Adaptive> {
        let m = dims.m;
        let mut ok = true;
        let mut p = Parts::default();
        for s in stmts {
            match s {
                AdaptiveStmt::Setting(s) => ok &= self.adaptive_setting(s, &mut p, dims),
                AdaptiveStmt::Estimate {
                    robust: is_robust,
                    name,
                    rate,
                    lo,
                    hi,
                    init,
                    layer,
                    span,
                } => {
                    let (slot, allowed): (usize, &[&str]) = if *is_robust {
                        (5, &["d"])
                    } else {
                        (3, &["a", "b"])
                    };
                    let Some(which) = allowed.iter().position(|n| *n == name.node) else {
                        self.err(unknown_choice(name.span, "estimated quantity", "they are", &name.node, allowed).with_help(
                            "`a`: the rules' state coefficients, `b`: their input gains (`estimate`); `d`: the disturbance bound (`robust`)",
                        ));
                        ok = false;
                        continue;
                    };
                    if !self.singleton(
                        &mut p.seen[slot + which],
                        *span,
                        &format!("`{}`", name.node),
                    ) {
                        ok = false;
                        continue;
                    }
                    let est = self.estimate(name, rate, lo, hi, init.as_ref(), *span);
                    match (is_robust, which, est) {
                        (true, _, Some(e)) => {
                            p.robust = self.robust(e, name, layer.as_ref(), *span);
                            ok &= p.robust.is_some();
                        }
                        (false, w, Some(e)) => {
                            ok &= self.adapted_estimate(&mut p, w, e, layer.as_ref(), *span)
                        }
                        _ => ok = false,
                    }
                }
                AdaptiveStmt::Signal {
                    name,
                    param,
                    value,
                    span,
                } => {
                    if !self.singleton(&mut p.seen[6], *span, "the reference input") {
                        ok = false;
                        continue;
                    }
                    p.r = self.reference_input(name, param, value, m);
                    ok &= p.r.is_some();
                }
                AdaptiveStmt::Converged {
                    signal,
                    tol,
                    by,
                    span,
                } => match self.claim(signal, tol, by, *span, dims.n) {
                    Some(c) => p.converged.push(c),
                    None => ok = false,
                },
            }
        }
        for (k, what) in [(0, "error"), (1, "reference")] {
            if p.seen[k].is_none() {
                self.err(Diagnostic::error(span, format!("the adaptive controller needs `{what} = ...;`")).with_help(
                    "e.g. `error = omega + 0.5 * rho;` (one component per input) and `reference = -0.5 * eye(3);` (A_m, Hurwitz)",
                ));
                ok = false;
            }
        }
        ok &= self.adaptive_size(span, dims);
        if !ok {
            return None;
        }
        Some(Adaptive {
            error: p.error?,
            reference: p.reference?,
            q: p.q.unwrap_or_else(|| Mat::identity(m, m)),
            a: p.a,
            b: p.b,
            robust: p.robust,
            r: p.r,
            converged: p.converged,
            span,
        })
    }

    /// `error = ...;`, `reference = ...;` or `Q = ...;`, into `p`; `false`
    /// if it was refused.
    fn adaptive_setting(&mut self, s: &Setting, p: &mut Parts, dims: Dims) -> bool {
        let m = dims.m;
        let Some(k) = SETTINGS.iter().position(|k| *k == s.key.node) else {
            self.err(unknown_choice(s.key.span, "adaptive setting", "settings", &s.key.node, &SETTINGS).with_help(
                "estimates are `estimate a|b rate g bounds lo .. hi [init v];`, the robust term `robust d rate g bounds lo .. hi [init v] layer phi;`",
            ));
            return false;
        };
        if !self.singleton(&mut p.seen[k], s.span, &format!("`{}`", s.key.node)) {
            return false;
        }
        let Some(e) = plain_expr(self, s) else {
            return false;
        };
        match k {
            0 => p.error = self.error_map(&s.key, e, dims),
            1 => p.reference = self.square(e, m, "the reference model A_m"),
            _ => {
                p.q = self
                    .square(e, m, "Q")
                    .and_then(|q| self.symmetric_pd_diag(e, q))
            }
        }
        [&p.error, &p.reference, &p.q][k].is_some()
    }

    /// A checked `estimate a` (`which` 0) or `estimate b` (1), into `p`;
    /// `false` if it was refused.
    fn adapted_estimate(
        &mut self,
        p: &mut Parts,
        which: usize,
        e: Estimate,
        layer: Option<&Expr>,
        span: Span,
    ) -> bool {
        if let Some(l) = layer {
            self.err(
                Diagnostic::error(l.span, "only the robust term has a boundary layer")
                    .with_help("remove `layer ...`"),
            );
            false
        } else if which == 1 && e.lo <= 0.0 && e.hi >= 0.0 {
            self.err(Diagnostic::error(span, "the input gain estimates must have a known sign")
                .with_label(format!("the bounds {} .. {} contain 0", Num(e.lo), Num(e.hi)))
                .with_help("give bounds on one side of 0 (e.g. `bounds 1e-4 .. 1e-3`): the law divides by b_hat"));
            false
        } else {
            if which == 0 {
                p.a = Some(e);
            } else {
                p.b = Some(e);
            }
            true
        }
    }

    /// The size limits of an adaptive controller (inputs, adapted numbers);
    /// `false` if one is passed.
    fn adaptive_size(&mut self, span: Span, dims: Dims) -> bool {
        let m = dims.m;
        let mut ok = true;
        if m > MAX_ADAPTIVE_INPUTS {
            self.err(Diagnostic::error(span, format!("an adaptive controller has at most {MAX_ADAPTIVE_INPUTS} inputs, this spec has {m}")));
            ok = false;
        }
        let rules = self
            .file
            .items
            .iter()
            .filter(|i| matches!(i.kind, ItemKind::Rule { .. }))
            .count();
        let count = rules.max(1) * m * (dims.n + 1) + 1;
        if count > MAX_ADAPTIVE_PARAMETERS {
            self.err(
                Diagnostic::error(
                    span,
                    format!(
                        "{count} adapted numbers exceed the limit of {MAX_ADAPTIVE_PARAMETERS}"
                    ),
                )
                .with_help("fewer rules, or fewer states (docs/limits.md)"),
            );
            ok = false;
        }
        ok
    }

    /// `error = expr;`: linear in the state only, one component per input.
    fn error_map(&mut self, key: &Ident, e: &Expr, dims: Dims) -> Option<Mat> {
        let out = self.output(key, e, dims)?;
        if out.e.iter().chain(out.g.iter()).any(|v| *v != 0.0) {
            self.err(
                Diagnostic::error(e.span, "the error signal may depend on the state only")
                    .with_help("write it from the states, e.g. `error = omega + 0.5 * rho;`"),
            );
            return None;
        }
        if out.c.nrows() != dims.m {
            self.err(Diagnostic::error(e.span, format!("the error signal has {} components but there are {} inputs", out.c.nrows(), dims.m))
                .with_label("one error component per input channel")
                .with_help("the adaptive law matches each error component with one input (docs/adaptive.md)"));
            return None;
        }
        if out.c.iter().all(|v| *v == 0.0) {
            self.err(Diagnostic::error(
                e.span,
                "the error signal is identically zero",
            ));
            return None;
        }
        Some(out.c)
    }

    fn square(&mut self, e: &Expr, m: usize, what: &str) -> Option<Mat> {
        let v = self.eval_const(e)?;
        if v.nrows() == m && v.ncols() == m {
            return Some(v);
        }
        self.err(
            Diagnostic::error(
                e.span,
                format!("{what} must be {m}x{m} (one row per input)"),
            )
            .with_label(format!("this is {}x{}", v.nrows(), v.ncols())),
        );
        None
    }

    /// Q symmetric with a positive diagonal (positive definiteness: the compiler).
    fn symmetric_pd_diag(&mut self, e: &Expr, q: Mat) -> Option<Mat> {
        let asym = (&q - q.transpose()).amax();
        if asym > 1e-12 * (1.0 + q.amax()) || q.diagonal().iter().any(|d| *d <= 0.0) {
            self.err(
                Diagnostic::error(e.span, "Q must be symmetric positive definite")
                    .with_help("e.g. `Q = eye(3);`"),
            );
            return None;
        }
        Some(q)
    }

    fn estimate(
        &mut self,
        name: &Ident,
        rate: &Expr,
        lo: &Expr,
        hi: &Expr,
        init: Option<&Expr>,
        span: Span,
    ) -> Option<Estimate> {
        let what = |w: &str| format!("the {w} of `{}`", name.node);
        let rate_v = self.positive(rate, &what("adaptation rate"));
        let lo_v = self.scalar(lo, &what("lower bound"));
        let hi_v = self.scalar(hi, &what("upper bound"));
        let init_v = match init {
            Some(e) => Some(self.scalar(e, &what("initial value"))?),
            None => None,
        };
        let (rate, lo_v, hi_v) = (rate_v?, lo_v?, hi_v?);
        if lo_v >= hi_v {
            self.err(
                Diagnostic::error(hi.span, "the projection bounds must satisfy lo < hi")
                    .with_label(format!("{} .. {}", Num(lo_v), Num(hi_v))),
            );
            return None;
        }
        if let (Some(v), Some(e)) = (init_v, init) {
            if !(lo_v..=hi_v).contains(&v) {
                self.err(
                    Diagnostic::error(
                        e.span,
                        "the initial value lies outside the projection bounds",
                    )
                    .with_label(format!(
                        "{} is not in {} .. {}",
                        Num(v),
                        Num(lo_v),
                        Num(hi_v)
                    ))
                    .with_help("projection keeps an estimate in its bounds; start it inside"),
                );
                return None;
            }
        }
        Some(Estimate {
            rate,
            lo: lo_v,
            hi: hi_v,
            init: init_v,
            span,
        })
    }

    fn robust(
        &mut self,
        mut e: Estimate,
        name: &Ident,
        layer: Option<&Expr>,
        span: Span,
    ) -> Option<Robust> {
        if e.lo < 0.0 {
            self.err(
                Diagnostic::error(span, "the disturbance bound estimate cannot be negative")
                    .with_label(format!("lower bound {}", Num(e.lo))),
            );
            return None;
        }
        let Some(layer) = layer else {
            self.err(Diagnostic::error(span, "the robust term needs a boundary layer")
                .with_label("a pure sign term chatters at the controller rate")
                .with_help(format!("add `layer phi` (phi > 0), e.g. `robust {} rate 0.1 bounds 0 .. 1 layer 0.01;`", name.node)));
            return None;
        };
        let layer = self.positive(layer, "the boundary layer")?;
        e.init = Some(e.init.unwrap_or(e.lo));
        Some(Robust { estimate: e, layer })
    }

    /// `r(t) = expr;`: an m-vector function of time.
    fn reference_input(
        &mut self,
        name: &Ident,
        param: &Ident,
        value: &Expr,
        m: usize,
    ) -> Option<Expr> {
        if name.node != "r" || param.node != "t" {
            self.err(Diagnostic::error(
                name.span.join(param.span),
                "the reference input is written `r(t) = ...;`",
            ));
            return None;
        }
        let mut env = self.const_env();
        env.unavailable.retain(|(n, _)| n != "t");
        env.locals.push(("t".into(), Mat::zeros(1, 1)));
        match self.evaluate(&env, value) {
            Ok(v) if v.nrows() == m && v.ncols() == 1 => Some(value.clone()),
            Ok(v) => {
                self.err(Diagnostic::error(
                    value.span,
                    format!(
                        "r(t) must have {m} components (one per input), this is {}x{}",
                        v.nrows(),
                        v.ncols()
                    ),
                ));
                None
            }
            Err(d) => {
                self.err(d);
                None
            }
        }
    }

    /// `converged |signal| <= tol by t;`
    fn claim(
        &mut self,
        signal: &Ident,
        tol: &Expr,
        by: &Expr,
        span: Span,
        n: usize,
    ) -> Option<Convergence> {
        let at = self.state_signal(signal, n);
        let tol_v = self.positive(tol, "the convergence bound");
        let by_v = self.positive(by, "the convergence time");
        Some(Convergence {
            signal: at?,
            name: signal.node.clone(),
            tol: tol_v?,
            by: by_v?,
            span,
        })
    }
}

/// The expression of `key = expr;` (no range, no qualifier, no modifier).
fn plain_expr<'s>(c: &mut Checker, s: &'s Setting) -> Option<&'s Expr> {
    match (&s.value, &s.qualifier, s.modifiers.is_empty()) {
        (Value::Expr(e), None, true) => Some(e),
        _ => {
            c.err(Diagnostic::error(
                s.span,
                format!(
                    "`{}` takes one expression: `{} = ...;`",
                    s.key.node, s.key.node
                ),
            ));
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::check::testing::*;

    const BLOCK: &str = "adaptive { error = x1; reference = -2; Q = 2; estimate a rate 4 bounds -10 .. 10 init 0; }";

    #[test]
    fn a_scalar_block_checks() {
        let spec = spec_with(BLOCK);
        let a = spec.adaptive.expect("adaptive"); // ok: unit test (cfg(test))
        assert_eq!(a.error.as_slice(), &[1.0]);
        assert_eq!(a.reference[(0, 0)], -2.0);
        assert_eq!(a.a.expect("a").rate, 4.0); // ok: unit test (cfg(test))
        assert!(a.b.is_none() && a.robust.is_none());
    }

    #[test]
    fn bad_blocks_are_spec_errors() {
        for (old, new, msg) in [
            ("rate 4", "rate 0", "must be positive"),
            ("init 0", "init 20", "outside the projection bounds"),
            ("-10 .. 10", "10 .. -10", "lo < hi"),
            ("estimate a", "estimate c", "unknown estimated quantity"),
            (
                "estimate a rate 4 bounds -10 .. 10 init 0",
                "estimate b rate 1 bounds -1 .. 1",
                "known sign",
            ),
            (
                "estimate a rate 4 bounds -10 .. 10 init 0",
                "robust d rate 1 bounds 0 .. 1",
                "boundary layer",
            ),
            ("Q = 2", "Q = -2", "positive definite"),
            ("reference = -2", "reference = [1, 2]", "must be 1x1"),
            ("error = x1", "error = [x1; x1]", "1 inputs"),
            ("error = x1", "error = x1 * x1", "not linear"),
            ("error = x1; ", "", "needs `error"),
            ("Q = 2", "gain = 2", "unknown adaptive setting"),
        ] {
            let text = BLOCK.replace(old, new);
            assert_ne!(text, BLOCK, "{old}");
            let diags = errors(&format!("{BASE}{text}"));
            assert!(
                diags.iter().any(|d| d.0.message.contains(msg)),
                "{new}: {diags:?}"
            );
        }
    }

    #[test]
    fn objectives_are_refused_and_emit_is_allowed() {
        let diags = errors(&format!("{BASE}{BLOCK}\nobjective stability;\nemit rust;"));
        assert!(diags
            .iter()
            .any(|d| d.0.message.contains("an LMI objective cannot")));
        assert!(!diags.iter().any(|d| d.0.message.contains("`emit`")));
        let (m, at) = only_error(&format!("{BLOCK}\nprecision f32;"));
        assert_eq!(
            m,
            "`precision f32` cannot be used with an adaptive controller"
        );
        assert_eq!(at, "precision f32;");
        spec_with(&format!("{BLOCK}\nprecision f64;"));
    }
}
