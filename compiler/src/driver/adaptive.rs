//! `tsfc compile` and `tsfc simulate` on an adaptive spec: the design report
//! (`<name>.adaptive.json`), and the run's metrics, CSV and estimates plot.

use crate::codegen::{generate_adaptive, GeneratedFile};
use crate::driver::pipeline::Front;
use crate::sim::adaptive as sim;
use crate::sim::source::SpecSource;
use crate::synth::adaptive::{design, Design, Outcome};
use crate::tables::adaptive_tables;
use crate::util::error::Error;
use crate::util::hash::sha256_hex;
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

fn write(files: &[(PathBuf, Vec<u8>)]) -> Result<(), Error> {
    crate::util::output::write_set(files)
        .map_err(|e| Error::usage(format!("cannot write the outputs: {e}")))
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
    let failed =
        |e: &dyn std::fmt::Display| Error::not_certified(format!("code generation failed: {e}"));
    let at = adaptive_tables(model, design, front.name(), &sha).map_err(|e| failed(&e))?;
    generate_adaptive(&at, targets).map_err(|e| failed(&e))
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

/// What `tsfc compile` or `tsfc simulate` of an adaptive spec did: the
/// lines the CLI prints, the files written and the exit code.
#[derive(Debug, Clone)]
pub struct Done {
    /// The verdict and its details, one line each (the CLI prints them).
    pub lines: Vec<String>,
    /// Files written.
    pub written: Vec<PathBuf>,
    /// Exit code: 0 well posed (or the run held its claims), 3 refused, 4 the run failed.
    pub exit_code: u8,
}

/// `tsfc compile` of an adaptive spec: writes the report and the generated
/// files for `targets` (none when the design is refused) and says the
/// verdict; `None` when the spec is not adaptive.
pub fn compile(front: &Front, out: &Path, targets: &[Emit]) -> Option<Result<Done, Error>> {
    let outcome = outcome(front)?;
    let name = front.checked.model.as_ref()?.spec.controller.node.clone();
    Some(compile_outcome(front, &outcome, &name, out, targets))
}

fn compile_outcome(
    front: &Front,
    outcome: &Outcome,
    name: &str,
    out: &Path,
    targets: &[Emit],
) -> Result<Done, Error> {
    let path = out.join(format!("{name}.adaptive.json"));
    let mut files = vec![(path, json(&outcome.report))];
    if let (Some(design), false) = (&outcome.design, targets.is_empty()) {
        let g = generate(front, design, targets)?;
        files.extend(
            g.into_iter()
                .map(|f| (out.join(&f.name), f.text.into_bytes())),
        );
    }
    write(&files)?;
    let r = &outcome.report;
    let mut lines = vec![format!(
        "{name}: {} ({} adapted numbers; no LMI certificate: docs/adaptive.md)",
        r.status, r.adapted
    )];
    lines.extend(r.refusals.iter().map(|why| format!("  refused: {why}")));
    if !r.reference_eigenvalues_re.is_empty() {
        lines.push(format!(
            "  A_m eigenvalues (real parts) {:?}, P eigenvalues {:?}",
            r.reference_eigenvalues_re, r.p_eigenvalues
        ));
    }
    lines.extend(r.guaranteed.iter().map(|g| format!("  guaranteed: {g}")));
    lines.extend(
        r.not_guaranteed
            .iter()
            .map(|g| format!("  not guaranteed: {g}")),
    );
    lines.extend(
        r.x0_outside_operating_range
            .iter()
            .map(|x| format!("  note: x0 component {x} (the rules' operating range)")),
    );
    if outcome.design.is_none() && !targets.is_empty() {
        lines.push("  no code generated: the design was refused".into());
    }
    let written: Vec<PathBuf> = files.into_iter().map(|(p, _)| p).collect();
    lines.extend(
        written
            .iter()
            .map(|p| format!("  wrote                {}", p.display())),
    );
    Ok(Done {
        lines,
        written,
        exit_code: outcome.exit_code(),
    })
}

/// `tsfc simulate` of an adaptive spec: writes `<name>.adaptive.csv`,
/// `<name>.adaptive.metrics.json` and `<name>.estimates.{svg,png}`;
/// `None` when the spec is not adaptive.
pub fn simulate(front: &Front, out: &Path, opts: &sim::Options) -> Option<Result<Done, Error>> {
    let outcome = outcome(front)?;
    let model = front.checked.model.as_ref()?;
    Some(match &outcome.design {
        Some(design) => simulate_design(front, model, design, out, opts),
        None => Err(Error::not_certified(format!(
            "the adaptive design was refused: {}",
            outcome.report.refusals.join("; ")
        ))),
    })
}

fn simulate_design(
    front: &Front,
    model: &crate::model::TsModel,
    design: &Design,
    out: &Path,
    opts: &sim::Options,
) -> Result<Done, Error> {
    let source = SpecSource {
        name: front.source.name.clone(),
        text: front.source.text.clone(),
    };
    let run = sim::run(model, design, &source, opts)?;
    let name = &run.name;
    let (svg, png) = sim::plot(&run, design)?;
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
    write(&files)?;
    let m = &run.metrics;
    let mut lines = vec![format!(
        "simulated `{name}` (adaptive): {} steps to t = {}, final ||x|| = {:.3e}, estimates within bounds: {}, {} steps outside the rules' operating range (last at {:?} s)",
        m.steps, m.t_end, m.final_state_norm, m.estimates_within_bounds, m.steps_outside_operating_range, m.last_outside_s
    )];
    lines.extend(m.claims.iter().map(|c| {
        format!(
            "  {} {} (largest after: {:.3e})",
            if c.held { "held:" } else { "FAILED:" },
            c.claim,
            c.max_after
        )
    }));
    let written: Vec<PathBuf> = files.into_iter().map(|(p, _)| p).collect();
    lines.extend(
        written
            .iter()
            .map(|p| format!("  wrote                {}", p.display())),
    );
    let failed =
        m.failure.is_some() || m.claims.iter().any(|c| !c.held) || !m.estimates_within_bounds;
    if let Some(f) = &m.failure {
        lines.push(format!("error: {f}"));
    }
    Ok(Done {
        lines,
        written,
        exit_code: if failed { RUN_FAILED } else { 0 },
    })
}
