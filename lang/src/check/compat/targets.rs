//! Code targets: generated C names its symbols after the controller, and the
//! C runtime's symbols start with `tsf_`, so a controller named `tsf` or
//! `tsf_..` cannot be emitted as C (`codegen/c/mod.rs` keeps the refusal for
//! `tsfc compile --emit c` on a spec that does not say `emit c`).

use crate::check::{Checker, Draft};
use crate::diag::Diagnostic;
use crate::span::Spanned;
use crate::spec::Emit;

/// Whether generated C would collide with the runtime's symbols.
pub fn reserved_in_c(name: &str) -> bool {
    let lower = name.to_ascii_lowercase();
    lower == "tsf" || lower.starts_with("tsf_")
}

impl Checker<'_> {
    /// An error when the spec emits C for a controller whose name the C
    /// runtime reserves; a warning when it does not emit C.
    pub(super) fn targets_fit(&mut self, name: &Spanned<String>, draft: &Draft) {
        if !reserved_in_c(&name.node) {
            return;
        }
        let what = format!(
            "the controller name `{}` is reserved in generated C (the runtime's symbols start with `tsf_`)",
            name.node
        );
        let d = match draft.emit_seen.filter(|_| draft.emit.contains(&Emit::C)) {
            Some(emit) => {
                Diagnostic::error(name.span, what).with_secondary(emit, "C code asked for here")
            }
            None => Diagnostic::warning(name.span, what)
                .with_note("`tsfc compile --emit c` refuses this controller"),
        };
        self.err(d.with_help("rename the controller"));
    }
}

#[cfg(test)]
mod tests {
    use crate::check::testing::*;

    #[test]
    fn a_c_reserved_name_is_refused_when_c_is_emitted() {
        let src = BASE.replace("controller c;", "controller tsf_ctl;");
        let (m, at) = only_error_of(&format!("{src}emit rust, c;"));
        assert_eq!(m, "the controller name `tsf_ctl` is reserved in generated C (the runtime's symbols start with `tsf_`)");
        assert_eq!(at, "tsf_ctl");
        valid(&format!("{src}emit rust;"));
        valid(&format!(
            "{}emit c;",
            BASE.replace("controller c;", "controller tsfc;")
        ));
    }
}
