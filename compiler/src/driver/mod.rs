//! The driver: the one place that sequences the stages. `tsfc compile`,
//! `tsfc simulate`, the build-script [`Builder`] and adaptive designs all run
//! through it; the CLI (`main.rs`) only parses arguments and prints.
//!
//! [`frontend`] reads a spec and runs the language and model stages (and the
//! loop laws' check-time refusals); [`pipeline`] carries a checked spec through
//! synthesis and the certificate ([`compile`]) to tables and generated files;
//! [`prepare`] hands the simulator a certified design ([`reuse`]: from a
//! certified report, without solving again); [`adaptive`] runs an adaptive
//! spec's design, code and simulation; [`plant`] the plant claim (robust design on a region); [`summary`] is the terminal summary;
//! [`format`] is `tsfc fmt`; [`check_json`] is `tsfc check --format json`'s
//! document; [`schema`] the JSON Schemas of every JSON tsfc writes.

pub mod adaptive;
pub mod builder;
pub mod check_json;
pub mod compile;
pub mod format;
pub mod frontend;
pub mod pipeline;
pub mod plant;
pub mod prepare;
pub mod reuse;
pub mod schema;
pub mod summary;
pub mod transmissions;

pub use builder::Builder;
pub use prepare::{prepare, prepare_reusing, prepare_run};
pub use reuse::Reuse;
