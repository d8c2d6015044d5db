//! The `tsfc` binary: exit codes, output formats, help and version.

use std::path::PathBuf;
use std::process::{Command, Output};

fn tsfc() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tsfc"))
}

fn fixture(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(rel)
}

#[test]
fn check_exit_codes() {
    let ok = tsfc()
        .arg("check")
        .arg(fixture("specs/inverted_pendulum.tsf"))
        .output()
        .expect("runs");
    assert_eq!(
        ok.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    let bad = tsfc()
        .arg("check")
        .arg(fixture("tests/bad/unknown_name.tsf"))
        .output()
        .expect("runs");
    assert_eq!(bad.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&bad.stderr);
    assert!(stderr.contains("unknown_name.tsf:"), "{stderr}");
    assert!(stderr.contains("unknown name `gg`"), "{stderr}");
    let missing = tsfc()
        .arg("check")
        .arg(fixture("specs/does_not_exist.tsf"))
        .output()
        .expect("runs");
    assert_eq!(missing.status.code(), Some(2));
    let usage = tsfc().arg("check").output().expect("runs");
    assert_eq!(usage.status.code(), Some(2));
    let unknown = tsfc().arg("frobnicate").output().expect("runs");
    assert_eq!(unknown.status.code(), Some(2));
}

#[test]
fn worst_exit_code_wins_over_several_files() {
    let out = tsfc()
        .arg("check")
        .arg(fixture("specs/inverted_pendulum.tsf"))
        .arg(fixture("tests/bad/wrong_version.tsf"))
        .arg(fixture("nope.tsf"))
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn json_format_is_machine_readable() {
    let out = tsfc()
        .args(["check", "--format", "json"])
        .arg(fixture("tests/bad/wrong_shape_A.tsf"))
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("valid JSON");
    let d = &v["files"][0]["diagnostics"][0];
    assert_eq!(v["files"][0]["ok"], false);
    assert_eq!(d["severity"], "error");
    assert!(d["line"].as_u64().expect("line") >= 1);
    assert!(d["message"]
        .as_str()
        .expect("message")
        .contains("`A` must be n x n"));
}

#[test]
fn help_and_version() {
    let v = tsfc().arg("--version").output().expect("runs");
    assert_eq!(v.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&v.stdout).contains(env!("CARGO_PKG_VERSION")));
    let h = tsfc().arg("--help").output().expect("runs");
    assert_eq!(h.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&h.stdout).contains("check"));
}

