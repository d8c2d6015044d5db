//! The one pipeline driver: read → check → model → synthesize → certify →
//! report → code. The CLI, the build-script [`crate::Builder`], the simulator
//! and the benches all go through it.

use crate::certify::Certificate;
use crate::codegen::{self, GeneratedFile};
use crate::driver::compile::{Compiled, Status};
use crate::driver::frontend::{self, Checked, Source};
use crate::model::TsModel;
use crate::report::SpecInfo;
use crate::synth::{Design, Settings};
use crate::tables::{self, Tables};
use crate::util::error::Error;
use crate::util::hash::sha256_hex;
use std::path::Path;
use tsf_lang::spec::Emit;
use tsf_lang::Diagnostic;

/// A spec read and checked.
#[derive(Debug)]
pub struct Front {
    /// The source.
    pub source: Source,
    /// Its diagnostics and, if valid, its model.
    pub checked: Checked,
    name: String,
}

/// Reads and checks a spec file (an unreadable file is a usage error).
/// Reports and generated headers name the spec by its file name only, so
/// their bytes do not depend on the working directory or where the project
/// lives; diagnostics show the path as typed.
pub fn read(path: &Path) -> Result<Front, Error> {
    let source = frontend::read_source(path).map_err(|e| Error::usage(e.message))?;
    let checked = frontend::check(&source);
    let name = path
        .file_name()
        .map_or_else(|| source.name.clone(), |n| n.to_string_lossy().into_owned());
    Ok(Front {
        source,
        checked,
        name,
    })
}

impl Front {
    /// Checks a source held in memory; reports and headers name it `name`.
    pub fn from_source(source: Source, name: String) -> Front {
        let checked = frontend::check(&source);
        Front {
            source,
            checked,
            name,
        }
    }

    /// How reports and generated headers name the spec (its file name).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The diagnostics, rendered for a terminal.
    pub fn render(&self, color: bool) -> String {
        self.render_only(color, |_| true)
    }

    /// The diagnostics `keep` selects, rendered.
    pub fn render_only(&self, color: bool, keep: impl Fn(&Diagnostic) -> bool) -> String {
        let kept: Vec<Diagnostic> = self
            .checked
            .diagnostics
            .iter()
            .filter(|d| keep(d))
            .cloned()
            .collect();
        if kept.is_empty() {
            return String::new();
        }
        tsf_lang::diag::render(&self.source.name, &self.source.text, &kept, color)
    }

    /// Synthesizes, certifies and reports (a spec with errors is a spec error
    /// carrying its rendered diagnostics).
    pub fn compile(self, settings: &Settings) -> Result<Run, Error> {
        let rendered = self.render(false);
        let Front {
            source,
            checked,
            name,
        } = self;
        let front_times = (checked.parse_time, checked.model_time);
        let Some(model) = checked.model else {
            return Err(Error::spec(rendered));
        };
        if model.spec.adaptive.is_some() {
            return Err(Error::spec(format!(
                "{name}: an adaptive controller has no LMI design (`tsfc compile` reports its adaptive design; docs/adaptive.md)"
            )));
        }
        let sha256 = sha256_hex(&source.bytes);
        let info = SpecInfo {
            path: name.clone(),
            sha256: sha256.clone(),
        };
        let request = crate::driver::plant::PlantRequest {
            bound: crate::driver::plant::production_bound(),
            region: None,
        };
        let mut compiled =
            crate::driver::plant::compile(&model, info, settings, front_times, request);
        // Without a plant claim, the sampled mismatch is the plant section's note.
        if let (None, Some(c)) = (&compiled.report.plant.claim, &model.consistency) {
            let said = compiled.report.plant.note.as_ref();
            if c.worst > crate::model::MISMATCH_TOLERANCE
                && !said.is_some_and(|n| n.contains("on a grid of"))
            {
                let note = &mut compiled.report.plant.note;
                *note = Some(match note.take() {
                    Some(n) => format!("{n}; {}", c.sentence()),
                    None => c.sentence(),
                });
            }
        }
        Ok(Run {
            source,
            model,
            name,
            sha256,
            compiled,
        })
    }
}

