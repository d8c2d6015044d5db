//! The `monte_carlo { }` block of the scenario: uncertain constants of the
//! truth plant, initial state and disturbance amplitudes, each drawn
//! uniformly per run, and the rule that decides whether a run converged.

use super::env::walk_names;
use super::{unknown_choice, Checker};
use crate::ast::{Expr, ExprKind, Ident, ItemKind, McStmt, Value, Vary};
use crate::diag::Diagnostic;
use crate::limits::MAX_MONTE_CARLO_RUNS;
use crate::span::Span;
use crate::spec::{Convergence, Dynamics, McTarget, MonteCarlo, Uncertain};
use std::collections::HashSet;

impl Checker<'_> {
    /// The block; `n` states, the scenario's `dynamics`, `time` span and
    /// disturbance `signals` are known.
    pub(super) fn monte_carlo(
        &mut self,
        stmts: &[McStmt],
        span: Span,
        n: usize,
        dynamics: Option<&Dynamics>,
        time: (f64, f64, f64),
        signals: &[(usize, Expr)],
    ) -> Option<MonteCarlo> {
        let mut ok = true;
        let mut runs = None;
        let mut uncertain: Vec<Uncertain> = Vec::new();
        let mut converged: Option<Convergence> = None;
        let mut seen: Vec<String> = Vec::new();
        for st in stmts {
            match st {
                McStmt::Setting(s) if s.key.node == "runs" => {
                    if runs.is_some() {
                        self.err(Diagnostic::error(s.key.span, "`runs` is given twice"));
                        ok = false;
                        continue;
                    }
                    match self.setting_scalar(s) {
                        Some(v)
                            if v >= 1.0 && v.fract() == 0.0 && v <= MAX_MONTE_CARLO_RUNS as f64 =>
                        {
                            runs = Some(v as u64)
                        }
                        Some(_) => {
                            let at = match &s.value {
                                Value::Expr(e) => e.span,
                                Value::Range(..) => s.span,
                            };
                            self.err(
                                Diagnostic::error(at, "`runs` is a whole number of runs")
                                    .with_help(format!("give 1 .. {MAX_MONTE_CARLO_RUNS} runs")),
                            );
                            ok = false;
                        }
                        None => ok = false,
                    }
                }
                McStmt::Setting(s) => {
                    self.err(
                        unknown_choice(
                            s.key.span,
                            "monte_carlo setting",
                            "settings",
                            &s.key.node,
                            &["runs"],
                        )
                        .with_help(
                            "vary a quantity with `name scale uniform(lo, hi);`, `x0 in uniform(lo, hi);` or `x0 offset uniform(lo, hi);`",
                        ),
                    );
                    ok = false;
                }
                McStmt::Vary {
                    name,
                    how,
                    dist,
                    span,
                } => {
                    if seen.contains(&name.node) {
                        self.err(Diagnostic::error(
                            name.span,
                            format!("`{}` is varied twice", name.node),
                        ));
                        ok = false;
                        continue;
                    }
                    seen.push(name.node.clone());
                    let target = self
                        .mc_target(&name.node, name.span, how.node, how.span, dynamics, signals);
                    let len = if target == Some(McTarget::InitialState) {
                        n
                    } else {
                        1
                    };
                    let bounds = self.uniform(dist, len);
                    match (target, bounds) {
                        (Some(target), Some((lo, hi))) => uncertain.push(Uncertain {
                            target,
                            how: how.node,
                            lo,
                            hi,
                            span: *span,
                        }),
                        _ => ok = false,
                    }
                }
                McStmt::Converged {
                    signal,
                    tol,
                    by,
                    span,
                } => {
                    if converged.is_some() {
                        self.err(Diagnostic::error(*span, "`converged` is given twice"));
                        ok = false;
                        continue;
                    }
                    let at = self.state_signal(signal, n);
                    let tol_v = self.positive(tol, "the convergence bound");
                    let by_v = self.scalar(by, "the convergence time");
                    if let Some(b) = by_v {
                        if !(b.is_finite() && b > time.0) {
                            self.err(
                                Diagnostic::error(by.span, "the convergence time must be after the start")
                                    .with_label(format!("the scenario starts at {} s", time.0))
                                    .with_help("a time in seconds; it may lie past the spec's span when `--horizon` extends it"),
                            );
                            ok = false;
                        }
                    }
                    match (at, tol_v, by_v) {
                        (Some(signal_at), Some(t), Some(b)) if t.is_finite() => {
                            converged = Some(Convergence {
                                signal: signal_at,
                                name: signal.node.clone(),
                                tol: t,
                                by: b,
                                span: *span,
                            })
                        }
                        _ => ok = false,
                    }
                }
            }
        }
        let Some(converged) = converged else {
            if ok {
                self.err(
                    Diagnostic::error(span, "`monte_carlo` needs a convergence rule").with_help(
                        "add `converged |x| <= 1e-2 by 250;` (norm bound and time in s)",
                    ),
                );
            }
            return None;
        };
        ok.then_some(MonteCarlo {
            runs,
            uncertain,
            converged,
            span,
        })
    }

    /// What `name` names, and whether `how` applies to it.
    fn mc_target(
        &mut self,
        name: &str,
        at: Span,
        how: Vary,
        how_at: Span,
        dynamics: Option<&Dynamics>,
        signals: &[(usize, Expr)],
    ) -> Option<McTarget> {
        let target = if name == "x0" {
            McTarget::InitialState
        } else if let Some(k) = self.disturbances.iter().position(|d| d.name == name) {
            if !signals.iter().any(|(i, _)| *i == k) {
                self.err(
                    Diagnostic::error(
                        at,
                        format!("disturbance `{name}` has no signal in `simulate`"),
                    )
                    .with_help(format!(
                        "define it with `{name}(t) = ...;` to vary its amplitude"
                    )),
                );
                return None;
            }
            McTarget::Disturbance(k)
        } else {
            let local = dynamics.is_some_and(|d| d.consts.iter().any(|(c, _)| c == name));
            if !local && !self.consts.contains_key(name) {
                let mut names: Vec<&str> = vec!["x0"];
                names.extend(self.consts.keys().map(String::as_str));
                names.extend(
                    dynamics
                        .iter()
                        .flat_map(|d| d.consts.iter().map(|(c, _)| c.as_str())),
                );
                names.extend(self.disturbances.iter().map(|d| d.name.as_str()));
                names[1..].sort_unstable();
                names.dedup();
                self.err(
                    unknown_choice(
                        at,
                        "uncertain quantity",
                        "constants, x0 and disturbances",
                        name,
                        &names,
                    )
                    .with_help("vary a `const` of the truth plant, `x0` or a disturbance signal"),
                );
                return None;
            }
            if !self.plant_uses(name, dynamics) {
                self.err(
                    Diagnostic::error(at, format!("the truth plant does not use `{name}`"))
                        .with_help(if dynamics.is_some() {
                            "vary a constant that the `dynamics` derivatives name (directly or through a `fn`)"
                        } else {
                            "vary a constant that the model matrices name (directly or through a `fn`)"
                        }),
                );
                return None;
            }
            McTarget::Const {
                name: name.to_string(),
                local,
            }
        };
        if how != Vary::Scale && target != McTarget::InitialState {
            self.err(
                Diagnostic::error(how_at, format!("`{name}` can only be scaled"))
                    .with_help(format!("write `{name} scale uniform(lo, hi);`")),
            );
            return None;
        }
        Some(target)
    }

    /// Whether the truth plant's expressions name `name` (through user functions too).
    /// (offset, length) of the state signal a `converged` claim names (`x`
    /// is the whole state), or an error at the name listing the states.
    pub(super) fn state_signal(&mut self, signal: &Ident, n: usize) -> Option<(usize, usize)> {
        let at = if signal.node == "x" {
            Some((0, n))
        } else {
            self.states
                .iter()
                .find(|s| s.name == signal.node)
                .map(|s| (s.offset, s.len))
        };
        if at.is_none() {
            let mut names: Vec<&str> = vec!["x"];
            names.extend(self.states.iter().map(|s| s.name.as_str()));
            self.err(unknown_choice(
                signal.span,
                "state",
                "states",
                &signal.node,
                &names,
            ));
        }
        at
    }

    fn plant_uses(&self, name: &str, dynamics: Option<&Dynamics>) -> bool {
        let exprs: Vec<&Expr> = match dynamics {
            Some(d) => d.derivatives.iter().map(|(_, e)| e).collect(),
            None => self
                .file
                .items
                .iter()
                .filter_map(|it| match &it.kind {
                    ItemKind::Matrix { name, value, .. }
                        if matches!(name.node.as_str(), "A" | "B" | "D") =>
                    {
                        Some(value)
                    }
                    _ => None,
                })
                .collect(),
        };
        let mut todo = exprs;
        let mut visited: HashSet<String> = HashSet::new();
        let mut found = false;
        while let Some(e) = todo.pop() {
            walk_names(e, &mut |n, _, call| {
                if n == name && !call {
                    found = true;
                } else if call && visited.insert(n.to_string()) {
                    if let Some(f) = self.fns.get(n) {
                        todo.push(&f.body);
                    }
                }
            });
        }
        found
    }

    /// `uniform(lo, hi)` with finite `lo <= hi` of `len` components (scalars broadcast).
    fn uniform(&mut self, dist: &Expr, len: usize) -> Option<(Vec<f64>, Vec<f64>)> {
        let args = match &dist.kind {
            ExprKind::Call(f, args)
                if f.node == "uniform"
                    && args.len() == 2
                    && args.iter().all(|a| a.name.is_none()) =>
            {
                args
            }
            _ => {
                self.err(
                    Diagnostic::error(dist.span, "expected a distribution `uniform(lo, hi)`")
                        .with_help("only uniform distributions with finite bounds are supported"),
                );
                return None;
            }
        };
        let mut bound = |e: &Expr| -> Option<Vec<f64>> {
            let v = self.eval_const(e)?;
            let vals: Vec<f64> = v.iter().copied().collect();
            let vals = if vals.len() == 1 {
                vec![vals[0]; len]
            } else {
                vals
            };
            if vals.len() != len || !(v.ncols() == 1 || v.nrows() == 1) {
                self.err(
                    Diagnostic::error(
                        e.span,
                        format!("this bound must be a scalar or have {len} components"),
                    )
                    .with_label(format!("this is {}x{}", v.nrows(), v.ncols())),
                );
                return None;
            }
            if let Some(bad) = vals.iter().find(|x| !x.is_finite()) {
                self.err(Diagnostic::error(
                    e.span,
                    format!("the bound {bad} is not finite"),
                ));
                return None;
            }
            Some(vals)
        };
        let lo = bound(&args[0].value);
        let hi = bound(&args[1].value);
        let (lo, hi) = (lo?, hi?);
        if let Some(k) = (0..len).find(|&k| lo[k] > hi[k]) {
            self.err(
                Diagnostic::error(dist.span, "the lower bound exceeds the upper bound")
                    .with_label(format!("component {}: {} > {}", k + 1, lo[k], hi[k])),
            );
            return None;
        }
        Some((lo, hi))
    }
}

