//! Code generation: a certified design becomes controller source code.
//!
//! [`tables`] gathers the plain data (dimensions, premise code, rule terms,
//! gains); one module per target language renders it. Only these modules know
//! Rust or C syntax. Outputs are deterministic (same spec, same bytes) and
//! carry a `@generated` marker with the spec's hash, no timestamps, no
//! absolute paths.

pub mod sym;
pub mod tables;

pub use tables::{tables, Header, PremiseCode, Tables};
