//! The double-sum relaxation: `relaxation basic | tanaka(s = ..) | tuan |
//! polya(d = ..) | membership_mismatch(kappa = ..);` (default `basic`).

use super::{unknown_choice, Checker, Draft};
use crate::ast::{Ident, Item, NamedArg};
use crate::diag::Diagnostic;
use crate::limits::{polya_lmis, MAX_MISMATCH_RULES, MAX_POLYA_DEGREE, MAX_POLYA_LMIS};
use crate::num::Num;
use crate::span::{Span, Spanned};
use crate::spec::{Relaxation, RuleSpec};

impl Checker<'_> {
    /// A `relaxation` item (given once).
    pub(super) fn relaxation_item(
        &mut self,
        it: &Item,
        name: &Ident,
        args: &[NamedArg],
        draft: &mut Draft,
    ) {
        let mut seen = draft.relaxation.as_ref().map(|r| r.span);
        if self.singleton(&mut seen, it.span, "the relaxation") {
            if let Some(r) = self.relaxation(name, args, it.span) {
                draft.relaxation = Some(Spanned::new(r, it.span));
            }
        }
    }

    /// The relaxation in force (`basic` when none is given); `tanaka(s)` needs
    /// 1 <= s <= r when every rule checked (`rule_items` of them).
    pub(super) fn settle_relaxation(
        &mut self,
        relaxation: Option<Spanned<Relaxation>>,
        rules: &[RuleSpec],
        rule_items: usize,
    ) -> Spanned<Relaxation> {
        let relaxation = relaxation.unwrap_or(Spanned::new(Relaxation::Basic, Span::new(0, 0)));
        if let Relaxation::Tanaka { s } = relaxation.node {
            if rules.len() == rule_items && (s < 1 || s > rules.len()) {
                self.err(
                    Diagnostic::error(
                        relaxation.span,
                        format!("tanaka(s = {s}) needs 1 <= s <= r = {}", rules.len()),
                    )
                    .with_label("s is the most rules that fire at once"),
                );
            }
        }
        if matches!(relaxation.node, Relaxation::MembershipMismatch { .. })
            && rules.len() > MAX_MISMATCH_RULES
        {
            self.err(
                Diagnostic::error(
                    relaxation.span,
                    format!(
                        "membership_mismatch with {} rules: at most {MAX_MISMATCH_RULES} rules (2 r^2 slack matrices per objective)",
                        rules.len()
                    ),
                )
                .with_help("use `tuan` or `tanaka(s = ..)` for many rules"),
            );
        }
        if let Relaxation::Polya { d } = relaxation.node {
            let count = polya_lmis(rules.len(), d);
            if count.is_none_or(|c| c > MAX_POLYA_LMIS) {
                self.err(
                    Diagnostic::error(
                        relaxation.span,
                        format!(
                            "polya(d = {d}) with {} rules needs {} LMIs per objective, over the limit of {MAX_POLYA_LMIS}",
                            rules.len(),
                            count.map_or_else(|| "too many".to_string(), |c| c.to_string())
                        ),
                    )
                    .with_help("lower d, or use `tuan` or `tanaka(s = ..)` for many rules"),
                );
            }
        }
        relaxation
    }

    fn relaxation(&mut self, name: &Ident, args: &[NamedArg], span: Span) -> Option<Relaxation> {
        let kinds = ["basic", "tanaka", "tuan", "polya", "membership_mismatch"];
        match name.node.as_str() {
            "basic" | "tuan" => {
                self.named(args, &[], &format!("relaxation `{}`", name.node))?;
                Some(if name.node == "basic" {
                    Relaxation::Basic
                } else {
                    Relaxation::Tuan
                })
            }
            "tanaka" => {
                let p = self.named(args, &["s"], "relaxation `tanaka`")?;
                let Some(s) = p.get("s").copied() else {
                    self.err(
                        Diagnostic::error(
                            span,
                            "`tanaka` needs `s`, the most rules that fire at once",
                        )
                        .with_help("write `relaxation tanaka(s = 4);`"),
                    );
                    return None;
                };
                if s.fract() != 0.0 || s < 1.0 {
                    self.err(Diagnostic::error(
                        span,
                        format!("`s` must be a whole number >= 1, found {}", Num(s)),
                    ));
                    return None;
                }
                Some(Relaxation::Tanaka { s: s as usize })
            }
            "polya" => {
                let p = self.named(args, &["d"], "relaxation `polya`")?;
                let d = p.get("d").copied().unwrap_or(1.0);
                if d.fract() != 0.0 || !(0.0..=MAX_POLYA_DEGREE as f64).contains(&d) {
                    self.err(
                        Diagnostic::error(
                            span,
                            format!(
                                "`d` must be a whole number in 0 ..= {MAX_POLYA_DEGREE}, found {}",
                                Num(d)
                            ),
                        )
                        .with_help("the number of LMIs grows as (r + d + 1 choose d + 2); d = 1 or 2 is usual"),
                    );
                    return None;
                }
                Some(Relaxation::Polya { d: d as usize })
            }
            "membership_mismatch" => {
                let p = self.named(args, &["kappa"], "relaxation `membership_mismatch`")?;
                let kappa = p.get("kappa").copied().unwrap_or(0.0);
                if !(0.0..=1.0).contains(&kappa) {
                    self.err(
                        Diagnostic::error(
                            span,
                            format!("`kappa` must be in [0, 1], found {}", Num(kappa)),
                        )
                        .with_help("kappa bounds |k_j - h_j|, the difference of the controller's and the plant's membership of each rule: 0 = the same memberships, 1 = any"),
                    );
                    return None;
                }
                Some(Relaxation::MembershipMismatch { kappa })
            }
            other => {
                self.err(unknown_choice(
                    name.span,
                    "relaxation",
                    "relaxations",
                    other,
                    &kinds,
                ));
                None
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::check::testing::*;
    use crate::spec::Relaxation;

    /// A spec with `r` rules (one triangle each on x1) and `relaxation`.
    fn rules_spec(r: usize, relaxation: &str) -> String {
        let sets: Vec<String> = (0..r)
            .map(|k| format!("s{k} = tri({}, {k}, {});", k as f64 - 1.0, k + 1))
            .collect();
        let rules: Vec<String> = (0..r)
            .map(|k| format!("rule R{k}: x1 is s{k} => A = -2;"))
            .collect();
        format!(
            "tsf 1; controller c; state x1; input u; A = -1; B = 1;\n\
             premise x1 range 0 .. {} {{ {} }}\n{}\nrelaxation {relaxation};\n",
            r - 1,
            sets.join(" "),
            rules.join("\n")
        )
    }

    #[test]
    fn membership_mismatch_is_bounded_in_rules() {
        let kappa = "membership_mismatch(kappa = 0.1)";
        assert_eq!(valid(&rules_spec(16, kappa)).rules.len(), 16);
        let (m, at) = only_error_of(&rules_spec(17, kappa));
        assert_eq!(
            m,
            "membership_mismatch with 17 rules: at most 16 rules (2 r^2 slack matrices per objective)"
        );
        assert_eq!(at, format!("relaxation {kappa};"));
        assert_eq!(valid(&rules_spec(17, "basic")).rules.len(), 17);
    }

    #[test]
    fn each_relaxation_with_its_parameters() {
        assert_eq!(spec_with("").relaxation.node, Relaxation::Basic);
        assert_eq!(
            spec_with("relaxation tuan;").relaxation.node,
            Relaxation::Tuan
        );
        assert_eq!(
            spec_with("relaxation tanaka(s = 1);").relaxation.node,
            Relaxation::Tanaka { s: 1 }
        );
        assert_eq!(
            spec_with("relaxation membership_mismatch(kappa = 0.12);")
                .relaxation
                .node,
            Relaxation::MembershipMismatch { kappa: 0.12 }
        );
    }

    #[test]
    fn parameters_are_checked() {
        let (m, at) = only_error("relaxation tanaka(s = 4);");
        assert_eq!(m, "tanaka(s = 4) needs 1 <= s <= r = 1");
        assert_eq!(at, "relaxation tanaka(s = 4);");
        let (m, _) = only_error("relaxation tanaka;");
        assert_eq!(m, "`tanaka` needs `s`, the most rules that fire at once");
        let (m, _) = only_error("relaxation polya(d = 7);");
        assert!(
            m.starts_with("`d` must be a whole number in 0 ..= 4"),
            "{m}"
        );
        let (m, _) = only_error("relaxation membership_mismatch(kappa = 1.5);");
        assert_eq!(m, "`kappa` must be in [0, 1], found 1.5");
        let (m, at) = only_error("relaxation basic(s = 1);");
        assert_eq!(m, "relaxation `basic` has no parameter `s`");
        assert_eq!(at, "s");
        let (m, at) = only_error("relaxation tanka(s = 1);");
        assert_eq!(m, "unknown relaxation `tanka`");
        assert_eq!(at, "tanka");
    }
}
