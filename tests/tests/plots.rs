//! Plots a person can read (`tsfc simulate`, Monte Carlo campaigns): every
//! figure carries its title, axis labels and legend entries as SVG text
//! (laid out with the font compiled into tsfc), a diverging or NaN trace
//! still gives a plot that says it was clipped, and rendering is
//! deterministic (same run, same bytes).

use std::path::PathBuf;
use tsfc::driver::prepare;
use tsfc::sim::campaign::plot::plots as campaign_plots;
use tsfc::sim::campaign::{run_campaign, Config};
use tsfc::sim::plot::plots;
use tsfc::sim::{simulate, Options, Outcome};

fn pendulum() -> Outcome {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../specs/inverted_pendulum.tsf");
    let p = prepare(&path).unwrap_or_else(|e| panic!("{e}"));
    simulate(&p, &Options::default()).unwrap_or_else(|e| panic!("{e}"))
}

/// The text nodes of an SVG file.
fn texts(files: &[(String, Vec<u8>)], name: &str) -> Vec<String> {
    let (_, bytes) = files
        .iter()
        .find(|f| f.0 == name)
        .unwrap_or_else(|| panic!("no {name}"));
    let svg = String::from_utf8(bytes.clone()).expect("SVG is UTF-8");
    svg.split("<text")
        .skip(1)
        .filter_map(|t| {
            Some(
                t.split_once('>')?
                    .1
                    .split_once("</text>")?
                    .0
                    .trim()
                    .to_string(),
            )
        })
        .collect()
}

fn has(texts: &[String], want: &str) -> bool {
    texts.iter().any(|t| t.contains(want))
}

fn png_ok(files: &[(String, Vec<u8>)]) {
    for (name, bytes) in files.iter().filter(|f| f.0.ends_with(".png")) {
        assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n"), "{name}");
        assert!(
            bytes.len() > 10_000,
            "{name}: {} bytes, no drawing?",
            bytes.len()
        );
    }
}

#[test]
fn run_figures_have_titles_axis_labels_and_legends() {
    let o = pendulum();
    let files = plots(&o).unwrap_or_else(|e| panic!("{e}"));
    png_ok(&files);
    let states = texts(&files, "inverted_pendulum.states.svg");
    for want in [
        "inverted_pendulum (inverted_pendulum.tsf): state trajectories",
        "time [s]",
        "theta",
        "omega",
        "trigger: continuous",
        "converged",
    ] {
        assert!(has(&states, want), "states: no `{want}` in {states:?}");
    }
    // Tick labels: numbers on both axes.
    assert!(states.iter().filter(|t| t.parse::<f64>().is_ok()).count() >= 10);
    let inputs = texts(&files, "inverted_pendulum.inputs.svg");
    assert!(
        has(&inputs, "control inputs") && has(&inputs, "u"),
        "{inputs:?}"
    );
    let events = texts(&files, "inverted_pendulum.events.svg");
    for want in [
        "transmission instants and inter-event times",
        "transmissions",
        "inter-event time [s]",
        "since the previous one",
        "5001 transmissions",
    ] {
        assert!(has(&events, want), "events: no `{want}` in {events:?}");
    }
}

#[test]
fn saturation_limits_are_in_the_legend() {
    let mut o = pendulum();
    o.u_max = vec![40.0];
    let files = plots(&o).unwrap_or_else(|e| panic!("{e}"));
    let inputs = texts(&files, "inverted_pendulum.inputs.svg");
    assert!(
        has(&inputs, "+u_bar = 40") && has(&inputs, "-u_bar = -40"),
        "{inputs:?}"
    );
}

#[test]
fn a_diverging_nan_trace_still_plots_and_says_it_was_clipped() {
    let mut o = pendulum();
    let n = o.trace.t.len();
    // From the middle on theta grows like exp(5 t) and omega like -1e30 t, then
    // theta turns NaN and omega infinite.
    let cut = n * 9 / 10;
    let half = o.trace.t[n / 2];
    for k in n / 2..n {
        let t = o.trace.t[k] - half;
        o.trace.x[k][0] = if k < cut { (5.0 * t).exp() } else { f64::NAN };
        o.trace.x[k][1] = if k < cut { -1e30 * t } else { f64::INFINITY };
        o.trace.u[k][0] = f64::NAN;
    }
    o.metrics.nonfinite_at_s = Some(o.trace.t[cut]);
    o.metrics.failed = true;
    let files = plots(&o).unwrap_or_else(|e| panic!("{e}"));
    png_ok(&files);
    let states = texts(&files, "inverted_pendulum.states.svg");
    assert!(has(&states, "y clipped at"), "{states:?}");
    assert!(has(&states, "non-finite at"), "{states:?}");
    assert!(has(&states, "RUN FAILED"), "{states:?}");
    // The tick labels stay finite and moderate.
    let ticks: Vec<f64> = states.iter().filter_map(|t| t.parse().ok()).collect();
    assert!(ticks.len() >= 10, "{states:?}");
    assert!(
        ticks.iter().all(|v| v.is_finite() && v.abs() < 1e12),
        "{ticks:?}"
    );
}

#[test]
fn rendering_is_deterministic() {
    let o = pendulum();
    let a = plots(&o).unwrap_or_else(|e| panic!("{e}"));
    let b = plots(&o).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(a.len(), 6);
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(x.0, y.0);
        assert!(x.1 == y.1, "{} differs between two renderings", x.0);
    }
}

#[test]
fn campaign_figures_have_bands_histograms_and_the_convergence_marker() {
    let text = crate::common::scalar_campaign_spec("mc_plot", 12, 1.5, "");
    let dir = std::env::temp_dir().join(format!("tsfc-plots-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("mc_plot.tsf");
    std::fs::write(&path, text).expect("write spec");
    let p = prepare(&path).unwrap_or_else(|e| panic!("{e}"));
    let cfg = Config {
        jobs: Some(2),
        ..Config::default()
    };
    let part = run_campaign(&p, &Options::default(), &cfg).unwrap_or_else(|e| panic!("{e}"));
    let files = campaign_plots(&part).unwrap_or_else(|e| panic!("{e}"));
    png_ok(&files);
    let env = texts(&files, "mc_plot.mc.envelope.svg");
    for want in [
        "state envelope (12 runs",
        "x1 min..max",
        "x1 nominal",
        "time [s]",
    ] {
        assert!(has(&env, want), "envelope: no `{want}` in {env:?}");
    }
    let settle = texts(&files, "mc_plot.mc.settle.svg");
    for want in [
        "settle times",
        "settle time [s]",
        "runs",
        "convergence time 3.5 s",
    ] {
        assert!(has(&settle, want), "settle: no `{want}` in {settle:?}");
    }
    let tx = texts(&files, "mc_plot.mc.transmissions.svg");
    assert!(
        has(&tx, "transmissions per run") && has(&tx, "runs per bin"),
        "{tx:?}"
    );
    // Counts above the bars add up to the runs.
    let again = campaign_plots(&part).unwrap_or_else(|e| panic!("{e}"));
    assert!(files == again, "campaign plots are not deterministic");
    let _ = std::fs::remove_dir_all(&dir);
}
