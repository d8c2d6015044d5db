//! Property campaign over the whole pipeline, not only the checker: generated
//! specs (numbers pushed to extremes, deep nesting near the limits, long sums,
//! random objective, relaxation and trigger combinations) go through read ->
//! check -> compile -> generate (Rust and C) -> simulate. Every input must get
//! an answer without a panic: a certified design whose generated code and
//! simulation run, or an error with a message and an exit code. Cases:
//! `TSFC_FUZZ_PIPELINE_CASES` (default 48), seed `TSFC_FUZZ_SEED`.

use proptest::prelude::*;
use std::cell::RefCell;
use std::collections::BTreeMap;
use std::time::{Duration, Instant};
use tsf_lang::spec::Emit;
use tsfc::synth::Settings;

/// A spec in the shape of the mass-spring-damper, from generated parts.
#[derive(Debug, Clone)]
pub(crate) struct Case {
    stiffness: f64,
    level: f64,
    damping_expr: String,
    objective: &'static str,
    relaxation: &'static str,
    trigger: String,
    x0: f64,
}

impl Case {
    pub(crate) fn text(&self) -> String {
        format!(
            "tsf 1;\ncontroller fz;\nstate x1, x2;\ninput u saturate {level:e};\ndisturbance w bound 0.01;\n\
             output z = [x1];\nconst c = {damping};\n\
             A(x) = [0, 1; -({k:e}) * (1 + x1 ^ 2), -c];\nB = [0; 1];\nD = [0; 1];\n\
             premise p = x1 ^ 2 range 0 .. 1 {{ small = trap(-1, -1, 0, 1); large = trap(0, 1, 2, 2); }}\n\
             rule R1: p is small => at(x1 = 0, x2 = 0);\nrule R2: p is large => at(x1 = 1, x2 = 0);\n\
             {objective}\nrelaxation {relaxation};\n{trigger}\n\
             simulate {{ x0 = [{x0:e}, 0]; time = 0 .. 0.2 step 0.001; }}\n",
            level = self.level,
            damping = self.damping_expr,
            k = self.stiffness,
            objective = self.objective,
            relaxation = self.relaxation,
            trigger = self.trigger,
            x0 = self.x0,
        )
    }
}

/// Numbers from ordinary to extreme.
fn number() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => 0.01f64..100.0,
        1 => Just(0.0),
        1 => Just(1e-300),
        1 => Just(1e300),
        1 => Just(-1.0),
        1 => Just(f64::MAX),
    ]
}

/// The damping constant as an expression: plain, deeply nested, or a long sum.
fn damping() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("0.5".to_string()),
        (1usize..300).prop_map(|d| format!("{}0.5{}", "(".repeat(d), ")".repeat(d))),
        (1usize..300).prop_map(|d| format!("{}0.5", "-".repeat(2 * d))),
        (1usize..3000).prop_map(|n| format!("0.5{}", " + 0".repeat(n))),
        (1usize..40).prop_map(|d| format!("{}0.5{}", "abs(".repeat(d), ")".repeat(d))),
    ]
}

fn objective() -> impl Strategy<Value = &'static str> {
    prop_oneof![
        Just("objective stability;"),
        Just("objective decay_rate >= 0.5;"),
        Just("objective decay_rate maximize;"),
        Just("objective hinf(w -> z) minimize;"),
        Just("objective linf(w -> z) minimize with phi = 0.5;\nobjective saturation region;"),
        Just("objective input_norm(u) <= 0.5 for x0 = [0.3, 0];"),
        Just("objective stability;\nobjective input_norm(u) <= 1e-6 for x0 = [1, 0];"),
    ]
}

fn relaxation() -> impl Strategy<Value = &'static str> {
    prop_oneof![
        Just("basic"),
        Just("tuan"),
        Just("tanaka(s = 2)"),
        Just("membership_mismatch(kappa = 0.1)")
    ]
}

