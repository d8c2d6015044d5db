//! Premise expressions the generated controllers can evaluate.
//!
//! The code generator expands each premise expression into scalar code of the
//! state (in the compiler, `codegen/sym.rs`: `Ctx::call` for functions,
//! `Ctx::binary` for `^`, `Ctx::index` for indices). It knows fewer functions
//! than the evaluator, so a premise the checker accepted could otherwise fail
//! only after solving, when code is generated.

use super::env::walk_names;
use super::Checker;
use crate::ast::{BinOp, Expr, ExprKind, Ident, IndexArg};
use crate::diag::Diagnostic;
use crate::eval::{Mode, BUILTINS};
use crate::span::Span;

/// The built-in functions a premise may call. The other side of this list is
/// the code generator's `Ctx::call` in the compiler's `codegen/sym.rs`: keep
/// the two in step.
pub const GENERATABLE_FUNCTIONS: &[&str] = &[
    "sin",
    "cos",
    "exp",
    "sqrt",
    "atan",
    "abs",
    "sinc",
    "exprel",
    "sum",
    "mean",
    "dot",
    "norm",
    "transpose",
];

/// How deep user functions are followed (the generator stops at 32).
const MAX_DEPTH: usize = 16;

impl Checker<'_> {
    /// Reports every function, power and index of the premise expression
    /// `bound` (bound to `names`) that generated code cannot evaluate.
    pub(super) fn check_generatable(&mut self, bound: &Expr, names: &[Ident]) {
        let mut found = Vec::new();
        self.unsupported_calls(bound, None, 0, &mut found);
        self.unsupported_operations(bound, &mut found);
        let which = names
            .iter()
            .map(|n| format!("`{}`", n.node))
            .collect::<Vec<_>>()
            .join(", ");
        for d in found {
            self.err(d.with_note(format!(
                "the generated controller evaluates premise {which}"
            )));
        }
    }

    /// Calls of built-ins outside [`GENERATABLE_FUNCTIONS`], through user
    /// functions too (`via`: the outermost user call in the premise).
    fn unsupported_calls(
        &self,
        e: &Expr,
        via: Option<(&str, Span)>,
        depth: usize,
        found: &mut Vec<Diagnostic>,
    ) {
        let mut calls = Vec::new();
        walk_names(e, &mut |name, span, is_call| {
            if is_call {
                calls.push((name.to_string(), span));
            }
        });
        for (name, span) in calls {
            if let Some(f) = self.fns.get(&name) {
                if depth < MAX_DEPTH {
                    let via = via.or(Some((name.as_str(), span)));
                    self.unsupported_calls(&f.body, via, depth + 1, found);
                }
            } else if BUILTINS.contains(&name.as_str())
                && !GENERATABLE_FUNCTIONS.contains(&name.as_str())
            {
                let mut d = Diagnostic::error(
                    span,
                    format!("generated code cannot evaluate `{name}` in a premise"),
                )
                .with_label("not available in generated premise code")
                .with_help(format!(
                    "a premise may call {} and functions built from them; compute constant parts in a `const`",
                    GENERATABLE_FUNCTIONS.join(", ")
                ));
                if let Some((f, at)) = via {
                    d = d.with_secondary(at, format!("the premise calls `{f}` here"));
                }
                found.push(d);
            }
        }
    }

    /// Powers and indices of the premise expression itself: the generator
    /// needs a scalar base with a constant whole exponent from 0 to 16 (or a
    /// constant base and exponent), and constant indices.
    fn unsupported_operations(&self, e: &Expr, found: &mut Vec<Diagnostic>) {
        let constant = |x: &Expr| self.evaluate(&self.const_env(), x).ok();
        match &e.kind {
            ExprKind::Number(_) | ExprKind::Name(_) => {}
            ExprKind::Matrix(rows) => rows
                .iter()
                .flatten()
                .for_each(|x| self.unsupported_operations(x, found)),
            ExprKind::Neg(a) | ExprKind::Transpose(a) => self.unsupported_operations(a, found),
            ExprKind::Call(_, args) => args
                .iter()
                .for_each(|a| self.unsupported_operations(&a.value, found)),
            ExprKind::Binary(op, a, b) => {
                self.unsupported_operations(a, found);
                self.unsupported_operations(b, found);
                if *op != BinOp::Pow {
                    return;
                }
                let base = self.evaluate(&self.state_env(Mode::Shapes, &[], &[]), a);
                if let Ok(v) = &base {
                    if v.nrows() != 1 || v.ncols() != 1 {
                        found.push(
                            Diagnostic::error(
                                e.span,
                                "generated code cannot raise a matrix to a power in a premise",
                            )
                            .with_label(format!("a {}x{} matrix power", v.nrows(), v.ncols()))
                            .with_help(
                                "write the product out, or compute a constant power in a `const`",
                            ),
                        );
                        return;
                    }
                }
                let whole = constant(b).is_some_and(|k| {
                    k.len() == 1 && k[(0, 0)].fract() == 0.0 && (0.0..=16.0).contains(&k[(0, 0)])
                });
                let both_constant = constant(a).is_some() && constant(b).is_some();
                if !whole && !both_constant {
                    found.push(
                        Diagnostic::error(
                            e.span,
                            "generated code supports only constant whole powers from 0 to 16 of the state in a premise",
                        )
                        .with_label("this power")
                        .with_help("write `sqrt(v)` for `v^0.5`, or a product for larger powers"),
                    );
                }
            }
            ExprKind::Index(a, idx) => {
                self.unsupported_operations(a, found);
                for i in idx {
                    let parts: Vec<&Expr> = match i {
                        IndexArg::Full => vec![],
                        IndexArg::One(x) => vec![x],
                        IndexArg::Range(x, y) => vec![x, y],
                    };
                    for x in parts {
                        self.unsupported_operations(x, found);
                        if constant(x).is_none() {
                            found.push(
                                Diagnostic::error(
                                    x.span,
                                    "generated code needs constant indices in a premise",
                                )
                                .with_label("depends on the state")
                                .with_help("index with numbers or constants"),
                            );
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::GENERATABLE_FUNCTIONS;
    use crate::check::testing::*;
    use crate::eval::BUILTINS;

    fn premise(expr: &str) -> String {
        base_with(
            "premise x1 range -1 .. 1 { all = trap(-1, -1, 1, 1); }",
            &format!(
                "premise x1 range -1 .. 1 {{ all = trap(-1, -1, 1, 1); }}\npremise p = {expr};"
            ),
        )
    }

    #[test]
    fn every_generatable_function_is_a_builtin() {
        for f in GENERATABLE_FUNCTIONS {
            assert!(BUILTINS.contains(f), "{f}");
        }
    }

    #[test]
    fn generatable_premises_are_accepted() {
        for e in [
            "sinc(x1) + atan(x1) * exp(-abs(x1))",
            "exp(0.5) * exprel(x1)",
            "sqrt(1 + x1 ^ 2) / cos(0.5)",
            "norm([x1; 2 * x1])",
            "sum([x1; x1]) + mean([x1, 1]) + dot([x1; 1], [1; x1])",
            "[x1; x1][1]",
            "2 ^ 0.5 * x1",
        ] {
            valid(&premise(e));
        }
    }

    #[test]
    fn a_function_generated_code_lacks_is_an_error_at_the_call() {
        let (m, at) = only_error_of(&premise("log(1 + x1 * x1)"));
        assert_eq!(m, "generated code cannot evaluate `log` in a premise");
        assert_eq!(at, "log");
        let (m, at) = only_error_of(&premise("x1 / pi()"));
        assert_eq!(m, "generated code cannot evaluate `pi` in a premise");
        assert_eq!(at, "pi");
    }

    #[test]
    fn calls_inside_user_functions_are_followed() {
        let src = format!("{}fn f(v) = tan(v);\nfn g(v) = 2 * f(v);", premise("g(x1)"));
        let e = errors(&src);
        assert_eq!(e.len(), 1, "{e:#?}");
        let d = &e[0].0;
        assert_eq!(
            d.message,
            "generated code cannot evaluate `tan` in a premise"
        );
        assert_eq!(e[0].1, "tan");
        assert_eq!(d.secondary[0].message, "the premise calls `g` here");
        assert_eq!(
            &src[d.secondary[0].span.start..d.secondary[0].span.end],
            "g"
        );
    }

    #[test]
    fn powers_and_indices_must_be_generatable() {
        let (m, at) = only_error_of(&premise("x1 ^ 0.5"));
        assert_eq!(
            m,
            "generated code supports only constant whole powers from 0 to 16 of the state in a premise"
        );
        assert_eq!(at, "x1 ^ 0.5");
        let (m, _) = only_error_of(&premise("x1 ^ x1"));
        assert!(m.contains("constant whole powers"), "{m}");
        let (m, at) = only_error_of(&premise("([x1, 0; 0, 1] ^ 2)[0, 0]"));
        assert_eq!(
            m,
            "generated code cannot raise a matrix to a power in a premise"
        );
        assert_eq!(at, "[x1, 0; 0, 1] ^ 2");
        let (m, at) = only_error_of(&premise("[x1; 1][x1 * 0]"));
        assert_eq!(m, "generated code needs constant indices in a premise");
        assert_eq!(at, "x1 * 0");
    }
}
