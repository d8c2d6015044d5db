//! tsfc: the compiler for Takagi-Sugeno fuzzy controllers.
//!
//! The pipeline flows one way, one module per stage, plain data between them:
//! `tsf_lang` (parse, resolve, shape-check) → [`model`] (local models, premises,
//! coverage) → synthesis → LMI solve → certificate → code generation / simulation
//! / report. [`frontend`] runs the first two stages on a file; [`tables`] is the
//! plain data of a certified design that code generation and simulation read.

#![allow(clippy::result_large_err)] // diagnostics travel on the cold error path

pub mod builder;
pub mod certify;
pub mod codegen;
pub mod compile;
pub mod frontend;
pub mod model;
pub mod report;
pub mod sim;
pub mod summary;
pub mod synth;
pub mod tables;

pub use builder::Builder;