#[cfg(test)]
mod tests {
    use crate::ast::Vary;
    use crate::check::testing::*;
    use crate::spec::McTarget;

    const SIM: &str = "const k = 2; disturbance d; D = 1;\nsimulate { x0 = 0.5; time = 0 .. 10 step 0.1; d(t) = sin(t);\n dynamics { x1' = -k * x1 + u + d; }\n";

    #[test]
    fn a_block_with_every_kind_of_statement() {
        let spec = spec_with(&format!(
            "{SIM} monte_carlo {{ runs = 20; k scale uniform(0.9, 1.1); x0 offset uniform(-0.1, 0.1); d scale uniform(0.5, 1.5); converged |x| <= 1e-2 by 8; }} }}"
        ));
        let mc = spec.simulate.and_then(|s| s.monte_carlo).expect("a block"); // ok: unit test
        assert_eq!(mc.runs, Some(20));
        assert_eq!(mc.uncertain.len(), 3);
        assert!(
            matches!(&mc.uncertain[0].target, McTarget::Const { name, local: false } if name == "k")
        );
        assert_eq!(mc.uncertain[1].how, Vary::Offset);
        assert_eq!(
            (mc.uncertain[1].lo.clone(), mc.uncertain[1].hi.clone()),
            (vec![-0.1], vec![0.1])
        );
        assert_eq!(mc.uncertain[2].target, McTarget::Disturbance(0));
        assert_eq!(
            (mc.converged.tol, mc.converged.by, mc.converged.signal),
            (1e-2, 8.0, (0, 1))
        );
    }

