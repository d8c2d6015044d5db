//! `bench-compile`: times the library pipeline (read, check, compile) on every
//! shipped spec and on generated Zhang-like scaling specs, and prints the
//! median time of each stage.
//!
//! ```sh
//! cargo run --release -p tsfc --bin bench-compile -- --repeat 7 --json bench/results.json
//! ```
//!
//! This is a measuring tool, not a test: nothing here asserts a timing goal.
//! The hidden `--dump-model SPEC` prints the local models and objective data of
//! a spec as JSON for `bench/compare_cvxpy.py`.

use clap::Parser;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;
use tsf_lang::spec::{InitialSet, Objective, Relaxation, Target};
use tsfc::driver::adaptive;
use tsfc::driver::compile::Status;
use tsfc::model::TsModel;
use tsfc::pipeline::read;
use tsfc::report::{rows, Report, Timings};

/// Seconds per pipeline stage (the report's `timings_s`).
#[derive(Serialize, Debug, Clone, Copy, Default)]
struct Stages {
    parse: f64,
    model: f64,
    build: f64,
    solve: f64,
    certify: f64,
    total: f64,
}

impl From<&Timings> for Stages {
    fn from(t: &Timings) -> Self {
        Stages {
            parse: t.parse,
            model: t.model,
            build: t.build,
            solve: t.solve,
            certify: t.certify,
            total: t.total,
        }
    }
}
use tsfc::synth::Settings;

/// Command-line options.
#[derive(Parser, Debug)]
#[command(
    name = "bench-compile",
    about = "Median per-stage compile times of the shipped specs and of generated scaling specs"
)]
struct Cli {
    /// Timed runs per spec (one untimed warm-up run comes first).
    #[arg(long, default_value_t = 5)]
    repeat: usize,
    /// Also write the results as JSON to this path.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Directory of the shipped specs (every `*.tsf` in it is benchmarked).
    #[arg(long, default_value = concat!(env!("CARGO_MANIFEST_DIR"), "/../specs"))]
    specs: PathBuf,
    /// Grid sizes k of the generated scaling specs (k x k rules), comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "2,3,4,6,8")]
    scaling: Vec<usize>,
    /// Skip the shipped specs (scaling run only).
    #[arg(long)]
    no_shipped: bool,
    /// Skip the generated scaling specs.
    #[arg(long)]
    no_scaling: bool,
    /// Benchmark these specs instead of every spec of `--specs`.
    #[arg(value_name = "SPEC")]
    only: Vec<PathBuf>,
    /// Write the generated scaling specs to this directory instead of a temporary one (kept).
    #[arg(long)]
    write_specs: Option<PathBuf>,
    /// Solve without Clarabel's chordal decomposition (experiment).
    #[arg(long, hide = true)]
    no_chordal: bool,
    /// Factor the KKT systems with QDLDL instead of faer (experiment).
    #[arg(long, hide = true)]
    qdldl: bool,
    /// Print the model data of SPEC as JSON (for bench/compare_cvxpy.py) and exit.
    #[arg(long, hide = true, value_name = "SPEC")]
    dump_model: Option<PathBuf>,
}

/// Median results of one spec.
#[derive(Serialize, Debug)]
struct Row {
    /// Spec label (file name or generated name).
    spec: String,
    /// Number of rules.
    rules: usize,
    /// Compile status of the last run.
    status: String,
    /// Achieved H-inf gamma, if any.
    hinf_gamma: Option<f64>,
    /// All achieved objectives, as in the report.
    objectives: serde_json::Value,
    /// SDPs solved per compile.
    sdps: usize,
    /// Interior-point iterations of the kept SDP.
    iterations: u32,
    /// Size of the kept SDP, as in the report.
    problem: serde_json::Value,
    /// Median of each stage over the timed runs, seconds.
    median_s: Stages,
    /// Median of (total - solve) / total over the runs, percent.
    overhead_pct: f64,
    /// Number of timed runs.
    runs: usize,
}

/// Where and on what a run was measured: printed above the tables and kept
/// in the JSON, so a table in bench/RESULTS.md carries its commit and load.
#[derive(Serialize, Debug)]
struct Provenance {
    /// `git rev-parse --short HEAD` of the working directory (`unknown`
    /// outside a git checkout).
    commit: String,
    /// Whether tracked files differ from that commit.
    dirty: bool,
    /// The 1, 5 and 15 minute load averages at the start (`/proc/loadavg`;
    /// empty where the system has none).
    load_start: Vec<f64>,
    /// The same at the end.
    load_end: Vec<f64>,
    /// Logical CPUs visible to the process.
    cpus: usize,
}

