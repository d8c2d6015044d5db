//! `trigger jittered { every = h; jitter = j; }`: nominally periodic sampling
//! with every interval in [h - j, h + j], every sample transmitted. Checked,
//! certified as the sampled loop with those intervals (the report's
//! `sampled_loop`), shipped with the interval constants and simulated; a
//! period outside the certificate is refused with a jittered law that is.

use crate::sampled_loop::msd;
use std::path::PathBuf;
use tsf_lang::spec::Emit;
use tsfc::synth::Settings;

/// `text` written as `msd.tsf` in a fresh folder.
fn spec_file(tag: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tsfc-jittered-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let path = dir.join("msd.tsf");
    std::fs::write(&path, text).expect("write");
    path
}

#[test]
fn a_jittered_sampler_is_certified_for_its_intervals_shipped_and_simulated() {
    let path = spec_file(
        "ok",
        &msd("trigger jittered { every = 0.01; jitter = 0.005; }"),
    );
    let front = tsfc::pipeline::read(&path).expect("read");
    assert!(
        front.checked.diagnostics.iter().all(|d| !d.is_error()),
        "{}",
        front.render(false)
    );
    let run = front.compile(&Settings::default()).expect("compile");
    assert_eq!(run.exit_code(), 0, "{:?}", run.compiled.report.diagnosis);
    let sampled = run
        .compiled
        .report
        .sampled_loop
        .as_ref()
        .expect("a sampled_loop section");
    assert_eq!(sampled.sampling, [0.005, 0.015]);
    // Every sample is sent: no sensor module, the controller carries the intervals.
    let files = run.generate(&[Emit::Rust, Emit::C]).expect("generate");
    assert!(files.iter().all(|f| !f.name.contains("sensor")));
    let rust = files.iter().find(|f| f.name.ends_with(".rs")).expect("rs");
    assert!(rust
        .text
        .contains("pub const SAMPLE_INTERVAL_MAX: f64 = 0.015;"));
    let header = files.iter().find(|f| f.name == "msd.h").expect("msd.h");
    assert!(header
        .text
        .contains("#define MSD_SAMPLE_INTERVAL_MIN 0.005 "));
    // The simulated loop samples near the 10 ms grid, sends every sample and converges.
    let prepared = tsfc::driver::prepare(&path).expect("prepare");
    let out = tsfc::sim::simulate(&prepared, &tsfc::sim::Options::default()).expect("simulate");
    let m = &out.metrics;
    assert!(m.converged && !m.failed, "{m:?}");
    assert_eq!(m.transmissions, m.samples);
    assert!(
        (1999..=2002).contains(&m.samples),
        "20 s / 10 ms: {}",
        m.samples
    );
    let longest = m.max_inter_event_s.expect("intervals");
    assert!(longest > 0.0125 && longest <= 0.015 + 1e-9, "{longest}");
    assert!(m.trigger.contains("jitter 0.005 s"), "{}", m.trigger);
}

#[test]
fn a_jitter_outside_the_certificate_is_refused_with_one_that_certifies() {
    let path = spec_file(
        "long",
        &msd("trigger jittered { every = 1.5; jitter = 0.5; }"),
    );
    let run = tsfc::pipeline::read(&path)
        .expect("read")
        .compile(&Settings::default())
        .expect("compile");
    assert_eq!(run.exit_code(), 3);
    let diagnosis = run.compiled.report.diagnosis.as_ref().expect("diagnosis");
    assert!(
        diagnosis.message.contains("intervals in [1, 2] s"),
        "{}",
        diagnosis.message
    );
    let advice = &diagnosis.achievable[0];
    let at = advice.find("`trigger jittered {").expect("a jittered law");
    let law = &advice[at + 1..];
    let law = &law[..law.find('`').expect("closing quote")];
    let path = spec_file("advised", &msd(law));
    let run = tsfc::pipeline::read(&path)
        .expect("read")
        .compile(&Settings::default())
        .expect("compile");
    assert_eq!(
        run.exit_code(),
        0,
        "{law}: {:?}",
        run.compiled.report.diagnosis
    );
}

#[test]
fn a_jittered_sampler_is_refused_with_modes_pointing_at_the_same_intervals() {
    let text = std::fs::read_to_string(crate::common::spec_path("xue2024_markov_sampled.tsf"))
        .expect("shipped spec")
        .replace(
            "\ntrigger aperiodic { sampling = 0.01 .. 0.08; }",
            "\ntrigger jittered { every = 0.04; jitter = 0.02; }",
        );
    let source = tsfc::driver::frontend::Source {
        name: "x.tsf".into(),
        text: text.clone(),
        bytes: text.as_bytes().to_vec(),
    };
    let checked = tsfc::driver::frontend::check(&source);
    let errors: Vec<_> = checked
        .diagnostics
        .iter()
        .filter(|d| d.is_error())
        .collect();
    // The first error is the refusal (a modes refusal is also followed by
    // "`mode0` needs a `modes` block" at `simulate`, as for every other one).
    assert!(!errors.is_empty(), "accepted");
    assert_eq!(
        errors[0].message,
        "a jittered trigger is not supported with `modes`"
    );
    assert!(
        errors[0]
            .help
            .iter()
            .any(|h| h.contains("`trigger aperiodic { sampling = 0.02 .. 0.06; }`")),
        "{:?}",
        errors[0].help
    );
}
