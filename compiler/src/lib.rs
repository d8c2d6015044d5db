//! tsfc: the compiler for Takagi-Sugeno fuzzy controllers.
//!
//! The pipeline flows one way, one module per stage, plain data between them:
//! `tsf_lang` (parse, resolve, shape-check) → [`model`] (local models,
//! premises, coverage) → [`synth`] (objectives, relaxations and loop laws →
//! LMIs → Clarabel) → [`certify`] → [`tables`] (the plain data of a certified
//! design) → [`codegen`] / [`sim`] / [`report`]. [`driver`] is the one place
//! that sequences the stages (for `tsfc compile`, `tsfc simulate`, the
//! build-script [`Builder`] and adaptive designs alike); [`util`] holds what
//! every stage may use. `tests/tests/tidy.rs` keeps imports flowing that way.
//!
//! The API for build scripts and tools is small: [`Builder`] (prost-build
//! style, for `build.rs`), [`pipeline`] (read → compile → tables / generated
//! files), [`Error`] (with its exit code), the [`report::Report`], the
//! [`codegen::GeneratedFile`]s and [`sim`] (closed-loop simulation). The other
//! modules are the stages themselves: public so the workspace's integration
//! tests and benches can test each stage on its own, hidden from the docs and
//! not a stable API.

#![allow(clippy::result_large_err)] // diagnostics travel on the cold error path

pub mod codegen;
pub mod driver;
pub mod lsp;
pub mod report;
pub mod review;
pub mod sim;
pub mod util;

#[doc(hidden)]
pub mod certify;
#[doc(hidden)]
pub mod model;
#[doc(hidden)]
pub mod synth;
#[doc(hidden)]
pub mod tables;
#[doc(hidden)]
pub mod tape;

pub use driver::{pipeline, Builder};
pub use util::error::{Error, ErrorKind};
