//! `saturate` levels and the saturation region: what the certificate of a
//! saturated loop needs from the rest of the spec. Declared levels must be
//! inside the certificate, by the saturation region (`objective saturation
//! region;`, or implied by the levels when no `input_norm` bound is given) or
//! by an input bound no larger than the smallest level; the region needs the
//! levels; with a bounded disturbance its level depends on xi / phi of the
//! L-inf objective, so one of them must be fixed. The compiler's side is
//! `synth/objectives/saturation.rs`, `linf.rs` and `synth/search.rs`.

use super::Around;
use crate::check::Checker;
use crate::diag::Diagnostic;
use crate::num::Num;
use crate::span::Span;
use crate::spec::{Objective, SpannedObjective, Target};

/// Where the saturation region of a spec comes from.
enum Region<'o> {
    /// `objective saturation region;`.
    Asked(&'o SpannedObjective),
    /// Implied by the `saturate` levels (written at the span), no input bound given.
    Implied(Span),
}

impl Checker<'_> {
    /// Errors for the saturation region and the `saturate` levels.
    pub(super) fn saturation_fits(&mut self, around: &Around<'_>) {
        let find = |f: fn(&Objective) -> bool| around.objectives.iter().find(|o| f(&o.node));
        let asked = find(|o| matches!(o, Objective::SaturationRegion { .. }));
        if let (Some(o), None) = (asked, around.saturate) {
            let at = around.first_input.unwrap_or(Span::new(0, 0));
            self.err(
                Diagnostic::error(
                    o.span,
                    "`objective saturation region` needs saturation levels",
                )
                .with_secondary(at, "input declared here")
                .with_help("declare them: `input u[3] saturate 2.0;`"),
            );
            return;
        }
        // With modes, saturation and these objectives are refused by `modes.rs`.
        let (Some(levels), None) = (around.levels, around.modes) else {
            return;
        };
        let saturate = around.saturate.unwrap_or(Span::new(0, 0));
        let input_norm = find(|o| matches!(o, Objective::InputNorm { .. }));
        let region = match (asked, input_norm) {
            (Some(o), _) => Some(Region::Asked(o)),
            (None, None) if around.objectives_complete => Some(Region::Implied(saturate)),
            (None, _) => None,
        };
        if let (Some(region), Some(_)) = (&region, around.disturbance_bound) {
            self.linf_level_fixed(around, region);
        }
        if let (None, Some(o)) = (asked, input_norm) {
            self.input_bound_within(o, levels, saturate);
        }
    }

    /// With the saturation region and a bounded disturbance the linear region
    /// shrinks by 1 + xi tau^2 / phi: an L-inf objective must fix xi or phi.
    fn linf_level_fixed(&mut self, around: &Around<'_>, region: &Region<'_>) {
        let Some(l) = around.objectives.iter().find(|o| {
            matches!(
                o.node,
                Objective::Linf {
                    xi: None,
                    phi: None,
                    ..
                }
            )
        }) else {
            return;
        };
        let d = Diagnostic::error(
            l.span,
            "with the saturation region and a bounded disturbance, the L-inf objective needs a fixed `phi` or `xi`",
        )
        .with_label("neither `phi` nor `xi` is given");
        let d = match region {
            Region::Asked(sat) => d.with_secondary(sat.span, "saturation region here"),
            Region::Implied(at) => d
                .with_secondary(*at, "saturation region implied by these levels")
                .with_note("declared `saturate` levels are certified by the saturation region unless an `input_norm` bound covers them"),
        };
        self.err(
            d.with_note("the linear region is shrunk by 1 + xi tau^2 / phi (tau: the disturbance bound); tsfc searches one of xi, phi with the other fixed")
                .with_help("add `with phi = 0.05` (tsfc then minimizes xi) or `with xi = ...` (tsfc then searches phi)"),
        );
    }

    /// Without the saturation region, a fixed input bound above the smallest
    /// level leaves the declared levels outside the certificate.
    fn input_bound_within(&mut self, o: &SpannedObjective, levels: &[f64], saturate: Span) {
        let Objective::InputNorm {
            target: Target::Fixed(bound),
            ..
        } = o.node
        else {
            return;
        };
        let smallest = levels.iter().copied().fold(f64::INFINITY, f64::min);
        if bound <= smallest {
            return;
        }
        self.err(
            Diagnostic::error(
                o.span,
                format!(
                    "the declared `saturate` level {} is outside the certificate: this input bound is {}",
                    Num(smallest),
                    Num(bound)
                ),
            )
            .with_label(format!("certifies ||u|| <= {} only", Num(bound)))
            .with_secondary(saturate, "levels declared here")
            .with_note("without the saturation region the certificate speaks of the unsaturated loop: the input bound must keep the actuator below its levels")
            .with_help(format!(
                "bound the input with `objective input_norm(u) <= {} for x0 = ...` or add `objective saturation region;`",
                Num(smallest)
            )),
        );
    }
}

