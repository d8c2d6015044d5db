//! The `tsfc` command line.

use clap::{Parser, Subcommand, ValueEnum};
use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::process::ExitCode;
use tsf_lang::diag;
use tsf_lang::spec::Emit;
use tsfc::driver::{adaptive, frontend, pipeline};

/// Exit codes: 0 ok, 1 spec error, 2 usage or I/O error, 3 infeasible or refused.
mod exit {
    pub const SPEC: u8 = 1;
    pub const IO: u8 = 2;
}

#[derive(Parser)]
#[command(
    name = "tsfc",
    version,
    about = "Compiler for Takagi-Sugeno fuzzy controllers: .tsf spec -> certified PDC gains -> Rust/C"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Target {
    /// A `no_std` Rust module.
    Rust,
    /// A C99 header and source.
    C,
}

#[derive(Clone, Copy, ValueEnum)]
enum Format {
    /// rustc-style messages on stderr.
    Human,
    /// One JSON document on stdout (for editors).
    Json,
}

#[derive(Subcommand)]
enum Command {
    /// Parse and check specs: names, shapes, operating points, coverage.
    Check {
        /// Spec files.
        #[arg(required = true)]
        specs: Vec<PathBuf>,
        /// Output format of the diagnostics.
        #[arg(long, value_enum, default_value = "human")]
        format: Format,
        /// Also print the T-S model as built: premises and sets, the sector
        /// construction, each rule's premise and local model (stdout).
        #[arg(long)]
        explain: bool,
    },
    /// Rewrite specs in the canonical layout (docs/language.md, "Formatting").
    ///
    /// Exit codes: 0 formatted (or, with --check, already formatted); 1 a spec would
    /// change (--check) or does not parse (it is left untouched); 2 I/O error.
    Fmt {
        /// Spec files.
        #[arg(required = true)]
        specs: Vec<PathBuf>,
        /// Write nothing: print the files that would change and their first change.
        #[arg(long)]
        check: bool,
    },
    /// Synthesize certified PDC gains and write the report (exit 3 when infeasible or refused).
    Compile {
        /// Spec file.
        spec: PathBuf,
        /// Output folder.
        #[arg(long, default_value = "tsfc-out")]
        out: PathBuf,
        /// Report path (default: OUT/<controller>.report.json).
        #[arg(long)]
        report: Option<PathBuf>,
        /// Code targets (default: the spec's `emit` line).
        #[arg(long, value_enum, value_delimiter = ',')]
        emit: Option<Vec<Target>>,
    },
    /// Run the spec's `simulate` scenario with its certified design (CSV, metrics JSON, plots).
    ///
    /// The design comes from the report of `tsfc compile` (--report, else OUT/<controller>.report.json)
    /// when that report is certified, written by this tsfc and records the sha256 of this very spec;
    /// otherwise the spec is compiled again (stderr says why).
    ///
    /// Exit codes: 0 the run finished inside the premise region; 1 spec error (also a scenario
    /// over the step limit of docs/limits.md); 2 usage or I/O error (a non-positive or too long
    /// --horizon, a non-finite --x0); 3 design not certified; 4 the run went non-finite, diverged
    /// (V = x'Px ended above its initial value) or left the premise region (outputs are written).
    ///
    /// Monte Carlo: `--monte-carlo [N]` runs N truth plants drawn from the scenario's
    /// `monte_carlo { }` block (default N: its `runs`) on all cores and writes
    /// OUT/<controller>.mc.summary.{md,csv,json}, .mc.runs.{csv,json} and plots; `--shard k/K`
    /// runs the indices i with i mod K == k - 1 and writes OUT/<controller>.mc.shard-k-of-K.json;
    /// `--merge DIR...` merges shard files into the summary one whole run gives (no spec needed).
    /// Exit code 4 when some run failed.
    ///
    /// Sweep: `--sweep` runs the design and every scenario of the spec's `sweep { }` block (and
    /// of each `--compare` spec) in parallel and writes one table OUT/<controller>.sweep.{md,csv,json}
    /// and the per-scenario metrics OUT/<controller>.sweep.metrics.json. A scenario's law is
    /// compiled on its own; a row it does not certify is marked NOT CERTIFIED. Exit code 4 when
    /// some row's run failed.
    Simulate {
        /// Spec file.
        #[arg(required_unless_present = "merge")]
        spec: Option<PathBuf>,
        /// Output folder.
        #[arg(long, default_value = "tsfc-out")]
        out: PathBuf,
        /// Initial state, comma-separated finite numbers (default: the spec's x0).
        #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
        x0: Option<Vec<f64>>,
        /// Initial estimate of an observer-based controller, comma-separated finite numbers
        /// (default: the spec's xhat0, else 0).
        #[arg(long, value_delimiter = ',', allow_negative_numbers = true, conflicts_with_all = ["monte_carlo", "sweep", "merge"])]
        xhat0: Option<Vec<f64>>,
        /// Simulated time in seconds from t0, positive (default: the spec's span); at most 1e7
        /// steps of the scenario's time step.
        #[arg(long, allow_negative_numbers = true)]
        horizon: Option<f64>,
        /// Certified report of the design (default: OUT/<controller>.report.json, if present).
        #[arg(long)]
        report: Option<PathBuf>,
        /// Run a Monte Carlo campaign of N runs, 1 .. 1000000 (default: the `runs` of the
        /// `monte_carlo` block).
        #[arg(long, value_name = "N", num_args = 0..=1)]
        monte_carlo: Option<Option<u64>>,
        /// Run only shard k of K of the campaign (run indices i with i mod K == k - 1), K at most
        /// 100000; `auto` (or `auto/K`) reads k and K from the job array of Slurm, Kubernetes,
        /// AWS Batch or Google Cloud Batch (docs/monte_carlo.md).
        #[arg(long, value_name = "k/K|auto[/K]", requires = "monte_carlo", value_parser = tsfc::sim::campaign::parse_shard)]
        shard: Option<tsfc::sim::campaign::ShardArg>,
        /// Campaign seed (default: the scenario's `seed`).
        #[arg(long, requires = "monte_carlo")]
        seed: Option<u64>,
        /// Worker threads of --monte-carlo or --sweep, 1 .. 1024 (default: all cores).
        #[arg(long, value_parser = tsfc::sim::limits::parse_jobs)]
        jobs: Option<usize>,
        /// Run the sweep of triggering laws and write its comparison table.
        #[arg(long, conflicts_with_all = ["monte_carlo", "merge"])]
        sweep: bool,
        /// Specs whose designs and sweep scenarios join the table (same plant and scenario).
        #[arg(long, value_name = "SPEC", num_args = 1.., requires = "sweep")]
        compare: Vec<PathBuf>,
        /// Merge the shard files (*.mc.shard-k-of-K.json) found in these folders into OUT.
        #[arg(long, value_name = "DIR", num_args = 1.., conflicts_with_all = ["monte_carlo", "x0", "report"])]
        merge: Option<Vec<PathBuf>>,
    },
    /// Write a self-contained HTML design review page, OUT/<controller>.review.html: the claim,
    /// the certificate table, the gains and P, membership functions, the model-consistency map,
    /// the scenario's closed-loop plots and metrics, the generated files' hashes (docs/review.md).
    ///
    /// The design comes from the certified report of `tsfc compile` when it matches the spec (as
    /// for `tsfc simulate`), else the spec is compiled. Exit codes: 0 written; 1 spec error;
    /// 2 usage or I/O error; 3 design not certified.
    Review {
        /// Spec file.
        spec: PathBuf,
        /// Output folder.
        #[arg(long, default_value = "tsfc-out")]
        out: PathBuf,
        /// Certified report of the design (default: OUT/<controller>.report.json, if present).
        #[arg(long)]
        report: Option<PathBuf>,
    },
    /// Run the language server on stdin/stdout (for editors; docs/editor.md).
    Lsp,
    /// Print the JSON Schema of one kind of JSON tsfc writes, or write them all to --out.
    ///
    /// Kinds: report, failed-report, metrics, sweep, sweep-metrics, mc-summary, mc-runs,
    /// mc-shard, check, adaptive-report, adaptive-metrics (docs/schema/README.md).
    Schema {
        /// The kind (all kinds with --out).
        kind: Option<String>,
        /// Write every schema (or KIND's) into this folder as KIND.json, atomically.
        #[arg(long)]
        out: Option<PathBuf>,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Check {
            specs,
            format,
            explain,
        } => check(&specs, format, explain),
        Command::Fmt { specs, check } => {
            let color = std::io::stderr().is_terminal() && std::env::var_os("NO_COLOR").is_none();
            let req = tsfc::driver::format::Request {
                specs,
                check,
                color,
            };
            let code =
                tsfc::driver::format::run(&req, &mut std::io::stdout(), &mut std::io::stderr());
            ExitCode::from(code)
        }
        Command::Compile {
            spec,
            out,
            report,
            emit,
        } => compile(&spec, &out, report, emit),
        Command::Lsp => ExitCode::from(tsfc::lsp::run_stdio()),
        Command::Simulate {
            spec,
            out,
            x0,
            xhat0,
            horizon,
            report,
            monte_carlo,
            shard,
            seed,
            jobs,
            merge,
            sweep,
            compare,
        } => match (merge, spec) {
            _ if jobs.is_some() && monte_carlo.is_none() && !sweep => {
                eprintln!("error: --jobs needs --monte-carlo or --sweep");
                ExitCode::from(exit::IO)
            }
            (Some(dirs), _) => merge_shards(&dirs, &out),
            (None, Some(spec)) if sweep => {
                let cfg = tsfc::sim::sweep::Config { jobs };
                let runs = Runs {
                    x0,
                    horizon,
                    report: report.as_deref(),
                };
                run_sweep(&spec, &compare, &out, &runs, &cfg)
            }
            (None, Some(spec)) => match monte_carlo {
                Some(runs) => {
                    let shard = match shard.map(|a| {
                        tsfc::sim::campaign::scheduler::resolve(a, &|v| std::env::var(v).ok())
                    }) {
                        None => (1, 1),
                        Some(Ok(s)) => s,
                        Some(Err(e)) => {
                            eprintln!("error: {e}");
                            return ExitCode::from(exit::IO);
                        }
                    };
                    let cfg = tsfc::sim::campaign::Config {
                        runs,
                        shard,
                        seed,
                        jobs,
                        progress: true,
                    };
                    campaign(&spec, &out, x0, horizon, report.as_deref(), &cfg)
                }
                None => simulate(&spec, &out, (x0, xhat0), horizon, report.as_deref()),
            },
            // ok: clap requires the spec unless --merge is given.
            (None, None) => ExitCode::from(2),
        },
        Command::Review { spec, out, report } => {
            match tsfc::review::review(&spec, report.as_deref(), &out) {
                Ok(w) => {
                    eprint!("{}", w.summary());
                    ExitCode::SUCCESS
                }
                Err(e) => report_error(&e),
            }
        }
        Command::Schema { kind, out } => {
            match tsfc::driver::schema::run(kind.as_deref(), out.as_deref()) {
                Ok(text) if std::io::stdout().lock().write_all(text.as_bytes()).is_ok() => {
                    ExitCode::SUCCESS
                }
                Ok(_) => ExitCode::from(exit::IO),
                Err(e) => {
                    eprintln!("error: {}", e.message);
                    ExitCode::from(e.exit_code())
                }
            }
        }
    }
}

