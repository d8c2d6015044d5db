//! Code targets: `emit rust, c;` and `precision f64 | f32;` (each given once).

use super::{Checker, Draft};
use crate::ast::{EmitTarget, ExprKind, Ident, Item};
use crate::diag::Diagnostic;
use crate::spec::{CStyle, Emit, Precision};

impl Checker<'_> {
    /// `emit targets;`: each target `rust` or `c`; `c` takes the option
    /// `style = auto | straight | table` (the generated C step).
    pub(super) fn emit_item(&mut self, it: &Item, targets: &[EmitTarget], draft: &mut Draft) {
        if !self.singleton(&mut draft.emit_seen, it.span, "`emit`") {
            return;
        }
        for t in targets {
            match t.name.node.as_str() {
                "rust" => draft.emit.push(Emit::Rust),
                "c" => draft.emit.push(Emit::C),
                _ => {
                    self.err(
                        Diagnostic::error(
                            t.name.span,
                            format!("unknown code target `{}`", t.name.node),
                        )
                        .with_label("targets are `rust` and `c`"),
                    );
                    continue;
                }
            }
            let mut seen = false;
            for a in &t.args {
                let option = (t.name.node == "c" && a.name.node == "style").then_some(());
                if option.is_none() {
                    let what = if t.name.node == "c" {
                        "the option of `c` is `style`"
                    } else {
                        "`rust` takes no options"
                    };
                    self.err(
                        Diagnostic::error(
                            a.name.span,
                            format!("unknown option `{}` of `{}`", a.name.node, t.name.node),
                        )
                        .with_label(what),
                    );
                    continue;
                }
                if seen {
                    self.err(Diagnostic::error(
                        a.name.span,
                        "`style` is given twice".to_string(),
                    ));
                    continue;
                }
                seen = true;
                let style = match &a.value.kind {
                    ExprKind::Name(v) if v == "auto" => Some(CStyle::Auto),
                    ExprKind::Name(v) if v == "straight" => Some(CStyle::Straight),
                    ExprKind::Name(v) if v == "table" => Some(CStyle::Table),
                    _ => None,
                };
                match style {
                    Some(s) => draft.c_style = s,
                    None => self.err(
                        Diagnostic::error(a.value.span, "unknown C style".to_string())
                            .with_label("styles are `auto`, `straight` and `table`"),
                    ),
                }
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
    use crate::spec::{CStyle, Emit, Precision};

    #[test]
    fn targets_and_precision() {
        let spec = spec_with("emit rust, c;\nprecision float;");
        assert_eq!(spec.emit, vec![Emit::Rust, Emit::C]);
        assert_eq!(spec.precision, Precision::F32);
        assert_eq!(spec_with("").precision, Precision::F64);
    }

    #[test]
    fn the_c_style_is_read() {
        assert_eq!(spec_with("emit rust, c;").c_style, CStyle::Auto);
        let spec = spec_with("emit rust, c(style = table);");
        assert_eq!(spec.emit, vec![Emit::Rust, Emit::C]);
        assert_eq!(spec.c_style, CStyle::Table);
        assert_eq!(
            spec_with("emit c(style = straight);").c_style,
            CStyle::Straight
        );
        assert_eq!(
            spec_with("emit c(style = auto), rust;").c_style,
            CStyle::Auto
        );
    }

    #[test]
    fn bad_c_styles_are_reported() {
        let (m, at) = only_error("emit c(style = fast);");
        assert_eq!(m, "unknown C style");
        assert_eq!(at, "fast");
        let (m, at) = only_error("emit c(form = table);");
        assert_eq!(m, "unknown option `form` of `c`");
        assert_eq!(at, "form");
        let (m, at) = only_error("emit rust(style = table);");
        assert_eq!(m, "unknown option `style` of `rust`");
        assert_eq!(at, "style");
        let (m, _) = only_error("emit c(style = table, style = straight);");
        assert_eq!(m, "`style` is given twice");
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
