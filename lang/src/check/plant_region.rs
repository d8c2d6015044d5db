//! `plant region x1 = lo .. hi, ..;`: the region the plant claim is asked
//! for (a box of scalar states around 0; states not written are unbounded).

use super::{Checker, Draft};
use crate::ast::{Expr, Ident, Item};
use crate::diag::Diagnostic;
use crate::span::Spanned;

impl<'a> Checker<'a> {
    /// Checks the item: one bound per scalar state, lo < 0 < hi, once per spec.
    pub(super) fn plant_region_item(
        &mut self,
        it: &Item,
        bounds: &[(Ident, Expr, Expr)],
        n: usize,
        draft: &mut Draft<'a>,
    ) {
        let mut seen = draft.plant_region.as_ref().map(|r| r.span);
        if !self.singleton(&mut seen, it.span, "the plant region") {
            return;
        }
        let mut region = vec![(f64::NEG_INFINITY, f64::INFINITY); n];
        let mut ok = true;
        for (name, lo, hi) in bounds {
            let Some(state) = self.states.iter().find(|s| s.name == name.node).cloned() else {
                self.err(
                    Diagnostic::error(name.span, format!("`{}` is not a state", name.node))
                        .with_label("the plant region bounds states"),
                );
                ok = false;
                continue;
            };
            if state.len != 1 {
                self.err(
                    Diagnostic::error(name.span, format!("`{}` is a vector state", name.node))
                        .with_label("the plant region bounds scalar states only"),
                );
                ok = false;
                continue;
            }
            let (Some(l), Some(h)) = (
                self.scalar(lo, "a plant region bound"),
                self.scalar(hi, "a plant region bound"),
            ) else {
                ok = false;
                continue;
            };
            if !(l < 0.0 && h > 0.0 && l.is_finite() && h.is_finite()) {
                self.err(
                    Diagnostic::error(
                        name.span,
                        format!("`plant region {}` needs lo < 0 < hi, found {l} .. {h}", name.node),
                    )
                    .with_help("the certified set is an ellipsoid around x = 0, so the box must contain 0 inside"),
                );
                ok = false;
                continue;
            }
            region[state.offset] = (l, h);
        }
        if ok {
            draft.plant_region = Some(Spanned::new(region, it.span));
        }
    }
}