fn compile(
    path: &std::path::Path,
    out: &std::path::Path,
    report_path: Option<PathBuf>,
    emit: Option<Vec<Target>>,
) -> ExitCode {
    let color = std::io::stderr().is_terminal() && std::env::var_os("NO_COLOR").is_none();
    let fail = |e: tsfc::Error| {
        eprint!("{}", e.message);
        if !e.message.ends_with('\n') {
            eprintln!();
        }
        ExitCode::from(e.exit_code())
    };
    let front = match pipeline::read(path) {
        Ok(f) => f,
        Err(e) => return fail(tsfc::Error::usage(format!("error: {}", e.message))),
    };
    // The blend-versus-A(x) warning waits for the plant claim: a claim bounds
    // that error rigorously and replaces it (docs/language.md, "The plant claim").
    let mismatch = tsfc::model::is_mismatch_warning;
    eprint!("{}", front.render_only(color, |d| !mismatch(d)));
    let held = front.render_only(color, mismatch);
    if front.checked.model.is_none() {
        eprint!("{held}");
        return ExitCode::from(exit::SPEC);
    }
    let spec_emit = front
        .checked
        .model
        .as_ref()
        .map_or_else(Vec::new, |m| m.spec.emit.clone());
    let targets = emit_targets(emit.as_deref(), &spec_emit);
    if let Some(done) = adaptive::compile(&front, out, &targets) {
        eprint!("{held}");
        return print_adaptive(done);
    }
    let run = match front.compile(&tsfc::synth::Settings::default()) {
        Ok(r) => r,
        Err(e) => return fail(e),
    };
    // A compile that is not certified leaves the outputs of an earlier design
    // untouched: its report goes beside them under another name.
    let certified = run.certified().is_ok();
    let default_report = report_path.is_none();
    let report_path = report_path.unwrap_or_else(|| {
        let name = &run.model.spec.controller.node;
        out.join(if certified {
            format!("{name}.report.json")
        } else {
            format!("{name}.failed.report.json")
        })
    });
    let json = match serde_json::to_string_pretty(&run.compiled.report) {
        Ok(j) => j + "\n",
        Err(e) => {
            eprintln!("error: cannot serialize the report: {e}");
            return ExitCode::from(exit::IO);
        }
    };
    let mut files = vec![(report_path.clone(), json.into_bytes())];
    let withheld = run
        .certified()
        .ok()
        .and_then(|(d, _)| pipeline::withheld(&run.model, d));
    if certified && withheld.is_none() {
        match run.generate(&targets) {
            Ok(generated) => files.extend(
                generated
                    .into_iter()
                    .map(|f| (out.join(&f.name), f.text.into_bytes())),
            ),
            Err(e) => {
                return fail(tsfc::Error {
                    message: format!("error: {}", e.message),
                    ..e
                })
            }
        }
    }
    if let Err(e) = tsfc::util::output::write_set(&files) {
        eprintln!("error: cannot write the outputs: {e}");
        return ExitCode::from(exit::IO);
    }
    if run.compiled.report.plant.claim.is_none() {
        eprint!("{held}");
    }
    eprint!(
        "{}",
        tsfc::driver::summary::summary(&run.model, &run.compiled, &report_path)
    );
    if let (Some(_), Some(c)) = (&run.compiled.report.plant.claim, &run.model.consistency) {
        if !held.is_empty() {
            eprintln!(
                "  note                 {}; the plant claim bounds it on its region",
                c.sentence()
            );
        }
    }
    for (path, _) in files.iter().skip(1) {
        eprintln!("  wrote                {}", path.display());
    }
    if certified && default_report {
        remove_stale_failed_report(out, &run.model.spec.controller.node);
    }
    if let (true, Some(why)) = (certified, withheld) {
        eprintln!("error: {}: {why}", run.name);
        return ExitCode::from(exit::IO);
    }
    ExitCode::from(run.exit_code())
}