impl Provenance {
    /// The commit and load now; `load_end` is filled by [`Provenance::finish`].
    fn now() -> Self {
        let git = |args: &[&str]| {
            std::process::Command::new("git")
                .args(args)
                .output()
                .ok()
                .filter(|o| o.status.success())
                .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        };
        Provenance {
            commit: git(&["rev-parse", "--short", "HEAD"]).unwrap_or_else(|| "unknown".into()),
            dirty: git(&["status", "--porcelain", "--untracked-files=no"])
                .is_some_and(|s| !s.is_empty()),
            load_start: load_average(),
            load_end: Vec::new(),
            cpus: std::thread::available_parallelism().map_or(1, |n| n.get()),
        }
    }

    /// Records the load at the end of the run.
    fn finish(&mut self) {
        self.load_end = load_average();
    }

    /// One line for the top of the printed tables.
    fn line(&self) -> String {
        let load = |l: &[f64]| {
            l.iter()
                .map(|v| format!("{v:.2}"))
                .collect::<Vec<_>>()
                .join(" ")
        };
        format!(
            "commit {}{}, {} CPUs, load average (1/5/15 min) {} at the start, {} at the end",
            self.commit,
            if self.dirty {
                " (with uncommitted changes)"
            } else {
                ""
            },
            self.cpus,
            load(&self.load_start),
            load(&self.load_end),
        )
    }
}

/// The load averages of `/proc/loadavg` (empty where it cannot be read).
fn load_average() -> Vec<f64> {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| {
            s.split_whitespace()
                .take(3)
                .filter_map(|v| v.parse().ok())
                .collect()
        })
        .unwrap_or_default()
}

/// Everything the bench measured.
#[derive(Serialize, Debug)]
struct Results {
    /// Timed runs per spec.
    repeat: usize,
    /// Commit, load and CPUs of the run.
    measured: Provenance,
    /// Shipped specs.
    shipped: Vec<Row>,
    /// Generated scaling specs, by rule count.
    scaling: Vec<Row>,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(&cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

fn run(cli: &Cli) -> Result<(), String> {
    if let Some(spec) = &cli.dump_model {
        let front = read(spec).map_err(|e| e.message)?;
        let Some(model) = front.checked.model else {
            return Err(format!(
                "`{}` has spec errors; run `tsfc check` on it",
                spec.display()
            ));
        };
        let json = serde_json::to_string_pretty(&dump_model(&model)?)
            .map_err(|e| format!("cannot serialize the model: {e}"))?;
        println!("{json}");
        return Ok(());
    }
    let repeat = cli.repeat.max(1);
    let mut measured = Provenance::now();
    let mut settings = Settings::default();
    settings.solver.chordal_decomposition = !cli.no_chordal;
    if cli.qdldl {
        settings.solver.linear_solver = tsf_lmi::LinearSolver::Qdldl;
    }
    let mut shipped = Vec::new();
    if !cli.no_shipped {
        let paths = if cli.only.is_empty() {
            shipped_specs(&cli.specs)?
        } else {
            cli.only.clone()
        };
        for path in paths {
            shipped.push(bench_spec(&path, repeat, &settings)?);
        }
        print_table("shipped specs", &shipped);
    }
    let (dir, keep) = match &cli.write_specs {
        Some(d) => (d.clone(), true),
        None => (
            std::env::temp_dir().join(format!("tsfc-bench-{}", std::process::id())),
            false,
        ),
    };
    let ks: &[usize] = if cli.no_scaling { &[] } else { &cli.scaling };
    let scaling = scaling_run(ks, &dir, repeat, &settings);
    if !keep {
        // Best effort: a leftover temporary directory is harmless.
        let _ = std::fs::remove_dir_all(&dir);
    }
    let scaling = scaling?;
    if !scaling.is_empty() {
        print_table("scaling (Zhang-like, k x k rules)", &scaling);
    }
    measured.finish();
    println!("\nMeasured at {}.", measured.line());
    if let Some(path) = &cli.json {
        let results = Results {
            repeat,
            measured,
            shipped,
            scaling,
        };
        let json = serde_json::to_string_pretty(&results)
            .map_err(|e| format!("cannot serialize the results: {e}"))?;
        std::fs::write(path, json + "\n")
            .map_err(|e| format!("cannot write `{}`: {e}", path.display()))?;
        println!("results written to {}", path.display());
    }
    Ok(())
}

/// Every `*.tsf` file of `dir`, sorted.
fn shipped_specs(dir: &Path) -> Result<Vec<PathBuf>, String> {
    let entries =
        std::fs::read_dir(dir).map_err(|e| format!("cannot list `{}`: {e}", dir.display()))?;
    let mut specs: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "tsf"))
        .collect();
    specs.sort();
    Ok(specs)
}

