//! Given gains: a rule may carry its PDC gain `F = ...` (m x n, u = F x);
//! the compiler then analyzes these gains instead of synthesizing them. Every
//! rule gives one or none (a method that designs the gains together with the
//! trigger weight refuses them: `compat/trigger.rs`).

use super::{Checker, Dims};
use crate::ast::{Ident, Item, ItemKind, NamedArg};
use crate::diag::Diagnostic;
use crate::display::literal;
use crate::eval::Mat;
use crate::span::Span;

/// The name of the gain in a rule.
pub(super) const GAIN: &str = "F";

/// The largest gain written out in a "write this instead" hint.
const HINT_ENTRIES: usize = 12;

/// "1x2, one row per input and one column per state".
fn shape_words(rows: usize, cols: usize) -> String {
    format!("{rows}x{cols}, one row per input and one column per state")
}

/// The `F = ...` of a rule item, if it gives one.
pub(super) fn gain_arg(it: &Item) -> Option<&NamedArg> {
    match &it.kind {
        ItemKind::Rule { matrices, .. } => matrices.iter().find(|m| m.name.node == GAIN),
        _ => None,
    }
}

impl Checker<'_> {
    /// The gain `F = value` of rule `rule`: an m x n matrix of finite numbers.
    pub(super) fn gain(&mut self, rule: &Ident, arg: &NamedArg, dims: Dims) -> Option<Mat> {
        let (rows, cols) = (dims.m, dims.n);
        let v = self.eval_const(&arg.value)?;
        if (v.nrows(), v.ncols()) == (rows, cols) {
            return Some(v);
        }
        let mut d = Diagnostic::error(
            arg.value.span,
            format!(
                "the gain `F` of rule {} must be {rows}x{cols}, but this is {}x{}",
                rule.node,
                v.nrows(),
                v.ncols()
            ),
        )
        .with_label(format!("{}x{} matrix", v.nrows(), v.ncols()))
        .with_note(format!("u = F x: F is {}", shape_words(rows, cols)));
        if (v.nrows(), v.ncols()) == (cols, rows) && rows != cols {
            d = d.with_help(if v.len() <= HINT_ENTRIES {
                format!(
                    "this looks transposed: write `F = {}`",
                    literal(&v.transpose())
                )
            } else {
                "this looks transposed: write its transpose (`[..]'`)".to_string()
            });
        } else if v.nrows() == 1 && v.len() == rows * cols && rows > 1 {
            d = d.with_help(
                "rows are separated by `;` (`[a, b; c, d]`); `[[a, b], [c, d]]` puts the blocks side by side",
            );
        }
        self.shape_err(d);
        None
    }

    /// Every rule gives its gain, or none does: a partial set is reported
    /// once, at the first rule without one. A rule that failed to parse may
    /// have given one, so it is not judged then.
    pub(super) fn gains_all_or_none(&mut self, rule_items: &[&Item]) {
        if self.broken("rule") {
            return;
        }
        let Some(given) = rule_items.iter().find_map(|it| gain_arg(it)) else {
            return;
        };
        let missing: Vec<&Ident> = rule_items
            .iter()
            .filter(|it| gain_arg(it).is_none())
            .filter_map(|it| match &it.kind {
                ItemKind::Rule { name, .. } => Some(name),
                _ => None,
            })
            .collect();
        let Some(first) = missing.first() else {
            return;
        };
        let names: Vec<&str> = missing.iter().map(|n| n.node.as_str()).collect();
        let mut d = Diagnostic::error(
            first.span,
            format!(
                "rule {} has no gain `F`, but other rules give theirs",
                first.node
            ),
        )
        .with_label("no `F = ...` in this rule")
        .with_secondary(gain_span(given), "a gain given here")
        .with_note("with given gains tsfc analyzes them instead of synthesizing: every rule needs its gain, or none");
        if names.len() > 1 {
            d = d.with_note(format!("rules without a gain: {}", names.join(", ")));
        }
        let (m, n) = self.gain_shape();
        self.err(d.with_help(format!(
            "give every rule its `F = ...` ({}), or remove `F` from every rule to synthesize the gains",
            shape_words(m, n)
        )));
    }

    /// (m, n) of a gain.
    fn gain_shape(&self) -> (usize, usize) {
        let d = self.dims();
        (d.m, d.n)
    }
}

/// The span of `F = value`, for messages pointing at a given gain.
pub(super) fn gain_span(arg: &NamedArg) -> Span {
    arg.name.span.join(arg.value.span)
}

#[cfg(test)]
mod tests {
    use crate::check::testing::*;

    /// Two states, one input, two rules; `r1` and `r2` complete the rules.
    fn two_rules(r1: &str, r2: &str) -> String {
        format!(
            "tsf 1; controller c; state x1, x2; input u; A = [0, 1; -1, 0]; B = [0; 1];\n\
             premise x1 range -1 .. 1 {{ lo = tri(-1, -1, 1); hi = tri(-1, 1, 1); }}\n\
             rule R1: x1 is lo => {r1};\nrule R2: x1 is hi => {r2};\n"
        )
    }

    #[test]
    fn every_rule_may_give_its_gain() {
        let spec = valid(&two_rules(
            "at(x1 = -1), F = [-1, -2]",
            "F = [-1.5, -2.25], A = [0, 1; -2, 0]",
        ));
        let f = spec.given_gains().expect("given gains"); // ok: unit test
        assert_eq!(f.len(), 2);
        assert_eq!((f[1].nrows(), f[1].ncols()), (1, 2));
        assert_eq!(f[1][(0, 1)].to_bits(), (-2.25f64).to_bits());
        assert_eq!(spec.rules[1].overrides.len(), 1);
        assert!(valid(&two_rules("at(x1 = -1)", "at(x1 = 1)"))
            .given_gains()
            .is_none());
    }

    #[test]
    fn a_gain_has_the_input_by_state_shape() {
        let (m, at) = only_error_of(&two_rules("F = [-1; -2]", "F = [-1, -2]"));
        assert_eq!(m, "the gain `F` of rule R1 must be 1x2, but this is 2x1");
        assert_eq!(at, "[-1; -2]");
        let e = crate::check::testing::errors(&two_rules("F = [-1; -2]", "F = [-1, -2]"));
        assert!(e[0]
            .0
            .help
            .as_deref()
            .is_some_and(|h| h.contains("transposed: write `F = [-1, -2]`")));
        let (m, _) = only_error_of(&two_rules("F = [-1, -2, 3]", "F = [-1, -2]"));
        assert_eq!(m, "the gain `F` of rule R1 must be 1x2, but this is 1x3");
        let (m, _) = only_error_of(&two_rules("F = [1, 2], F = [1, 2]", "F = [-1, -2]"));
        assert_eq!(m, "`F` is given twice in rule R1");
    }

    #[test]
    fn a_gain_is_finite() {
        let (m, at) = only_error_of(&two_rules("F = [exp(1000), 1]", "F = [-1, -2]"));
        assert_eq!(m, "value is not finite");
        assert_eq!(at, "[exp(1000), 1]");
    }

    #[test]
    fn gains_are_given_in_every_rule_or_none() {
        let (m, at) = only_error_of(&two_rules("F = [-1, -2]", "at(x1 = 1)"));
        assert_eq!(m, "rule R2 has no gain `F`, but other rules give theirs");
        assert_eq!(at, "R2");
        // A gain of the wrong shape still counts as given: both mistakes are reported.
        let e = crate::check::testing::errors(&two_rules("F = [-1]", "at(x1 = 1)"));
        assert_eq!(e.len(), 2, "{e:#?}");
    }
}
