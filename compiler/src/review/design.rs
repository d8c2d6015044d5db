//! The design a review page shows: the certified report of `tsfc compile`
//! when it matches the spec (the checks of [`crate::driver::reuse`]) and the
//! generated files beside it are this spec's, else the spec compiled again.

use crate::codegen;
use crate::driver::pipeline::{self, Front};
use crate::driver::{prepare_run, reuse};
use crate::sim::Prepared;
use crate::util::error::Error;
use crate::util::hash::sha256_hex;
use std::path::{Path, PathBuf};
use tsf_lang::spec::{Emit, Trigger};

/// Where the design came from.
#[derive(Debug, Clone, PartialEq)]
pub enum Origin {
    /// The certified report at this path (nothing solved).
    Reused(PathBuf),
    /// Compiled by the review; `Some(why)` when a report was there but could not be used.
    Compiled(Option<String>),
}

/// A generated file: its name and the SHA-256 of its bytes.
#[derive(Debug, Clone, PartialEq)]
pub struct FileHash {
    /// File name (as `tsfc compile` writes it into its output folder).
    pub name: String,
    /// SHA-256 (hex) of its bytes.
    pub sha256: String,
}

/// A certified design and everything the page shows about it.
#[derive(Debug)]
pub struct Design {
    /// The spec's file name.
    pub spec_name: String,
    /// SHA-256 of the spec's bytes.
    pub sha256: String,
    /// Warnings of the language and model stages (message and help).
    pub warnings: Vec<String>,
    /// The report of `tsfc compile`, as JSON.
    pub report: serde_json::Value,
    /// The simulator's design.
    pub prepared: Prepared,
    /// The files `tsfc compile` writes for the spec's `emit` targets.
    pub files: Vec<FileHash>,
    /// Where the design came from.
    pub origin: Origin,
}

/// The certified design of the spec at `path`: from the report `report`
/// (given: it must be readable) or `out/<controller>.report.json`, else compiled.
pub fn design(path: &Path, report: Option<&Path>, out: &Path) -> Result<Design, Error> {
    let front = pipeline::read(path)?;
    let Some(model) = &front.checked.model else {
        return Err(Error::spec(front.render(false)));
    };
    if model.spec.adaptive.is_some() {
        return Err(Error::unsupported(format!(
            "{}: an adaptive controller has no LMI design to review (docs/adaptive.md)",
            front.name()
        )));
    }
    let warnings = front
        .checked
        .diagnostics
        .iter()
        .filter(|d| !d.is_error())
        .map(|d| match &d.help {
            Some(h) => format!("{} ({h})", d.message),
            None => d.message.clone(),
        })
        .collect();
    let targets = model.spec.emit.clone();
    let default = out.join(format!("{}.report.json", model.spec.controller.node));
    let candidate = report.unwrap_or(&default);
    let why = match std::fs::read_to_string(candidate) {
        Ok(json) => match reused(&front, &json, candidate, &targets) {
            Ok((prepared, report, files)) => {
                return Ok(Design {
                    spec_name: front.name().to_string(),
                    sha256: sha256_hex(&front.source.bytes),
                    warnings,
                    report,
                    prepared,
                    files,
                    origin: Origin::Reused(candidate.to_path_buf()),
                })
            }
            Err(why) => Some(format!("`{}` cannot be used: {why}", candidate.display())),
        },
        Err(e) if report.is_some() => {
            return Err(Error::usage(format!(
                "cannot read the report `{}`: {e}",
                candidate.display()
            )))
        }
        Err(_) => None,
    };
    let spec_name = front.name().to_string();
    let run = front.compile(&crate::synth::Settings::default())?;
    let prepared = prepare_run(&run)?;
    let files = run
        .generate(&targets)?
        .into_iter()
        .map(|f| FileHash {
            sha256: sha256_hex(f.text.as_bytes()),
            name: f.name,
        })
        .collect();
    let report = serde_json::to_value(&run.compiled.report)
        .map_err(|e| Error::usage(format!("cannot serialize the report: {e}")))?;
    Ok(Design {
        spec_name,
        sha256: run.sha256.clone(),
        warnings,
        report,
        prepared,
        files,
        origin: Origin::Compiled(why),
    })
}

/// The design of a matching certified report and the hashes of the files
/// `tsfc compile` wrote beside it, or why they cannot be used. A file counts
/// when it is exactly what the report's design generates or carries the
/// `@generated` line of this tsfc and this spec's SHA-256 (compiles are
/// deterministic, so such a file is the one `tsfc compile` writes).
fn reused(
    front: &Front,
    json: &str,
    report: &Path,
    targets: &[Emit],
) -> Result<(Prepared, serde_json::Value, Vec<FileHash>), String> {
    let Some(model) = &front.checked.model else {
        return Err("the spec has errors".into());
    };
    let prepared = reuse::from_report(front, model, json)?;
    // A trigger with a sensor-side module: the report does not hold its
    // tables, so the list of generated files cannot be made from it.
    let sensor = matches!(
        model.spec.trigger.as_ref().map(|t| &t.node),
        Some(Trigger::Aperiodic { .. } | Trigger::Mixed { .. })
    );
    if sensor && model.spec.modes.is_none() {
        return Err("the sensor module of its trigger is not described by the report".into());
    }
    let value: serde_json::Value =
        serde_json::from_str(json).map_err(|e| format!("it is not JSON ({e})"))?;
    let generated = codegen::generate(&prepared.tables, targets).map_err(|e| e.to_string())?;
    let dir = report
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let marks = [
        format!("@generated by tsfc {} ", env!("CARGO_PKG_VERSION")),
        format!("(sha256 {})", sha256_hex(&front.source.bytes)),
    ];
    let mut files = Vec::new();
    for f in generated {
        let path = dir.join(&f.name);
        let bytes = std::fs::read(&path)
            .map_err(|e| format!("the generated file `{}` is not there ({e})", f.name))?;
        let text = String::from_utf8_lossy(&bytes);
        let ours = bytes == f.text.as_bytes() || marks.iter().all(|m| text.contains(m.as_str()));
        if !ours {
            return Err(format!(
                "the generated file `{}` beside it is not this spec's",
                f.name
            ));
        }
        files.push(FileHash {
            name: f.name,
            sha256: sha256_hex(&bytes),
        });
    }
    Ok((prepared, value, files))
}