/// Writes the scaling specs into `dir` and benchmarks them.
fn scaling_run(
    ks: &[usize],
    dir: &Path,
    repeat: usize,
    settings: &Settings,
) -> Result<Vec<Row>, String> {
    if ks.is_empty() {
        return Ok(Vec::new());
    }
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create `{}`: {e}", dir.display()))?;
    ks.iter()
        .map(|&k| {
            if k < 2 {
                return Err(format!("scaling grid size {k} < 2"));
            }
            let path = dir.join(format!("zhang_grid{k}x{k}.tsf"));
            std::fs::write(&path, zhang_like(k))
                .map_err(|e| format!("cannot write `{}`: {e}", path.display()))?;
            bench_spec(&path, repeat, settings)
        })
        .collect()
}

/// One full pipeline run: read, check, compile.
fn pipeline(path: &Path, settings: &Settings) -> Result<(Report, Status), String> {
    let run = read(path)
        .and_then(|f| f.compile(settings))
        .map_err(|e| e.message)?;
    Ok((run.compiled.report, run.compiled.status))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// One run of an adaptive spec's own route (read, check, the adaptive
/// design, as `tsfc compile` does): its stage times (parse, model; the rest
/// of the run counted as `build`, no SDP) and whether the design is well
/// posed; `None` when the spec is not adaptive.
fn adaptive_run(path: &Path) -> Result<Option<(Stages, bool, usize)>, String> {
    let t0 = Instant::now();
    let front = read(path).map_err(|e| e.message)?;
    let (parse, model) = (
        front.checked.parse_time.as_secs_f64(),
        front.checked.model_time.as_secs_f64(),
    );
    let rules = front.checked.model.as_ref().map_or(0, |m| m.rules.len());
    let Some(outcome) = adaptive::outcome(&front) else {
        return Ok(None);
    };
    let total = t0.elapsed().as_secs_f64();
    let stages = Stages {
        parse,
        model,
        build: (total - parse - model).max(0.0),
        total,
        ..Stages::default()
    };
    Ok(Some((stages, outcome.design.is_some(), rules)))
}

/// The row of an adaptive spec (`None` when the spec is not adaptive).
fn adaptive_row(path: &Path, label: &str, repeat: usize) -> Result<Option<Row>, String> {
    if adaptive_run(path)?.is_none() {
        return Ok(None);
    }
    let mut runs = Vec::with_capacity(repeat);
    let mut last = (false, 0);
    for _ in 0..repeat {
        if let Some((t, posed, rules)) = adaptive_run(path)? {
            runs.push(t);
            last = (posed, rules);
        }
    }
    let median_s = medians(&runs);
    Ok(Some(Row {
        spec: label.to_string(),
        rules: last.1,
        status: if last.0 {
            "AdaptiveWellPosed"
        } else {
            "AdaptiveRefused"
        }
        .into(),
        hinf_gamma: None,
        objectives: serde_json::Value::Null,
        sdps: 0,
        iterations: 0,
        problem: serde_json::Value::Null,
        median_s,
        overhead_pct: 100.0,
        runs: repeat,
    }))
}

/// The median of each stage over `runs`.
fn medians(runs: &[Stages]) -> Stages {
    let stage = |f: fn(&Stages) -> f64| median(runs.iter().map(f).collect());
    Stages {
        parse: stage(|t| t.parse),
        model: stage(|t| t.model),
        build: stage(|t| t.build),
        solve: stage(|t| t.solve),
        certify: stage(|t| t.certify),
        total: stage(|t| t.total),
    }
}

/// Runs the pipeline `repeat` times (after one warm-up) and takes medians;
/// an adaptive spec runs its own design route (no LMIs).
fn bench_spec(path: &Path, repeat: usize, settings: &Settings) -> Result<Row, String> {
    let label = path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    eprintln!("bench: {label} ({repeat} runs)");
    if let Some(row) = adaptive_row(path, &label, repeat)? {
        return Ok(row);
    }
    let mut runs = Vec::with_capacity(repeat);
    let (mut last, mut status) = pipeline(path, settings)?;
    for _ in 0..repeat {
        (last, status) = pipeline(path, settings)?;
        runs.push(Stages::from(&last.timings_s));
    }
    let median_s = medians(&runs);
    let overhead_pct = median(
        runs.iter()
            .map(|t| 100.0 * (t.total - t.solve) / t.total)
            .collect(),
    );
    let objectives = serde_json::to_value(&last.objectives).unwrap_or_default();
    Ok(Row {
        spec: label,
        rules: last.rules,
        status: format!("{status:?}"),
        hinf_gamma: objectives.get("hinf_gamma").and_then(|g| g.as_f64()),
        objectives,
        sdps: last.solver.solves,
        iterations: last.solver.iterations,
        problem: serde_json::to_value(&last.solver.problem).unwrap_or_default(),
        median_s,
        overhead_pct,
        runs: repeat,
    })
}

fn print_table(title: &str, rows: &[Row]) {
    println!(
        "\n## {title} (median of {} runs, seconds)\n",
        rows.first().map_or(0, |r| r.runs)
    );
    println!(
        "| spec | rules | parse | model | build | solve | certify | total | overhead | gamma | status | SDPs | unknowns | rows | PSD cones (largest) |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|");
    for r in rows {
        let t = &r.median_s;
        let p = |k: &str| r.problem.get(k).and_then(|v| v.as_u64()).unwrap_or(0);
        let gamma = r
            .hinf_gamma
            .map_or_else(|| "-".to_string(), |g| format!("{g:.6}"));
        println!(
            "| {} | {} | {:.4} | {:.4} | {:.4} | {:.4} | {:.4} | {:.4} | {:.1}% | {} | {} | {} | {} | {} | {} ({}) |",
            r.spec,
            r.rules,
            t.parse,
            t.model,
            t.build,
            t.solve,
            t.certify,
            t.total,
            r.overhead_pct,
            gamma,
            r.status,
            r.sdps,
            p("scalar_unknowns"),
            p("rows"),
            p("psd_cones"),
            p("largest_psd_cone"),
        );
    }
}

/// A number as spec text (12 decimals, no `-0`).
fn num(v: f64) -> String {
    let s = format!("{v:.12}");
    let s = s.trim_end_matches('0').trim_end_matches('.').to_string();
    if s == "-0" {
        "0".into()
    } else {
        s
    }
}

/// `k` evenly spaced points from `-half` to `half`.
fn grid(k: usize, half: f64) -> Vec<String> {
    (0..k)
        .map(|t| num(-half + 2.0 * half * t as f64 / (k - 1) as f64))
        .collect()
}

/// Premise `name = mean(of)` with `k` triangular sets peaking at `pts`
/// (outer sets are shoulders out to +-10, as in the Zhang spec).
fn premise(name: &str, of: &str, pts: &[String]) -> String {
    let k = pts.len();
    let mut s = format!(
        "premise {name} = mean({of}) range {} .. {} {{\n",
        pts[0],
        pts[k - 1]
    );
    for t in 0..k {
        let shape = if t == 0 {
            format!("trap(-10, -10, {}, {})", pts[0], pts[1])
        } else if t == k - 1 {
            format!("trap({}, {}, 10, 10)", pts[k - 2], pts[k - 1])
        } else {
            format!("tri({}, {}, {})", pts[t - 1], pts[t], pts[t + 1])
        };
        s += &format!("    s{t} = {shape};\n");
    }
    s + "}\n"
}

/// The Zhang & Zeng spacecraft model (n = 6, m = 3) with a `k x k` rule grid
/// on mean(w) in [-0.1, 0.1] and mean(rho) in [-0.15, 0.15], operating points
/// on the diagonals, and the objectives of specs/zhang2013_multiobjective.tsf.
fn zhang_like(k: usize) -> String {
    let (w, r) = (grid(k, 0.1), grid(k, 0.15));
    let mut s = format!(
        "tsf 1;\ncontroller zhang_grid{k}x{k};\n\
const J = [127, 1.8, -3.4; 1.8, 117, -2.3; -3.4, -2.3, 210];\n\
state w[3], rho[3];\ninput u[3];\ndisturbance d[3];\noutput z = x;\n\
fn Phi(v) = [0, v[2], -v[1]; -v[2], 0, v[0]; v[1], -v[0], 0];\n\
A(x) = [ -inv(J) * Phi(w) * J, zeros(3, 3); 0.5 * (eye(3) + rho * rho'), 0.5 * Phi(w) ];\n\
B = [inv(J); zeros(3, 3)];\nD = B;\n"
    );
    s += &premise("wm", "w", &w);
    s += &premise("rm", "rho", &r);
    for (a, cw) in w.iter().enumerate() {
        for (b, cr) in r.iter().enumerate() {
            s += &format!(
                "rule R{}: wm is s{a} and rm is s{b} => at(w = [{cw}, {cw}, {cw}], rho = [{cr}, {cr}, {cr}]);\n",
                a * k + b + 1
            );
        }
    }
    s + "objective hinf(d -> z) minimize;\nobjective decay_rate >= 0.01;\n\
objective input_norm(u) <= 5 for x0 = [0.08, -0.05, 0.1, 0.12, 0.06, -0.08];\n\
relaxation tanaka(s = 4);\n"
}

/// Model data of the LMIs for the CVXPY comparison: local models, the H-inf
/// channel, the input-norm x0 and bound, decay rate, relaxation and margin.
#[derive(Serialize)]
struct ModelDump {
    n: usize,
    m: usize,
    rules: Vec<RuleDump>,
    /// H-inf channel: disturbance columns and output matrices C, E, G.
    hinf: Option<ChannelDump>,
    decay_rate: Option<f64>,
    input_norm: Option<f64>,
    x0: Option<Vec<f64>>,
    relaxation: String,
    tanaka_s: Option<usize>,
    overlap: Vec<Vec<bool>>,
    eps: f64,
}

#[derive(Serialize)]
struct RuleDump {
    name: String,
    a: Vec<Vec<f64>>,
    b: Vec<Vec<f64>>,
    /// Disturbance columns of the H-inf channel.
    d: Vec<Vec<f64>>,
}

#[derive(Serialize)]
struct ChannelDump {
    minimize: bool,
    c: Vec<Vec<f64>>,
    e: Vec<Vec<f64>>,
    g: Vec<Vec<f64>>,
}

fn dump_model(model: &TsModel) -> Result<ModelDump, String> {
    let spec = &model.spec;
    let mut dump = ModelDump {
        n: model.n,
        m: model.m,
        rules: Vec::new(),
        hinf: None,
        decay_rate: None,
        input_norm: None,
        x0: None,
        relaxation: spec.relaxation.node.to_string(),
        tanaka_s: match spec.relaxation.node {
            Relaxation::Tanaka { s } => Some(s),
            _ => None,
        },
        overlap: model.coverage.overlap.clone(),
        eps: Settings::default().eps,
    };
    let mut dist = None;
    for o in &spec.objectives {
        match &o.node {
            Objective::Hinf { from, to, target } => {
                let out = &spec.outputs[*to];
                let sig = &spec.disturbances[*from];
                dist = Some((sig.offset, sig.len));
                dump.hinf = Some(ChannelDump {
                    minimize: *target == Target::Optimize,
                    c: rows(&out.c),
                    e: rows(&out.e),
                    g: rows(&out.g.columns(sig.offset, sig.len).into_owned()),
                });
            }
            Objective::DecayRate(Target::Fixed(a)) => dump.decay_rate = Some(*a),
            Objective::InputNorm {
                target: Target::Fixed(mu),
                initial: InitialSet::Point(x0),
            } => {
                dump.input_norm = Some(*mu);
                dump.x0 = Some(x0.clone());
            }
            Objective::Stability => {}
            other => return Err(format!("--dump-model does not support {other:?}")),
        }
    }
    dump.rules = model
        .rules
        .iter()
        .map(|r| RuleDump {
            name: r.name.clone(),
            a: rows(&r.a),
            b: rows(&r.b),
            d: dist.map_or_else(Vec::new, |(off, len)| {
                rows(&r.d.columns(off, len).into_owned())
            }),
        })
        .collect();
    Ok(dump)
}