/// A compiled spec: model, verdict, design and report.
#[derive(Debug)]
pub struct Run {
    /// The source.
    pub source: Source,
    /// The checked model.
    pub model: TsModel,
    /// How outputs name the spec.
    pub name: String,
    /// SHA-256 of the spec's bytes.
    pub sha256: String,
    /// Verdict, design, certificate and report.
    pub compiled: Compiled,
}

impl Run {
    /// The certified design, or why there is none.
    pub fn certified(&self) -> Result<(&Design, &Certificate), Error> {
        match (&self.compiled.status, &self.compiled.outcome) {
            (Status::Certified, Ok((d, c))) => Ok((d, c)),
            _ => Err(Error::not_certified(format!(
                "{}: not certified ({})",
                self.name,
                self.compiled.report.diagnosis.as_ref().map_or_else(
                    || self.compiled.report.status.to_string(),
                    |d| {
                        if d.achievable.is_empty() {
                            d.message.clone()
                        } else {
                            format!("{}; {}", d.message, d.achievable.join("; "))
                        }
                    }
                )
            ))),
        }
    }

    /// The certified design's tables (what generated code and the simulator use).
    /// Output-feedback designs [`withheld`] have none.
    pub fn tables(&self) -> Result<Tables, Error> {
        let (design, cert) = self.certified()?;
        if let Some(why) = withheld(&self.model, design) {
            return Err(Error::usage(format!("{}: {why}", self.name)));
        }
        tables::tables(&self.model, design, cert, &self.name, &self.sha256)
            .map_err(|e| Error::not_certified(format!("{}: {e}", self.name)))
    }

    /// The generated files of the certified design for `targets`.
    pub fn generate(&self, targets: &[Emit]) -> Result<Vec<GeneratedFile>, Error> {
        let (design, cert) = self.certified()?;
        if let Some(why) = withheld(&self.model, design) {
            return Err(Error::usage(format!("{}: {why}", self.name)));
        }
        let failed = |e: &dyn std::fmt::Display| {
            Error::not_certified(format!("code generation failed: {e}"))
        };
        let t = tables::tables(&self.model, design, cert, &self.name, &self.sha256)
            .map_err(|e| failed(&e))?;
        codegen::generate(&t, targets).map_err(|e| failed(&e))
    }

    /// The exit code of the compile: 0 certified, 3 otherwise.
    pub fn exit_code(&self) -> u8 {
        match self.compiled.status {
            Status::Certified => 0,
            _ => 3,
        }
    }
}

/// Why a certified design of `model` has no tables or code in this build
/// (exit 2, docs/limits.md): an observer-based controller whose sampled loop
/// is not certified (no `trigger periodic { every = T; }`: only the
/// continuous augmented loop is). Static output feedback ships like state
/// feedback (its loop, continuous or sampled, is certified with F_j = K_j C;
/// the step reads y, [`crate::tables::static_output`]).
pub fn withheld(model: &TsModel, design: &Design) -> Option<String> {
    use tsf_lang::spec::ControlKind;
    match model.spec.control.kind {
        ControlKind::StateFeedback => None,
        ControlKind::ObserverBased if design.loop_design.observer_sampled().is_some() => None,
        ControlKind::ObserverBased => {
            let base = "an observer-based controller runs every period T: its code and simulation need `trigger periodic { every = T; }` (the certificate then covers the sampled loop; without it only the continuous loop is certified, and no code or simulation is emitted)";
            Some(match crate::synth::observer::bounded::Bounds::of(&model.spec) {
                // What a newcomer would try next is refused at check time.
                Some(_) => format!("{base}; the sampled loop covers an input bound and saturation levels (the actuator kept linear on its certified set), not an output bound or H-inf (docs/limits.md)"),
                None => base.into(),
            })
        }
        ControlKind::StaticOutput => None,
    }
}
