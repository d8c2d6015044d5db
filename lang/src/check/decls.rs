//! Declarations: the language version, the controller name, functions,
//! constants and the signals (states, inputs with their saturation levels,
//! disturbances with their bound).

use super::env::walk_names;
use super::{Checker, Kind};
use crate::ast::{DisturbanceLimit, Expr, Item, ItemKind, VarDecl};
use crate::diag::Diagnostic;
use crate::eval::{FnDef, BUILTINS};
use crate::span::{Span, Spanned};
use crate::spec::Signal;
use crate::suggest::suggest;

/// The language versions this checker reads.
const SUPPORTED_VERSION: f64 = 1.0;

/// The expressions after `saturate` and `bound`, evaluated once every signal is known.
pub(super) struct Limits<'a> {
    /// `input u[3] saturate <e>;`
    pub saturate: Option<&'a Expr>,
    /// `disturbance d bound <e>;`
    pub bound: Option<&'a Expr>,
    /// `disturbance d energy <e>;`
    pub energy: Option<&'a Expr>,
}

impl<'a> Checker<'a> {
    /// The version and controller items (each given once); the controller name.
    pub(super) fn header(&mut self, items: &[Item]) -> Option<Spanned<String>> {
        // Version: must come first.
        let mut version_seen = None;
        let mut controller: Option<Spanned<String>> = None;
        for it in items {
            match &it.kind {
                ItemKind::Version(v)
                    if self.singleton(&mut version_seen, it.span, "the language version")
                        && v.node != SUPPORTED_VERSION =>
                {
                    self.err(
                        Diagnostic::error(
                            v.span,
                            format!("unsupported language version {}", v.node),
                        )
                        .with_label("this tsfc reads version 1")
                        .with_help("write `tsf 1;`"),
                    );
                }
                ItemKind::Controller(n) => {
                    let mut seen = controller.as_ref().map(|c| c.span);
                    if self.singleton(&mut seen, it.span, "the controller name") {
                        if !is_c_identifier(&n.node) {
                            self.err(Diagnostic::error(
                                n.span,
                                "controller name is not a valid Rust and C identifier",
                            ));
                        }
                        controller = Some(n.clone());
                    }
                }
                _ => {}
            }
        }
        if version_seen.is_none() && !self.broken("tsf") {
            let at = items
                .first()
                .map_or(Span::new(0, 0), |i| Span::new(i.span.start, i.span.start));
            self.err(
                Diagnostic::error(at, "missing language version")
                    .with_label("the file should start with the version")
                    .with_help("add `tsf 1;` as the first line"),
            );
        }
        if controller.is_none() && !self.broken("controller") {
            self.err(
                Diagnostic::error(Span::new(0, 0), "missing controller name")
                    .with_help("add `controller my_controller;` (it names the generated module)"),
            );
        }
        controller
    }

    /// Declares every function (before constants, which may call them).
    pub(super) fn functions(&mut self, items: &[Item]) {
        for it in items {
            if let ItemKind::Fn(name, params, body) = &it.kind {
                if self.declare(name, Kind::Fn) {
                    self.fns.insert(
                        name.node.clone(),
                        FnDef {
                            params: params.iter().map(|p| p.node.clone()).collect(),
                            body: body.clone(),
                        },
                    );
                }
            }
        }
    }

