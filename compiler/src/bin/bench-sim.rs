//! Simulation benchmark: 1000 s of the 7-rule spacecraft (Xu & Huang 2020
//! spec) at a 1 ms RK4 step with its adaptive event trigger, in closed loop
//! with the runtime controller, the CSV trace formatted and discarded (as
//! `tsfc simulate` streams it). Prints the wall time, the real-time factor
//! (simulated seconds per wall second) and the run's figures; `--report PATH`
//! takes the design from a certified report of `tsfc compile` instead of
//! compiling it, `--interpreter` runs the language's evaluator instead of the
//! compiled tape (the reference path).
//!
//! `cargo run --release -p tsfc --bin bench-sim [-- [--report PATH] [--interpreter] [SPEC [HORIZON_S]]]`

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

/// Prints `e` with an `error:` prefix unless it is a rendered diagnostic.
fn fail(e: &tsfc::sim::SimError) -> ExitCode {
    let rendered = e.message.starts_with("error") || e.message.starts_with("warning");
    eprintln!(
        "{}{}",
        if rendered { "" } else { "error: " },
        e.message.trim_end()
    );
    ExitCode::from(e.exit_code())
}

/// Time this thread has run on a CPU, in seconds (Linux `schedstat`).
fn cpu_time_s() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = text.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}

const USAGE: &str = "usage: bench-sim [--report PATH] [--interpreter] [SPEC [HORIZON_S]]";

fn main() -> ExitCode {
    let mut report = None;
    let mut evaluator = tsfc::sim::Evaluator::Compiled;
    let mut positional = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--report" => match args.next() {
                Some(p) => report = Some(PathBuf::from(p)),
                None => {
                    eprintln!("{USAGE}");
                    return ExitCode::from(2);
                }
            },
            "--interpreter" => evaluator = tsfc::sim::Evaluator::Interpreter,
            _ => positional.push(a),
        }
    }
    let mut positional = positional.into_iter();
    let spec = positional.next().map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../specs/xu2020_event_triggered.tsf"),
        PathBuf::from,
    );
    let horizon = match positional.next().map(|h| h.parse::<f64>()) {
        None => 1000.0,
        Some(Ok(h)) if h > 0.0 => h,
        Some(_) => {
            eprintln!("{USAGE}");
            return ExitCode::from(2);
        }
    };
    let t = Instant::now();
    let prepared = match &report {
        None => tsfc::driver::prepare(&spec),
        Some(r) => {
            tsfc::driver::prepare_reusing(&spec, Some(r), Path::new(".")).map(|(p, reuse)| {
                if let tsfc::driver::Reuse::Refused(why) = reuse {
                    eprintln!("note: {why}; compiled the design");
                }
                p
            })
        }
    };
    let prepared = match prepared {
        Ok(p) => p,
        Err(e) => return fail(&e),
    };
    let compile_s = t.elapsed().as_secs_f64();
    let opts = tsfc::sim::Options {
        horizon: Some(horizon),
        evaluator,
        ..tsfc::sim::Options::default()
    };
    let (t, cpu) = (Instant::now(), cpu_time_s());
    let outcome = match tsfc::sim::simulate_csv(&prepared, &opts, &mut std::io::sink()) {
        Ok(o) => o,
        Err(e) => return fail(&e),
    };
    let sim_s = t.elapsed().as_secs_f64();
    let sim_cpu = cpu.zip(cpu_time_s()).map(|(a, b)| b - a);
    let m = &outcome.metrics;
    println!("spec                {}", spec.display());
    println!("prepare             {compile_s:.3} s");
    println!(
        "simulate            {sim_s:.3} s for {horizon} s simulated ({}, {evaluator:?})",
        m.integrator
    );
    println!(
        "real-time factor    {:.0}x (simulated s per wall s)",
        horizon / sim_s
    );
    if let Some(cpu) = sim_cpu {
        // On a shared machine the wall time includes waiting for a core.
        println!(
            "on-CPU time         {cpu:.3} s ({:.0}x simulated s per CPU s)",
            horizon / cpu
        );
    }
    println!(
        "rhs evaluations     {} ({:.2} us each, all-in)",
        m.rhs_evaluations,
        1e6 * sim_s / m.rhs_evaluations.max(1) as f64
    );
    let checked = &prepared.model.spec;
    let describe = |tape: Option<&tsfc::sim::tape::Tape>| {
        tape.map_or_else(
            || "interpreted".to_string(),
            |t| format!("{} instructions in {} batches", t.len(), t.batches()),
        )
    };
    if let Ok(plant) = tsfc::sim::plant::Plant::new(checked, &prepared.source, evaluator) {
        println!("plant tape          {}", describe(plant.tape()));
    }
    let signals = tsfc::sim::signal::Signals::new(checked, &prepared.source, evaluator);
    println!("signals tape        {}", describe(signals.tape()));
    println!("samples             {}", m.samples);
    println!("transmissions       {}", m.transmissions);
    println!(
        "inter-event (mean)  {:?} s, min {:?} s",
        m.mean_inter_event_s, m.min_inter_event_s
    );
    println!(
        "final ||x||         {:.3e} (converged: {})",
        m.final_state_norm, m.converged
    );
    println!("max |u|             {:?}", m.max_abs_u);
    ExitCode::SUCCESS
}
