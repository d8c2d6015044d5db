//! The playground (docs/playground.md) in headless Chromium: `playground/build.sh`
//! builds the page (or `TSFC_PLAYGROUND_DIR` names a folder CI built), a
//! loopback file server in this test serves it, and the test drives the page
//! over the DevTools protocol on a pipe (`--remote-debugging-pipe`): it
//! certifies the Zhang and the regional Xu examples in the page and compares
//! them with the native compiler, types a mistake and finds its diagnostic at
//! the right line, and sees no console error. Skipped, with a message, when
//! `chromium` or the `wasm32-wasip1` target is missing.

use crate::common::{chromium, fresh_dir, spec_path, tsfc_binary};
use serde_json::{json, Value};
use std::io::{BufRead, BufReader, Write};
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use std::time::{Duration, Instant};

/// Whether rustup has the playground's target.
fn wasm_target() -> bool {
    Command::new("rustup")
        .args(["target", "list", "--installed"])
        .output()
        .is_ok_and(|o| {
            String::from_utf8_lossy(&o.stdout)
                .lines()
                .any(|l| l == "wasm32-wasip1")
        })
}

/// The built page: `TSFC_PLAYGROUND_DIR`, else `playground/build.sh` into `dir`.
fn built_page(dir: &Path) -> PathBuf {
    if let Some(d) = std::env::var_os("TSFC_PLAYGROUND_DIR") {
        return PathBuf::from(d);
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let out = dir.join("site");
    let status = Command::new("sh")
        .arg(root.join("playground/build.sh"))
        .arg(&out)
        .status()
        .expect("run playground/build.sh");
    assert!(status.success(), "playground/build.sh failed");
    out
}

/// Serves the files of `dir` on a loopback port (GET only, no listing);
/// returns the base URL. Any path outside the folder's files is a 404.
fn serve(dir: PathBuf) -> String {
    let listener = TcpListener::bind("127.0.0.1:0").expect("a loopback port");
    let port = listener.local_addr().expect("its address").port();
    std::thread::spawn(move || {
        for stream in listener.incoming().flatten() {
            let dir = dir.clone();
            std::thread::spawn(move || {
                let mut stream = stream;
                let mut line = String::new();
                let mut reader = BufReader::new(&mut stream);
                if reader.read_line(&mut line).is_err() {
                    return;
                }
                loop {
                    let mut h = String::new();
                    if reader.read_line(&mut h).map_or(true, |n| n == 0) || h.trim().is_empty() {
                        break;
                    }
                }
                let path = line.split(' ').nth(1).unwrap_or("/");
                let path = path
                    .split('?')
                    .next()
                    .unwrap_or("/")
                    .trim_start_matches('/');
                let name = if path.is_empty() { "index.html" } else { path };
                let file = (!name.contains("..") && !name.contains('/'))
                    .then(|| std::fs::read(dir.join(name)).ok())
                    .flatten();
                let kind = match name.rsplit('.').next() {
                    Some("html") => "text/html; charset=utf-8",
                    Some("js") => "text/javascript",
                    Some("css") => "text/css",
                    Some("wasm") => "application/wasm",
                    _ => "application/octet-stream",
                };
                let (head, body) = match file {
                    Some(b) => (format!("200 OK\r\nContent-Type: {kind}"), b),
                    None => ("404 Not Found".to_string(), b"not found".to_vec()),
                };
                let _ = write!(
                    stream,
                    "HTTP/1.1 {head}\r\nContent-Length: {}\r\nConnection: close\r\n\r\n",
                    body.len()
                );
                let _ = stream.write_all(&body);
            });
        }
    });
    format!("http://127.0.0.1:{port}/")
}

/// A DevTools protocol session with one page over Chromium's pipe (fd 3 in,
/// fd 4 out, messages separated by NUL); every event seen is kept.
struct Browser {
    child: Child,
    to: ChildStdin,
    from: BufReader<ChildStdout>,
    next: u64,
    session: String,
    events: Vec<Value>,
}

impl Browser {
    fn launch(chromium: &Path, profile: &Path) -> Browser {
        // sh puts our pipes on the descriptors Chromium reads and writes.
        let mut child = Command::new("sh")
            .arg("-c")
            .arg(r#"exec "$0" "$@" 3<&0 4>&1 </dev/null >/dev/null 2>/dev/null"#)
            .arg(chromium)
            .args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--no-first-run",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--hide-scrollbars",
                "--remote-debugging-pipe",
                "--window-size=1400,1000",
            ])
            .arg(format!("--user-data-dir={}", profile.display()))
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .expect("chromium starts");
        let to = child.stdin.take().expect("its input pipe");
        let from = BufReader::new(child.stdout.take().expect("its output pipe"));
        let mut b = Browser {
            child,
            to,
            from,
            next: 0,
            session: String::new(),
            events: Vec::new(),
        };
        let target = b.call("Target.createTarget", json!({ "url": "about:blank" }));
        let attached = b.call(
            "Target.attachToTarget",
            json!({ "targetId": target["targetId"], "flatten": true }),
        );
        b.session = attached["sessionId"]
            .as_str()
            .expect("a session")
            .to_string();
        for domain in ["Runtime.enable", "Log.enable", "Page.enable"] {
            b.call(domain, json!({}));
        }
        b
    }

    /// Sends a command (to the page once attached) and returns its result.
    fn call(&mut self, method: &str, params: Value) -> Value {
        self.next += 1;
        let mut msg = json!({ "id": self.next, "method": method, "params": params });
        if !self.session.is_empty() {
            msg["sessionId"] = json!(self.session);
        }
        self.to
            .write_all(msg.to_string().as_bytes())
            .expect("write to chromium");
        self.to.write_all(b"\0").expect("write to chromium");
        self.to.flush().expect("flush");
        loop {
            let mut buf = Vec::new();
            let n = self
                .from
                .read_until(0, &mut buf)
                .expect("read from chromium");
            assert!(n > 0, "chromium closed the pipe");
            buf.pop();
            let v: Value = serde_json::from_slice(&buf).expect("a DevTools message");
            if v["id"] == json!(self.next) {
                assert!(v.get("error").is_none(), "{method}: {v}");
                return v["result"].clone();
            }
            self.events.push(v);
        }
    }

    /// Sends a command to the browser itself (not to the page).
    fn browser_call(&mut self, method: &str, params: Value) -> Value {
        let session = std::mem::take(&mut self.session);
        let r = self.call(method, params);
        self.session = session;
        r
    }

    /// Evaluates `expr` in the page (awaiting a promise) and returns its value.
    fn eval(&mut self, expr: &str) -> Value {
        let r = self.call(
            "Runtime.evaluate",
            json!({ "expression": expr, "awaitPromise": true, "returnByValue": true }),
        );
        assert!(r.get("exceptionDetails").is_none(), "{expr}: {r}");
        r["result"]["value"].clone()
    }

    /// Polls `expr` until it is true (panics after `secs` seconds).
    fn wait(&mut self, expr: &str, secs: u64) {
        let start = Instant::now();
        while self.eval(expr) != json!(true) {
            assert!(
                start.elapsed() < Duration::from_secs(secs),
                "timed out waiting for {expr}"
            );
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    /// The console errors, exceptions and error log entries seen so far.
    fn errors(&self) -> Vec<String> {
        self.events
            .iter()
            .filter(|e| {
                let p = &e["params"];
                match e["method"].as_str() {
                    Some("Runtime.consoleAPICalled") => p["type"] == "error",
                    Some("Runtime.exceptionThrown") => true,
                    Some("Log.entryAdded") => p["entry"]["level"] == "error",
                    _ => false,
                }
            })
            .map(Value::to_string)
            .collect()
    }

    /// A PNG screenshot of the page.
    fn screenshot(&mut self, path: &Path) {
        let r = self.call("Page.captureScreenshot", json!({ "format": "png" }));
        let png = decode_base64(r["data"].as_str().expect("image data"));
        std::fs::write(path, png).expect("write the screenshot");
    }
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn decode_base64(s: &str) -> Vec<u8> {
    let val = |c: u8| match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        _ => 63,
    };
    let bytes: Vec<u8> = s.bytes().filter(|&c| c != b'=').collect();
    let mut out = Vec::new();
    for chunk in bytes.chunks(4) {
        let n = chunk
            .iter()
            .fold(0u32, |a, &c| (a << 6) | u32::from(val(c)))
            << (6 * (4 - chunk.len()));
        out.extend(&n.to_be_bytes()[1..chunk.len()]);
    }
    out
}

/// The native compile of a shipped spec with C: its report and its files by name.
fn native(name: &str, out: &Path) -> (Value, Vec<(String, String)>) {
    let o = Command::new(tsfc_binary())
        .arg("compile")
        .arg(spec_path(name))
        .arg("--out")
        .arg(out)
        .args(["--emit", "rust", "--emit", "c"])
        .output()
        .expect("tsfc runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut files = Vec::new();
    for e in std::fs::read_dir(out).expect("the output folder").flatten() {
        let n = e.file_name().to_string_lossy().into_owned();
        if n.starts_with('.') {
            continue; // the output folder's lock
        }
        files.push((
            n,
            std::fs::read_to_string(e.path()).expect("an output file"),
        ));
    }
    files.sort();
    let report = files
        .iter()
        .find(|f| f.0.ends_with(".report.json"))
        .map(|f| serde_json::from_str(&f.1).expect("JSON"));
    (report.expect("a report"), files)
}

/// The objective's gamma: H-infinity or L-infinity (whichever the spec asks for).
fn gamma(report: &Value) -> f64 {
    let o = &report["objectives"];
    o["hinf_gamma"]
        .as_f64()
        .or(o["linf_gamma"].as_f64())
        .expect("a gamma")
}

/// `s` with every decimal number (with a point or exponent) replaced by `#`,
/// and those numbers.
fn masked(s: &str) -> (Vec<u8>, Vec<f64>) {
    let b = s.as_bytes();
    let (mut text, mut nums, mut i) = (Vec::new(), Vec::new(), 0);
    while i < b.len() {
        let after_ident = i > 0 && (b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_');
        if !after_ident && b[i].is_ascii_digit() {
            let mut j = i;
            while j < b.len()
                && (b[j].is_ascii_digit()
                    || matches!(b[j], b'.' | b'e' | b'E')
                    || (matches!(b[j], b'-' | b'+') && matches!(b[j - 1], b'e' | b'E')))
            {
                j += 1;
            }
            let word = &s[i..j];
            match word.parse::<f64>() {
                Ok(v) if word.contains(['.', 'e', 'E']) => {
                    nums.push(v);
                    text.push(b'#');
                }
                _ => text.extend_from_slice(word.as_bytes()),
            }
            i = j;
        } else {
            text.push(b[i]);
            i += 1;
        }
    }
    (text, nums)
}

/// `a` and `b` are the same text once the numbers are masked, and each pair
/// of numbers differs by at most 1e-3 times the largest magnitude in `b`.
fn same_c_up_to_rounding(a: &str, b: &str, spec: &str) {
    let ((ta, na), (tb, nb)) = (masked(a), masked(b));
    assert!(
        ta == tb,
        "{spec}: the generated C differs beyond its numbers"
    );
    let scale = nb.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (x, y) in na.iter().zip(&nb) {
        assert!(
            (x - y).abs() <= 1e-3 * scale,
            "{spec}: {x} in the page, {y} natively"
        );
    }
}

/// The code pane's Copy and Download buttons on the generated file `name`
/// (certified just before): the clipboard and the downloaded file hold
/// exactly the text the compiler returned for it.
fn copy_and_download(b: &mut Browser, url: &str, name: &str, text: &str, dir: &Path) {
    let downloads = dir.join("downloads");
    std::fs::create_dir_all(&downloads).expect("downloads folder");
    let origin = url.trim_end_matches('/');
    b.browser_call(
        "Browser.grantPermissions",
        json!({ "origin": origin, "permissions": ["clipboardReadWrite", "clipboardSanitizedWrite"] }),
    );
    b.browser_call(
        "Browser.setDownloadBehavior",
        json!({ "behavior": "allow", "downloadPath": downloads.display().to_string() }),
    );
    // Headless pages are never focused; the clipboard needs focus.
    b.call(
        "Emulation.setFocusEmulationEnabled",
        json!({ "enabled": true }),
    );
    let copied = b.eval(&format!(
        "(async () => {{ const s = document.getElementById('files'); s.value = {name:?}; \
         s.dispatchEvent(new Event('change')); document.getElementById('copy').click(); \
         await new Promise(r => setTimeout(r, 200)); return await navigator.clipboard.readText(); }})()"
    ));
    assert_eq!(
        copied.as_str(),
        Some(text),
        "Copy: the clipboard is not {name}"
    );
    b.eval("document.getElementById('download').click()");
    let file = downloads.join(name);
    let start = Instant::now();
    while !file.exists() || std::fs::read(&file).map_or(0, |d| d.len()) < text.len() {
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "Download: {} was not written",
            file.display()
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    assert_eq!(
        std::fs::read_to_string(&file).expect("the download"),
        text,
        "Download: the file is not {name}"
    );
}

/// Certifies the example `name` in the page; returns the page's answer.
fn certify_in_page(b: &mut Browser, name: &str) -> Value {
    b.eval(&format!(
        "(async () => {{ openExample({name:?}); await certify(); \
         const r = window.lastCertify; return {{ ms: r.ms, status: r.result.status, \
         report: r.result.report, files: r.result.files, \
         summary: document.getElementById('summary').textContent, \
         rows: document.querySelectorAll('#certificate tbody tr').length }}; }})()"
    ))
}

#[test]
fn playground_certifies_in_chromium_like_the_native_compiler() {
    let Some(chromium) = chromium() else {
        eprintln!("SKIPPED playground_certifies_in_chromium_like_the_native_compiler: `chromium` is not installed (apt-get install chromium)");
        return;
    };
    if std::env::var_os("TSFC_PLAYGROUND_DIR").is_none() && !wasm_target() {
        eprintln!("SKIPPED playground_certifies_in_chromium_like_the_native_compiler: the wasm32-wasip1 target is not installed (rustup target add wasm32-wasip1)");
        return;
    }
    let dir = fresh_dir("playground", "chromium");
    let url = serve(built_page(&dir));
    let mut b = Browser::launch(&chromium, &dir.join("profile"));
    b.call("Page.navigate", json!({ "url": url }));
    b.wait("document.body && document.body.dataset.ready === '1'", 120);
    // The console route sees an error (then the page must log none).
    b.eval("console.error('tsfc-probe-error')");
    assert!(
        b.errors().iter().any(|e| e.contains("tsfc-probe-error")),
        "no console route"
    );
    b.events.clear();

    let shots = std::env::var_os("TSFC_PLAYGROUND_SHOTS").map(PathBuf::from);
    for (spec, tag) in [
        ("zhang2013_multiobjective.tsf", "zhang"),
        ("xu2020_regional.tsf", "xu"),
    ] {
        let page = certify_in_page(&mut b, spec);
        assert_eq!(page["status"], "certified", "{spec}: {page}");
        let report: Value =
            serde_json::from_str(page["report"].as_str().expect("report")).expect("JSON");
        let lmis = report["certificate"]["lmis"]
            .as_array()
            .expect("LMIs")
            .len();
        assert_eq!(page["rows"], json!(lmis), "{spec}: a table row per LMI");
        let page_files: Vec<(String, String)> = page["files"]
            .as_array()
            .expect("files")
            .iter()
            .map(|f| {
                (
                    f["name"].as_str().unwrap_or("").to_string(),
                    f["text"].as_str().unwrap_or("").to_string(),
                )
            })
            .collect();
        let (native_report, native_files) = native(spec, &dir.join(tag));
        let (g_page, g_native) = (gamma(&report), gamma(&native_report));
        let mut page_sorted: Vec<&String> = page_files.iter().map(|f| &f.0).collect();
        page_sorted.sort();
        let native_names: Vec<&String> = native_files.iter().map(|f| &f.0).collect();
        assert_eq!(page_sorted, native_names, "{spec}: the same files");
        let identical: Vec<&str> = native_files
            .iter()
            .filter(|(n, t)| page_files.iter().any(|(pn, pt)| pn == n && pt == t))
            .map(|(n, _)| n.as_str())
            .collect();
        eprintln!(
            "{spec}: page {:.0} ms, gamma page {g_page:e}, native {g_native:e}, byte-identical files: {identical:?}",
            page["ms"].as_f64().unwrap_or(f64::NAN),
        );
        assert!(
            page["summary"]
                .as_str()
                .is_some_and(|s| s.contains("_gamma")),
            "{page}"
        );
        assert!(
            (g_page - g_native).abs() <= 1e-8 * g_native.abs(),
            "{spec}: gamma {g_page} in the page, {g_native} natively"
        );
        // Not byte-identical (docs/playground.md, "Same results?"): the same
        // text, the numbers within a thousandth of the file's largest one.
        for (name, text) in &native_files {
            if name.ends_with(".c") || name.ends_with(".h") {
                let page_text = &page_files
                    .iter()
                    .find(|f| &f.0 == name)
                    .expect("the file")
                    .1;
                same_c_up_to_rounding(page_text, text, name);
            }
        }
        if let Some(d) = &shots {
            b.screenshot(&d.join(format!("playground_{tag}.png")));
        }
        if tag == "zhang" {
            let (name, text) = page_files
                .iter()
                .find(|f| f.0.ends_with(".c") && !f.0.starts_with("tsf_runtime"))
                .expect("the controller's C file");
            copy_and_download(&mut b, &url, name, text, &dir);
        }
    }

    // The Zhang scenario simulated in the page: its plots drawn, the samples
    // and the verdict the native simulator gives.
    let sim = b.eval(
        "(async () => { openExample('zhang2013_multiobjective.tsf'); await simulate(); \
         const r = window.lastSimulate.result; return { error: r.error || null, \
         samples: r.metrics && r.metrics.samples, converged: r.metrics && r.metrics.converged, \
         svgs: (r.plots || []).filter(p => p.svg.startsWith('<svg') && p.svg.includes('<text')).length, \
         imgs: document.querySelectorAll('#plots svg').length, \
         font: [...document.fonts].some(f => f.family.replace(/\"/g, '') === 'tsfc-sans' && f.status === 'loaded') }; })()",
    );
    let o = Command::new(tsfc_binary())
        .arg("simulate")
        .arg(spec_path("zhang2013_multiobjective.tsf"))
        .arg("--out")
        .arg(dir.join("sim"))
        .output()
        .expect("tsfc simulate");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let metrics: Value = serde_json::from_slice(
        &std::fs::read(dir.join("sim/zhang_multiobjective.metrics.json")).expect("metrics"),
    )
    .expect("JSON");
    assert_eq!(sim["error"], Value::Null, "{sim}");
    assert_eq!(sim["samples"], metrics["samples"], "{sim}");
    assert_eq!(sim["converged"], metrics["converged"], "{sim}");
    assert!(
        sim["svgs"].as_u64() >= Some(3) && sim["imgs"] == sim["svgs"] && sim["font"] == true,
        "{sim}"
    );

    if let Some(d) = &shots {
        b.eval("document.getElementById('plots').scrollIntoView()");
        b.screenshot(&d.join("playground_simulate.png"));
    }

    // A mistake on line 3: the page lists it at line 3 (as `tsfc check` does).
    let text = std::fs::read_to_string(spec_path("zhang2013_multiobjective.tsf")).expect("spec");
    let mut lines: Vec<&str> = text.lines().collect();
    lines.insert(2, "stat x9 = ;");
    let broken = lines.join("\n") + "\n";
    b.eval(&format!(
        "(() => {{ const s = document.getElementById('source'); s.value = {broken:?}; \
         s.dispatchEvent(new Event('input')); }})()"
    ));
    b.wait(
        "document.querySelector('#diagnostics li.error') !== null",
        30,
    );
    let first = b.eval("document.querySelector('#diagnostics li.error').dataset.line");
    let check_file = dir.join("broken.tsf");
    std::fs::write(&check_file, &broken).expect("write");
    let o = Command::new(tsfc_binary())
        .args(["check", "--format", "json"])
        .arg(&check_file)
        .output()
        .expect("tsfc check");
    let doc: Value = serde_json::from_slice(&o.stdout).expect("check JSON");
    let native_line = &doc["files"][0]["diagnostics"][0]["line"];
    assert_eq!(native_line, &json!(3), "{doc}");
    assert_eq!(
        first.as_str(),
        Some("3"),
        "the page's first error is not at line 3"
    );
    assert_eq!(
        b.eval("document.querySelectorAll('#highlight .err').length > 0"),
        json!(true),
        "the mistake is not underlined in the editor"
    );
    if let Some(d) = &shots {
        b.eval("window.scrollTo(0, 0)");
        b.screenshot(&d.join("playground_diagnostic.png"));
    }
    let errors = b.errors();
    assert!(errors.is_empty(), "console errors: {errors:#?}");
    drop(b);
    let _ = std::fs::remove_dir_all(&dir);
}
