//! Simulating a certified design without solving again: the JSON report of
//! `tsfc compile` holds what the simulator takes from the design (the gains
//! F_j per rule (per mode with `modes`), the Lyapunov matrix P, the synthesized trigger weight
//! Upsilon); everything else (premises, sets, rule centres, saturation,
//! trigger law, scenario) comes from the spec, checked again. A report is
//! used only when it is certified (status and certificate), was written by
//! this tsfc version, and records the SHA-256 of the very spec bytes being
//! simulated, with the spec's controller, sizes and rules; otherwise the
//! design is compiled again ([`Reuse::Refused`] says why). Gains of
//! another version of the spec are never simulated.

use crate::driver::pipeline::{self, Front};
use crate::model::TsModel;
use crate::sim::{source, Prepared, SimError};
use crate::tables::{Header, ModeTables, Tables};
use crate::util::hash::sha256_hex;
use nalgebra::DMatrix;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// Where the simulated design came from.
#[derive(Debug, Clone, PartialEq)]
pub enum Reuse {
    /// The certified report at this path (no solve).
    Reused(PathBuf),
    /// Compiled: the report could not be used, for this reason (a sentence
    /// naming the report).
    Refused(String),
    /// Compiled: no report was given and there is none in the output folder.
    NoReport,
}

/// The parts of the report the simulator reads (other fields are ignored).
#[derive(Debug, Deserialize)]
struct ReportView {
    tsfc_version: String,
    spec: SpecView,
    controller: String,
    n: usize,
    m: usize,
    status: String,
    gains: Vec<GainView>,
    #[serde(rename = "P")]
    p: Vec<Vec<f64>>,
    certificate: Option<CertificateView>,
    trigger: Option<TriggerView>,
    sampled_loop: Option<SampledView>,
    stored_precision: Option<StoredView>,
    modes: Option<Vec<ModeView>>,
    region_of_attraction: Option<RegionView>,
}

#[derive(Debug, Deserialize)]
struct RegionView {
    #[serde(rename = "U")]
    u: Vec<Vec<f64>>,
}

#[derive(Debug, Deserialize)]
struct ModeView {
    name: String,
    gains: Vec<GainView>,
}

#[derive(Debug, Deserialize)]
struct StoredView {
    certified: bool,
    worst_margin: f64,
}

#[derive(Debug, Deserialize)]
struct SpecView {
    sha256: String,
}

#[derive(Debug, Deserialize)]
struct GainView {
    rule: String,
    #[serde(rename = "F")]
    f: Vec<Vec<f64>>,
}

#[derive(Debug, Deserialize)]
struct CertificateView {
    ok: bool,
    min_margin: f64,
}

#[derive(Debug, Deserialize)]
struct TriggerView {
    weight: Vec<Vec<f64>>,
}

#[derive(Debug, Deserialize)]
struct SampledView {
    sampling: [f64; 2],
}

/// A `rows x cols` matrix of finite numbers from JSON rows.
fn matrix(rows: &[Vec<f64>], r: usize, c: usize, what: &str) -> Result<DMatrix<f64>, String> {
    let fits = rows.len() == r && rows.iter().all(|row| row.len() == c);
    if !fits || rows.iter().flatten().any(|v| !v.is_finite()) {
        return Err(format!(
            "its {what} is not a {r}x{c} matrix of finite numbers"
        ));
    }
    Ok(DMatrix::from_fn(r, c, |i, j| rows[i][j]))
}

