//! The simulator's design: a checked spec compiled (or taken from its
//! certified report, [`super::reuse`]) and handed to [`crate::sim`] as a
//! [`Prepared`] (the plain data the closed loop runs).

use super::frontend::Source;
use super::pipeline::{self, Run};
use crate::sim::{source, Prepared, SimError};
use std::path::Path;

pub use super::reuse::prepare_reusing;

/// Reads, checks and compiles the spec at `path`; the design must be certified.
/// Spec diagnostics are rendered into the error message.
pub fn prepare(path: &Path) -> Result<Prepared, SimError> {
    let run = pipeline::read(path)?.compile(&crate::synth::Settings::default())?;
    prepare_run(&run)
}

/// Checks and compiles a spec held in memory (`source_name` in messages,
/// `name` in reports and headers) into the simulator's design: what a sweep
/// scenario's law is compiled with ([`crate::sim::sweep::CompileLaw`]).
pub fn prepare_text(source_name: &str, text: String, name: String) -> Result<Prepared, SimError> {
    let source = Source {
        name: source_name.to_string(),
        bytes: text.clone().into_bytes(),
        text,
    };
    let run =
        pipeline::Front::from_source(source, name).compile(&crate::synth::Settings::default())?;
    prepare_run(&run)
}

/// The simulator's design of a compiled spec (it must be certified).
pub fn prepare_run(run: &Run) -> Result<Prepared, SimError> {
    let tables = run.tables()?;
    let design = run.certified()?.0.clone();
    let source = source::SpecSource {
        name: run.source.name.clone(),
        text: run.source.text.clone(),
    };
    let model = run.model.clone();
    // The synthesized trigger weight Upsilon (two-step method); without one,
    // `weight = synthesize` falls back to P / lambda_max(P) (see
    // `trigger::trigger_weight`).
    let trigger_weight = design.loop_design.event().map(|t| t.weight.clone());
    let region = design.certified_region().map(|(p, c)| p / c);
    Ok(Prepared {
        model,
        tables,
        p: design.p,
        trigger_weight,
        region,
        source,
    })
}
