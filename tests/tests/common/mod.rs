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

/// The seeded generator of the simulator (SplitMix64), for random test points.
pub use tsfc::sim::trigger::SplitMix64 as Rng;

/// The local models (A_i, B_i) of the three-rule Kim & Lee-type benchmark
/// (Kim and Lee, "New approaches to relaxed quadratic stability condition of
/// fuzzy control systems", 2000), with the parameters a and b.
pub fn kim_lee_rules(a: f64, b: f64) -> [(nalgebra::DMatrix<f64>, nalgebra::DMatrix<f64>); 3] {
    let m = |r: &[f64]| nalgebra::DMatrix::from_row_slice(2, 2, r);
    let v = |r: &[f64]| nalgebra::DMatrix::from_row_slice(2, 1, r);
    [
        (m(&[1.59, -7.29, 0.01, 0.0]), v(&[1.0, 0.0])),
        (m(&[0.02, -4.64, 0.35, 0.21]), v(&[8.0, 0.0])),
        (m(&[-a, -4.33, 0.0, 0.05]), v(&[-b + 6.0, -1.0])),
    ]
}
