//! tsfc: the compiler for Takagi-Sugeno fuzzy controllers.
//!
//! The pipeline flows one way, one module per stage, plain data between them:
//! `tsf_lang` (parse, resolve, shape-check) → model (local models, premises,
//! coverage) → synthesis → LMI solve → certificate → tables (the plain data of
//! a certified design) → code generation / simulation / report.
//!
//! The API for build scripts and tools is small: [`Builder`] (prost-build
//! style, for `build.rs`), [`pipeline`] (read → compile → tables / generated
//! files), [`Error`] (with its exit code), the [`report::Report`], the
//! [`codegen::GeneratedFile`]s and [`sim`] (closed-loop simulation). The other
//! modules are the stages themselves: public so the workspace's integration
//! tests and benches can test each stage on its own, hidden from the docs and
//! not a stable API.

#![allow(clippy::result_large_err)] // diagnostics travel on the cold error path

pub mod adaptive;
pub mod builder;
pub mod codegen;
pub mod error;
pub mod output;
pub mod pipeline;
pub mod report;
pub mod sim;

#[doc(hidden)]
pub mod certify;
#[doc(hidden)]
pub mod compile;
#[doc(hidden)]
pub mod frontend;
#[doc(hidden)]
pub mod model;
#[doc(hidden)]
pub mod summary;
#[doc(hidden)]
pub mod synth;
#[doc(hidden)]
pub mod tables;
#[doc(hidden)]
pub mod tape;

pub use builder::Builder;
pub use error::{Error, ErrorKind};