/// After a certified compile, the failed report of an earlier refused
/// attempt in the same folder describes a design that no longer ships: it is
/// removed (and said), so the folder never holds a report that contradicts it.
fn remove_stale_failed_report(out: &std::path::Path, controller: &str) {
    let stale = out.join(format!("{controller}.failed.report.json"));
    if stale.is_file() {
        match std::fs::remove_file(&stale) {
            Ok(()) => eprintln!("  removed              {} (stale)", stale.display()),
            Err(e) => eprintln!("warning: cannot remove the stale {}: {e}", stale.display()),
        }
    }
}

/// The `--emit` targets, else the spec's `emit`.
fn emit_targets(emit: Option<&[Target]>, spec: &[Emit]) -> Vec<Emit> {
    match emit {
        Some(t) => t
            .iter()
            .map(|t| match t {
                Target::Rust => Emit::Rust,
                Target::C => Emit::C,
            })
            .collect(),
        None => spec.to_vec(),
    }
}

fn simulate(
    path: &std::path::Path,
    out: &std::path::Path,
    (x0, xhat0): (Option<Vec<f64>>, Option<Vec<f64>>),
    horizon: Option<f64>,
    report: Option<&std::path::Path>,
) -> ExitCode {
    /// The run went non-finite, diverged or left the premise region.
    const RUN_FAILED: u8 = 4;
    // An adaptive spec has its own simulator (docs/adaptive.md); other specs are read once.
    let adaptive = std::fs::read_to_string(path).is_ok_and(|t| t.contains("adaptive"));
    if let Some(front) = adaptive.then(|| pipeline::read(path).ok()).flatten() {
        if front.checked.model.is_some() {
            let opts = tsfc::sim::adaptive::Options {
                horizon,
                x0: x0.clone(),
            };
            if let Some(done) = adaptive::simulate(&front, out, &opts) {
                return print_adaptive(done);
            }
        }
    }
    type Ran = (tsfc::sim::Outcome, Vec<PathBuf>, Option<String>);
    let run = || -> Result<Ran, tsfc::sim::SimError> {
        let prepared = prepare(path, report, out)?;
        let start = x0
            .clone()
            .or_else(|| prepared.model.spec.simulate.as_ref().map(|s| s.x0.clone()));
        let outside = prepared
            .region
            .as_ref()
            .zip(start.as_deref())
            .and_then(|(u, x)| tsfc::driver::summary::outside_region(u, x));
        let mut opts = tsfc::sim::Options {
            x0,
            horizon,
            progress: true,
            ..tsfc::sim::Options::default()
        };
        opts.observer.xhat0 = xhat0;
        let (outcome, files) = tsfc::sim::simulate_to(&prepared, &opts, out)?;
        Ok((outcome, files, outside))
    };
    match run() {
        Ok((outcome, files, outside)) => {
            let m = &outcome.metrics;
            eprintln!(
                "simulated `{}`: {} samples, {} transmissions, final ||x|| = {:.3e} ({}converged, tol {:.3e}), max |u| = [{}], {:.2} s",
                outcome.name,
                m.samples,
                m.transmissions,
                m.final_state_norm,
                if m.converged { "" } else { "not " },
                m.convergence_tolerance,
                m.max_abs_u
                    .iter()
                    .map(|u| format!("{u:.3e}"))
                    .collect::<Vec<_>>()
                    .join(", "),
                m.wall_time_s
            );
            if let Some(mm) = &m.modes {
                eprintln!(
                    "  modes ({}, seed {}): {} jumps; {}",
                    mm.design,
                    mm.seed,
                    mm.transitions,
                    mm.modes
                        .iter()
                        .map(|s| format!("{} {:.1}% of the time", s.name, 100.0 * s.fraction))
                        .collect::<Vec<_>>()
                        .join(", ")
                );
            }
            for f in files {
                eprintln!("  wrote                {}", f.display());
            }
            for w in outside.into_iter().chain(m.warnings()) {
                eprintln!("warning: {w}");
            }
            let failures = m.failures();
            for f in &failures {
                eprintln!("error: {f}");
            }
            if failures.is_empty() {
                ExitCode::SUCCESS
            } else {
                ExitCode::from(RUN_FAILED)
            }
        }
        Err(e) => report_error(&e),
    }
}

