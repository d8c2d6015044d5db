//! The environments expressions are checked in, and which names they may use.

use super::{Checker, Kind};
use crate::ast::{Expr, ExprKind, IndexArg};
use crate::diag::Diagnostic;
use crate::eval::{Env, Mat, Mode};
use crate::span::Span;
use std::collections::HashMap;

impl Checker<'_> {
    /// Constants and functions only: every signal is named but unavailable.
    pub(super) fn const_env(&self) -> Env<'_> {
        let not_constant = |k: Kind| {
            format!(
                "a {} is not a constant; only constants may appear here",
                k.word()
            )
        };
        let mut unavailable: Vec<(String, String)> = self
            .signal_names
            .iter()
            .map(|(n, k)| (n.clone(), not_constant(*k)))
            .collect();
        for (n, k) in &self.signal_items {
            if !self.names.contains_key(n) {
                unavailable.push((n.clone(), not_constant(*k)));
            }
        }
        unavailable.push((
            "x".into(),
            "the state is not a constant; only constants may appear here".into(),
        ));
        unavailable.push((
            "t".into(),
            "time `t` is only available in `simulate` signals and dynamics".into(),
        ));
        Env {
            consts: &self.consts,
            fns: &self.fns,
            locals: Vec::new(),
            unavailable,
            mode: Mode::Exact,
        }
    }

    /// An environment with the states (zeros) bound, for expressions of x.
    pub(super) fn state_env(
        &self,
        mode: Mode,
        extra: &[(String, Mat)],
        allowed_signals: &[Kind],
    ) -> Env<'_> {
        let n: usize = self.states.iter().map(|s| s.len).sum();
        let mut env = self.const_env();
        env.mode = mode;
        env.unavailable.retain(|(name, _)| {
            let k = self.names.get(name).map(|p| p.0);
            !(name == "x"
                || k == Some(Kind::State)
                || k.is_some_and(|k| allowed_signals.contains(&k)))
        });
        for (name, k) in &self.signal_names {
            if matches!(k, Kind::Input | Kind::Disturbance) && !allowed_signals.contains(k) {
                if let Some(u) = env.unavailable.iter_mut().find(|(n, _)| n == name) {
                    u.1 = format!(
                        "a {} cannot appear here: only states and constants can",
                        k.word()
                    );
                }
            }
        }
        env.locals.push(("x".into(), Mat::zeros(n, 1)));
        for s in &self.states {
            env.locals.push((s.name.clone(), Mat::zeros(s.len, 1)));
        }
        env.locals.extend(extra.iter().cloned());
        env
    }

    /// Evaluates `e` in `env`, paying from the check's work budget.
    pub(super) fn evaluate(&self, env: &Env, e: &Expr) -> Result<Mat, Diagnostic> {
        let part = self.budget.part();
        let r = env.eval_with(e, &part);
        self.budget.settle(&part);
        r
    }

    /// Whether `e` uses a name whose definition failed, directly or through
    /// the functions it calls (the errors were reported already).
    pub(super) fn poisoned(&self, e: &Expr) -> bool {
        let mut hit = false;
        walk_names(e, &mut |n, _, is_call| {
            hit |= self.poisoned.contains(n) || (is_call && self.tainted.contains(n));
        });
        hit
    }

    /// Records which functions use each name, and taints the functions that
    /// use the names poisoned so far (call once the functions are declared).
    pub(super) fn index_function_uses(&mut self) {
        let mut users: HashMap<String, Vec<String>> = HashMap::new();
        for (f, def) in &self.fns {
            walk_names(&def.body, &mut |n, _, _| {
                let list = users.entry(n.to_string()).or_default();
                if list.last() != Some(f) {
                    list.push(f.clone());
                }
            });
        }
        self.users = users;
        let names: Vec<String> = self.poisoned.iter().cloned().collect();
        names.into_iter().for_each(|n| self.poison(n));
    }

    /// Marks `name` as failed, with every function that uses it through any
    /// chain of calls: later uses are not reported again.
    pub(super) fn poison(&mut self, name: String) {
        let mut queue = vec![name.clone()];
        self.poisoned.insert(name);
        while let Some(n) = queue.pop() {
            for f in self.users.get(&n).into_iter().flatten() {
                if self.tainted.insert(f.clone()) {
                    queue.push(f.clone());
                }
            }
        }
    }
}

/// Calls `f(name, span, is_call)` for every name and call in `e`.
pub(super) fn walk_names(e: &Expr, f: &mut impl FnMut(&str, Span, bool)) {
    match &e.kind {
        ExprKind::Number(_) => {}
        ExprKind::Name(n) => f(n, e.span, false),
        ExprKind::Matrix(rows) => rows.iter().flatten().for_each(|x| walk_names(x, f)),
        ExprKind::Neg(a) | ExprKind::Transpose(a) => walk_names(a, f),
        ExprKind::Binary(_, a, b) => {
            walk_names(a, f);
            walk_names(b, f);
        }
        ExprKind::Index(a, idx) => {
            walk_names(a, f);
            for i in idx {
                match i {
                    IndexArg::Full => {}
                    IndexArg::One(x) => walk_names(x, f),
                    IndexArg::Range(x, y) => {
                        walk_names(x, f);
                        walk_names(y, f);
                    }
                }
            }
        }
        ExprKind::Call(name, args) => {
            f(&name.node, name.span, true);
            args.iter().for_each(|a| walk_names(&a.value, f));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::walk_names;
    use crate::check::testing::*;

    #[test]
    fn signals_are_not_constants() {
        let (m, at) = only_error("const k = 2 * u;");
        assert!(m.contains("`u`"), "{m}");
        assert_eq!(at, "u");
        let (_, at) = only_error("const k = x;");
        assert_eq!(at, "x");
    }

    #[test]
    fn a_failed_definition_is_reported_once() {
        // `a` fails; its uses (directly and through a function) are not reported again.
        let e = errors(&format!(
            "{BASE}const a = [1, 2] + [1; 2];\nfn f(v) = a * v;\nconst b = a + 1;\nconst c = f(2);"
        ));
        assert_eq!(e.len(), 1, "{e:#?}");
        assert_eq!(e[0].1, "[1, 2] + [1; 2]");
    }

    #[test]
    fn walk_names_sees_names_calls_and_indices() {
        let (file, d, _) = crate::parser::parse_file("const y = f(x1[k])' + g;");
        assert!(d.is_empty(), "{d:?}");
        let crate::ast::ItemKind::Const(_, e) = &file.items[0].kind else {
            panic!("not a constant"); // ok: unit test
        };
        let mut seen = Vec::new();
        walk_names(e, &mut |n, _, call| seen.push((n.to_string(), call)));
        let want = [("f", true), ("x1", false), ("k", false), ("g", false)];
        assert_eq!(seen, want.map(|(n, c)| (n.to_string(), c)));
    }
}