#[test]
fn binary_garbage_is_a_spec_error_not_a_crash() {
    let dir = std::env::temp_dir().join(format!("tsfc-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("tmp dir");
    let f = dir.join("garbage.tsf");
    std::fs::write(&f, [0xff, 0xfe, 0x00, b'{', 0x80, b';']).expect("write");
    let out = tsfc().arg("check").arg(&f).output().expect("runs");
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not valid UTF-8"));
    let _ = std::fs::remove_dir_all(&dir);
}

fn tmp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tsfc-cli-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("tmp dir");
    dir
}

#[test]
fn compile_writes_a_certified_report() {
    let dir = tmp_dir("compile");
    let out = tsfc()
        .arg("compile")
        .arg(fixture("specs/inverted_pendulum.tsf"))
        .arg("--out")
        .arg(&dir)
        .output()
        .expect("runs");
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(
        &std::fs::read(dir.join("inverted_pendulum.report.json")).expect("report written"),
    )
    .expect("JSON");
    for key in [
        "tsfc_version",
        "spec",
        "controller",
        "n",
        "m",
        "rules",
        "status",
        "objectives",
        "gains",
        "P",
        "certificate",
        "solver",
        "timings_s",
    ] {
        assert!(report.get(key).is_some(), "report lacks `{key}`");
    }
    assert_eq!(report["status"], "certified");
    assert_eq!(report["spec"]["sha256"].as_str().map(str::len), Some(64));
    assert_eq!(report["gains"].as_array().map(Vec::len), Some(2));
    assert_eq!(
        report["gains"][0]["F"].as_array().map(Vec::len),
        Some(1),
        "F is m x n rows"
    );
    assert!(
        report["certificate"]["min_margin"]
            .as_f64()
            .expect("margin")
            > 0.0
    );
    for k in ["parse", "model", "build", "solve", "certify", "total"] {
        assert!(report["timings_s"][k].as_f64().is_some(), "timing {k}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn compile_of_an_infeasible_spec_exits_3_without_gains() {
    let dir = tmp_dir("infeasible");
    let spec = dir.join("tight.tsf");
    let text = std::fs::read_to_string(fixture("specs/inverted_pendulum.tsf")).expect("spec");
    // A decay rate no bounded gain reaches together with a tight input bound.
    let tight = text.replace(
        "objective decay_rate >= 0.5;",
        "objective decay_rate >= 0.5;\nobjective input_norm(u) <= 0.001 for x0 = [1.0, 0];",
    );
    assert_ne!(tight, text, "the spec's decay line changed");
    std::fs::write(&spec, tight).expect("write");
    // An earlier design's outputs in the same folder stay as they were.
    let earlier = [
        ("inverted_pendulum.report.json", "earlier report"),
        ("inverted_pendulum.rs", "earlier code"),
    ];
    for (name, text) in earlier {
        std::fs::write(dir.join(name), text).expect("earlier output");
    }
    let out = tsfc()
        .arg("compile")
        .arg(&spec)
        .arg("--out")
        .arg(&dir)
        .output()
        .expect("runs");
    assert_eq!(
        out.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for (name, text) in earlier {
        assert_eq!(
            std::fs::read_to_string(dir.join(name)).expect("still there"),
            text,
            "{name} changed by a failed compile"
        );
    }
    let report: serde_json::Value = serde_json::from_slice(
        &std::fs::read(dir.join("inverted_pendulum.failed.report.json")).expect("report"),
    )
    .expect("JSON");
    assert_ne!(report["status"], "certified");
    assert_eq!(report["gains"].as_array().map(Vec::len), Some(0));
    assert!(String::from_utf8_lossy(&out.stderr).contains("input_norm"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_failed_compile_leaves_earlier_outputs_untouched() {
    let dir = tmp_dir("atomic");
    let good = fixture("specs/inverted_pendulum.tsf");
    let run = |spec: &std::path::Path| {
        tsfc()
            .arg("compile")
            .arg(spec)
            .arg("--out")
            .arg(&dir)
            .arg("--emit")
            .arg("rust")
            .output()
            .expect("runs tsfc")
    };
    let first = run(&good);
    assert_eq!(
        first.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    let out = dir.join("inverted_pendulum.rs");
    let before = std::fs::read(&out).expect("generated");
    let report = dir.join("inverted_pendulum.report.json");
    let report_before = std::fs::read(&report).expect("report");
    let bad = dir.join("bad.tsf");
    let text = std::fs::read_to_string(&good).expect("spec");
    std::fs::write(
        &bad,
        text.replace(
            "objective decay_rate >= 0.5;",
            "objective decay_rate >= 0.5;\nobjective input_norm(u) <= 0.001 for x0 = [1.0, 0];",
        ),
    )
    .expect("write");
    let second = run(&bad);
    assert_eq!(second.status.code(), Some(3));
    assert_eq!(
        std::fs::read(&out).expect("still there"),
        before,
        "the earlier output changed"
    );
    assert_eq!(
        std::fs::read(&report).expect("still there"),
        report_before,
        "the earlier report changed"
    );
    let failed = dir.join("inverted_pendulum.failed.report.json");
    assert!(failed.exists());
    // A later certified compile removes the refused attempt's report, and says so.
    let third = run(&good);
    assert_eq!(third.status.code(), Some(0));
    assert!(
        !failed.exists(),
        "a stale failed report stayed beside the certified one"
    );
    let stderr = String::from_utf8_lossy(&third.stderr);
    assert!(stderr.contains("failed.report.json (stale)"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs `tsfc compile` on `spec` into `dir` with extra arguments.
fn compile_into(spec: &std::path::Path, dir: &std::path::Path, extra: &[&str]) -> Output {
    tsfc()
        .arg("compile")
        .arg(spec)
        .arg("--out")
        .arg(dir)
        .args(extra)
        .output()
        .expect("runs tsfc")
}

#[cfg(unix)]
#[test]
fn outputs_onto_special_files_are_refused_with_exit_2() {
    let dir = tmp_dir("special");
    let good = fixture("specs/inverted_pendulum.tsf");
    let out = compile_into(&good, &dir, &["--report", "/dev/null", "--emit", "rust"]);
    assert_eq!(
        out.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stderr).contains("not a regular file"));
    // A symlink at an output path is neither followed nor replaced.
    let target = dir.join("elsewhere.txt");
    std::fs::write(&target, "user data").expect("write");
    let link = dir.join("inverted_pendulum.rs");
    std::os::unix::fs::symlink(&target, &link).expect("symlink");
    let out = compile_into(&good, &dir, &["--emit", "rust"]);
    assert_eq!(
        out.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(std::fs::symlink_metadata(&link)
        .expect("link")
        .file_type()
        .is_symlink());
    assert_eq!(
        std::fs::read_to_string(&target).expect("target"),
        "user data"
    );
    // Endless input is read up to the limit only.
    let out = tsfc().args(["check", "/dev/zero"]).output().expect("runs");
    assert_eq!(
        out.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stderr).contains("larger than the limit"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn reports_and_headers_name_the_spec_by_file_name_only() {
    let dir = tmp_dir("names");
    let good = fixture("specs/inverted_pendulum.tsf");
    let absolute = std::fs::canonicalize(&good).expect("absolute path");
    let out = compile_into(&absolute, &dir, &["--emit", "rust,c"]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report =
        std::fs::read_to_string(dir.join("inverted_pendulum.report.json")).expect("report");
    let code = std::fs::read_to_string(dir.join("inverted_pendulum.rs")).expect("code");
    let header = std::fs::read_to_string(dir.join("inverted_pendulum.h")).expect("header");
    let parent = absolute
        .parent()
        .expect("folder")
        .to_string_lossy()
        .into_owned();
    for (what, text) in [("report", &report), ("rust", &code), ("c header", &header)] {
        assert!(!text.contains(&parent), "{what} records the absolute path");
        assert!(
            text.contains("inverted_pendulum.tsf"),
            "{what} names the spec"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn concurrent_compiles_of_one_controller_leave_a_consistent_set() {
    let dir = tmp_dir("concurrent");
    let text = std::fs::read_to_string(fixture("specs/inverted_pendulum.tsf")).expect("spec");
    let a = dir.join("a.tsf");
    let b = dir.join("b.tsf");
    std::fs::write(&a, &text).expect("write");
    // The same controller with a slower decay rate: other gains, other sha256.
    let slower = text.replace(
        "objective decay_rate >= 0.5;",
        "objective decay_rate >= 0.4;",
    );
    assert_ne!(slower, text);
    std::fs::write(&b, slower).expect("write");
    for _ in 0..20 {
        let spawn = |spec: &std::path::Path| {
            tsfc()
                .arg("compile")
                .arg(spec)
                .arg("--out")
                .arg(&dir)
                .args(["--emit", "rust,c"])
                .stderr(std::process::Stdio::null())
                .spawn()
                .expect("spawn")
        };
        let (mut pa, mut pb) = (spawn(&a), spawn(&b));
        assert!(pa.wait().expect("a").success());
        assert!(pb.wait().expect("b").success());
        let report: serde_json::Value = serde_json::from_slice(
            &std::fs::read(dir.join("inverted_pendulum.report.json")).expect("report"),
        )
        .expect("JSON");
        let sha = report["spec"]["sha256"].as_str().expect("sha").to_string();
        for f in [
            "inverted_pendulum.rs",
            "inverted_pendulum.h",
            "inverted_pendulum.c",
        ] {
            let code = std::fs::read_to_string(dir.join(f)).expect("code");
            assert!(
                code.contains(&sha),
                "{f} is not from the spec of the report"
            );
        }
    }
    let leftovers: Vec<String> = std::fs::read_dir(&dir)
        .expect("list")
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains("tsfc-tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The README's first command is `cargo run --release -p tsfc -- compile ...`:
/// with several binaries in the package, cargo needs `default-run`.
#[test]
fn readme_command_runs_the_tsfc_binary_by_default() {
    let manifest =
        std::fs::read_to_string(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("Cargo.toml"))
            .expect("manifest");
    assert!(manifest.contains("default-run = \"tsfc\""));
    let readme = std::fs::read_to_string(fixture("README.md")).expect("README");
    assert!(readme.contains("cargo run --release -p tsfc -- compile specs/"));
}

/// A two-rule spec with `n` states (one scalar premise state and a vector).
fn wide_spec(n: usize) -> String {
    format!(
        "tsf 1;\ncontroller wide;\nstate x1;\nstate s[{k}];\ninput u;\n\
         A = -eye({n}) + 0.1 * ones({n}, {n});\nB(x) = ones({n}, 1) * (1 + 0.1 * x1);\n\
         premise p = x1 range -1 .. 1 {{ lo = trap(-2, -2, -1, 1); hi = trap(-1, 1, 2, 2); }}\n\
         rule R1: p is lo => at(x1 = -1);\nrule R2: p is hi => at(x1 = 1);\n\
         objective stability;\nrelaxation basic;\n",
        k = n - 1
    )
}

#[test]
fn oversized_sdps_are_refused_before_solving_with_the_estimate() {
    let dir = tmp_dir("oversized");
    // 200 states: refused from the dimensions alone (the case aborted
    // inside the solver allocating 3.2 GB).
    let big = dir.join("big.tsf");
    std::fs::write(&big, wide_spec(200)).expect("write");
    let out = compile_into(&big, &dir, &["--emit", "rust"]);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(3), "{err}");
    assert!(
        err.contains("too large to solve") && err.contains("at least"),
        "{err}"
    );
    assert!(err.contains("over the limit of 8.0 GiB"), "{err}");
    // 12 states under a 1 MiB limit: built, estimated, refused, not solved.
    let small = dir.join("small.tsf");
    std::fs::write(&small, wide_spec(12)).expect("write");
    let out = tsfc()
        .env("TSFC_SDP_MEMORY_LIMIT_MB", "1")
        .arg("compile")
        .arg(&small)
        .arg("--out")
        .arg(&dir)
        .output()
        .expect("runs");
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(3), "{err}");
    assert!(err.contains("would need about"), "{err}");
    assert!(err.contains("0 SDP(s)"), "nothing solved: {err}");
    // Within the default limit it compiles and reports its estimate.
    let out = compile_into(&small, &dir, &["--emit", "rust"]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("wide.report.json")).expect("report"))
            .expect("JSON");
    let est = report["solver"]["problem"]["memory_estimate_bytes"]
        .as_u64()
        .expect("estimate");
    assert!(est > 1 << 20 && est < 1 << 30, "{est}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `tsfc simulate SPEC --out DIR ARGS...`: exit code and stderr.
fn simulate(spec: &std::path::Path, dir: &std::path::Path, args: &[&str]) -> (Option<i32>, String) {
    let out = tsfc()
        .arg("simulate")
        .arg(spec)
        .arg("--out")
        .arg(dir)
        .args(args)
        .output()
        .expect("runs");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn simulate_exit_codes_for_bad_overrides_are_2_with_an_error_prefix() {
    let dir = tmp_dir("sim-usage");
    let spec = fixture("specs/inverted_pendulum.tsf");
    for args in [
        &["--horizon", "0"][..],
        &["--horizon", "-1"],
        &["--horizon", "NaN"],
        &["--horizon", "inf"],
        &["--horizon", "1e12"],
        &["--x0", "NaN,0"],
        &["--x0", "inf,0"],
        &["--x0", "1,2,3"],
    ] {
        let (code, stderr) = simulate(&spec, &dir, args);
        assert_eq!(code, Some(2), "{args:?}: {stderr}");
        assert!(stderr.starts_with("error: "), "{args:?}: {stderr}");
    }
    let (_, stderr) = simulate(&spec, &dir, &["--horizon", "1e12"]);
    assert!(stderr.contains("at most 1e7"), "{stderr}");
    assert!(
        std::fs::read_dir(&dir).expect("dir").next().is_none(),
        "refused runs write nothing"
    );
    let (code, stderr) = simulate(&fixture("specs/nope.tsf"), &dir, &[]);
    assert_eq!(code, Some(2));
    assert!(stderr.starts_with("error: cannot read"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn simulate_exits_4_when_the_run_fails_and_0_when_it_does_not() {
    let dir = tmp_dir("sim-fail");
    let spec = fixture("specs/inverted_pendulum.tsf");
    let (code, stderr) = simulate(&spec, &dir, &["--horizon", "0.5"]);
    assert_eq!(code, Some(0), "{stderr}");
    // 172 degrees: outside the premise range of sinc(theta).
    let (code, stderr) = simulate(&spec, &dir, &["--horizon", "0.5", "--x0", "3,0"]);
    assert_eq!(code, Some(4), "{stderr}");
    assert!(
        stderr.contains("error: the state left the premise region"),
        "{stderr}"
    );
    // x0 = [1e160, 0]: beyond the simulator's state range, a usage error.
    let (code, stderr) = simulate(&spec, &dir, &["--horizon", "0.5", "--x0", "1e160,0"]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("beyond 1e150"), "{stderr}");
    // x0 = [1e149, 0]: never "converged", the state leaves the range.
    let (code, stderr) = simulate(&spec, &dir, &["--horizon", "0.5", "--x0", "1e149,0"]);
    assert_eq!(code, Some(4), "{stderr}");
    assert!(stderr.contains("not converged"), "{stderr}");
    assert!(stderr.contains("NaN, infinite or beyond 1e150"), "{stderr}");
    let metrics: serde_json::Value = serde_json::from_slice(
        &std::fs::read(dir.join("inverted_pendulum.metrics.json")).expect("outputs are written"),
    )
    .expect("JSON");
    assert_eq!(metrics["converged"], false);
    assert_eq!(metrics["failed"], true);
    assert_eq!(metrics["initial_state_norm"], 1e149);
    let help = tsfc().args(["simulate", "--help"]).output().expect("runs");
    assert!(String::from_utf8_lossy(&help.stdout).contains("4 the run went non-finite"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn simulate_errors_from_the_spec_exit_1_or_3_and_point_into_it() {
    let dir = tmp_dir("sim-spec");
    let text = std::fs::read_to_string(fixture("specs/inverted_pendulum.tsf")).expect("spec");
    // 5e7 steps: accepted by `check`, over the simulator's limit.
    let long = dir.join("long.tsf");
    std::fs::write(
        &long,
        text.replace("time = 0 .. 5 step 0.001;", "time = 0 .. 50000 step 0.001;"),
    )
    .expect("write");
    let line = text
        .lines()
        .position(|l| l.starts_with("simulate {"))
        .expect("simulate block")
        + 1;
    let (code, stderr) = simulate(&long, &dir, &[]);
    assert_eq!(code, Some(1), "{stderr}");
    assert!(stderr.starts_with("error: cannot simulate"), "{stderr}");
    assert!(stderr.contains(&format!("long.tsf:{line}:1")), "{stderr}");
    // ... and a horizon override makes it usable.
    let (code, stderr) = simulate(&long, &dir, &["--horizon", "0.2"]);
    assert_eq!(code, Some(0), "{stderr}");
    // A design that is not certified: exit 3, with the prefix.
    let tight = dir.join("tight.tsf");
    std::fs::write(
        &tight,
        text.replace(
            "objective decay_rate >= 0.5;",
            "objective decay_rate >= 0.5;\nobjective input_norm(u) <= 0.001 for x0 = [1.0, 0];",
        ),
    )
    .expect("write");
    let (code, stderr) = simulate(&tight, &dir, &[]);
    assert_eq!(code, Some(3), "{stderr}");
    assert!(stderr.starts_with("error: "), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn simulate_refuses_a_csv_target_that_is_not_a_regular_file() {
    let dir = tmp_dir("sim-special");
    let spec = fixture("specs/inverted_pendulum.tsf");
    let csv = dir.join("inverted_pendulum.csv");
    let elsewhere = dir.join("elsewhere.txt");
    std::fs::write(&elsewhere, "keep me\n").expect("write");
    std::os::unix::fs::symlink(&elsewhere, &csv).expect("symlink");
    let (code, stderr) = simulate(&spec, &dir, &["--horizon", "0.1"]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("not a regular file"), "{stderr}");
    assert!(std::fs::symlink_metadata(&csv)
        .expect("still there")
        .file_type()
        .is_symlink());
    assert_eq!(
        std::fs::read_to_string(&elsewhere).expect("read"),
        "keep me\n"
    );
    std::fs::remove_file(&csv).expect("remove link");
    std::fs::create_dir(&csv).expect("a folder in the way");
    let (code, stderr) = simulate(&spec, &dir, &["--horizon", "0.1"]);
    assert_eq!(code, Some(2), "{stderr}");
    let names: Vec<String> = std::fs::read_dir(&dir)
        .expect("dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    assert!(
        names.iter().all(|n| !n.contains(".tmp")),
        "no temporary file is left: {names:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// An adaptive spec's `emit rust, c;` writes the Rust module, the C files
/// and the C runtime next to its report; `--emit` overrides it; `precision
/// f32` is refused at generation (exit 3, no outputs).
#[test]
fn compile_of_an_adaptive_spec_writes_its_code() {
    let dir = tmp_dir("adaptive");
    let spec = fixture("specs/wang2013_adaptive_mrac.tsf");
    let out = compile_into(&spec, &dir, &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    for f in [
        "wang_adaptive.adaptive.json",
        "wang_adaptive.rs",
        "wang_adaptive.h",
        "wang_adaptive.c",
        "tsf_runtime.h",
        "tsf_runtime.c",
    ] {
        assert!(dir.join(f).exists(), "{f}: {stderr}");
    }
    let only_rust = tmp_dir("adaptive-rust");
    let out = compile_into(&spec, &only_rust, &["--emit", "rust"]);
    assert_eq!(out.status.code(), Some(0));
    assert!(only_rust.join("wang_adaptive.rs").exists());
    assert!(!only_rust.join("wang_adaptive.c").exists());
    let f32 = dir.join("f32.tsf");
    let text = std::fs::read_to_string(&spec).expect("spec");
    std::fs::write(&f32, format!("{text}\nprecision f32;\n")).expect("write");
    let refused = tmp_dir("adaptive-f32");
    let out = compile_into(&f32, &refused, &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    // A spec error at check time (lang/src/check/compat), with the span.
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("generated in f64 only"), "{stderr}");
    assert!(stderr.contains("f32.tsf:"), "{stderr}");
    assert!(!refused.join("wang_adaptive.rs").exists());
    for d in [dir, only_rust, refused] {
        let _ = std::fs::remove_dir_all(&d);
    }
}

/// Issue 33: a sector premise that is 0/0 at the equilibrium is refused by
/// `check` and `compile` (exit 1) at the division, file:line:col, with
/// `exprel` as the fix; nothing is written.
#[test]
fn zero_over_zero_premise_is_refused_by_check_and_compile() {
    let spec = fixture("tests/bad/premise_zero_over_zero.tsf");
    let check = tsfc().arg("check").arg(&spec).output().expect("runs");
    let dir = tmp_dir("zero_over_zero");
    let compile = compile_into(&spec, &dir, &[]);
    for out in [&check, &compile] {
        assert_eq!(out.status.code(), Some(1));
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("premise `s` is not finite at x = 0 (0/0)"),
            "{err}"
        );
        assert!(err.contains("premise_zero_over_zero.tsf:31:13"), "{err}");
        assert!(
            err.contains("help: a removable singularity: write it with `exprel`"),
            "{err}"
        );
    }
    assert!(!dir.join("cstr_zero_over_zero.c").exists());
}