/// Prints a pipeline error (rendered diagnostics carry their own `error:` lines).
fn report_error(e: &tsfc::sim::SimError) -> ExitCode {
    let rendered = e.message.starts_with("error") || e.message.starts_with("warning");
    eprint!("{}{}", if rendered { "" } else { "error: " }, e.message);
    if !e.message.ends_with('\n') {
        eprintln!();
    }
    ExitCode::from(e.exit_code())
}

/// Loads the certified design of `path` (reusing a matching report).
fn prepare(
    path: &std::path::Path,
    report: Option<&std::path::Path>,
    out: &std::path::Path,
) -> Result<tsfc::sim::Prepared, tsfc::sim::SimError> {
    let (prepared, reuse) = tsfc::driver::prepare_reusing(path, report, out)?;
    match reuse {
        tsfc::driver::Reuse::Reused(r) => eprintln!(
            "using the certified design of `{}` (same spec sha256; nothing solved)",
            r.display()
        ),
        tsfc::driver::Reuse::Refused(why) => eprintln!("note: {why}; compiled the design"),
        tsfc::driver::Reuse::NoReport => {}
    }
    Ok(prepared)
}

/// Prints a campaign summary and the files written; exit 4 when a run failed.
fn campaign_done(s: &tsfc::sim::campaign::summary::Summary, files: &[PathBuf]) -> ExitCode {
    eprintln!(
        "monte carlo `{}`: {} runs, {} converged ({:.2} %), {} failed",
        s.name,
        s.runs,
        s.converged,
        100.0 * s.fraction_converged,
        s.failed
    );
    for f in files {
        eprintln!("  wrote                {}", f.display());
    }
    if s.failed == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(4)
    }
}

