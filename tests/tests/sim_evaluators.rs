//! The simulator's compiled tape against the language's evaluator on every
//! shipped spec with a `simulate` block (same samples and transmissions,
//! states and inputs within 1e-9 relative), and simulating from a certified
//! report without solving again (the same trajectory to the byte; a stale,
//! uncertified or foreign report is never used).

use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use tsfc::driver::{prepare_reusing, prepare_run, Reuse};
use tsfc::sim::{simulate_csv, ErrorKind, Evaluator, Options, Prepared};

fn specs_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../specs")
}

/// A shipped spec compiled once per test binary: its design and its report (JSON).
struct Compiled {
    path: PathBuf,
    prepared: Prepared,
    report: String,
}

fn compile(path: &Path) -> Compiled {
    let run = tsfc::pipeline::read(path)
        .and_then(|f| f.compile(&tsfc::synth::Settings::default()))
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let prepared = prepare_run(&run).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    crate::common::schema::report_json(&run.compiled.report);
    let report = serde_json::to_string_pretty(&run.compiled.report).expect("report JSON");
    Compiled {
        path: path.to_path_buf(),
        prepared,
        report,
    }
}

/// Every shipped spec with a `simulate` block, compiled.
fn shipped() -> &'static [Compiled] {
    static ALL: OnceLock<Vec<Compiled>> = OnceLock::new();
    ALL.get_or_init(|| {
        let mut paths: Vec<PathBuf> = std::fs::read_dir(specs_dir())
            .expect("specs/")
            .map(|e| e.expect("entry").path())
            .filter(|p| p.extension().is_some_and(|x| x == "tsf"))
            .filter(|p| {
                let text = std::fs::read_to_string(p).expect("spec");
                // Adaptive specs have their own simulator (tests/tests/adaptive.rs);
                // output-feedback specs are not simulated in this build (docs/limits.md).
                tsf_lang::check_source(&text).0.is_some_and(|s| {
                    s.simulate.is_some()
                        && s.adaptive.is_none()
                        && s.control.kind == tsf_lang::spec::ControlKind::StateFeedback
                })
            })
            .collect();
        paths.sort();
        assert!(paths.len() >= 3, "{paths:?}");
        paths.iter().map(|p| compile(p)).collect()
    })
}

fn csv(p: &Prepared, opts: &Options) -> (tsfc::sim::Outcome, String) {
    let mut bytes = Vec::new();
    let o = simulate_csv(p, opts, &mut bytes).unwrap_or_else(|e| panic!("{e}"));
    (o, String::from_utf8(bytes).expect("UTF-8"))
}

fn parse(row: &str) -> Vec<f64> {
    row.split(',')
        .map(|v| v.parse::<f64>().expect("number"))
        .collect()
}

#[test]
fn compiled_and_interpreted_trajectories_agree_on_every_shipped_spec() {
    for c in shipped() {
        let name = c.path.file_name().expect("name").to_string_lossy();
        let run = |evaluator| {
            csv(
                &c.prepared,
                &Options {
                    evaluator,
                    ..Options::default()
                },
            )
        };
        let (tape, tape_csv) = run(Evaluator::Compiled);
        let (reference, reference_csv) = run(Evaluator::Interpreter);
        let (mt, mr) = (&tape.metrics, &reference.metrics);
        assert_eq!(
            (
                mt.samples,
                mt.transmissions,
                mt.saturated_samples,
                mt.no_rule_samples
            ),
            (
                mr.samples,
                mr.transmissions,
                mr.saturated_samples,
                mr.no_rule_samples
            ),
            "{name}"
        );
        assert_eq!(mt.rhs_evaluations, mr.rhs_evaluations, "{name}");
        let (rows_t, rows_r): (Vec<&str>, Vec<&str>) =
            (tape_csv.lines().collect(), reference_csv.lines().collect());
        assert_eq!(rows_t.len(), rows_r.len(), "{name}");
        assert_eq!(rows_t[0], rows_r[0], "{name}: header");
        let body_r: Vec<Vec<f64>> = rows_r[1..].iter().map(|r| parse(r)).collect();
        let width = body_r[0].len();
        // Each column's peak, the scale of values that cross zero.
        let peak: Vec<f64> = (0..width)
            .map(|j| body_r.iter().map(|r| r[j].abs()).fold(0.0, f64::max))
            .collect();
        let mut worst: f64 = 0.0;
        for (k, (row_t, r)) in rows_t[1..].iter().zip(&body_r).enumerate() {
            let t = parse(row_t);
            assert_eq!(t[0], r[0], "{name}: sampling instant of row {k}");
            assert_eq!(
                t[width - 1],
                r[width - 1],
                "{name}: transmission at row {k}"
            );
            for j in 1..width - 1 {
                let scale = t[j].abs().max(r[j].abs()).max(1e-6 * peak[j]);
                let rel = (t[j] - r[j]).abs() / scale.max(f64::MIN_POSITIVE);
                assert!(
                    rel <= 1e-9,
                    "{name}: row {k} column {j}: {} vs {} (relative {rel:e})",
                    t[j],
                    r[j]
                );
                worst = worst.max(rel);
            }
        }
        eprintln!(
            "{name}: {} rows, {} transmissions, worst relative difference {worst:e}; \
             {:.3} s compiled, {:.3} s interpreted",
            rows_t.len() - 1,
            mt.transmissions,
            mt.wall_time_s,
            mr.wall_time_s
        );
    }
}

