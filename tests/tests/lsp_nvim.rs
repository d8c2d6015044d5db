//! `tsfc lsp` in a real editor: headless Neovim (Debian package `neovim`)
//! with its built-in LSP client runs tests/lsp/nvim_session.lua on a spec with
//! a mistake: the diagnostic arrives at the right line and column (a UTF-16
//! position, converted by the client), hover shows a constant's value and a
//! set's parameters, go to definition moves the cursor to the declaration,
//! formatting is applied, and fixing the mistake in the buffer clears the
//! diagnostics. The script writes what it saw as JSON; the assertions are
//! here. Skipped, with a message, when `nvim` is not installed.

use crate::common::{spec_path, tsfc_binary};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The whole editor session's time limit.
const SESSION_LIMIT: Duration = Duration::from_secs(60);

fn nvim() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join("nvim"))
        .find(|p| p.is_file())
}

/// 0-based line and byte column of the `k`-th occurrence of `needle` in `text`, plus `shift` bytes.
fn place(text: &str, needle: &str, k: usize, shift: usize) -> (usize, usize) {
    let at = text
        .match_indices(needle)
        .nth(k)
        .unwrap_or_else(|| panic!("`{needle}` #{k} in the spec"))
        .0
        + shift;
    let line = text[..at].matches('\n').count();
    let col = at - text[..at].rfind('\n').map_or(0, |i| i + 1);
    (line, col)
}

#[test]
fn neovim_session() {
    let Some(nvim) = nvim() else {
        println!(
            "SKIPPED lsp_nvim::neovim_session: `nvim` is not installed (Debian package `neovim`)"
        );
        return;
    };
    let good = std::fs::read_to_string(spec_path("inverted_pendulum.tsf")).expect("read spec");
    // The mistake: `gg` for `g`, after a non-ASCII comment on the same line, so
    // a byte column sent as a UTF-16 column would land one column off.
    let line_good = "        g * sinc(theta) / den(theta),";
    assert!(good.contains(line_good), "the pendulum spec changed");
    let fixed_line = "        /* θ */ g * sinc(theta) / den(theta),";
    // And a line out of the canonical layout, for formatting to fix.
    let fixed = good.replacen(line_good, fixed_line, 1).replacen(
        "const a = 1 / (m + Mc);",
        "const a =1/( m+Mc ) ;",
        1,
    );
    let broken = fixed.replacen("/* θ */ g *", "/* θ */ gg *", 1);

    let dir = std::env::temp_dir().join(format!("tsfc-lsp-nvim-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let spec = dir.join("pendulum.tsf");
    std::fs::write(&spec, &broken).expect("write spec");
    let out = dir.join("found.json");
    let _ = std::fs::remove_file(&out);

    let mistake = place(&broken, "gg *", 0, 0);
    let fix_line = mistake.0;
    let fix_text = fixed.lines().nth(fix_line).expect("the fixed line");
    let const_decl = place(&fixed, "const g ", 0, "const ".len());
    let hover_const = place(&fixed, "/* θ */ g *", 0, "/* θ */ ".len());
    let hover_set = place(&fixed, "s is near", 0, "s is ".len());
    let definition_from = place(&fixed, "den(theta),", 0, 1);
    let declaration = place(&fixed, "fn den(", 0, "fn ".len());
    let plan = json!({
        "tsfc": tsfc_binary(),
        "spec": spec,
        "out": out,
        "fix_line": fix_line,
        "fix_text": fix_text,
        "hover_const_decl": [const_decl.0, const_decl.1],
        "hover_const": [hover_const.0, hover_const.1],
        "hover_set": [hover_set.0, hover_set.1],
        "definition_from": [definition_from.0, definition_from.1],
    });
    let plan_path = dir.join("plan.json");
    std::fs::write(&plan_path, plan.to_string()).expect("write plan");

    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("lsp/nvim_session.lua");
    let mut child = Command::new(nvim)
        .args(["--headless", "--clean", "-n", "-c"])
        .arg(format!("luafile {}", script.display()))
        .env("TSFC_LSP_PLAN", &plan_path)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start nvim");
    let start = Instant::now();
    loop {
        if child.try_wait().expect("wait for nvim").is_some() {
            break;
        }
        if start.elapsed() > SESSION_LIMIT {
            let _ = child.kill();
            let _ = child.wait();
            panic!("the Neovim session took more than {SESSION_LIMIT:?}: killed");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let elapsed = start.elapsed();
    let found: Value = serde_json::from_str(
        &std::fs::read_to_string(&out).expect("the session wrote its findings"),
    )
    .expect("findings are JSON");
    println!("Neovim {} session: {elapsed:.2?}", found["nvim"]);
    assert!(
        found.get("error").is_none(),
        "the Lua script failed: {}",
        found["error"]
    );
    assert_eq!(found["client"], true, "the LSP client did not start");

    // The diagnostic at the mistake, at the right line and (byte) column.
    assert_eq!(
        found["opened_diagnostics"], true,
        "no diagnostics arrived: {found:#}"
    );
    let diags = found["diagnostics"].as_array().expect("diagnostics");
    assert_eq!(diags.len(), 1, "one diagnostic expected: {diags:#?}");
    let d = &diags[0];
    assert_eq!(
        (d["line"].as_u64(), d["col"].as_u64()),
        (Some(mistake.0 as u64), Some(mistake.1 as u64)),
        "diagnostic at the wrong place: {d:#}"
    );
    assert_eq!(d["end_col"].as_u64(), Some(mistake.1 as u64 + 2), "{d:#}");
    assert_eq!(d["severity"], 1, "an error: {d:#}");
    let message = d["message"].as_str().unwrap_or_default();
    assert!(
        message.contains("`gg`") && message.contains("did you mean `g`?"),
        "{message}"
    );

    // While the spec is broken (and never checked clean), the hover shows the
    // constant's definition.
    let broken_hover = found["hover_const_broken"].as_str().unwrap_or_default();
    assert!(broken_hover.contains("const g = 9.8;"), "{broken_hover}");

    // The fix (a buffer edit, sent as didChange) clears the diagnostics.
    assert_eq!(
        found["cleared"], true,
        "diagnostics not cleared: {:#}",
        found["diagnostics_after_fix"]
    );

    let hover = found["hover_const"].as_str().unwrap_or_default();
    assert!(
        hover.contains("**constant** `g`") && hover.contains("= 9.8 (scalar)"),
        "{hover}"
    );
    let set = found["hover_set"].as_str().unwrap_or_default();
    assert!(
        set.contains("near = tri(0.6366197723675814, 1, 1)")
            && set.contains("of premise `s`")
            && set.contains("triangle: feet 0.6366197723675814 and 1, peak 1"),
        "{set}"
    );
    assert_eq!(
        found["definition"],
        json!([declaration.0, declaration.1]),
        "go to definition from `den(theta)` should land on `fn den`"
    );
    check_formatting(&found, &fixed);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Formatting replaced the buffer with `tsfc fmt`'s layout of the fixed spec.
fn check_formatting(found: &Value, fixed: &str) {
    let want = tsf_lang::format::format_source(fixed).expect("the fixed spec formats");
    assert_ne!(want, fixed, "the test spec should need formatting");
    assert_eq!(found["format_error"], Value::Null, "{found:#}");
    assert_eq!(found["format_changed"], true, "formatting changed nothing");
    assert_eq!(
        found["formatted"].as_str(),
        Some(want.as_str()),
        "the buffer after formatting is not `tsfc fmt`'s layout"
    );
}