    /// Constants and signals, in source order.
    pub(super) fn declarations(&mut self, items: &'a [Item]) -> Limits<'a> {
        let mut limits = Limits {
            saturate: None,
            bound: None,
            energy: None,
        };
        for it in items {
            match &it.kind {
                ItemKind::Const(name, e) => {
                    let v = self.eval_const(e);
                    if self.declare(name, Kind::Const) {
                        match v {
                            Some(v) => {
                                self.consts.insert(name.node.clone(), v);
                            }
                            // Later uses are not reported again.
                            None => {
                                self.poison(name.node.clone());
                            }
                        }
                    }
                }
                ItemKind::State(vars) => {
                    let off = self.states.iter().map(|s| s.len).sum();
                    let s = self.signals(vars, Kind::State, off);
                    self.states.extend(s);
                }
                ItemKind::Input(vars, sat) => {
                    let off = self.inputs.iter().map(|s| s.len).sum();
                    let s = self.signals(vars, Kind::Input, off);
                    if let Some(e) = sat {
                        limits.saturate = Some(e);
                    }
                    self.inputs.extend(s);
                }
                ItemKind::Disturbance(vars, limit) => {
                    let off = self.disturbances.iter().map(|s| s.len).sum();
                    let s = self.signals(vars, Kind::Disturbance, off);
                    match limit {
                        Some(DisturbanceLimit::Bound(e)) => limits.bound = Some(e),
                        Some(DisturbanceLimit::Energy(e)) => {
                            if let Some(first) = limits.energy.replace(e) {
                                self.err(
                                    Diagnostic::error(e.span, "the disturbance energy bound is given twice")
                                        .with_secondary(first.span, "first given here")
                                        .with_note("`energy w2` bounds the integral of w'w over every disturbance together: give it once"),
                                );
                            }
                        }
                        None => {}
                    }
                    self.disturbances.extend(s);
                }
                _ => {}
            }
        }
        limits
    }

    /// At least one state and one input.
    pub(super) fn require_signals(&mut self) {
        if self.states.is_empty() && !self.broken("state") {
            self.err(
                Diagnostic::error(Span::new(0, 0), "no states declared")
                    .with_help("declare the state, e.g. `state w[3], q[3];`"),
            );
        }
        if self.inputs.is_empty() && !self.broken("input") {
            self.err(
                Diagnostic::error(Span::new(0, 0), "no inputs declared")
                    .with_help("declare the control input, e.g. `input u[3];`"),
            );
        }
    }

    /// The saturation levels (a scalar for every channel, or one per channel), all positive.
    pub(super) fn saturation_levels(&mut self, e: &Expr, m: usize) -> Option<Vec<f64>> {
        let v = self.eval_const(e)?;
        let levels: Vec<f64> = if v.len() == 1 {
            vec![v[(0, 0)]; m]
        } else if v.len() == m && (v.ncols() == 1 || v.nrows() == 1) {
            v.iter().copied().collect()
        } else {
            self.err(Diagnostic::error(
                e.span,
                format!("saturation needs a scalar or {m} levels (one per input channel)"),
            ));
            return None;
        };
        if levels.iter().any(|l| *l <= 0.0) {
            self.err(Diagnostic::error(
                e.span,
                "saturation levels must be positive",
            ));
            return None;
        }
        Some(levels)
    }

    /// The signals of one declaration, laid out from `offset0`.
    fn signals(&mut self, vars: &[VarDecl], kind: Kind, offset0: usize) -> Vec<Signal> {
        let mut out = Vec::new();
        let mut offset = offset0;
        for v in vars {
            let len = match &v.len {
                None => 1,
                Some(n) if n.node.fract() == 0.0 && n.node >= 1.0 && n.node <= 1000.0 => {
                    n.node as usize
                }
                Some(n) => {
                    self.err(
                        Diagnostic::error(
                            n.span,
                            format!(
                                "invalid size `{}` for {} `{}`",
                                n.node,
                                kind.word(),
                                v.name.node
                            ),
                        )
                        .with_label("a size is a whole number from 1 to 1000"),
                    );
                    continue;
                }
            };
            // A duplicate is reported but kept, so dimensions stay as written.
            self.declare(&v.name, kind);
            out.push(Signal {
                name: v.name.node.clone(),
                len,
                is_vector: v.len.is_some(),
                offset,
                span: v.name.span,
            });
            offset += len;
        }
        out
    }

    /// Checks that every name in every function body is a parameter, constant or function.
    pub(super) fn check_fn_bodies(&mut self) {
        let mut found = Vec::new();
        for f in self.file.items.iter() {
            if let ItemKind::Fn(_, params, body) = &f.kind {
                let mut ps: Vec<&str> = params.iter().map(|p| p.node.as_str()).collect();
                let mut seen = Vec::new();
                for p in params {
                    if seen.contains(&p.node.as_str()) {
                        found.push(Diagnostic::error(
                            p.span,
                            format!("parameter `{}` is repeated", p.node),
                        ));
                    }
                    seen.push(p.node.as_str());
                }
                ps.extend(self.consts.keys().map(String::as_str));
                if self.poisoned(body) {
                    continue;
                }
                walk_names(body, &mut |name, span, is_call| {
                    let ok = if is_call {
                        BUILTINS.contains(&name) || self.fns.contains_key(name)
                    } else {
                        ps.contains(&name)
                    };
                    if !ok {
                        let mut d = Diagnostic::error(
                            span,
                            format!("unknown name `{name}` in function body"),
                        )
                        .with_label(if is_call {
                            "not a function"
                        } else {
                            "not a parameter or constant"
                        });
                        if let Some(s) = suggest(name, ps.iter().copied()) {
                            d = d.with_help(format!("did you mean `{s}`?"));
                        } else if !is_call {
                            d = d.with_help("a function sees only its parameters and constants; pass state values as arguments");
                        }
                        found.push(d);
                    }
                });
            }
        }
        self.diags.extend(found);
    }
}

fn is_c_identifier(s: &str) -> bool {
    let mut ch = s.chars();
    matches!(ch.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
        && ch.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

#[cfg(test)]
mod tests {
    use super::is_c_identifier;
    use crate::check::testing::*;

    #[test]
    fn version_must_be_one_and_present() {
        let (m, at) = only_error_of(&base_with("tsf 1;", "tsf 2;"));
        assert_eq!(m, "unsupported language version 2");
        assert_eq!(at, "2");
        let (m, at) = only_error_of(&base_with("tsf 1; ", ""));
        assert_eq!(m, "missing language version");
        assert_eq!(at, "");
    }

    #[test]
    fn signals_are_laid_out_in_declaration_order() {
        let spec = valid(
            &base_with("state x1;", "state x1; state w[2];\nconst Z = zeros(3, 3);")
                .replace("A = -1;", "A = -eye(3);")
                .replace("B = 1;", "B = [1; 0; 0];")
                .replace("A = -2;", "A = -2 * eye(3) + Z;"),
        );
        let w = &spec.states[1];
        assert_eq!((w.offset, w.len, w.is_vector), (1, 2, true));
        assert_eq!(spec.n(), 3);
        assert_eq!(spec.consts["Z"].shape(), (3, 3));
    }

    #[test]
    fn saturation_and_disturbance_bound_are_checked_values() {
        let spec = valid(
            &base_with("input u;", "input u saturate 2; disturbance d bound 0.5;")
                .replace("B = 1;", "B = 1; D = 1;"),
        );
        assert_eq!(spec.saturation, Some(vec![2.0]));
        assert_eq!(spec.disturbance_bound, Some(0.5));
        let (m, at) = only_error_of(&base_with("input u;", "input u saturate -1;"));
        assert_eq!(m, "saturation levels must be positive");
        assert_eq!(at, "-1");
        let (m, at) = only_error_of(&base_with("input u;", "input u saturate [1, 2];"));
        assert_eq!(
            m,
            "saturation needs a scalar or 1 levels (one per input channel)"
        );
        assert_eq!(at, "[1, 2]");
    }

    #[test]
    fn invalid_sizes_and_missing_signals_are_reported() {
        let (m, at) = only_error("state y[0];");
        assert_eq!(m, "invalid size `0` for state `y`");
        assert_eq!(at, "0");
        let e = errors(&base_with("input u;", ""));
        assert_eq!(e[0].0.message, "no inputs declared");
        assert_eq!(e[0].0.span, crate::Span::new(0, 0));
    }

    #[test]
    fn function_bodies_see_only_parameters_and_constants() {
        let (m, at) = only_error("fn f(a) = a + x1;");
        assert_eq!(m, "unknown name `x1` in function body");
        assert_eq!(at, "x1");
        let (m, at) = only_error("fn g(a, a) = a;");
        assert_eq!(m, "parameter `a` is repeated");
        assert_eq!(at, "a");
        let spec = spec_with("const k = 2;\nfn f(a) = k * a;\nconst j = f(3);");
        assert_eq!(spec.consts["j"][(0, 0)], 6.0);
    }

    #[test]
    fn controller_names_are_c_identifiers() {
        assert!(is_c_identifier("_ctl2"));
        assert!(!is_c_identifier("2ctl"));
        assert!(!is_c_identifier("c-tl"));
        assert!(!is_c_identifier(""));
    }
}
