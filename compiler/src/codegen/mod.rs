//! Code generation: a certified design becomes controller source code.
//!
//! [`crate::tables`] gathers the plain data (dimensions, premise code, rule
//! terms, gains, the sensor-side trigger); one module per target language
//! renders it.
//!
//! An event-triggered loop (`trigger aperiodic { .. }`) has two networked
//! roles, generated separately: the controller module `<name>` (PDC on the
//! received state x(t_k), saturation) and the sensor module `<name>_sensor`
//! (decides at each sampling instant whether to transmit x, holds x(t_k) and
//! the threshold nu(t_k)). Only these modules know
//! Rust or C syntax. Outputs are deterministic (same spec, same bytes) and
//! carry a `@generated` marker with the spec's hash, no timestamps, no
//! absolute paths.

pub mod c;
pub mod rust;

use crate::certify::Certificate;
use crate::model::TsModel;
use crate::synth::Design;
use crate::tables::tables;
use tsf_lang::spec::Emit;

/// One generated file: its name (in the output folder) and its text.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GeneratedFile {
    /// File name, e.g. `zhang_multiobjective.rs`.
    pub name: String,
    /// Contents.
    pub text: String,
}

/// Generates the requested targets for a certified design.
pub fn generate(
    model: &TsModel,
    design: &Design,
    cert: &Certificate,
    spec_path: &str,
    spec_sha256: &str,
    targets: &[Emit],
) -> Result<Vec<GeneratedFile>, String> {
    if !cert.ok {
        return Err("the certificate was refused: no code is generated".into());
    }
    let t = tables(model, design, cert, spec_path, spec_sha256).map_err(|e| e.to_string())?;
    let mut out = Vec::new();
    for target in targets {
        match target {
            Emit::Rust => {
                out.push(GeneratedFile {
                    name: format!("{}.rs", t.name),
                    text: rust::emit_rust(&t)?,
                });
                if t.trigger.is_some() {
                    out.push(GeneratedFile {
                        name: format!("{}.rs", rust::sensor_name(&t)),
                        text: rust::emit_rust_sensor(&t)?,
                    });
                }
            }
            Emit::C => {
                push_c(&mut out, c::c_file_names(&t), c::emit_c(&t));
                if t.trigger.is_some() {
                    push_c(&mut out, c::c_sensor_file_names(&t), c::emit_c_sensor(&t)?);
                }
            }
        }
    }
    Ok(out)
}

/// Appends a C header/source pair named `(header, source)`.
fn push_c(out: &mut Vec<GeneratedFile>, (h, src): (String, String), files: c::CFiles) {
    out.push(GeneratedFile {
        name: h,
        text: files.header,
    });
    out.push(GeneratedFile {
        name: src,
        text: files.source,
    });
}
