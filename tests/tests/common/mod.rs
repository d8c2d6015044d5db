//! Helpers shared by the end-to-end tests.
#![allow(dead_code)] // each test crate uses a subset

use std::path::{Path, PathBuf};
use tsfc::frontend::{self, Source};
use tsfc::model::TsModel;

/// Path of a shipped spec.
pub fn spec_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../specs")
        .join(name)
}

/// The model of a source text; panics with the errors if it does not check clean.
pub fn model_of(name: &str, text: &str) -> TsModel {
    let source = Source {
        name: name.into(),
        text: text.into(),
        bytes: text.as_bytes().to_vec(),
    };
    let checked = frontend::check(&source);
    let errors: Vec<_> = checked
        .diagnostics
        .iter()
        .filter(|d| d.is_error())
        .map(|d| d.message.clone())
        .collect();
    assert!(errors.is_empty(), "{name}: {errors:?}");
    checked.model.expect("a model for a clean spec")
}

/// The model of a shipped spec.
pub fn shipped(name: &str) -> TsModel {
    let text = std::fs::read_to_string(spec_path(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
    model_of(name, &text)
}