fn tmp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tsfc-reuse-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("dir");
    dir
}

fn report_name(c: &Compiled) -> String {
    format!("{}.report.json", c.prepared.model.spec.controller.node)
}

#[test]
fn a_certified_report_is_simulated_without_solving_again() {
    let short = Options {
        horizon: Some(2.0),
        ..Options::default()
    };
    for c in shipped() {
        let dir = tmp_dir("ok");
        std::fs::write(dir.join(report_name(c)), &c.report).expect("report");
        // Found as OUT/<controller>.report.json.
        let (p, reuse) = prepare_reusing(&c.path, None, &dir).expect("prepared");
        assert_eq!(reuse, Reuse::Reused(dir.join(report_name(c))));
        let fresh = &c.prepared;
        // Gains, P and the trigger weight round-trip through JSON bit for bit.
        assert_eq!(p.tables.gains, fresh.tables.gains);
        assert_eq!(p.p, fresh.p);
        assert_eq!(p.trigger_weight, fresh.trigger_weight);
        let t = (&p.tables, &fresh.tables);
        assert_eq!((t.0.n, t.0.m, t.0.p, t.0.r), (t.1.n, t.1.m, t.1.p, t.1.r));
        assert_eq!(t.0.premise, t.1.premise);
        assert_eq!(t.0.terms, t.1.terms);
        assert_eq!(t.0.centres, t.1.centres);
        assert_eq!(t.0.u_max, t.1.u_max);
        assert_eq!(t.0.state_names, t.1.state_names);
        assert_eq!(csv(&p, &short).1, csv(fresh, &short).1);
        let _ = std::fs::remove_dir_all(&dir);
    }
}

#[test]
fn a_stale_uncertified_or_foreign_report_is_never_used() {
    // The pendulum compiles in a moment.
    let c = shipped()
        .iter()
        .find(|c| c.path.ends_with("inverted_pendulum.tsf"))
        .expect("pendulum");
    let dir = tmp_dir("stale");
    let report = dir.join("given.json");
    let recompiled = |spec: &Path, json: &str| -> String {
        std::fs::write(&report, json).expect("report");
        match prepare_reusing(spec, Some(&report), &dir) {
            Ok((_, Reuse::Refused(why))) => why,
            other => panic!("{other:?}"),
        }
    };
    // The spec changed (one comment more): its sha256 differs.
    let edited = dir.join("inverted_pendulum.tsf");
    let text = std::fs::read_to_string(&c.path).expect("spec");
    std::fs::write(&edited, format!("{text}// edited\n")).expect("spec copy");
    assert!(recompiled(&edited, &c.report).contains("sha256"));
    // The same bytes elsewhere are the same spec.
    std::fs::write(&edited, &text).expect("spec copy");
    let (_, reuse) = prepare_reusing(&edited, Some(&report), &dir).expect("prepared");
    assert_eq!(reuse, Reuse::Reused(report.clone()));
    // Not certified, another tsfc version, not a report at all.
    let uncertified = c
        .report
        .replace("\"status\": \"certified\"", "\"status\": \"refused\"");
    assert!(recompiled(&c.path, &uncertified).contains("not certified"));
    let version = format!("\"tsfc_version\": \"{}\"", env!("CARGO_PKG_VERSION"));
    let foreign = c.report.replace(&version, "\"tsfc_version\": \"0.0.0\"");
    assert!(recompiled(&c.path, &foreign).contains("tsfc 0.0.0"));
    assert!(recompiled(&c.path, "{}").contains("not a tsfc report"));
    // Without a report in OUT the design is compiled; a given report must exist.
    let (_, reuse) = prepare_reusing(&c.path, None, &dir).expect("prepared");
    assert_eq!(reuse, Reuse::NoReport);
    let e = prepare_reusing(&c.path, Some(&dir.join("missing.json")), &dir).expect_err("missing");
    assert_eq!(e.kind, ErrorKind::Usage, "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