#[cfg(test)]
mod tests {
    use crate::check::testing::*;

    /// `BASE` with saturation levels, a bounded disturbance and an output, then `extra`.
    fn spec(extra: &str) -> String {
        format!(
            "{}disturbance d bound 0.1; D = 1;\noutput z = x1;\n{extra}",
            base_with("input u;", "input u saturate 2;")
        )
    }

    #[test]
    fn supported_combinations_are_accepted() {
        valid(&spec(
            "objective linf(d -> z) minimize with xi = 0.5;\nobjective saturation region;",
        ));
        valid(&spec(
            "objective hinf(d -> z) minimize;\nobjective decay_rate >= 0.1;",
        ));
        valid(&spec(
            "objective hinf(d -> z) minimize;\nobjective saturation region;",
        ));
        // An input bound within the level; a minimized one is judged by synthesis.
        valid(&spec("objective input_norm(u) <= 2 for x0 = 1;"));
        valid(&spec("objective input_norm(u) minimize for x0 = 1;"));
        // The levels covered by an input bound: no region implied.
        valid(&spec(
            "objective linf(d -> z) minimize;\nobjective input_norm(u) <= 1 for x0 = 1;",
        ));
    }

    #[test]
    fn the_region_needs_levels() {
        let src = format!(
            "{BASE}disturbance d bound 0.1; D = 1;\noutput z = x1;\n\
             objective hinf(d -> z) minimize;\nobjective saturation region;"
        );
        let (m, at) = only_error_of(&src);
        assert_eq!(m, "`objective saturation region` needs saturation levels");
        assert_eq!(at, "objective saturation region;");
    }

    #[test]
    fn a_bounded_disturbance_needs_a_fixed_phi_or_xi() {
        let want = "with the saturation region and a bounded disturbance, the L-inf objective needs a fixed `phi` or `xi`";
        let (m, at) = only_error_of(&spec(
            "objective linf(d -> z) minimize;\nobjective saturation region;",
        ));
        assert_eq!(
            (m.as_str(), at.as_str()),
            (want, "objective linf(d -> z) minimize;")
        );
        // The region implied by the levels asks the same.
        let e = errors(&spec("objective linf(d -> z) minimize;"));
        assert_eq!(e.len(), 1, "{e:#?}");
        assert_eq!(e[0].0.message, want);
        assert_eq!(
            e[0].0.secondary[0].message,
            "saturation region implied by these levels"
        );
    }

    #[test]
    fn an_input_bound_above_the_level_is_refused() {
        let (m, at) = only_error_of(&spec("objective input_norm(u) <= 5 for x0 = 1;"));
        assert_eq!(
            m,
            "the declared `saturate` level 2 is outside the certificate: this input bound is 5"
        );
        assert_eq!(at, "objective input_norm(u) <= 5 for x0 = 1;");
        // With the region the levels are covered by it.
        valid(&spec(
            "objective input_norm(u) <= 5 for x0 = 1;\nobjective saturation region;",
        ));
    }
}
