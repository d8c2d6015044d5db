//! Code targets: `emit rust, c;` and `precision f64 | f32;` (each given once).

use super::{Checker, Draft};
use crate::ast::{Ident, Item};
use crate::diag::Diagnostic;
use crate::spec::{Emit, Precision};

impl Checker<'_> {
    /// `emit targets;`: each target `rust` or `c`.
    pub(super) fn emit_item(&mut self, it: &Item, targets: &[Ident], draft: &mut Draft) {
        if !self.singleton(&mut draft.emit_seen, it.span, "`emit`") {
            return;
        }
        for t in targets {
            match t.node.as_str() {
                "rust" => draft.emit.push(Emit::Rust),
                "c" => draft.emit.push(Emit::C),
                _ => self.err(
                    Diagnostic::error(t.span, format!("unknown code target `{}`", t.node))
                        .with_label("targets are `rust` and `c`"),
                ),
            }
        }
    }

    /// `precision p;`: `f64` (or `double`), `f32` (or `float`).
    pub(super) fn precision_item(&mut self, it: &Item, p: &Ident, draft: &mut Draft) {
        if !self.singleton(&mut draft.precision_seen, it.span, "the precision") {
            return;
        }
        match p.node.as_str() {
            "f64" | "double" => draft.precision = Some(Precision::F64),
            "f32" | "float" => draft.precision = Some(Precision::F32),
            _ => self.err(
                Diagnostic::error(p.span, format!("unknown precision `{}`", p.node))
                    .with_label("use `f64` or `f32`"),
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::check::testing::*;
    use crate::spec::{Emit, Precision};

    #[test]
    fn targets_and_precision() {
        let spec = spec_with("emit rust, c;\nprecision float;");
        assert_eq!(spec.emit, vec![Emit::Rust, Emit::C]);
        assert_eq!(spec.precision, Precision::F32);
        assert_eq!(spec_with("").precision, Precision::F64);
    }

    #[test]
    fn unknown_targets_and_precisions_are_reported() {
        let (m, at) = only_error("emit rust, go;");
        assert_eq!(m, "unknown code target `go`");
        assert_eq!(at, "go");
        let (m, at) = only_error("precision f16;");
        assert_eq!(m, "unknown precision `f16`");
        assert_eq!(at, "f16");
        let (m, _) = only_error("emit c;\nemit rust;");
        assert_eq!(m, "`emit` is given twice");
    }
}
