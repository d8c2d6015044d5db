//! Sweeps (`tsfc simulate --sweep`): a list of scenarios (the spec's own
//! design first, then the triggering laws of its `sweep { }` block, then the
//! same for every compared spec) run in parallel on the campaign's worker
//! pool, and one comparison table ([`table`]).
//!
//! Certification per row: a law that differs from the compiled one is not
//! covered by the design's certificate, so the spec is compiled again with
//! that law in place of its `trigger` item (the normal pipeline: given gains
//! are analyzed, synthesized designs re-solved). A certified row runs its own
//! design; a refused row runs the compiled design's gains under the new law
//! and says so. Every row is a normal run (same integrator, `x0`, horizon,
//! disturbance signals); rows are computed independently and collected in
//! order, so the table's bytes do not depend on the thread count.

pub mod table;

use super::campaign::{json, pool, write};
use super::metrics::WindowedNorms;
use super::scenario::run_truth;
use super::{Options, Prepared, SimError};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use table::{Gains, Row, Table, TABLE_FORMAT};
use tsf_lang::spec::{Spec, SweepScenario, Trigger};

/// Worker threads of a sweep.
#[derive(Debug, Clone, Default)]
pub struct Config {
    /// Worker threads (default: all cores).
    pub jobs: Option<usize>,
}

/// One row to run: a spec of the table and one of its scenarios (`None`: its design).
struct Job<'a> {
    spec: usize,
    scenario: Option<&'a SweepScenario>,
}

/// A scenario's design: its own, certified, or why the certificate does not cover it.
enum Design {
    Own(Box<Prepared>),
    Refused(String),
}

/// The law a spec was compiled with (no `trigger` item: continuous).
fn own_trigger(spec: &Spec) -> Trigger {
    spec.trigger
        .as_ref()
        .map_or(Trigger::Continuous, |t| t.node.clone())
}

/// The spec's text with its `trigger` item replaced by the scenario's law
/// (appended when the spec has none); `None` if a span does not fit the text.
pub fn scenario_text(text: &str, spec: &Spec, sc: &SweepScenario) -> Option<String> {
    let (stmt, subs) = &sc.source;
    let mut subs = subs.clone();
    subs.sort_by_key(|(list, _)| list.start);
    let mut item = String::new();
    let mut at = stmt.start;
    for (list, elem) in subs {
        item.push_str(text.get(at..list.start)?);
        item.push_str(text.get(elem.start..elem.end)?);
        at = list.end;
    }
    item.push_str(text.get(at..stmt.end)?);
    Some(match &spec.trigger {
        Some(t) => format!(
            "{}{item}{}",
            text.get(..t.span.start)?,
            text.get(t.span.end..)?
        ),
        None => format!("{text}\n{item}\n"),
    })
}

/// Longest refusal reason kept in a row (characters).
const MAX_REASON_CHARS: usize = 400;

/// The first line of an error, without `error: ` and the spec's name.
fn short(message: &str, name: &str) -> String {
    let line = message
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty())
        .unwrap_or("refused");
    let line = line.strip_prefix("error: ").unwrap_or(line);
    let line = line.strip_prefix(&format!("{name}: ")).unwrap_or(line);
    if line.chars().count() <= MAX_REASON_CHARS {
        return line.to_string();
    }
    let cut: String = line.chars().take(MAX_REASON_CHARS).collect();
    format!("{cut}...")
}

/// Compiles a spec text into a certified design: `(source name, text,
/// display name)`. The driver passes its pipeline
/// (`crate::driver::prepare::prepare_text`); the simulator never compiles.
pub type CompileLaw<'a> = &'a (dyn Fn(&str, String, String) -> Result<Prepared, SimError> + Sync);

/// Compiles the spec of `p` with the scenario's law (the normal pipeline).
fn compile_scenario(p: &Prepared, sc: &SweepScenario, compile: CompileLaw<'_>) -> Design {
    let spec = &p.model.spec;
    let Some(text) = scenario_text(&p.source.text, spec, sc) else {
        return Design::Refused("the scenario's law could not be written into the spec".into());
    };
    let name = format!("{} [{}]", spec.controller.node, sc.name);
    match compile(&p.source.name, text, name.clone()) {
        Ok(prepared) => Design::Own(Box::new(prepared)),
        Err(e) => Design::Refused(short(&e.message, &name)),
    }
}

