//! Property campaign over the features past the basic loop: one seed spec per
//! feature in `tests/fuzz_seeds/` (modes, a mixed trigger on a signal, a
//! premise region, a sweep, a Monte Carlo block, given gains, sector rules,
//! a fuzzy Lyapunov function, Polya, co-design, f32), mutated (tokens, bytes,
//! numbers replaced by extremes) and taken through check, compile, code
//! generation, simulation, the sweep and the campaign with its shard merge;
//! and shard files mutated and merged. Every input gets an answer with an exit
//! code in 0 ..= 4 and a message, never a panic; nothing is written outside
//! the output folder. Cases: `TSFC_FUZZ_FEATURE_CASES` (default 400),
//! `TSFC_FUZZ_SHARD_CASES` (default 1500); deterministic (ChaCha seed).

use super::fuzz::{apply, mutation, tokens, Mutation};
use proptest::prelude::*;
use proptest::test_runner::{RngAlgorithm, TestRng, TestRunner};
use std::cell::RefCell;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use tsf_lang::spec::Emit;
use tsfc::sim::campaign::{merge_dirs, run_campaign, write_campaign, write_shard, Config};
use tsfc::synth::Settings;

/// The seed specs, sorted by file name.
fn seeds() -> Vec<String> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz_seeds");
    let mut paths: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("tests/fuzz_seeds")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "tsf"))
        .collect();
    paths.sort();
    let out: Vec<String> = paths
        .iter()
        .map(|p| std::fs::read_to_string(p).expect("seed"))
        .collect();
    assert!(out.len() >= 10, "{} seeds", out.len());
    out
}

/// Numbers a mutation writes in place of one of the spec's numbers.
const EXTREMES: [&str; 12] = [
    "0",
    "-1",
    "1e-320",
    "1e-300",
    "1e-12",
    "3.5",
    "1e39",
    "1e200",
    "1e300",
    "1e999",
    "18446744073709551615",
    "-1e300",
];

/// `text` with the `k`-th numeric tokens replaced by extremes.
fn with_extremes(text: &str, picks: &[(usize, usize)]) -> String {
    let mut toks = tokens(text);
    let numeric: Vec<usize> = (0..toks.len())
        .filter(|&i| toks[i].starts_with(|c: char| c.is_ascii_digit()))
        .collect();
    if numeric.is_empty() {
        return text.to_string();
    }
    for &(k, e) in picks {
        toks[numeric[k % numeric.len()]] = EXTREMES[e % EXTREMES.len()].to_string();
    }
    toks.concat()
}

/// One generated input: a seed, number replacements, then token/byte edits.
#[derive(Debug, Clone)]
struct Case {
    seed: usize,
    numbers: Vec<(usize, usize)>,
    edits: Vec<Mutation>,
}

fn case() -> impl Strategy<Value = Case> {
    (
        any::<usize>(),
        proptest::collection::vec((any::<usize>(), any::<usize>()), 0..3),
        proptest::collection::vec(mutation(), 0..2),
    )
        .prop_map(|(seed, numbers, edits)| Case {
            seed,
            numbers,
            edits,
        })
}

impl Case {
    fn text(&self, seeds: &[String]) -> String {
        let text = with_extremes(&seeds[self.seed % seeds.len()], &self.numbers);
        String::from_utf8_lossy(&apply(&text, &self.edits)).into_owned()
    }
}

/// An error's exit code, checked to be in 1 ..= 4 with a message.
fn code(e: &tsfc::Error) -> Result<u8, TestCaseError> {
    prop_assert!(!e.message.is_empty());
    prop_assert!((1..=4).contains(&e.exit_code()), "{}", e.message);
    Ok(e.exit_code())
}

