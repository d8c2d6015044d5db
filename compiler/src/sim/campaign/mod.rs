//! Monte Carlo campaigns (`tsfc simulate --monte-carlo N`): the certified
//! design in closed loop with N truth plants drawn from the spec's
//! `monte_carlo { }` block ([`draw`]), in parallel on all cores (rayon), each
//! run seeded from `(seed, run index)` alone so results do not depend on the
//! thread count or the sharding. A run keeps only its figures of merit and
//! widens a decimated state envelope ([`summary`]); shards (`--shard k/K`,
//! the indices `i` with `i mod K == k - 1`) write their partial output, which
//! [`summary::merge`] combines into what one whole run gives. Outputs: summary
//! table (Markdown, CSV, JSON), per-run CSV and plots ([`plot`]).

pub mod draw;
pub mod plot;
pub mod scheduler;
pub mod shard;
pub mod summary;

use super::limits::{MAX_CAMPAIGN_STEPS, MAX_SHARDS, MAX_SHARD_FILE_BYTES};
use super::metrics::norm;
use super::plant::Plant;
use super::scenario::{plan, run_truth};
use super::{Evaluator, Options, Prepared, SimError};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::Instant;
use summary::{Envelope, Partial, RunRecord, SHARD_FORMAT};
use tsf_lang::limits::MAX_MONTE_CARLO_RUNS;
use tsf_lang::spec::MonteCarlo;

/// Time bins of the state envelope.
pub const ENVELOPE_BINS: usize = 400;

/// A campaign's size and split.
#[derive(Debug, Clone)]
pub struct Config {
    /// Runs N (default: the block's `runs`).
    pub runs: Option<u64>,
    /// `(k, K)`: run the indices `i` with `i mod K == k - 1`.
    pub shard: (u64, u64),
    /// Campaign seed (default: the scenario's `seed`).
    pub seed: Option<u64>,
    /// Worker threads (default: all cores).
    pub jobs: Option<usize>,
    /// Progress lines on stderr.
    pub progress: bool,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            runs: None,
            shard: (1, 1),
            seed: None,
            jobs: None,
            progress: false,
        }
    }
}

pub use scheduler::{parse_shard, ShardArg};

/// The spec's `monte_carlo` block.
fn block(prepared: &Prepared) -> Result<&MonteCarlo, SimError> {
    let sim = prepared.model.spec.simulate.as_ref();
    sim.and_then(|s| s.monte_carlo.as_ref()).ok_or_else(|| {
        SimError::spec(
            "the scenario has no `monte_carlo { ... }` block: declare the uncertainty inside `simulate` (docs/language.md)",
        )
    })
}

