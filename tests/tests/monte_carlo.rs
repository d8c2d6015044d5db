//! Monte Carlo campaigns (`tsfc simulate --monte-carlo`): reproducible from
//! the seed whatever the thread count, shards merge into the whole run's
//! summary (also through their files), failing runs are counted and listed,
//! and the runs really draw different truth plants.

use std::path::PathBuf;
use std::sync::OnceLock;
use tsfc::driver::prepare;
use tsfc::sim::campaign::summary::{summarize, Partial};
use tsfc::sim::campaign::{merge_dirs, run_campaign, write_campaign, write_shard, Config};
use tsfc::sim::{Options, Prepared};

/// An unstable scalar plant `x' = k x + u + d` stabilized by a certified gain;
/// the campaign scales `k` (up to `k_hi`), the initial state and the disturbance.
fn small_spec(tag: &str, k_hi: f64) -> PathBuf {
    let text = crate::common::scalar_campaign_spec(&format!("mc_{tag}"), 24, k_hi, "");
    let dir = std::env::temp_dir().join(format!("tsfc-mc-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("spec.tsf");
    std::fs::write(&path, text).expect("write spec");
    path
}

fn stable() -> &'static Prepared {
    static P: OnceLock<Prepared> = OnceLock::new();
    P.get_or_init(|| prepare(&small_spec("stable", 1.5)).unwrap_or_else(|e| panic!("{e}")))
}

fn campaign(p: &Prepared, cfg: Config) -> Partial {
    run_campaign(p, &Options::default(), &cfg).unwrap_or_else(|e| panic!("{e}"))
}

fn cfg(jobs: usize, shard: (u64, u64)) -> Config {
    Config {
        jobs: Some(jobs),
        shard,
        ..Config::default()
    }
}

#[test]
fn the_same_seed_gives_the_same_campaign_on_any_thread_count() {
    let one = campaign(stable(), cfg(1, (1, 1)));
    let many = campaign(stable(), cfg(4, (1, 1)));
    assert_eq!(one, many);
    assert_eq!(one.runs.len(), 24);
    let again = campaign(stable(), cfg(2, (1, 1)));
    assert_eq!(summarize(&one), summarize(&again));
    let other = campaign(
        stable(),
        Config {
            seed: Some(12345),
            ..cfg(2, (1, 1))
        },
    );
    assert_ne!(one.runs, other.runs);
    // The runs draw different plants: settle times and transmissions differ.
    let settle: Vec<_> = one.runs.iter().map(|r| r.settle_time_s).collect();
    assert!(settle.iter().any(|s| *s != settle[0]), "{settle:?}");
    assert!(
        one.runs.iter().all(|r| r.converged),
        "{:#?}",
        summarize(&one)
    );
}

#[test]
fn shards_merge_into_the_whole_campaign() {
    let whole = campaign(stable(), cfg(2, (1, 1)));
    let dir = std::env::temp_dir().join(format!("tsfc-mc-shards-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("dir");
    for k in 1..=3 {
        let part = campaign(stable(), cfg(1, (k, 3)));
        assert!(part.runs.iter().all(|r| r.index % 3 == k - 1));
        write_shard(&part, &dir).expect("shard file");
    }
    assert_eq!(
        crate::common::schema::validate_dir(&dir),
        3,
        "the shard files"
    );
    let merged = merge_dirs(std::slice::from_ref(&dir)).expect("merge");
    assert_eq!(merged.runs, whole.runs);
    assert_eq!(merged.envelope, whole.envelope);
    assert_eq!(summarize(&merged), summarize(&whole));
    let out = dir.join("out");
    std::fs::create_dir_all(&out).expect("out");
    let (s, files) = write_campaign(&merged, &out).expect("outputs");
    assert_eq!(s, summarize(&whole));
    assert_eq!(files.len(), 11);
    assert_eq!(
        crate::common::schema::validate_dir(&out),
        2,
        "runs and summary"
    );
    for f in &files {
        assert!(
            std::fs::metadata(f).expect("written").len() > 0,
            "{}",
            f.display()
        );
    }
    // A missing shard is refused.
    std::fs::remove_file(dir.join("mc_stable.mc.shard-2-of-3.json")).expect("remove");
    let e = merge_dirs(&[dir]).expect_err("incomplete");
    assert!(e.message.contains("needs each of 1..=3"), "{}", e.message);
}

#[test]
fn runs_that_fail_are_counted_and_listed() {
    // k up to 40: the certified gain cannot hold the fastest plants.
    let p = prepare(&small_spec("unstable", 40.0)).unwrap_or_else(|e| panic!("{e}"));
    let part = campaign(&p, cfg(2, (1, 1)));
    let s = summarize(&part);
    let failed: Vec<u64> = part
        .runs
        .iter()
        .filter(|r| !r.converged)
        .map(|r| r.index)
        .collect();
    assert!(!failed.is_empty() && failed.len() < 24, "{s:#?}");
    assert_eq!(s.failed, failed.len() as u64);
    assert_eq!(s.runs - s.converged, s.failed);
    assert_eq!(
        s.failures.iter().map(|f| f.index).collect::<Vec<_>>(),
        failed
    );
    assert!(s.markdown().contains("## Failed runs"));
}
