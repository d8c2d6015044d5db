//! "Simulate": the spec's closed-loop scenario on the certified design, its
//! metrics and its plots as SVG, through the simulator `tsfc simulate` runs.

use crate::check::source;
use crate::limits;
use serde_json::{json, Value};
use tsfc::driver::pipeline::Front;
use tsfc::driver::prepare_run;
use tsfc::sim::{self, limits::step_count, Options};
use tsfc::synth::Settings;

/// The simulation of `text` over `horizon` seconds (the spec's span when
/// `None`): `{metrics (the JSON `tsfc simulate` writes), warnings, failures,
/// plots: [{name, svg}]}`, or `{error}`.
pub fn simulate(name: &str, text: &str, horizon: Option<f64>) -> Value {
    match run(name, text, horizon) {
        Ok(v) => v,
        Err(error) => json!({ "error": error }),
    }
}

fn run(name: &str, text: &str, horizon: Option<f64>) -> Result<Value, String> {
    limits::spec_size(text)?;
    let front = Front::from_source(source(name, text), name.to_string());
    let rendered = front.render(false);
    let model = front.checked.model.as_ref().ok_or(rendered)?;
    limits::problem_size(model.n, model.r())?;
    let sim = model
        .spec
        .simulate
        .as_ref()
        .ok_or("the spec has no `simulate { ... }` block (add one with `x0` and `time`)")?;
    let (t0, t1, h) = sim.time;
    let t1 = horizon.map_or(t1, |hz| t0 + hz);
    if let Ok(steps) = step_count(t0, t1, h, h) {
        limits::sim_steps(steps)?;
    }
    let run = front.compile(&Settings::default()).map_err(|e| e.message)?;
    let prepared = prepare_run(&run).map_err(|e| e.message)?;
    let opts = Options {
        horizon,
        ..Options::default()
    };
    let outcome = sim::run(&prepared, &opts, None).map_err(|e| e.message)?;
    let plots = sim::plot::svgs(&outcome).map_err(|e| e.message)?;
    let m = &outcome.metrics;
    Ok(json!({
        "metrics": m,
        "warnings": m.warnings(),
        "failures": m.failures(),
        "plots": plots
            .into_iter()
            .map(|(name, svg)| json!({ "name": name, "svg": svg }))
            .collect::<Vec<_>>(),
    }))
}