fn campaign(
    path: &std::path::Path,
    out: &std::path::Path,
    x0: Option<Vec<f64>>,
    horizon: Option<f64>,
    report: Option<&std::path::Path>,
    cfg: &tsfc::sim::campaign::Config,
) -> ExitCode {
    use tsfc::sim::campaign;
    let run = || -> Result<ExitCode, tsfc::sim::SimError> {
        let prepared = prepare(path, report, out)?;
        let opts = tsfc::sim::Options {
            x0,
            horizon,
            ..tsfc::sim::Options::default()
        };
        let started = std::time::Instant::now();
        let part = campaign::run_campaign(&prepared, &opts, cfg)?;
        let wall = started.elapsed().as_secs_f64();
        eprintln!(
            "ran {} runs (shard {}/{}) in {wall:.2} s ({:.3} s per run on {} threads)",
            part.runs.len(),
            part.shard.0,
            part.shard.1,
            wall / part.runs.len().max(1) as f64,
            cfg.jobs
                .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
        );
        if part.shard.1 > 1 {
            let f = campaign::write_shard(&part, out)?;
            eprintln!("  wrote                {}", f.display());
            return Ok(ExitCode::SUCCESS);
        }
        let (s, files) = campaign::write_campaign(&part, out)?;
        Ok(campaign_done(&s, &files))
    };
    run().unwrap_or_else(|e| report_error(&e))
}

