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

/// A small deterministic generator (SplitMix64, Steele, Lea and Flood,
/// "Fast splittable pseudorandom number generators", 2014).
pub struct Rng(pub u64);

impl Rng {
    /// The next 64 random bits.
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}

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