/// The whole pipeline on `text`: the exit code the CLI would give and the stage.
fn answer(text: &str, dir: &Path) -> Result<(u8, &'static str), TestCaseError> {
    let _ = std::fs::remove_dir_all(dir);
    std::fs::create_dir_all(dir).map_err(|e| TestCaseError::fail(e.to_string()))?;
    let path = dir.join("f.tsf");
    std::fs::write(&path, text).map_err(|e| TestCaseError::fail(e.to_string()))?;
    let front = match tsfc::pipeline::read(&path) {
        Ok(f) => f,
        Err(e) => return Ok((code(&e)?, "read")),
    };
    if front.checked.model.is_none() {
        return Ok((1, "spec error"));
    }
    let run = match front.compile(&Settings::default()) {
        Ok(r) => r,
        Err(e) => return Ok((code(&e)?, "compile error")),
    };
    if run.exit_code() != 0 {
        prop_assert!(run.certified().is_err());
        return Ok((3, "not certified"));
    }
    if let Err(e) = run.generate(&[Emit::Rust, Emit::C]) {
        return Ok((code(&e)?, "not generated"));
    }
    let spec = &run.model.spec;
    let Some(sim) = spec.simulate.as_ref() else {
        return Ok((0, "generated"));
    };
    let (mc, sweep) = (sim.monte_carlo.is_some(), sim.sweep.is_some());
    let prepared = match tsfc::driver::prepare_run(&run) {
        Ok(p) => p,
        Err(e) => return Ok((code(&e)?, "not prepared")),
    };
    let opts = tsfc::sim::Options::default();
    if mc {
        let cfg = |shard| Config {
            runs: Some(4),
            shard,
            jobs: Some(1),
            ..Config::default()
        };
        let whole = match run_campaign(&prepared, &opts, &cfg((1, 1))) {
            Ok(w) => w,
            Err(e) => return Ok((code(&e)?, "campaign refused")),
        };
        let shards = dir.join("shards");
        for k in 1..=2 {
            let part = run_campaign(&prepared, &opts, &cfg((k, 2)))
                .map_err(|e| TestCaseError::fail(format!("shard {k} after the whole: {e}")))?;
            write_shard(&part, &shards).map_err(|e| TestCaseError::fail(e.to_string()))?;
        }
        crate::common::schema::validate_dir(&shards);
        let merged = merge_dirs(std::slice::from_ref(&shards))
            .map_err(|e| TestCaseError::fail(format!("own shards refused: {e}")))?;
        prop_assert_eq!(&merged.runs, &whole.runs);
        let failed = whole.runs.iter().any(|r| r.failed());
        return Ok((if failed { 4 } else { 0 }, "campaign"));
    }
    if sweep {
        let cfg = tsfc::sim::sweep::Config { jobs: Some(1) };
        return Ok(
            match tsfc::sim::sweep::run_sweep(
                &prepared,
                &[],
                &opts,
                &cfg,
                &tsfc::driver::prepare::prepare_text,
            ) {
                Ok((table, _)) => (if table.any_failed() { 4 } else { 0 }, "swept"),
                Err(e) => (code(&e)?, "sweep refused"),
            },
        );
    }
    Ok(match tsfc::sim::simulate(&prepared, &opts) {
        Ok(o) => {
            let finite = o.trace.x.iter().flatten().all(|v| v.is_finite());
            prop_assert!(finite || o.metrics.failed, "non-finite run not flagged");
            (if o.metrics.failed { 4 } else { 0 }, "simulated")
        }
        Err(e) => (code(&e)?, "simulation refused"),
    })
}