/// The scenario overrides of the command line.
struct Runs<'a> {
    x0: Option<Vec<f64>>,
    horizon: Option<f64>,
    report: Option<&'a std::path::Path>,
}

fn run_sweep(
    path: &std::path::Path,
    compare: &[PathBuf],
    out: &std::path::Path,
    runs: &Runs,
    cfg: &tsfc::sim::sweep::Config,
) -> ExitCode {
    use tsfc::sim::sweep;
    let run = || -> Result<ExitCode, tsfc::sim::SimError> {
        let main = prepare(path, runs.report, out)?;
        let others = compare
            .iter()
            .map(|p| prepare(p, None, out))
            .collect::<Result<Vec<_>, _>>()?;
        let opts = tsfc::sim::Options {
            x0: runs.x0.clone(),
            horizon: runs.horizon,
            ..tsfc::sim::Options::default()
        };
        let started = std::time::Instant::now();
        let (table, metrics) = sweep::run_sweep(
            &main,
            &others,
            &opts,
            cfg,
            &tsfc::driver::prepare::prepare_text,
        )?;
        let files = sweep::write_sweep(&table, &metrics, out)?;
        let refused = table.rows.iter().filter(|r| !r.certified).count();
        let failed = table.rows.iter().filter(|r| r.failed).count();
        eprintln!(
            "sweep `{}`: {} rows in {:.2} s, {refused} not certified, {failed} failed",
            table.name,
            table.rows.len(),
            started.elapsed().as_secs_f64()
        );
        for f in files {
            eprintln!("  wrote                {}", f.display());
        }
        for r in table.rows.iter().filter(|r| r.failed) {
            eprintln!(
                "error: `{}` {}: {}",
                r.spec,
                r.scenario,
                r.why.as_deref().unwrap_or("failed")
            );
        }
        Ok(if table.any_failed() {
            ExitCode::from(4)
        } else {
            ExitCode::SUCCESS
        })
    };
    run().unwrap_or_else(|e| report_error(&e))
}

