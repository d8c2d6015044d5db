//! Sweeps (`tsfc simulate --sweep`): a periodic sweep of a scalar linear
//! loop whose transmissions and energy are computed here in closed form, a
//! refused law marked not certified, a synthesized design in the same table,
//! and tables whose bytes do not depend on the thread count.

use std::path::PathBuf;
use std::sync::OnceLock;
use tsfc::driver::prepare;
use tsfc::sim::sweep::table::{Gains, Table};
use tsfc::sim::sweep::{run_sweep, write_sweep, Config};
use tsfc::sim::{Options, Prepared};

/// The plant `x' = A x + u` with `x(0) = X0`, sampled with zero-order hold.
const A: f64 = 0.5;
const F: f64 = -2.0;
const X0: f64 = 1.0;
const HORIZON: f64 = 10.0;
const PERIODS: [f64; 5] = [0.25, 0.5, 1.0, 2.5, 4.0];

/// Writes `text` as `<tag>.tsf` in a fresh temporary folder.
fn write_spec(tag: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tsfc-sweep-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join(format!("{tag}.tsf"));
    std::fs::write(&path, text).expect("write spec");
    path
}

/// A scalar loop; `rule` ends the rule (given gain or not), `extra` adds items.
fn scalar_spec(name: &str, rule: &str, extra: &str, sweep: &str) -> String {
    format!(
        "tsf 1; controller {name};\nstate x1; input u;\nA = {A}; B = 1;\n\
         premise x1 range -100 .. 100 {{ all = trap(-100, -100, 100, 100); }}\n\
         rule R: x1 is all => at(x1 = 0){rule};\n{extra}\n\
         simulate {{\n  x0 = {X0}; time = 0 .. {HORIZON} step 0.01;\n  {sweep}\n}}\n"
    )
}