fn cases(var: &str, default: u32) -> u32 {
    std::env::var(var)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// Runs `strategy` for `n` deterministic cases; the tally of outcomes and the
/// highest exit code (panics with the failing case).
fn campaign<S: Strategy>(
    n: u32,
    strategy: S,
    one: impl Fn(S::Value) -> Result<(u8, &'static str), TestCaseError>,
) -> (BTreeMap<&'static str, usize>, u8)
where
    S::Value: std::fmt::Debug,
{
    let mut config = ProptestConfig::with_cases(n);
    config.failure_persistence = None;
    let mut runner =
        TestRunner::new_with_rng(config, TestRng::deterministic_rng(RngAlgorithm::ChaCha));
    let tally = RefCell::new(BTreeMap::<&'static str, usize>::new());
    let worst = RefCell::new(0u8);
    let result = runner.run(&strategy, |v| {
        let (code, what) = one(v)?;
        prop_assert!(code <= 4, "exit code {code}");
        *tally.borrow_mut().entry(what).or_default() += 1;
        let mut w = worst.borrow_mut();
        *w = (*w).max(code);
        Ok(())
    });
    if let Err(e) = result {
        panic!("{e}");
    }
    (tally.take(), worst.take())
}

#[test]
fn mutated_feature_specs_get_an_answer_through_the_whole_pipeline() {
    let seeds = seeds();
    let dir = std::env::temp_dir().join(format!("tsfc-fuzz-features-{}", std::process::id()));
    let n = cases("TSFC_FUZZ_FEATURE_CASES", 400);
    let slowest = RefCell::new((Duration::ZERO, String::new()));
    let started = Instant::now();
    let (tally, worst) = campaign(n, case(), |c| {
        let text = c.text(&seeds);
        let t0 = Instant::now();
        let out = answer(&text, &dir)?;
        if t0.elapsed() > slowest.borrow().0 {
            *slowest.borrow_mut() = (t0.elapsed(), text);
        }
        Ok(out)
    });
    let _ = std::fs::remove_dir_all(&dir);
    let (took, text) = slowest.take();
    eprintln!(
        "feature campaign: {n} cases in {:.1} s, highest exit code {worst}: {tally:?}; slowest {:.2} s:\n{text}",
        started.elapsed().as_secs_f64(),
        took.as_secs_f64()
    );
    // The campaign reaches code generation and the runs, not only the checker.
    let reached: usize = ["generated", "simulated", "swept", "campaign"]
        .iter()
        .filter_map(|k| tally.get(k))
        .sum();
    assert!(reached > 0, "{tally:?}");
}

/// A mutation of a shard file's JSON.
#[derive(Debug, Clone)]
enum ShardEdit {
    /// Replace the `k`-th node (pre-order) with a hostile value.
    Node(usize, usize),
    /// Token or byte edits of the text.
    Text(Vec<Mutation>),
}

/// Values a shard field is replaced with.
fn hostile(k: usize) -> serde_json::Value {
    use serde_json::json;
    let values = [
        json!(null),
        json!(-1),
        json!(1e300),
        json!(u64::MAX),
        json!("../../evil"),
        json!("a/b"),
        json!("\u{1b}[2J"),
        json!(""),
        json!([]),
        json!({}),
        json!(0.5),
        json!(true),
        json!([[1.0, 2.0], [3.0]]),
        json!(vec![0.0; 5000]),
    ];
    values[k % values.len()].clone()
}

/// The `k`-th node of `v` in pre-order (modulo the count), replaced by `with`.
fn replace_node(v: &mut serde_json::Value, k: usize, with: serde_json::Value) {
    fn count(v: &serde_json::Value) -> usize {
        1 + match v {
            serde_json::Value::Array(a) => a.iter().map(count).sum(),
            serde_json::Value::Object(m) => m.values().map(count).sum(),
            _ => 0,
        }
    }
    fn walk(v: &mut serde_json::Value, k: &mut usize, with: &serde_json::Value) -> bool {
        if *k == 0 {
            *v = with.clone();
            return true;
        }
        *k -= 1;
        let children: Vec<&mut serde_json::Value> = match v {
            serde_json::Value::Array(a) => a.iter_mut().collect(),
            serde_json::Value::Object(m) => m.values_mut().collect(),
            _ => Vec::new(),
        };
        children.into_iter().any(|c| walk(c, k, with))
    }
    let mut k = k % count(v);
    walk(v, &mut k, &with);
}

fn shard_edit() -> impl Strategy<Value = (bool, Vec<ShardEdit>)> {
    let edit = prop_oneof![
        3 => (any::<usize>(), any::<usize>()).prop_map(|(a, b)| ShardEdit::Node(a, b)),
        1 => proptest::collection::vec(mutation(), 1..4).prop_map(ShardEdit::Text),
    ];
    (any::<bool>(), proptest::collection::vec(edit, 1..3))
}

/// Every file under `dir`, recursively.
fn files_under(dir: &Path) -> usize {
    std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| {
            let p = e.path();
            if p.is_dir() {
                files_under(&p)
            } else {
                1
            }
        })
        .sum()
}

#[test]
fn mutated_shard_files_never_panic_the_merge_nor_leave_out() {
    let seeds = seeds();
    let mc = seeds
        .iter()
        .find(|s| s.contains("monte_carlo"))
        .expect("a Monte Carlo seed");
    let root = std::env::temp_dir().join(format!("tsfc-fuzz-shards-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(&root).expect("dir");
    let spec = root.join("mc.tsf");
    std::fs::write(&spec, mc).expect("spec");
    let prepared = tsfc::driver::prepare(&spec).unwrap_or_else(|e| panic!("{e}"));
    let originals: Vec<(String, String)> = (1..=2)
        .map(|k| {
            let cfg = Config {
                shard: (k, 2),
                jobs: Some(1),
                ..Config::default()
            };
            let part = run_campaign(&prepared, &tsfc::sim::Options::default(), &cfg)
                .unwrap_or_else(|e| panic!("{e}"));
            let file = tsfc::sim::campaign::shard_file(&part);
            let text = serde_json::to_string_pretty(&part).expect("json");
            (file, text)
        })
        .collect();
    let work = root.join("w");
    let n = cases("TSFC_FUZZ_SHARD_CASES", 1500);
    let (tally, worst) = campaign(n, shard_edit(), |(first, edits)| {
        let _ = std::fs::remove_dir_all(&work);
        let (shards, out) = (
            work.join("a").join("b"),
            work.join("a").join("b").join("out"),
        );
        std::fs::create_dir_all(&out).map_err(|e| TestCaseError::fail(e.to_string()))?;
        for (k, (file, text)) in originals.iter().enumerate() {
            let mut text = text.clone();
            if (k == 0) == first {
                for e in &edits {
                    text = match e {
                        ShardEdit::Node(at, what) => match serde_json::from_str(&text) {
                            Ok(mut v) => {
                                replace_node(&mut v, *at, hostile(*what));
                                serde_json::to_string(&v).unwrap_or_default()
                            }
                            Err(_) => text,
                        },
                        ShardEdit::Text(m) => {
                            String::from_utf8_lossy(&apply(&text, m)).into_owned()
                        }
                    };
                }
            }
            std::fs::write(shards.join(file), text)
                .map_err(|e| TestCaseError::fail(e.to_string()))?;
        }
        let before = files_under(&work);
        let what = match merge_dirs(std::slice::from_ref(&shards)) {
            Err(e) => {
                prop_assert_eq!(e.exit_code(), 2, "{}", e.message);
                (2, "refused")
            }
            Ok(p) => match write_campaign(&p, &out) {
                Ok((s, files)) => {
                    prop_assert!(files.iter().all(|f| f.starts_with(&out)));
                    crate::common::schema::validate_dir(&out);
                    (if s.failed > 0 { 4 } else { 0 }, "merged")
                }
                Err(e) => (code(&e)?, "not written"),
            },
        };
        // Only the campaign's own outputs were added, inside `out`.
        prop_assert_eq!(files_under(&work) - files_under(&out), before);
        Ok(what)
    });
    let _ = std::fs::remove_dir_all(&root);
    eprintln!("shard campaign: {n} cases, highest exit code {worst}: {tally:?}");
    assert!(tally.get("refused").copied().unwrap_or(0) > 0, "{tally:?}");
}
