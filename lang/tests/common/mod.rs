//! Helpers shared by the language's integration tests.
#![allow(dead_code)] // each test crate uses a subset

use tsf_lang::{check_source, Diagnostic};

/// A valid spec, one item per line, to which items are appended.
pub const SPEC: &str = "tsf 1; controller c; state x1; input u; A = -1; B = 1;\n\
    premise x1 range -1 .. 1 { all = trap(-1, -1, 1, 1); }\n\
    rule R: x1 is all => A = -2;\n";

/// The errors of `src` (a spec is built exactly when there are none).
pub fn errors(src: &str) -> Vec<Diagnostic> {
    let (spec, diags) = check_source(src);
    let errors: Vec<_> = diags.into_iter().filter(Diagnostic::is_error).collect();
    assert_eq!(spec.is_none(), !errors.is_empty());
    errors
}