/// Runs this shard of the campaign (the whole campaign for shard 1/1).
pub fn run_campaign(
    prepared: &Prepared,
    opts: &Options,
    cfg: &Config,
) -> Result<Partial, SimError> {
    let started = Instant::now();
    let mc = block(prepared)?;
    let spec = &prepared.model.spec;
    let runs = cfg.runs.or(mc.runs).unwrap_or(100);
    if !(1..=MAX_MONTE_CARLO_RUNS).contains(&runs) {
        return Err(SimError::usage(format!(
            "a campaign has 1 .. {MAX_MONTE_CARLO_RUNS} runs (got {runs})"
        )));
    }
    let (k, kk) = cfg.shard;
    if !(1 <= k && k <= kk && kk <= MAX_SHARDS) {
        return Err(SimError::usage(format!(
            "shard {k}/{kk}: need 1 <= k <= K <= {MAX_SHARDS}"
        )));
    }
    if !shard::plain_name(&spec.controller.node) {
        return Err(SimError::usage(format!(
            "the controller name `{}` is longer than {} bytes: a campaign's file names start with it",
            spec.controller.node,
            shard::MAX_NAME_BYTES
        )));
    }
    let dim = Plant::new(spec, &prepared.source, Evaluator::Interpreter)?.dim();
    let plan = plan(prepared, opts, dim)?;
    let (t0, t1) = (plan.t0, plan.t1);
    let total_steps = (runs as f64) * (plan.steps as f64);
    if total_steps > MAX_CAMPAIGN_STEPS as f64 {
        return Err(SimError::usage(format!(
            "{runs} runs of {} steps are {total_steps:.3e} steps, more than the campaign limit {MAX_CAMPAIGN_STEPS:e} (docs/limits.md): fewer runs, a shorter horizon or a larger step",
            plan.steps
        )));
    }
    let rule = &mc.converged;
    if rule.by > t1 {
        return Err(SimError::usage(format!(
            "the convergence time {} s of the `monte_carlo` block is after the end of the run ({t1} s)",
            rule.by
        )));
    }
    let seed = cfg.seed.unwrap_or(plan.seed);
    let n = spec.n();
    let x0_nominal = plan.x0[..n].to_vec();
    let empty = Envelope::new((t0, t1), ENVELOPE_BINS, dim);

    // The nominal run (the plots' reference line).
    let mut nominal = vec![vec![f64::NAN; dim]; ENVELOPE_BINS];
    {
        let mut obs = |t: f64, x: &[f64], _: &[f64]| {
            if let Some(row) = nominal.get_mut(empty.bin(t)) {
                row.copy_from_slice(&x[..dim.min(x.len())]);
            }
        };
        let quiet = Options {
            progress: false,
            ..opts.clone()
        };
        run_truth(prepared, spec, &quiet, None, Some(&mut obs))?;
    }
    for k in 1..nominal.len() {
        if nominal[k].iter().all(|v| v.is_nan()) {
            nominal[k] = nominal[k - 1].clone();
        }
    }
    let nominal: Vec<Vec<Option<f64>>> = nominal
        .into_iter()
        .map(|r| r.into_iter().map(|v| v.is_finite().then_some(v)).collect())
        .collect();

    let indices: Vec<u64> = (k - 1..runs).step_by(kk as usize).collect();
    let count = indices.len() as u64;
    let done = AtomicU64::new(0);
    let last_print = Mutex::new(Instant::now());
    let one = |env: &mut Envelope, i: u64| -> RunRecord {
        let rec = one_run(prepared, opts, mc, &x0_nominal, seed, i, env);
        let d = done.fetch_add(1, Ordering::Relaxed) + 1;
        if cfg.progress {
            if let Ok(mut last) = last_print.try_lock() {
                if last.elapsed().as_secs_f64() >= super::limits::PROGRESS_LOG_PERIOD_S {
                    *last = Instant::now();
                    eprintln!(
                        "  monte carlo: {d} of {count} runs, {:.0} s elapsed",
                        started.elapsed().as_secs_f64()
                    );
                }
            }
        }
        rec
    };
    let pool = pool(cfg.jobs)?;
    let (mut records, envelope) = pool.install(|| {
        indices
            .into_par_iter()
            .fold(
                || (Vec::new(), empty.clone()),
                |(mut recs, mut env), i| {
                    recs.push(one(&mut env, i));
                    (recs, env)
                },
            )
            .reduce(
                || (Vec::new(), empty.clone()),
                |(mut a, mut ea), (b, eb)| {
                    a.extend(b);
                    ea.merge(&eb);
                    (a, ea)
                },
            )
    });
    records.sort_by_key(|r| r.index);
    let names = |v: &[String]| v.to_vec();
    let tables = &prepared.tables;
    let mut state_names = names(&tables.state_names);
    state_names.extend(Plant::new(spec, &prepared.source, Evaluator::Interpreter)?.extra_names());
    Ok(Partial {
        format: SHARD_FORMAT.into(),
        tsfc_version: env!("CARGO_PKG_VERSION").into(),
        spec_sha256: tables.header.spec_sha256.clone(),
        design_sha256: shard::design_sha256(prepared),
        name: spec.controller.node.clone(),
        runs_total: runs,
        seed,
        shard: (k, kk),
        time_s: (t0, t1),
        converged_rule: (rule.name.clone(), rule.tol, rule.by),
        state_names,
        input_names: names(&tables.input_names),
        runs: records,
        envelope,
        nominal,
    })
}

/// A pool of `jobs` worker threads (default: all cores).
pub(crate) fn pool(jobs: Option<usize>) -> Result<rayon::ThreadPool, SimError> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(jobs.unwrap_or(0))
        .build()
        .map_err(|e| SimError::usage(format!("cannot start the worker threads: {e}")))
}

