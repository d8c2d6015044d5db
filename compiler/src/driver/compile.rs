//! `tsfc compile`: synthesis, certificate and report for a checked model.

use crate::certify::{certify, Certificate};
use crate::model::TsModel;
use crate::report::{report, Report, SpecInfo, Timings};
use crate::synth::{synthesize_logged, Design, Settings, SolverLog, SynthError};
use std::time::{Duration, Instant};

/// How a compile ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// Gains certified.
    Certified,
    /// Objectives infeasible together.
    Infeasible,
    /// Solver trouble or certificate refused.
    Refused,
}

/// The result of compiling one model.
#[derive(Debug)]
pub struct Compiled {
    /// Verdict.
    pub status: Status,
    /// Design and certificate, or why there is none.
    pub outcome: Result<(Design, Certificate), SynthError>,
    /// The JSON report.
    pub report: Report,
}

/// Synthesizes and certifies. If the certificate fails only because the
/// solver's answer sits within rounding of the strict margin, the synthesis is
/// retried once with a 100 times larger margin (noted in the report).
pub fn compile(
    model: &TsModel,
    spec: SpecInfo,
    settings: &Settings,
    front: (Duration, Duration),
) -> Compiled {
    let t0 = Instant::now();
    let mut settings = settings.clone();
    settings.verifier = Some(crate::certify::verdict);
    settings.scorer = Some(super::transmissions::score);
    let (mut outcome, mut log) = run(model, &settings);
    if matches!(&outcome, Ok((_, c)) if !c.ok) {
        settings.eps *= 100.0;
        let (retry, retry_log) = run(model, &settings);
        let failed = format!(
            "certificate failed at margin {:.1e}; re-solved with margin {:.1e}",
            settings.eps / 100.0,
            settings.eps
        );
        match retry {
            Ok((mut d, c)) if c.ok => {
                d.notes.push(failed);
                outcome = Ok((d, c));
                let first = std::mem::replace(&mut log, retry_log);
                log.count_also(&first);
            }
            _ => {
                if let Ok((d, _)) = &mut outcome {
                    d.notes.push(format!(
                        "{failed}, which did not certify either (its SDPs are counted)"
                    ));
                }
                log.count_also(&retry_log);
            }
        }
    }
    let status = match &outcome {
        Ok((_, c)) if c.ok => Status::Certified,
        Err(SynthError::Infeasible { .. }) => Status::Infeasible,
        _ => Status::Refused,
    };
    let (solve, build, cert) = (log.solve_time, log.build_time, Duration::ZERO);
    let total = front.0 + front.1 + t0.elapsed();
    let timings = Timings {
        parse: front.0.as_secs_f64(),
        model: front.1.as_secs_f64(),
        build: build.as_secs_f64(),
        solve: solve.as_secs_f64(),
        certify: cert.as_secs_f64(),
        total: total.as_secs_f64(),
    };
    let mut report = report(model, spec, &outcome, &log, timings);
    if let Ok((d, _)) = &outcome {
        report.timings_s.certify = d.certify_time.as_secs_f64();
    }
    Compiled {
        status,
        outcome,
        report,
    }
}

/// Synthesizes and certifies; the solver log also when synthesis fails.
fn run(
    model: &TsModel,
    settings: &Settings,
) -> (Result<(Design, Certificate), SynthError>, SolverLog) {
    let (design, log) = synthesize_logged(model, settings);
    let out = design.and_then(|mut design| {
        let t = Instant::now();
        let cert = certify(model, &design)?;
        design.certify_time = t.elapsed();
        Ok((design, cert))
    });
    (out, log)
}