fn trigger() -> impl Strategy<Value = String> {
    prop_oneof![
        Just(String::new()),
        Just("trigger continuous;".to_string()),
        (1u32..400)
            .prop_map(|k| format!("trigger periodic {{ every = {}; }}", f64::from(k) * 1e-3)),
        Just("trigger periodic { every = 0.0125; }".to_string()),
        Just("trigger aperiodic { sampling = 0.001 .. 0.02; weight = synthesize; }".to_string()),
        Just("trigger mixed { sampling = 0.001 .. 0.1; beta = 0.5; rho = 1e-4; }".to_string()),
    ]
}

pub(crate) fn case() -> impl Strategy<Value = Case> {
    (
        number(),
        number(),
        damping(),
        objective(),
        relaxation(),
        trigger(),
        prop_oneof![3 => -1.0f64..1.0, 1 => Just(1e160)],
    )
        .prop_map(
            |(stiffness, level, damping_expr, objective, relaxation, trigger, x0)| Case {
                stiffness,
                level,
                damping_expr,
                objective,
                relaxation,
                trigger,
                x0,
            },
        )
}

/// Runs one case through the pipeline; the outcome in one word.
fn run(case: &Case, dir: &std::path::Path) -> Result<&'static str, TestCaseError> {
    let path = dir.join("fz.tsf");
    std::fs::write(&path, case.text()).map_err(|e| TestCaseError::fail(e.to_string()))?;
    let front = match tsfc::pipeline::read(&path) {
        Ok(f) => f,
        Err(e) => {
            prop_assert!(!e.message.is_empty());
            return Ok("spec error");
        }
    };
    let run = match front.compile(&Settings::default()) {
        Ok(r) => r,
        Err(e) => {
            prop_assert!(!e.message.is_empty());
            prop_assert!(e.exit_code() != 0);
            return Ok("spec error");
        }
    };
    if run.exit_code() != 0 {
        prop_assert!(run.certified().is_err());
        return Ok("not certified");
    }
    let files = run
        .generate(&[Emit::Rust, Emit::C])
        .map_err(|e| TestCaseError::fail(format!("certified but not generated: {e}")))?;
    prop_assert!(files.iter().all(|f| !f.text.is_empty()));
    match tsfc::driver::prepare(&path)
        .and_then(|p| tsfc::sim::simulate(&p, &tsfc::sim::Options::default()))
    {
        Ok(o) => {
            // A run is either finite or flagged as failed.
            let finite = o.trace.x.iter().flatten().all(|v| v.is_finite());
            prop_assert!(finite || o.metrics.failed, "non-finite run not flagged");
            Ok("simulated")
        }
        Err(e) => {
            prop_assert!(!e.to_string().is_empty());
            Ok("simulation refused")
        }
    }
}

fn cases() -> u32 {
    std::env::var("TSFC_FUZZ_PIPELINE_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(48)
}

#[test]
fn every_generated_spec_gets_an_answer_through_the_whole_pipeline() {
    use proptest::test_runner::{RngAlgorithm, TestRng, TestRunner};
    let dir = std::env::temp_dir().join(format!("tsfc-fuzz-pipeline-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let mut config = ProptestConfig::with_cases(cases());
    config.failure_persistence = None;
    let mut runner =
        TestRunner::new_with_rng(config, TestRng::deterministic_rng(RngAlgorithm::ChaCha));
    let tally = RefCell::new(BTreeMap::<&str, usize>::new());
    let slowest = RefCell::new((Duration::ZERO, String::new()));
    let result = runner.run(&case(), |c| {
        let t0 = Instant::now();
        let what = run(&c, &dir)?;
        let took = t0.elapsed();
        if took > slowest.borrow().0 {
            *slowest.borrow_mut() = (took, c.text());
        }
        *tally.borrow_mut().entry(what).or_default() += 1;
        Ok(())
    });
    let _ = std::fs::remove_dir_all(&dir);
    let (took, text) = slowest.take();
    let tally = tally.take();
    eprintln!(
        "pipeline campaign: {} cases {tally:?}; slowest {:.3} s:\n{text}",
        cases(),
        took.as_secs_f64(),
    );
    if let Err(e) = result {
        panic!("{e}");
    }
    // The deterministic campaign reaches code generation and simulation.
    assert!(
        tally.get("simulated").copied().unwrap_or(0) > 0,
        "{tally:?}"
    );
}
