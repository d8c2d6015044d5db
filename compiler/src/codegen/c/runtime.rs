//! The fixed C runtime, `tsf_runtime.h` and `tsf_runtime.c` (checked in under
//! `runtime/c`), embedded so that every C output folder is complete: the
//! backend writes both files, byte for byte, next to the generated ones.
//! They carry no `@generated` marker: they do not depend on the spec.

use crate::codegen::GeneratedFile;

/// File name of the runtime header.
pub const HEADER_NAME: &str = "tsf_runtime.h";
/// File name of the runtime source.
pub const SOURCE_NAME: &str = "tsf_runtime.c";
/// Contents of `tsf_runtime.h`.
pub const HEADER: &str = include_str!("../../../../runtime/c/tsf_runtime.h");
/// Contents of `tsf_runtime.c`.
pub const SOURCE: &str = include_str!("../../../../runtime/c/tsf_runtime.c");

/// The two runtime files.
pub fn files() -> Vec<GeneratedFile> {
    vec![
        GeneratedFile {
            name: HEADER_NAME.to_string(),
            text: HEADER.to_string(),
        },
        GeneratedFile {
            name: SOURCE_NAME.to_string(),
            text: SOURCE.to_string(),
        },
    ]
}
