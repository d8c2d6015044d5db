//! Code generation: a certified design becomes controller source code.
//!
//! [`crate::tables`] gathers the plain data (dimensions, premise code, rule
//! terms, gains, the sensor-side trigger); one [`Backend`] per output
//! language renders it, and [`generate`] runs the backends the spec's `emit`
//! selects. Adding a language is one new backend module and one line in
//! [`BACKENDS`].
//!
//! An event-triggered loop (`trigger aperiodic { .. }`) has two networked
//! roles, generated separately: the controller module `<name>` (PDC on the
//! received state x(t_k), saturation) and the sensor module `<name>_sensor`
//! (decides at each sampling instant whether to transmit x, holds x(t_k) and
//! the threshold nu(t_k)). Only the backends know
//! Rust or C syntax. Outputs are deterministic (same spec, same bytes) and
//! carry a `@generated` marker with the spec's hash, no timestamps, no
//! absolute paths.

pub mod c;
mod error;
mod header;
pub mod rust;

pub use error::CodegenError;
pub use header::{marker, sensor_name};

use crate::tables::{AdaptiveTables, Tables};
use tsf_lang::spec::Emit;

/// One generated file: its name (in the output folder) and its text.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GeneratedFile {
    /// File name, e.g. `zhang_multiobjective.rs`.
    pub name: String,
    /// Contents.
    pub text: String,
}

/// A code generator for one output language: one method per networked
/// role of the generated loop.
pub trait Backend: Sync {
    /// The `emit` target this backend serves.
    fn target(&self) -> Emit;
    /// The controller module (PDC on the received state, saturation).
    fn controller(&self, t: &Tables) -> Result<Vec<GeneratedFile>, CodegenError>;
    /// The sensor module of the loop's law ([`crate::tables::Sensor`]):
    /// none for a continuous or periodic loop.
    fn sensor(&self, t: &Tables) -> Result<Vec<GeneratedFile>, CodegenError>;
    /// The module of an adaptive design (docs/adaptive.md).
    fn adaptive(&self, at: &AdaptiveTables) -> Result<Vec<GeneratedFile>, CodegenError>;
    /// Files every module of this language includes (the C runtime).
    fn support(&self) -> Vec<GeneratedFile> {
        Vec::new()
    }
    /// Every file of a certified PDC design in this language: the controller,
    /// the sensor module, support files.
    fn files(&self, t: &Tables) -> Result<Vec<GeneratedFile>, CodegenError> {
        let mut out = self.controller(t)?;
        out.extend(self.sensor(t)?);
        out.extend(self.support());
        Ok(out)
    }
}

/// An observer-based design's features the generated observer step covers:
/// no Markov modes, no sensor module (its loop is periodic).
pub(crate) fn observer_supported(t: &Tables) -> Result<(), CodegenError> {
    if t.modes.is_some() {
        return Err(CodegenError::ObserverUnsupported("Markov-switching modes"));
    }
    if t.sensor.is_some() {
        return Err(CodegenError::ObserverUnsupported(
            "an event trigger (the observer runs at a fixed period)",
        ));
    }
    Ok(())
}

/// Every backend; [`generate`] picks them by [`Backend::target`].
pub const BACKENDS: &[&dyn Backend] = &[&rust::RustBackend, &c::CBackend];

/// The backend of an `emit` target.
pub fn backend(target: Emit) -> Option<&'static dyn Backend> {
    BACKENDS.iter().copied().find(|b| b.target() == target)
}

/// Generates the requested targets for a well-posed adaptive design
/// (docs/adaptive.md) from its tables: `<name>.rs`, or `<name>.h`, `<name>.c`
/// and the C runtime. The law is generated in f64 only.
pub fn generate_adaptive(
    at: &AdaptiveTables,
    targets: &[Emit],
) -> Result<Vec<GeneratedFile>, CodegenError> {
    if at.base.precision != tsf_lang::spec::Precision::F64 {
        return Err(CodegenError::AdaptivePrecision);
    }
    let mut out = Vec::new();
    for &target in targets {
        let b = backend(target).ok_or(CodegenError::NoBackend(target))?;
        out.extend(b.adaptive(at)?);
        out.extend(b.support());
    }
    Ok(out)
}

/// Generates the requested targets from the tables of a certified design
/// ([`crate::tables::tables`] refuses a design whose certificate failed).
pub fn generate(t: &Tables, targets: &[Emit]) -> Result<Vec<GeneratedFile>, CodegenError> {
    let mut out = Vec::new();
    for &target in targets {
        let b = backend(target).ok_or(CodegenError::NoBackend(target))?;
        out.extend(b.files(t)?);
    }
    Ok(out)
}
