//! The truth plant of a simulation: `dynamics { state ..; const ..; x' = ..; }`,
//! a derivative of the right shape for every declared and extra state.

use super::{Checker, Kind};
use crate::ast::{DynStmt, Expr};
use crate::diag::Diagnostic;
use crate::eval::{Mat, Mode};
use crate::span::{Span, Spanned};
use crate::spec::{Dynamics, Signal};
use crate::suggest::suggest;

impl Checker<'_> {
    /// The block's extra states, constants and derivatives (ordered as the states).
    pub(super) fn dynamics(&mut self, body: &[Spanned<DynStmt>], span: Span) -> Option<Dynamics> {
        let mut extra: Vec<Signal> = Vec::new();
        let mut consts: Vec<(String, Mat)> = Vec::new();
        let mut ders: Vec<(String, Expr, Span)> = Vec::new();
        let mut ok = true;
        for st in body {
            match &st.node {
                DynStmt::State(vars) => {
                    let mut off = extra.iter().map(|s| s.len).sum();
                    for v in vars {
                        let len = v.len.as_ref().map_or(1.0, |l| l.node);
                        if len.fract() != 0.0 || !(1.0..=1000.0).contains(&len) {
                            self.err(Diagnostic::error(v.name.span, "invalid size"));
                            ok = false;
                            continue;
                        }
                        if self.names.contains_key(&v.name.node)
                            || extra.iter().any(|s| s.name == v.name.node)
                        {
                            self.err(Diagnostic::error(
                                v.name.span,
                                format!("`{}` is already declared", v.name.node),
                            ));
                            ok = false;
                            continue;
                        }
                        extra.push(Signal {
                            name: v.name.node.clone(),
                            len: len as usize,
                            is_vector: v.len.is_some(),
                            offset: off,
                            span: v.name.span,
                        });
                        off += len as usize;
                    }
                }
                DynStmt::Const(name, e) => match self.eval_const(e) {
                    Some(v) => consts.push((name.node.clone(), v)),
                    None => ok = false,
                },
                DynStmt::Derivative(name, e) => {
                    if let Some(prev) = ders.iter().find(|d| d.0 == name.node) {
                        let d =
                            Diagnostic::error(st.span, format!("`{}'` is given twice", name.node))
                                .with_secondary(prev.2, "first here");
                        self.err(d);
                        ok = false;
                        continue;
                    }
                    ders.push((name.node.clone(), e.clone(), st.span));
                }
            }
        }
        // Shape-check every derivative against its state.
        let mut locals: Vec<(String, Mat)> = consts.clone();
        for s in &extra {
            locals.push((s.name.clone(), Mat::zeros(s.len, 1)));
        }
        for s in &self.inputs {
            locals.push((s.name.clone(), Mat::zeros(s.len, 1)));
        }
        for s in &self.disturbances {
            locals.push((s.name.clone(), Mat::zeros(s.len, 1)));
        }
        locals.push(("t".into(), Mat::zeros(1, 1)));
        let all: Vec<Signal> = self
            .states
            .iter()
            .cloned()
            .chain(extra.iter().cloned())
            .collect();
        let mut out = Vec::new();
        for (name, e, dspan) in &ders {
            let Some(sig) = all.iter().find(|s| s.name == *name) else {
                ok = false;
                if self.poisoned.contains(name) {
                    continue;
                }
                let mut d = Diagnostic::error(*dspan, format!("`{name}` is not a state"))
                    .with_label("a derivative needs a state");
                if let Some(c) = suggest(name, all.iter().map(|s| s.name.as_str())) {
                    d = d.with_help(format!("did you mean `{c}`?"));
                } else {
                    d = d.with_help(format!("declare it in the block: `state {name};`"));
                }
                self.err(d);
                continue;
            };
            let env = self.state_env(Mode::Shapes, &locals, &[Kind::Input, Kind::Disturbance]);
            match self.evaluate(&env, e) {
                Ok(v) if v.nrows() == sig.len && v.ncols() == 1 => {
                    out.push((name.clone(), e.clone()))
                }
                Ok(v) => {
                    self.err(Diagnostic::error(
                        e.span,
                        format!(
                            "`{name}'` must have {} component{}, but this is {}x{}",
                            sig.len,
                            if sig.len == 1 { "" } else { "s" },
                            v.nrows(),
                            v.ncols()
                        ),
                    ));
                    ok = false;
                }
                Err(d) => {
                    self.err(d);
                    ok = false;
                }
            }
        }
        for s in &all {
            if !ders.iter().any(|d| d.0 == s.name) {
                self.err(
                    Diagnostic::error(
                        span,
                        format!("`dynamics` gives no derivative for state `{}`", s.name),
                    )
                    .with_help(format!("add `{}' = ...;`", s.name)),
                );
                ok = false;
            }
        }
        // Order derivatives as the states.
        out.sort_by_key(|(n, _)| all.iter().position(|s| s.name == *n));
        ok.then_some(Dynamics {
            extra_states: extra,
            consts,
            derivatives: out,
            span,
        })
    }
}

#[cfg(test)]
mod tests {
    use crate::check::testing::*;

    fn scenario(dynamics: &str) -> String {
        format!("{BASE}simulate {{ x0 = 0; time = 0 .. 1; dynamics {{ {dynamics} }} }}")
    }

    #[test]
    fn extra_states_constants_and_derivatives() {
        let spec = valid(&scenario(
            "state e[2]; const k = 3; e' = -k * e; x1' = -x1 + u + e[0];",
        ));
        let d = spec.simulate.and_then(|s| s.dynamics).expect("dynamics"); // ok: unit test
        assert_eq!(d.extra_states[0].len, 2);
        assert_eq!(d.consts[0].0, "k");
        // Ordered as the states: declared first, then extra.
        let names: Vec<&str> = d.derivatives.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, vec!["x1", "e"]);
    }

    #[test]
    fn every_state_needs_one_derivative_of_its_shape() {
        let (m, _) = only_error_of(&scenario("state e; x1' = -x1;"));
        assert_eq!(m, "`dynamics` gives no derivative for state `e`");
        let (m, at) = only_error_of(&scenario("x1' = [x1; x1];"));
        assert_eq!(m, "`x1'` must have 1 component, but this is 2x1");
        assert_eq!(at, "[x1; x1]");
        let (m, _) = only_error_of(&scenario("x1' = -x1; x1' = x1;"));
        assert_eq!(m, "`x1'` is given twice");
        let (m, at) = only_error_of(&scenario("x1' = -x1; y' = 1;"));
        assert_eq!(m, "`y` is not a state");
        assert_eq!(at, "y' = 1;");
    }
}