/// The simulator's design from a report of the spec read in `front`, or why
/// it cannot be used (the same checks as [`prepare_reusing`]; nothing is compiled).
pub fn from_report(front: &Front, model: &TsModel, json: &str) -> Result<Prepared, String> {
    if model.spec.control.kind != tsf_lang::spec::ControlKind::StateFeedback {
        return Err("an output-feedback design's observer tables are not in the report".into());
    }
    let r: ReportView =
        serde_json::from_str(json).map_err(|e| format!("it is not a tsfc report ({e})"))?;
    let spec = &model.spec;
    let (n, m) = (model.n, model.m);
    let certified = r.status == "certified" && r.certificate.as_ref().is_some_and(|c| c.ok);
    if !certified {
        return Err(format!(
            "its design is not certified (status `{}`)",
            r.status
        ));
    }
    let version = env!("CARGO_PKG_VERSION");
    if r.tsfc_version != version {
        return Err(format!(
            "it was written by tsfc {} (this is {version})",
            r.tsfc_version
        ));
    }
    if r.stored_precision.as_ref().is_some_and(|s| !s.certified) {
        return Err("its design is not certified as stored (stored_precision)".into());
    }
    let sha256 = sha256_hex(&front.source.bytes);
    if r.spec.sha256 != sha256 {
        return Err("it records another version of the spec (its sha256 differs)".into());
    }
    let rules: Vec<&str> = model.rules.iter().map(|r| r.name.as_str()).collect();
    let named: Vec<&str> = r.gains.iter().map(|g| g.rule.as_str()).collect();
    if r.controller != spec.controller.node || (r.n, r.m) != (n, m) || named != rules {
        return Err("its controller, sizes or rules differ from the spec's".into());
    }
    let gain_set = |gains: &[GainView]| -> Result<Vec<Vec<Vec<f64>>>, String> {
        let named: Vec<&str> = gains.iter().map(|g| g.rule.as_str()).collect();
        if named != rules {
            return Err("its rules differ from the spec's".into());
        }
        gains
            .iter()
            .map(|g| matrix(&g.f, m, n, &format!("gain of {}", g.rule)).map(|_| g.f.clone()))
            .collect()
    };
    let gains = gain_set(&r.gains)?;
    let modes = match &spec.modes {
        None => None,
        Some(sm) => {
            let rm = r.modes.as_ref().ok_or("it has no `modes` section")?;
            let names: Vec<&str> = sm.modes.iter().map(|md| md.name.as_str()).collect();
            let named: Vec<&str> = rm.iter().map(|md| md.name.as_str()).collect();
            if names != named {
                return Err("its modes differ from the spec's".into());
            }
            let sets = rm
                .iter()
                .map(|md| gain_set(&md.gains))
                .collect::<Result<Vec<_>, _>>()?;
            (sm.design == tsf_lang::modes::ModeDesign::Dependent).then(|| ModeTables {
                names: names.iter().map(|s| s.to_string()).collect(),
                gains: sets,
            })
        }
    };
    let p = matrix(&r.p, n, n, "P")?;
    let trigger_weight = match &r.trigger {
        Some(t) => Some(matrix(&t.weight, n, n, "trigger weight")?),
        None => None,
    };
    let names = tsf_lang::spec::Signal::names_of;
    let tables = Tables {
        name: spec.controller.node.clone(),
        header: Header {
            tsfc_version: version.to_string(),
            spec_path: front.source.name.clone(),
            spec_sha256: sha256,
            objectives: Vec::new(),
            min_margin: r.certificate.as_ref().map_or(f64::NAN, |c| c.min_margin),
            precision: spec.precision,
            stored_margin: r.stored_precision.as_ref().map(|s| s.worst_margin),
            relaxation: spec.relaxation.node.to_string(),
            sampling: r
                .sampled_loop
                .as_ref()
                .map(|s| (s.sampling[0], s.sampling[1])),
            reads: None,
        },
        n,
        m,
        p: model.premises.len(),
        r: model.r(),
        state_names: names(&spec.states),
        input_names: names(&spec.inputs),
        rule_names: rules.iter().map(|s| s.to_string()).collect(),
        premise: crate::tables::premise_code(model).map_err(|e| e.to_string())?,
        terms: model.terms.clone(),
        factored: crate::tables::FactoredTerms::new(&model.terms),
        centres: model.centers.clone(),
        gains,
        u_max: spec
            .saturation
            .clone()
            .unwrap_or_else(|| vec![f64::INFINITY; m]),
        precision: spec.precision,
        c_style: spec.c_style,
        sensor: crate::tables::Sensor::None,
        modes,
        observer: None,
        static_output: None,
    };
    let region = match &r.region_of_attraction {
        Some(roa) => Some(matrix(&roa.u, n, n, "region of attraction U")?),
        None => None,
    };
    Ok(Prepared {
        model: model.clone(),
        tables,
        p,
        trigger_weight,
        region,
        source: source::SpecSource {
            name: front.source.name.clone(),
            text: front.source.text.clone(),
        },
    })
}

/// Reads and checks the spec at `path` and takes its design from the report
/// at `report` (given: it must be readable) or `out/<controller>.report.json`
/// (if present) when that report is usable; otherwise compiles the design
/// (it must be certified). Returns the design and where it came from.
pub fn prepare_reusing(
    path: &Path,
    report: Option<&Path>,
    out: &Path,
) -> Result<(Prepared, Reuse), SimError> {
    let front = pipeline::read(path)?;
    let Some(model) = &front.checked.model else {
        return Err(SimError::spec(front.render(false)));
    };
    let default = out.join(format!("{}.report.json", model.spec.controller.node));
    let candidate = report.unwrap_or(&default);
    let reuse = match std::fs::read_to_string(candidate) {
        Ok(json) => match from_report(&front, model, &json) {
            Ok(prepared) => return Ok((prepared, Reuse::Reused(candidate.to_path_buf()))),
            Err(why) => Reuse::Refused(format!("`{}` cannot be used: {why}", candidate.display())),
        },
        Err(e) if report.is_some() => {
            return Err(SimError::usage(format!(
                "cannot read the report `{}`: {e}",
                candidate.display()
            )))
        }
        Err(_) => Reuse::NoReport,
    };
    let run = front.compile(&crate::synth::Settings::default())?;
    Ok((super::prepare_run(&run)?, reuse))
}
