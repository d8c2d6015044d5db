//! `tsfc compile` and `tsfc simulate` on an adaptive spec: the design report
//! (`<name>.adaptive.json`), and the run's metrics, CSV and estimates plot.

use super::{design, sim, Design, Outcome};
use crate::codegen::{generate_adaptive, GeneratedFile};
use crate::error::Error;
use crate::pipeline::Front;
use crate::report::sha256_hex;
use crate::sim::source::SpecSource;
use std::path::{Path, PathBuf};
use tsf_lang::spec::Emit;

/// Exit code of a run whose claims failed, or that stopped early (as `tsfc simulate`).
pub const RUN_FAILED: u8 = 4;

/// The design of a checked front whose spec is adaptive; `None` otherwise.
pub fn outcome(front: &Front) -> Option<Outcome> {
    let model = front.checked.model.as_ref()?;
    model.spec.adaptive.as_ref()?;
    Some(design(model))
}

fn write(files: &[(PathBuf, Vec<u8>)]) -> Result<(), u8> {
    crate::output::write_set(files).map_err(|e| {
        eprintln!("error: cannot write the outputs: {e}");
        2
    })
}

fn json<T: serde::Serialize>(v: &T) -> Vec<u8> {
    (serde_json::to_string_pretty(v).unwrap_or_else(|e| format!("\"cannot serialize: {e}\""))
        + "\n")
        .into_bytes()
}

/// The generated files of a well-posed adaptive design of `front` for
/// `targets` (headers name the spec by its file name).
pub fn generate(
    front: &Front,
    design: &Design,
    targets: &[Emit],
) -> Result<Vec<GeneratedFile>, Error> {
    let model = front
        .checked
        .model
        .as_ref()
        .ok_or_else(|| Error::spec(front.render(false)))?;
    let sha = sha256_hex(&front.source.bytes);
    generate_adaptive(model, design, front.name(), &sha, targets)
        .map_err(|e| Error::not_certified(format!("code generation failed: {e}")))
}

/// The generated files of an adaptive spec for `targets`: `None` when the
/// spec is not adaptive, an error when its design is refused.
pub fn generated(front: &Front, targets: &[Emit]) -> Option<Result<Vec<GeneratedFile>, Error>> {
    let outcome = outcome(front)?;
    Some(match &outcome.design {
        Some(design) => generate(front, design, targets),
        None => Err(Error::not_certified(format!(
            "{}: the adaptive design was refused: {}",
            front.name(),
            outcome.report.refusals.join("; ")
        ))),
    })
}

/// `tsfc compile` of an adaptive spec: writes the report and the generated
/// files for `targets` (none when the design is refused), prints the
/// verdict; `None` when the spec is not adaptive.
pub fn compile(front: &Front, out: &Path, targets: &[Emit]) -> Option<u8> {
    let outcome = outcome(front)?;
    let name = &front.checked.model.as_ref()?.spec.controller.node;
    let path = out.join(format!("{name}.adaptive.json"));
    let mut files = vec![(path.clone(), json(&outcome.report))];
    if let (Some(design), false) = (&outcome.design, targets.is_empty()) {
        match generate(front, design, targets) {
            Ok(g) => files.extend(
                g.into_iter()
                    .map(|f| (out.join(&f.name), f.text.into_bytes())),
            ),
            Err(e) => {
                eprintln!("error: {}", e.message);
                return Some(e.exit_code());
            }
        }
    }
    if let Err(code) = write(&files) {
        return Some(code);
    }
    let r = &outcome.report;
    eprintln!(
        "{name}: {} ({} adapted numbers; no LMI certificate: docs/adaptive.md)",
        r.status, r.adapted
    );
    for why in &r.refusals {
        eprintln!("  refused: {why}");
    }
    if !r.reference_eigenvalues_re.is_empty() {
        eprintln!(
            "  A_m eigenvalues (real parts) {:?}, P eigenvalues {:?}",
            r.reference_eigenvalues_re, r.p_eigenvalues
        );
    }
    for g in &r.guaranteed {
        eprintln!("  guaranteed: {g}");
    }
    for g in &r.not_guaranteed {
        eprintln!("  not guaranteed: {g}");
    }
    for x in &r.x0_outside_operating_range {
        eprintln!("  note: x0 component {x} (the rules' operating range)");
    }
    if outcome.design.is_none() && !targets.is_empty() {
        eprintln!("  no code generated: the design was refused");
    }
    for (path, _) in &files {
        eprintln!("  wrote                {}", path.display());
    }
    Some(outcome.exit_code())
}

/// `tsfc simulate` of an adaptive spec: writes `<name>.adaptive.csv`,
/// `<name>.adaptive.metrics.json` and `<name>.estimates.{svg,png}`;
/// `None` when the spec is not adaptive.
pub fn simulate(front: &Front, out: &Path, opts: &sim::Options) -> Option<u8> {
    let outcome = outcome(front)?;
    let model = front.checked.model.as_ref()?;
    let Some(design) = &outcome.design else {
        eprintln!(
            "error: the adaptive design was refused: {}",
            outcome.report.refusals.join("; ")
        );
        return Some(3);
    };
    let source = SpecSource {
        name: front.source.name.clone(),
        text: front.source.text.clone(),
    };
    let run = match sim::run(model, design, &source, opts) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {}", e.message);
            return Some(e.exit_code());
        }
    };
    let name = &run.name;
    let (svg, png) = match sim::plot(&run, design) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("error: {}", e.message);
            return Some(e.exit_code());
        }
    };
    let files = vec![
        (
            out.join(format!("{name}.adaptive.csv")),
            sim::csv(&run, design).into_bytes(),
        ),
        (
            out.join(format!("{name}.adaptive.metrics.json")),
            json(&run.metrics),
        ),
        (out.join(format!("{name}.estimates.svg")), svg),
        (out.join(format!("{name}.estimates.png")), png),
    ];
    if let Err(code) = write(&files) {
        return Some(code);
    }
    let m = &run.metrics;
    eprintln!(
        "simulated `{name}` (adaptive): {} steps to t = {}, final ||x|| = {:.3e}, estimates within bounds: {}, {} steps outside the rules' operating range (last at {:?} s)",
        m.steps, m.t_end, m.final_state_norm, m.estimates_within_bounds, m.steps_outside_operating_range, m.last_outside_s
    );
    for c in &m.claims {
        eprintln!(
            "  {} {} (largest after: {:.3e})",
            if c.held { "held:" } else { "FAILED:" },
            c.claim,
            c.max_after
        );
    }
    for (path, _) in &files {
        eprintln!("  wrote                {}", path.display());
    }
    let failed =
        m.failure.is_some() || m.claims.iter().any(|c| !c.held) || !m.estimates_within_bounds;
    if let Some(f) = &m.failure {
        eprintln!("error: {f}");
    }
    Some(if failed { RUN_FAILED } else { 0 })
}
