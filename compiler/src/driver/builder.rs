//! A `build.rs` API in the style of prost-build: compile specs into Rust (and
//! C) sources in `OUT_DIR`, to be `include!`d by the crate.
//!
//! ```no_run
//! // build.rs
//! fn main() -> Result<(), Box<dyn std::error::Error>> {
//!     tsfc::Builder::new().spec("specs/controller.tsf").emit_rust(true).compile()?;
//!     Ok(())
//! }
//! // src/lib.rs:  include!(concat!(env!("OUT_DIR"), "/<controller>.rs"));
//! ```
//!
//! A spec with `trigger aperiodic { .. }` also yields the sensor-side trigger
//! `<controller>_sensor.rs` (and `.h`/`.c` with C): include it in its own
//! module, next to the controller it feeds.

use crate::codegen::GeneratedFile;
use crate::driver::pipeline;
use crate::synth::Settings;
use crate::util::error::Error;
use crate::util::output::write_set;
use std::path::{Path, PathBuf};
use tsf_lang::spec::Emit;

/// Why a build failed; `Display` gives the full message (diagnostics included).
pub type BuildError = Error;

/// Configures and runs spec compilation from a build script.
#[derive(Debug, Clone)]
pub struct Builder {
    specs: Vec<PathBuf>,
    rust: bool,
    c: bool,
    out_dir: Option<PathBuf>,
    settings: Settings,
}

impl Default for Builder {
    fn default() -> Self {
        Self::new()
    }
}

impl Builder {
    /// A builder emitting Rust into `OUT_DIR`.
    pub fn new() -> Self {
        Builder {
            specs: Vec::new(),
            rust: true,
            c: false,
            out_dir: None,
            settings: Settings::default(),
        }
    }

    /// Adds a spec file.
    pub fn spec(mut self, path: impl AsRef<Path>) -> Self {
        self.specs.push(path.as_ref().to_path_buf());
        self
    }

    /// Whether to write `<controller>.rs` (default on), and
    /// `<controller>_sensor.rs` for an event-triggered loop.
    pub fn emit_rust(mut self, on: bool) -> Self {
        self.rust = on;
        self
    }

    /// Whether to write `<controller>.h` and `<controller>.c` (default off),
    /// and `<controller>_sensor.h`/`.c` for an event-triggered loop.
    pub fn emit_c(mut self, on: bool) -> Self {
        self.c = on;
        self
    }

    /// Output folder (default: the `OUT_DIR` cargo gives build scripts).
    pub fn out_dir(mut self, dir: impl AsRef<Path>) -> Self {
        self.out_dir = Some(dir.as_ref().to_path_buf());
        self
    }

    /// Synthesis settings.
    pub fn settings(mut self, settings: Settings) -> Self {
        self.settings = settings;
        self
    }

    /// Compiles every spec; returns the paths written. Prints
    /// `cargo:rerun-if-changed` for each spec.
    pub fn compile(self) -> Result<Vec<PathBuf>, BuildError> {
        let out = match &self.out_dir {
            Some(d) => d.clone(),
            None => PathBuf::from(std::env::var_os("OUT_DIR").ok_or_else(|| {
                Error::usage("OUT_DIR is not set: call from a build script or set `out_dir`")
            })?),
        };
        let mut targets = Vec::new();
        if self.rust {
            targets.push(Emit::Rust);
        }
        if self.c {
            targets.push(Emit::C);
        }
        let mut written = Vec::new();
        let mut owners: Vec<(PathBuf, &Path)> = Vec::new();
        for spec in &self.specs {
            println!("cargo:rerun-if-changed={}", spec.display());
            let files: Vec<(PathBuf, Vec<u8>)> = self
                .compile_one(spec, &targets)?
                .into_iter()
                .map(|f| (out.join(&f.name), f.text.into_bytes()))
                .collect();
            claim_files(&mut owners, &files, spec)?;
            write_set(&files)
                .map_err(|e| Error::usage(format!("cannot write into {}: {e}", out.display())))?;
            written.extend(files.into_iter().map(|(p, _)| p));
        }
        Ok(written)
    }

    fn compile_one(&self, spec: &Path, targets: &[Emit]) -> Result<Vec<GeneratedFile>, Error> {
        let front = pipeline::read(spec)?;
        if let Some(files) = super::adaptive::generated(&front, targets) {
            return files;
        }
        front.compile(&self.settings)?.generate(targets)
    }
}

/// Records that `spec` writes `files`; an error when an earlier spec of the
/// same build writes one of them (two controllers of one name would
/// overwrite each other's code).
fn claim_files<'s>(
    owners: &mut Vec<(PathBuf, &'s Path)>,
    files: &[(PathBuf, Vec<u8>)],
    spec: &'s Path,
) -> Result<(), Error> {
    for (path, _) in files {
        if let Some((_, first)) = owners.iter().find(|(p, _)| p == path) {
            return Err(Error::usage(format!(
                "`{}` and `{}` both generate `{}`: their controllers have the same name; rename one (`controller <name>;`)",
                first.display(),
                spec.display(),
                path.display()
            )));
        }
    }
    owners.extend(files.iter().map(|(p, _)| (p.clone(), spec)));
    Ok(())
}
