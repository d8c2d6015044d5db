//! `plant region x1 = lo .. hi, w = lo .. hi, q[2] = lo .. hi;`: the region
//! the plant claim is asked for (a box of states around 0; a vector state's
//! name bounds every component, `q[k]` its component k, 0-based as the
//! language indexes vectors (`v[i]`); states not written are unbounded).

use super::{Checker, Draft};
use crate::ast::{Item, PlantBound};
use crate::diag::Diagnostic;
use crate::span::Spanned;

impl<'a> Checker<'a> {
    /// Checks the item: every written component bounded once, lo < 0 < hi,
    /// once per spec.
    pub(super) fn plant_region_item(
        &mut self,
        it: &Item,
        bounds: &[PlantBound],
        n: usize,
        draft: &mut Draft<'a>,
    ) {
        let mut seen = draft.plant_region.as_ref().map(|r| r.span);
        if !self.singleton(&mut seen, it.span, "the plant region") {
            return;
        }
        let mut region = vec![(f64::NEG_INFINITY, f64::INFINITY); n];
        let mut written: Vec<Option<crate::span::Span>> = vec![None; n];
        let mut ok = true;
        for b in bounds {
            let Some(components) = self.plant_components(b) else {
                ok = false;
                continue;
            };
            let (Some(l), Some(h)) = (
                self.scalar(&b.lo, "a plant region bound"),
                self.scalar(&b.hi, "a plant region bound"),
            ) else {
                ok = false;
                continue;
            };
            let written_as = match &b.index {
                Some(k) => format!("{}[{}]", b.name.node, k.node),
                None => b.name.node.clone(),
            };
            if !(l < 0.0 && h > 0.0 && l.is_finite() && h.is_finite()) {
                self.err(
                    Diagnostic::error(
                        b.name.span,
                        format!("`plant region {written_as}` needs lo < 0 < hi, found {l} .. {h}"),
                    )
                    .with_help("the certified set is an ellipsoid around x = 0, so the box must contain 0 inside"),
                );
                ok = false;
                continue;
            }
            for k in components {
                if let Some(first) = written[k] {
                    self.err(
                        Diagnostic::error(
                            b.name.span,
                            format!("`{written_as}` bounds a state component a second time"),
                        )
                        .with_label("bounded again here")
                        .with_secondary(first, "bounded first here"),
                    );
                    ok = false;
                    continue;
                }
                written[k] = Some(b.name.span);
                region[k] = (l, h);
            }
        }
        if ok {
            draft.plant_region = Some(Spanned::new(region, it.span));
        }
    }

    /// The state components (offsets into x) a bound names: every component
    /// of the state without an index, component k (0-based) with one; `None`
    /// after reporting a bad name or index.
    fn plant_components(&mut self, b: &PlantBound) -> Option<Vec<usize>> {
        let Some(state) = self.states.iter().find(|s| s.name == b.name.node).cloned() else {
            self.err(
                Diagnostic::error(b.name.span, format!("`{}` is not a state", b.name.node))
                    .with_label("the plant region bounds states"),
            );
            return None;
        };
        let Some(index) = &b.index else {
            return Some((state.offset..state.offset + state.len).collect());
        };
        let k = index.node;
        let valid = state.is_vector && k.fract() == 0.0 && k >= 0.0 && k < state.len as f64;
        if !valid {
            let has = match state.len {
                _ if !state.is_vector => format!(
                    "`{}` is a scalar state: write `{}` without an index",
                    b.name.node, b.name.node
                ),
                len => format!(
                    "`{}` has components {}[0] .. {}[{}] (0-based)",
                    b.name.node,
                    b.name.node,
                    b.name.node,
                    len - 1
                ),
            };
            self.err(
                Diagnostic::error(
                    index.span,
                    format!("`{}[{k}]` is not a component of a state", b.name.node),
                )
                .with_label("component index out of range")
                .with_help(has),
            );
            return None;
        }
        Some(vec![state.offset + k as usize])
    }
}

#[cfg(test)]
mod tests {
    use crate::check::testing::*;

    /// A valid spec with a vector state `w[2]` and a scalar `x1`.
    const VECTOR: &str = "tsf 1; controller c; state w[2], x1; input u;\n\
        A = [-1, 0, 0; 0, -1, 0; 0, 0, -1]; B = [0; 0; 1];\n\
        premise x1 range -1 .. 1 { all = trap(-1, -1, 1, 1); }\n\
        rule R: x1 is all => A = [-2, 0, 0; 0, -2, 0; 0, 0, -2];\n";

    fn region_of(line: &str) -> Vec<(f64, f64)> {
        valid(&format!("{VECTOR}{line}\n"))
            .plant_region
            .expect("a plant region")
    }

    #[test]
    fn a_vector_state_is_bounded_whole_or_per_component() {
        let inf = (f64::NEG_INFINITY, f64::INFINITY);
        assert_eq!(
            region_of("plant region w = -0.1 .. 0.2;"),
            vec![(-0.1, 0.2), (-0.1, 0.2), inf]
        );
        assert_eq!(
            region_of("plant region w[1] = -0.3 .. 0.3, x1 = -1 .. 2;"),
            vec![inf, (-0.3, 0.3), (-1.0, 2.0)]
        );
        assert_eq!(
            region_of("plant region w[0] = -1 .. 1, w[1] = -2 .. 2;"),
            vec![(-1.0, 1.0), (-2.0, 2.0), inf]
        );
    }

    #[test]
    fn bad_components_names_and_intervals_are_errors_at_their_spans() {
        let (m, at) = only_error_of(&format!("{VECTOR}plant region w[2] = -1 .. 1;"));
        assert_eq!(m, "`w[2]` is not a component of a state");
        assert_eq!(at, "2");
        let (m, at) = only_error_of(&format!("{VECTOR}plant region w[0.5] = -1 .. 1;"));
        assert_eq!(m, "`w[0.5]` is not a component of a state");
        assert_eq!(at, "0.5");
        let (m, _) = only_error_of(&format!("{VECTOR}plant region x1[0] = -1 .. 1;"));
        assert_eq!(m, "`x1[0]` is not a component of a state");
        let (m, at) = only_error_of(&format!("{VECTOR}plant region v = -1 .. 1;"));
        assert_eq!((m.as_str(), at.as_str()), ("`v` is not a state", "v"));
        let (m, at) = only_error_of(&format!("{VECTOR}plant region w[1] = 0.5 .. -0.5;"));
        assert_eq!(
            m,
            "`plant region w[1]` needs lo < 0 < hi, found 0.5 .. -0.5"
        );
        assert_eq!(at, "w");
        let (m, at) = only_error_of(&format!(
            "{VECTOR}plant region w = -1 .. 1, w[1] = -2 .. 2;"
        ));
        assert_eq!(m, "`w[1]` bounds a state component a second time");
        assert_eq!(at, "w");
    }
}
