//! Small utilities every stage may use (the bottom of the pipeline): the
//! tool's error with its exit code, atomic output files, content hashes and a
//! deterministic pseudo-random generator. Nothing here knows a stage.

pub mod error;
pub mod hash;
pub mod matrix;
pub mod output;
pub mod rng;