    #[test]
    fn bad_statements_point_at_their_cause() {
        let bad = |body: &str| {
            only_error(&format!(
                "{SIM} monte_carlo {{ {body} converged |x| <= 1e-2 by 8; }} }}"
            ))
        };
        assert_eq!(
            bad("k scale uniform(1.1, 0.9);"),
            (
                "the lower bound exceeds the upper bound".into(),
                "uniform(1.1, 0.9)".into()
            )
        );
        assert_eq!(bad("q scale uniform(0.9, 1.1);").1, "q");
        assert_eq!(
            bad("k scale normal(1, 0.1);").0,
            "expected a distribution `uniform(lo, hi)`"
        );
        assert_eq!(bad("x0 in uniform([0, 1], 1);").1, "[0, 1]");
        assert_eq!(
            bad("k offset uniform(0, 1);"),
            ("`k` can only be scaled".into(), "offset".into())
        );
        assert_eq!(bad("runs = 0.5;").0, "`runs` is a whole number of runs");
        let (m, at) = only_error(&format!("const unused = 1; {SIM} monte_carlo {{ unused scale uniform(0, 1); converged |x| <= 1 by 8; }} }}"));
        assert_eq!(
            (m.as_str(), at.as_str()),
            ("the truth plant does not use `unused`", "unused")
        );
        let (m, _) = only_error(&format!("{SIM} monte_carlo {{ runs = 3; }} }}"));
        assert_eq!(m, "`monte_carlo` needs a convergence rule");
        let (m, at) = only_error(&format!(
            "{SIM} monte_carlo {{ converged |x| <= 1 by -1; }} }}"
        ));
        assert_eq!(
            (m.as_str(), at.as_str()),
            ("the convergence time must be after the start", "-1")
        );
    }
}
