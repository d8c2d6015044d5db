//! Named signals `signal name = expr;`: a vector expression of the state
//! (constants and functions allowed, inputs and disturbances not), which
//! generated code can evaluate. A `trigger mixed { on = name; }` monitors one.

use super::{Checker, Draft, Kind};
use crate::ast::{Expr, Ident};
use crate::diag::Diagnostic;
use crate::eval::Mode;
use crate::spec::{NamedSignal, Trigger};
use crate::suggest::suggest;

impl Checker<'_> {
    /// `signal name = expr;`: declared, then checked; a failed one is poisoned.
    pub(super) fn signal_item(&mut self, name: &Ident, e: &Expr, draft: &mut Draft) {
        if !self.declare(name, Kind::Named) {
            return;
        }
        match self.named_signal(name, e) {
            Some(s) => draft.signals.push(s),
            None => self.poison(name.node.clone()),
        }
    }

    fn named_signal(&mut self, name: &Ident, e: &Expr) -> Option<NamedSignal> {
        if self.poisoned(e) {
            return None;
        }
        let v = match self.evaluate(&self.state_env(Mode::Shapes, &[], &[]), e) {
            Ok(v) => v,
            Err(d) => {
                self.err(d.with_note("a signal is an expression of the state and constants"));
                return None;
            }
        };
        if v.ncols() != 1 || v.nrows() == 0 {
            self.err(
                Diagnostic::error(e.span, "a signal must be a scalar or a column vector")
                    .with_label(format!("this is {}x{}", v.nrows(), v.ncols())),
            );
            return None;
        }
        let errors = self.diags.len();
        self.check_generatable(e, std::slice::from_ref(name));
        if self.diags.len() != errors {
            return None;
        }
        let n: usize = self.states.iter().map(|s| s.len).sum();
        let at_origin = self.evaluate(&self.state_env(Mode::Exact, &[], &[]), e);
        let finite =
            at_origin.is_ok_and(|z| z.iter().all(|x| x.is_finite()) && z.len() == v.nrows());
        {
            if !finite {
                self.err(
                    Diagnostic::error(e.span, "the signal is not finite at the origin")
                        .with_label(format!("evaluated at x = 0 ({n} states)"))
                        .with_help("a monitored signal must be finite wherever the loop runs"),
                );
                return None;
            }
        }
        Some(NamedSignal {
            name: name.node.clone(),
            expr: e.clone(),
            dim: v.nrows(),
            span: name.span,
        })
    }

    /// Resolves the `on = name;` of a mixed trigger against the named signals.
    pub(super) fn resolve_trigger_signal(&mut self, draft: &mut Draft) {
        let Some(on) = draft.trigger_on.take() else {
            return;
        };
        let Some(sig) = self.declared_signal(&on, &draft.signals) else {
            draft.trigger = None;
            return;
        };
        if let Some(t) = draft.trigger.as_mut() {
            if let Trigger::Mixed { on, .. } = &mut t.node {
                *on = Some(sig);
            }
        }
    }

    /// Resolves the `on = name;` of every mixed law of the `sweep` scenarios
    /// (recorded by the sweep checker in scenario order); an unknown name
    /// drops the sweep with an error.
    pub(super) fn resolve_sweep_signals(&mut self, draft: &mut Draft) {
        let ons = std::mem::take(&mut self.sweep_on);
        let Some(sweep) = draft.simulate.as_mut().and_then(|s| s.sweep.as_mut()) else {
            return;
        };
        let mut ok = true;
        for (sc, on) in sweep.scenarios.iter_mut().zip(ons) {
            let Some(on) = on else { continue };
            match self.declared_signal(&on, &draft.signals) {
                Some(sig) => {
                    if let Trigger::Mixed { on, .. } = &mut sc.trigger {
                        *on = Some(sig);
                    }
                }
                None => ok = false,
            }
        }
        if !ok {
            if let Some(s) = draft.simulate.as_mut() {
                s.sweep = None;
            }
        }
    }

    /// The declared signal `on` names; an error (with a suggestion) if there is none.
    fn declared_signal(&mut self, on: &Ident, signals: &[NamedSignal]) -> Option<NamedSignal> {
        let found = signals.iter().find(|s| s.name == on.node).cloned();
        let Some(sig) = found else {
            if self.poisoned.contains(&on.node) {
                return None;
            }
            let mut d = Diagnostic::error(on.span, format!("unknown signal `{}`", on.node))
                .with_label("not a declared `signal`");
            if let Some(s) = suggest(&on.node, signals.iter().map(|s| s.name.as_str())) {
                d = d.with_help(format!("did you mean `{s}`?"));
            } else {
                d = d.with_help(format!(
                    "declare it: `signal {} = <expression of the state>;` (or leave `on` out to monitor the state)",
                    on.node
                ));
            }
            self.err(d);
            return None;
        };
        Some(sig)
    }
}

#[cfg(test)]
mod tests {
    use crate::check::testing::*;
    use crate::spec::{Monitor, Trigger};

    #[test]
    fn a_signal_is_a_vector_of_the_state_monitored_by_a_mixed_trigger() {
        let spec = spec_with(
            "signal s = [x1 + 2; x1 * x1];\n\
             trigger mixed { on = s; beta = 0.5; rho = 1e-6; monitor = continuous; }",
        );
        assert_eq!(spec.signals.len(), 1);
        let Some(Trigger::Mixed {
            monitor,
            beta,
            rho,
            on,
        }) = spec.trigger.clone().map(|t| t.node)
        else {
            panic!("not mixed"); // ok: unit test (cfg(test))
        };
        assert_eq!((monitor, beta, rho), (Monitor::Continuous, 0.5, 1e-6));
        let on = on.expect("a signal"); // ok: unit test (cfg(test))
        assert_eq!((on.name.as_str(), on.dim), ("s", 2));
        assert_eq!(on.eval(&spec, &[3.0]), Some(vec![5.0, 9.0]));
    }

    #[test]
    fn signal_errors_name_the_cause() {
        let (m, at) = only_error("signal s = u;");
        assert_eq!(m, "`u` cannot be used here");
        assert_eq!(at, "u");
        let (m, at) =
            only_error("trigger mixed { on = sig; beta = 0.1; rho = 0.1; monitor = step; }");
        assert_eq!(m, "unknown signal `sig`");
        assert_eq!(at, "sig");
        let (m, _) = only_error("signal s = [x1, x1];");
        assert_eq!(m, "a signal must be a scalar or a column vector");
        let (m, _) = only_error("signal s = 1 / x1;");
        assert_eq!(m, "the signal is not finite at the origin");
    }
}