/// `(offset, len)` of a state group of `spec`: `x`, a state or an extra state of `dynamics`.
fn group_at(spec: &Spec, group: &str) -> Option<(usize, usize)> {
    let n = spec.n();
    if group == "x" {
        return Some((0, n));
    }
    if let Some(s) = spec.states.iter().find(|s| s.name == group) {
        return Some((s.offset, s.len));
    }
    let dynamics = spec.simulate.as_ref()?.dynamics.as_ref()?;
    let s = dynamics.extra_states.iter().find(|s| s.name == group)?;
    Some((n + s.offset, s.len))
}

/// Runs the sweep of `main` (its design, then its `sweep` scenarios) and of
/// every spec of `compare`, with the table's columns and window from `main`;
/// a scenario whose law differs from its spec's is compiled by `compile`.
pub fn run_sweep(
    main: &Prepared,
    compare: &[Prepared],
    opts: &Options,
    cfg: &Config,
    compile: CompileLaw<'_>,
) -> Result<(Table, Vec<ScenarioMetrics>), SimError> {
    let entries: Vec<&Prepared> = std::iter::once(main).chain(compare).collect();
    let spec = &main.model.spec;
    let sim = spec.simulate.as_ref().ok_or_else(|| {
        SimError::spec("the spec has no `simulate { ... }` block (add one with `x0` and `time`)")
    })?;
    let sweep = sim.sweep.as_ref();
    let (t0, t1) = (
        sim.time.0,
        opts.horizon.map_or(sim.time.1, |h| sim.time.0 + h),
    );
    let window = sweep.and_then(|s| s.window).unwrap_or((t0, t1));
    if window.1 > t1 {
        return Err(SimError::usage(format!(
            "the sweep window {} .. {} s ends after the run ({t1} s): extend --horizon or move the window",
            window.0, window.1
        )));
    }
    let columns = sweep.map_or(&[][..], |s| s.columns.as_slice());
    // Each spec's column groups, by name.
    let mut groups = Vec::new();
    for p in &entries {
        let s = &p.model.spec;
        let at = columns
            .iter()
            .map(|c| {
                group_at(s, &c.group).ok_or_else(|| {
                    SimError::usage(format!(
                        "column `{}`: `{}` has no state group `{}`",
                        c.name, s.controller.node, c.group
                    ))
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        groups.push(at);
    }
    let mut jobs = Vec::new();
    for (k, p) in entries.iter().enumerate() {
        jobs.push(Job {
            spec: k,
            scenario: None,
        });
        let scenarios = p
            .model
            .spec
            .simulate
            .as_ref()
            .and_then(|s| s.sweep.as_ref());
        for sc in scenarios.map_or(&[][..], |s| s.scenarios.as_slice()) {
            jobs.push(Job {
                spec: k,
                scenario: Some(sc),
            });
        }
    }
    let pool = pool(cfg.jobs)?;
    // The distinct laws that need a design of their own, compiled in parallel.
    let mut todo: Vec<(usize, &SweepScenario)> = Vec::new();
    for j in &jobs {
        if let Some(sc) = j.scenario {
            let own = own_trigger(&entries[j.spec].model.spec);
            let known = todo
                .iter()
                .any(|(k, s)| *k == j.spec && s.trigger == sc.trigger);
            if sc.trigger != own && !known {
                todo.push((j.spec, sc));
            }
        }
    }
    let designs: Vec<Design> = pool.install(|| {
        todo.par_iter()
            .map(|(k, sc)| compile_scenario(entries[*k], sc, compile))
            .collect()
    });
    let design_of = |j: &Job| -> Option<&Design> {
        let sc = j.scenario?;
        todo.iter()
            .position(|(k, s)| *k == j.spec && s.trigger == sc.trigger)
            .map(|i| &designs[i])
    };
    let results: Vec<(Row, ScenarioMetrics)> = pool.install(|| {
        jobs.par_iter()
            .map(|j| {
                let base = entries[j.spec];
                let given = base.model.spec.given_gains().is_some();
                let (prepared, gains, refused) = match design_of(j) {
                    None if j.scenario.is_none() => (base, Gains::Design, None),
                    None => (base, Gains::Same, None),
                    Some(Design::Own(p)) => (&**p, Gains::own(given), None),
                    Some(Design::Refused(why)) => (base, Gains::fallback(given), Some(why.clone())),
                };
                let trigger = j
                    .scenario
                    .map_or_else(|| own_trigger(&base.model.spec), |s| s.trigger.clone());
                let o = Options {
                    trigger: Some(trigger),
                    progress: false,
                    ..opts.clone()
                };
                let mut norms = WindowedNorms::new(window, groups[j.spec].clone());
                let mut obs = |t: f64, x: &[f64], _: &[f64]| norms.sample(t, x);
                let result = run_truth(prepared, &prepared.model.spec, &o, None, Some(&mut obs));
                let scenario = j.scenario.map_or("design", |s| s.name.as_str());
                let row = Row::new(
                    &base.model.spec.controller.node,
                    scenario,
                    refused,
                    gains,
                    result
                        .as_ref()
                        .map(|r| &r.metrics)
                        .map_err(|e| e.message.as_str()),
                    norms.finish(),
                );
                let metrics = ScenarioMetrics {
                    error: result.as_ref().err().map(|e| e.message.clone()),
                    metrics: result.as_ref().ok().map(|r| r.metrics.clone()),
                    scenario: scenario.to_string(),
                    spec: base.model.spec.controller.node.clone(),
                };
                (row, metrics)
            })
            .collect()
    });
    let (rows, metrics): (Vec<Row>, Vec<ScenarioMetrics>) = results.into_iter().unzip();
    let table = Table {
        format: TABLE_FORMAT.into(),
        name: spec.controller.node.clone(),
        time_s: (t0, t1),
        window_s: window,
        columns: columns
            .iter()
            .map(|c| (c.name.clone(), c.group.clone()))
            .collect(),
        rows,
    };
    Ok((table, metrics))
}

/// Writes `<name>.sweep.{md,csv,json}` and the per-scenario metrics
/// `<name>.sweep.metrics.json` into `dir`, each atomically.
pub fn write_sweep(
    table: &Table,
    metrics: &[ScenarioMetrics],
    dir: &Path,
) -> Result<Vec<PathBuf>, SimError> {
    let name = &table.name;
    let files = [
        (format!("{name}.sweep.md"), table.markdown().into_bytes()),
        (format!("{name}.sweep.csv"), table.csv().into_bytes()),
        (format!("{name}.sweep.json"), json(table)?),
        (
            format!("{name}.sweep.metrics.json"),
            json(&sorted(metrics)?)?,
        ),
    ];
    files.into_iter().map(|(f, b)| write(dir, f, &b)).collect()
}

/// One row's run in `<name>.sweep.metrics.json`: its metrics, or why it has
/// none. The file lists every object's keys in name order.
#[derive(Debug, Clone, serde::Serialize, schemars::JsonSchema)]
pub struct ScenarioMetrics {
    /// Why the run stopped without metrics (null when it has them).
    pub error: Option<String>,
    /// The run's metrics (null on an error).
    pub metrics: Option<super::metrics::Metrics>,
    /// The scenario (`design`: the spec's own design).
    pub scenario: String,
    /// The spec's controller name.
    pub spec: String,
}

/// `metrics` as a JSON value, whose objects list their keys in name order.
fn sorted(metrics: &[ScenarioMetrics]) -> Result<serde_json::Value, SimError> {
    serde_json::to_value(metrics)
        .map_err(|e| SimError::usage(format!("cannot serialize the sweep metrics: {e}")))
}

#[cfg(test)]
mod tests {
    use super::short;

    #[test]
    fn a_refusal_reason_is_one_line_without_prefixes() {
        assert_eq!(
            short(
                "error: c [p]: not certified (LMI infeasible)\nmore",
                "c [p]"
            ),
            "not certified (LMI infeasible)"
        );
        assert_eq!(short("\n  error: bad\n", "c"), "bad");
    }
}