/// Run `i`: its draw, the closed loop, its record; widens `env`.
fn one_run(
    prepared: &Prepared,
    opts: &Options,
    mc: &MonteCarlo,
    x0_nominal: &[f64],
    seed: u64,
    i: u64,
    env: &mut Envelope,
) -> RunRecord {
    let run_seed = draw::run_seed(seed, i);
    let d = draw::draw(&prepared.model.spec, mc, x0_nominal, run_seed);
    let o = Options {
        x0: Some(d.x0),
        seed: Some(run_seed),
        progress: false,
        ..opts.clone()
    };
    let rule = &mc.converged;
    let (at, len) = rule.signal;
    let mut settle: Option<f64> = None;
    let mut last_norm = f64::NAN;
    let mut obs = |t: f64, x: &[f64], _: &[f64]| {
        env.add(env.bin(t), x);
        let r = x.get(at..at + len).map_or(f64::NAN, norm);
        if r.is_finite() && r <= rule.tol {
            settle.get_or_insert(t);
        } else {
            settle = None;
        }
        last_norm = r;
    };
    let result = run_truth(prepared, &d.truth, &o, None, Some(&mut obs));
    let m = prepared.tables.u_max.len();
    let mut rec = RunRecord {
        index: i,
        seed: run_seed,
        converged: false,
        settle_time_s: settle,
        max_abs_u: vec![0.0; m],
        transmissions: 0,
        final_norm: last_norm.is_finite().then_some(last_norm),
        diverged: false,
        nonfinite: false,
        error: None,
    };
    match result {
        Ok(out) => {
            let mt = out.metrics;
            // JSON has no infinity: an overflowed |u| is kept as f64::MAX.
            rec.max_abs_u = mt.max_abs_u.iter().map(|u| u.min(f64::MAX)).collect();
            rec.transmissions = mt.transmissions;
            rec.diverged = mt.diverged;
            rec.nonfinite = mt.nonfinite_at_s.is_some();
            rec.converged = !rec.nonfinite && settle.is_some_and(|s| s <= rule.by);
        }
        Err(e) => rec.error = Some(e.message),
    }
    rec
}

/// Writes `bytes` to `dir/file` atomically; `file` must be a plain file name
/// (nothing is written outside `dir`).
pub(crate) fn write(dir: &Path, file: String, bytes: &[u8]) -> Result<PathBuf, SimError> {
    let plain = !file.is_empty()
        && !file.starts_with('.')
        && file
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'));
    if !plain {
        return Err(SimError::usage(format!(
            "refusing to write `{}`: not a plain file name",
            file.escape_debug()
        )));
    }
    let path = dir.join(file);
    crate::util::output::write_atomic(&path, bytes)
        .map_err(|e| SimError::usage(format!("cannot write `{}`: {e}", path.display())))?;
    Ok(path)
}

/// `v` as pretty JSON with a final newline.
pub(crate) fn json<T: serde::Serialize>(v: &T) -> Result<Vec<u8>, SimError> {
    serde_json::to_string_pretty(v)
        .map(|s| (s + "\n").into_bytes())
        .map_err(|e| SimError::usage(format!("cannot serialize: {e}")))
}

/// The shard file name of `p`.
pub fn shard_file(p: &Partial) -> String {
    format!("{}.mc.shard-{}-of-{}.json", p.name, p.shard.0, p.shard.1)
}

/// Writes the shard's partial output (`<name>.mc.shard-k-of-K.json`) into
/// `dir`, checked as `--merge` will check it.
pub fn write_shard(p: &Partial, dir: &Path) -> Result<PathBuf, SimError> {
    shard::validate(p).map_err(|e| SimError::usage(format!("the shard is not written: {e}")))?;
    write(dir, shard_file(p), &json(p)?)
}