fn merge_shards(dirs: &[PathBuf], out: &std::path::Path) -> ExitCode {
    let run = || -> Result<ExitCode, tsfc::sim::SimError> {
        let part = tsfc::sim::campaign::merge_dirs(dirs)?;
        let (s, files) = tsfc::sim::campaign::write_campaign(&part, out)?;
        Ok(campaign_done(&s, &files))
    };
    run().unwrap_or_else(|e| report_error(&e))
}

fn check(specs: &[PathBuf], format: Format, explain: bool) -> ExitCode {
    let mut worst = 0u8;
    let mut json_files = Vec::new();
    let color = std::io::stderr().is_terminal() && std::env::var_os("NO_COLOR").is_none();
    for path in specs {
        let source = match frontend::read_source(path) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("error: {}", e.message);
                worst = worst.max(exit::IO);
                continue;
            }
        };
        let checked = frontend::check(&source);
        if checked.has_errors() {
            worst = worst.max(exit::SPEC);
        }
        match format {
            Format::Human => {
                eprint!(
                    "{}",
                    diag::render(&source.name, &source.text, &checked.diagnostics, color)
                );
                if let Some(m) = &checked.model {
                    eprintln!(
                        "ok: {} — controller `{}`: n = {}, m = {}, {} rules, {} premise components; coverage checked at {} points{}",
                        source.name,
                        m.spec.controller.node,
                        m.n,
                        m.m,
                        m.r(),
                        m.premises.len(),
                        m.coverage.points,
                        if m.coverage.exhaustive { "" } else { " (sampled)" }
                    );
                    if explain {
                        print!("{}", tsfc::model::explain::explain(m));
                    }
                }
            }
            Format::Json => json_files.push((source, checked)),
        }
    }
    if matches!(format, Format::Json) {
        let doc = tsfc::driver::check_json::CheckReport::of(&json_files);
        let mut out = std::io::stdout().lock();
        if writeln!(out, "{}", doc.to_json().unwrap_or_default()).is_err() {
            return ExitCode::from(exit::IO);
        }
    }
    ExitCode::from(worst)
}

/// Prints what an adaptive compile or simulation did (or its error) and
/// returns its exit code.
fn print_adaptive(done: Result<adaptive::Done, tsfc::Error>) -> ExitCode {
    match done {
        Ok(d) => {
            for line in &d.lines {
                eprintln!("{line}");
            }
            ExitCode::from(d.exit_code)
        }
        Err(e) => {
            eprintln!("error: {}", e.message);
            ExitCode::from(e.exit_code())
        }
    }
}