fn periods() -> String {
    PERIODS
        .iter()
        .map(|t| t.to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// The given-gain spec: its own law is periodic every 0.5 s.
fn given() -> &'static Prepared {
    static P: OnceLock<Prepared> = OnceLock::new();
    P.get_or_init(|| {
        let text = scalar_spec(
            "given",
            &format!(", F = [{F}]"),
            "objective stability;\ntrigger periodic { every = 0.5; }",
            &format!(
                "sweep {{ trigger periodic {{ every = [{}]; }}\n window = 5 .. 10; columns {{ s = x1; }} }}",
                periods()
            ),
        );
        prepare(&write_spec("given", &text)).unwrap_or_else(|e| panic!("{e}"))
    })
}

fn sweep(main: &Prepared, compare: &[Prepared], jobs: usize) -> Table {
    run_sweep(
        main,
        compare,
        &Options::default(),
        &Config { jobs: Some(jobs) },
        &tsfc::driver::prepare::prepare_text,
    )
    .unwrap_or_else(|e| panic!("{e}"))
    .0
}

/// Energy `sum_i T_i (F x_i)^2` of the periodic loop (the last interval
/// cut at the horizon): `x_{i+1} = phi x_i` with
/// `phi = e^{AT} + (e^{AT} - 1) / A * F` (exact discretization of the held command).
fn energy(t: f64) -> f64 {
    let e = (A * t).exp();
    let phi = e + (e - 1.0) / A * F;
    let intervals = (HORIZON / t - 1e-9).ceil() as i32;
    (0..intervals)
        .map(|i| {
            let held = t.min(HORIZON - f64::from(i) * t);
            held * (F * X0 * phi.powi(i)).powi(2)
        })
        .sum()
}

#[test]
fn periodic_rows_match_the_closed_form() {
    let table = sweep(given(), &[], 2);
    assert_eq!(table.rows.len(), 1 + PERIODS.len());
    assert_eq!(table.rows[0].scenario, "design");
    assert_eq!(table.window_s, (5.0, 10.0));
    for (row, t) in table.rows[1..].iter().zip(PERIODS) {
        assert_eq!(row.scenario, format!("periodic every = {t}"));
        // A transmission at t0 and one every period up to the end, inclusive.
        let expected = (HORIZON / t).floor() as u64 + 1;
        assert_eq!(row.transmissions, Some(expected), "T = {t}");
        assert_eq!(
            row.mean_inter_event_s.map(|m| (m - t).abs() < 1e-9),
            Some(true)
        );
        let e = row.energy.expect("an energy");
        assert!(
            (e - energy(t)).abs() <= 1e-6 * energy(t),
            "T = {t}: energy {e} vs {}",
            energy(t)
        );
    }
    // The windowed norm is the largest |x| over 5 .. 10 s: with |phi| < 1 the
    // state at the first sample in the window (before it decays further).
    let row = &table.rows[1];
    let phi = (A * 0.25).exp() + ((A * 0.25).exp() - 1.0) / A * F;
    let at5 = X0 * phi.powi(20);
    let s = row.norms[0].expect("a norm");
    assert!((s - at5.abs()).abs() <= 1e-6 * at5.abs(), "{s} vs {at5}");
}

#[test]
fn a_law_the_certificate_does_not_cover_is_marked_and_still_run() {
    let table = sweep(given(), &[], 2);
    let by_name = |n: &str| {
        table
            .rows
            .iter()
            .find(|r| r.scenario == n)
            .unwrap_or_else(|| panic!("no row {n}"))
    };
    let fast = by_name("periodic every = 0.25");
    assert!(
        fast.certified && fast.gains == Gains::GivenCertified,
        "{fast:?}"
    );
    assert!(by_name("periodic every = 0.5").gains == Gains::Same);
    let slow = by_name("periodic every = 4");
    assert!(!slow.certified, "{slow:?}");
    assert_eq!(slow.gains, Gains::GivenNotCertified);
    assert!(slow
        .refused
        .as_deref()
        .is_some_and(|r| r.contains("not certified")));
    // phi = e^2 - 4 (e^2 - 1) < -1: the sampled loop diverges, and the row says so.
    assert!(slow.failed && slow.transmissions == Some(3));
    assert!(table.any_failed());
    let md = table.markdown();
    assert!(md.contains("NOT CERTIFIED") && md.contains("## Not certified"));
}

#[test]
fn the_table_does_not_depend_on_the_thread_count() {
    let one = sweep(given(), &[], 1);
    let two = sweep(given(), &[], 2);
    assert_eq!(one, two);
    let dir = std::env::temp_dir().join(format!("tsfc-sweep-out-{}", std::process::id()));
    let read = |jobs: usize| {
        let d = dir.join(jobs.to_string());
        std::fs::create_dir_all(&d).expect("out dir");
        let (t, m) = run_sweep(
            given(),
            &[],
            &Options::default(),
            &Config { jobs: Some(jobs) },
            &tsfc::driver::prepare::prepare_text,
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let files = write_sweep(&t, &m, &d).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            crate::common::schema::validate_dir(&d),
            2,
            "table and metrics"
        );
        files
            .iter()
            .map(|f| std::fs::read(f).expect("read"))
            .collect::<Vec<_>>()
    };
    let (a, b) = (read(1), read(2));
    assert_eq!(a.len(), 4);
    assert_eq!(a, b);
    let metrics: serde_json::Value = serde_json::from_slice(&a[3]).expect("json");
    assert_eq!(metrics.as_array().map(Vec::len), Some(1 + PERIODS.len()));
    assert!(metrics[1]["metrics"]["transmissions"].is_u64());
}

#[test]
fn a_synthesized_design_joins_the_table() {
    let text = scalar_spec(
        "synth",
        "",
        "objective decay_rate >= 0.5;\ntrigger continuous;",
        "sweep { trigger periodic { every = [0.05]; } }",
    );
    let synth = prepare(&write_spec("synth", &text)).unwrap_or_else(|e| panic!("{e}"));
    let table = sweep(given(), std::slice::from_ref(&synth), 2);
    let rows: Vec<_> = table.rows.iter().filter(|r| r.spec == "synth").collect();
    assert_eq!(rows.len(), 2);
    assert_eq!(rows[0].gains, Gains::Design);
    assert!(rows[0].converged && !rows[0].failed, "{:?}", rows[0]);
    // Its column is resolved by the group's name in its own spec.
    assert!(rows[0].norms[0].is_some());
    // The periodic law is either certified by a re-solved design or refused
    // and run with the compiled gains: never silently certified.
    let p = rows[1];
    assert!(
        (p.certified && p.gains == Gains::Resolved)
            || (!p.certified && p.gains == Gains::DesignNotCertified),
        "{p:?}"
    );
}