/// Writes a whole (or merged) campaign into `dir`: `<name>.mc.runs.json` (the
/// runs and envelope, mergeable), `<name>.mc.summary.{md,csv,json}`,
/// `<name>.mc.runs.csv` and the plots `<name>.mc.{envelope,settle,transmissions}.{svg,png}`.
pub fn write_campaign(
    p: &Partial,
    dir: &Path,
) -> Result<(summary::Summary, Vec<PathBuf>), SimError> {
    shard::validate(p).map_err(|e| SimError::usage(format!("the campaign is not written: {e}")))?;
    let s = summary::summarize(p);
    let name = &p.name;
    let mut files: Vec<(String, Vec<u8>)> = vec![
        (format!("{name}.mc.runs.json"), json(p)?),
        (format!("{name}.mc.summary.json"), json(&s)?),
        (format!("{name}.mc.summary.md"), s.markdown().into_bytes()),
        (format!("{name}.mc.summary.csv"), s.csv().into_bytes()),
        (
            format!("{name}.mc.runs.csv"),
            summary::runs_csv(p).into_bytes(),
        ),
    ];
    files.extend(plot::plots(p)?);
    let written = files
        .into_iter()
        .map(|(f, b)| write(dir, f, &b))
        .collect::<Result<_, _>>()?;
    Ok((s, written))
}

/// Reads every `*.mc.shard-*.json` in `dirs`, checks each
/// ([`shard::validate`]: identity, sizes, finite values, a plain controller
/// name) and merges them ([`summary::merge`]: one campaign, every shard once).
pub fn merge_dirs(dirs: &[PathBuf]) -> Result<Partial, SimError> {
    let mut parts = Vec::new();
    for dir in dirs {
        let entries = std::fs::read_dir(dir)
            .map_err(|e| SimError::usage(format!("cannot read `{}`: {e}", dir.display())))?;
        let mut paths: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                p.file_name()
                    .and_then(|f| f.to_str())
                    .is_some_and(|f| f.contains(".mc.shard-") && f.ends_with(".json"))
            })
            .collect();
        paths.sort();
        for path in paths {
            parts.push(read_shard(&path)?);
        }
    }
    summary::merge(parts).map_err(SimError::usage)
}

/// One shard file, read (a regular file of at most [`MAX_SHARD_FILE_BYTES`])
/// and checked.
fn read_shard(path: &Path) -> Result<Partial, SimError> {
    use std::io::Read;
    // A file name may hold control characters: shown escaped.
    let shown = path.display().to_string().escape_debug().to_string();
    let cannot = |e: std::io::Error| SimError::usage(format!("cannot read `{shown}`: {e}"));
    // Checked before opening: opening a FIFO would wait for a writer.
    if !std::fs::metadata(path).map_err(cannot)?.is_file() {
        return Err(SimError::usage(format!("`{shown}` is not a regular file")));
    }
    let file = std::fs::File::open(path).map_err(cannot)?;
    let mut text = String::new();
    file.take(MAX_SHARD_FILE_BYTES + 1)
        .read_to_string(&mut text)
        .map_err(cannot)?;
    if text.len() as u64 > MAX_SHARD_FILE_BYTES {
        return Err(SimError::usage(format!(
            "`{shown}` is larger than the shard file limit of {} GiB (docs/limits.md)",
            MAX_SHARD_FILE_BYTES >> 30
        )));
    }
    /// The format tag alone, read first: a file of another format version
    /// is named as such, not as missing fields.
    #[derive(serde::Deserialize)]
    struct Tag {
        format: String,
        tsfc_version: Option<String>,
    }
    if let Ok(tag) = serde_json::from_str::<Tag>(&text) {
        if tag.format != SHARD_FORMAT {
            return Err(SimError::usage(format!(
                "`{shown}` has format `{}` ({}); this tsfc merges `{SHARD_FORMAT}`: run the shard again with this tsfc",
                tag.format.escape_debug(),
                match tag.tsfc_version {
                    Some(v) => format!("written by tsfc {}", v.escape_debug()),
                    None => "written by an earlier tsfc".into(),
                }
            )));
        }
    }
    let part: Partial = serde_json::from_str(&text)
        .map_err(|e| SimError::usage(format!("`{shown}` is not a shard file: {e}")))?;
    shard::validate(&part).map_err(|e| SimError::usage(format!("`{shown}` is refused: {e}")))?;
    Ok(part)
}
