//! `tsfc lsp` spoken to over its real stdio (JSON-RPC frames, as an editor
//! does): initialize, diagnostics equal to `tsfc check`'s, hover, definition,
//! references, completion, the outline, hostile documents answered within
//! bounds, and error responses for malformed or unknown requests.

use crate::common::{spec_path, tsfc_binary};
use serde_json::{json, Value};
use std::io::{BufRead, BufReader, Read, Write};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{channel, Receiver};
use std::time::{Duration, Instant};
use tsfc::driver::frontend::{self, Source};

/// Longest wait for one answer.
const ANSWER_LIMIT: Duration = Duration::from_secs(30);

const URI: &str = "file:///tmp/pendulum.tsf";

/// A running `tsfc lsp` and the frames it sent.
struct Server {
    child: Child,
    stdin: ChildStdin,
    frames: Receiver<Value>,
    next_id: i64,
}

impl Server {
    fn start() -> Server {
        let mut child = Command::new(tsfc_binary())
            .arg("lsp")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("start tsfc lsp");
        let stdin = child.stdin.take().expect("stdin");
        let mut stdout = BufReader::new(child.stdout.take().expect("stdout"));
        let (tx, frames) = channel();
        std::thread::spawn(move || loop {
            let mut length = 0usize;
            loop {
                let mut line = String::new();
                if stdout.read_line(&mut line).unwrap_or(0) == 0 {
                    return;
                }
                let line = line.trim_end();
                if line.is_empty() {
                    break;
                }
                if let Some(v) = line.strip_prefix("Content-Length:") {
                    length = v.trim().parse().expect("a length");
                }
            }
            let mut body = vec![0; length];
            if stdout.read_exact(&mut body).is_err() {
                return;
            }
            let v: Value = serde_json::from_slice(&body).expect("the server sends JSON");
            if tx.send(v).is_err() {
                return;
            }
        });
        Server {
            child,
            stdin,
            frames,
            next_id: 1,
        }
    }

    fn send_raw(&mut self, body: &[u8]) {
        write!(self.stdin, "Content-Length: {}\r\n\r\n", body.len()).expect("write header");
        self.stdin.write_all(body).expect("write body");
        self.stdin.flush().expect("flush");
    }

    fn notify(&mut self, method: &str, params: Value) {
        let msg = json!({ "jsonrpc": "2.0", "method": method, "params": params });
        self.send_raw(msg.to_string().as_bytes());
    }

    /// Sends a request and waits for its response (notifications in between are dropped).
    fn request(&mut self, method: &str, params: Value) -> Value {
        let id = self.next_id;
        self.next_id += 1;
        let msg = json!({ "jsonrpc": "2.0", "id": id, "method": method, "params": params });
        self.send_raw(msg.to_string().as_bytes());
        self.wait_for(|v| v["id"] == id)
    }

    fn wait_for(&mut self, want: impl Fn(&Value) -> bool) -> Value {
        let deadline = Instant::now() + ANSWER_LIMIT;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.frames.recv_timeout(left) {
                Ok(v) if want(&v) => return v,
                Ok(_) => {}
                Err(e) => panic!("no answer within {ANSWER_LIMIT:?}: {e}"),
            }
        }
    }

    fn diagnostics(&mut self) -> Vec<Value> {
        let v = self.wait_for(|v| v["method"] == "textDocument/publishDiagnostics");
        v["params"]["diagnostics"]
            .as_array()
            .cloned()
            .unwrap_or_default()
    }

    fn initialize(&mut self) -> Value {
        let r = self.request("initialize", json!({ "capabilities": {} }));
        self.notify("initialized", json!({}));
        r
    }

    fn open(&mut self, text: &str) -> Vec<Value> {
        self.notify(
            "textDocument/didOpen",
            json!({ "textDocument": { "uri": URI, "languageId": "tsf", "version": 1, "text": text } }),
        );
        self.diagnostics()
    }

    fn at(&mut self, method: &str, text: &str, needle: &str, shift: usize) -> Value {
        let at = text.find(needle).unwrap_or_else(|| panic!("`{needle}`")) + shift;
        self.request(
            method,
            json!({ "textDocument": { "uri": URI }, "position": position(text, at),
                    "context": { "includeDeclaration": true } }),
        )
    }

    /// shutdown, exit, and the exit code.
    fn stop(mut self) -> Option<i32> {
        let r = self.request("shutdown", Value::Null);
        assert_eq!(r["result"], Value::Null, "{r}");
        self.notify("exit", Value::Null);
        let deadline = Instant::now() + ANSWER_LIMIT;
        while Instant::now() < deadline {
            if let Some(s) = self.child.try_wait().expect("wait") {
                return s.code();
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let _ = self.child.kill();
        panic!("tsfc lsp did not exit after `exit`");
    }
}

/// The LSP position of byte `at` of an ASCII text.
fn position(text: &str, at: usize) -> Value {
    let line = text[..at].matches('\n').count();
    let col = at - text[..at].rfind('\n').map_or(0, |i| i + 1);
    json!({ "line": line, "character": col })
}

fn pendulum() -> String {
    std::fs::read_to_string(spec_path("inverted_pendulum.tsf")).expect("read spec")
}

fn hover_text(v: &Value) -> String {
    v["result"]["contents"]["value"]
        .as_str()
        .unwrap_or_else(|| panic!("a hover: {v}"))
        .to_string()
}

#[test]
fn diagnostics_are_tsfc_checks() {
    // Two mistakes: an unknown name (with a help line) and a duplicate
    // constant (with a secondary label).
    let text = pendulum()
        .replacen(
            "g * sinc(theta) / den(theta)",
            "gg * sinc(theta) / den(theta)",
            1,
        )
        .replacen("const l = 0.5;", "const l = 0.5;\nconst m = 3;", 1);
    let mut s = Server::start();
    let init = s.initialize();
    let caps = &init["result"]["capabilities"];
    for cap in [
        "hoverProvider",
        "definitionProvider",
        "referencesProvider",
        "documentSymbolProvider",
        "documentFormattingProvider",
    ] {
        assert_eq!(caps[cap], true, "{cap}: {caps}");
    }
    let got = s.open(&text);
    let source = Source {
        name: "pendulum.tsf".into(),
        text: text.clone(),
        bytes: text.as_bytes().to_vec(),
    };
    let want = frontend::check(&source).diagnostics;
    assert!(want.len() >= 2, "{want:?}");
    assert_eq!(got.len(), want.len(), "{got:#?}");
    for (g, w) in got.iter().zip(&want) {
        let j = tsf_lang::diag::to_json("pendulum.tsf", &text, w);
        // The text is ASCII: UTF-16 columns are character columns.
        assert_eq!(
            g["range"]["start"],
            json!({ "line": j.line - 1, "character": j.column - 1 }),
            "{g}"
        );
        assert_eq!(
            g["range"]["end"],
            json!({ "line": j.end_line - 1, "character": j.end_column - 1 }),
            "{g}"
        );
        let message = g["message"].as_str().expect("message");
        assert!(message.starts_with(&w.message), "{message}");
        if let Some(h) = &w.help {
            assert!(message.contains(&format!("help: {h}")), "{message}");
        }
        assert_eq!(g["severity"], if w.is_error() { 1 } else { 2 });
        let related = g["relatedInformation"].as_array().map_or(0, Vec::len);
        assert_eq!(related, w.secondary.len(), "{g}");
        for (r, l) in g["relatedInformation"]
            .as_array()
            .into_iter()
            .flatten()
            .zip(&w.secondary)
        {
            assert_eq!(r["message"], l.message.as_str());
            assert_eq!(r["location"]["uri"], URI);
            assert_eq!(
                r["location"]["range"]["start"],
                position(&text, l.span.start)
            );
        }
    }
    assert!(
        got.iter().any(|g| g["relatedInformation"].is_array()),
        "the duplicate constant's first declaration is related information: {got:#?}"
    );
    // The fix, as a full-text change, clears them.
    assert_eq!(change(&mut s, &pendulum(), 2), Vec::<Value>::new());
    assert_eq!(s.stop(), Some(0));
}

#[test]
fn hover_definition_references_completion_outline() {
    let text = pendulum();
    let mut s = Server::start();
    s.initialize();
    assert!(s.open(&text).is_empty(), "the pendulum checks clean");

    let g = hover_text(&s.at(
        "textDocument/hover",
        &text,
        "g * sinc(theta) / den(theta)",
        0,
    ));
    assert!(
        g.contains("**constant** `g`") && g.contains("= 9.8 (scalar)"),
        "{g}"
    );
    let set = hover_text(&s.at("textDocument/hover", &text, "far = trap", 0));
    assert!(
        set.contains("far = trap(-0.25, -0.25, 0.6366197723675814, 1)"),
        "{set}"
    );
    assert!(
        set.contains("trapezoid: feet -0.25 and 1, plateau -0.25 .. 0.6366197723675814"),
        "{set}"
    );
    // The rule's local model at its operating point, as `check --explain` prints it.
    let rule = hover_text(&s.at("textDocument/hover", &text, "rule R2", 5));
    let model = crate::common::shipped("inverted_pendulum.tsf");
    assert!(
        rule.contains(&tsfc::model::explain::rule(&model, 1)),
        "{rule}"
    );
    assert!(
        rule.contains("9.360021") && rule.contains("-0.005236"),
        "{rule}"
    );
    let objective = hover_text(&s.at("textDocument/hover", &text, "decay_rate >= 0.5", 0));
    assert!(objective.contains("V(t) <= V(0) e^{-2 a t}"), "{objective}");
    let matrix = hover_text(&s.at("textDocument/hover", &text, "B(x) =", 0));
    assert!(
        matrix.contains("2 x 1 (n x m), depends on the state"),
        "{matrix}"
    );
    let state = hover_text(&s.at("textDocument/hover", &text, "omega' =", 0));
    assert!(state.contains("x[1] (of 2 components)"), "{state}");

    // Definition of a use of `den`, and its references.
    let def = s.at("textDocument/definition", &text, "den(theta)", 0);
    let decl = text.find("fn den(").unwrap() + 3;
    assert_eq!(
        def["result"]["range"]["start"],
        position(&text, decl),
        "{def}"
    );
    assert_eq!(def["result"]["uri"], URI);
    let refs = s.at("textDocument/references", &text, "den(theta)", 1);
    let refs = refs["result"].as_array().expect("references").clone();
    // `den(` outside comments: the declaration, two uses in A(x), one in B(x), one in R2.
    assert_eq!(refs.len(), 5, "{refs:#?}");
    assert_eq!(refs[0]["range"]["start"], position(&text, decl));
    // A premise's set used in a rule resolves to that premise's set.
    let near = s.at("textDocument/definition", &text, "s is near", 5);
    assert_eq!(
        near["result"]["range"]["start"],
        position(&text, text.find("near = tri").unwrap())
    );

    // Completion: after `s is `, the sets of `s` only; elsewhere keywords and names.
    let sets = s.at("textDocument/completion", &text, "s is near", 5);
    let labels: Vec<&str> = sets["result"]
        .as_array()
        .expect("items")
        .iter()
        .filter_map(|i| i["label"].as_str())
        .collect();
    assert_eq!(labels, ["near", "far"]);
    let all = s.at("textDocument/completion", &text, "objective stability", 0);
    let labels: Vec<&str> = all["result"]
        .as_array()
        .expect("items")
        .iter()
        .filter_map(|i| i["label"].as_str())
        .collect();
    for want in ["premise", "objective", "theta", "den", "R1", "g"] {
        assert!(labels.contains(&want), "{want} in {labels:?}");
    }

    // The outline: declarations in order, the sets under their premise.
    let outline = s.request(
        "textDocument/documentSymbol",
        json!({ "textDocument": { "uri": URI } }),
    );
    let symbols = outline["result"].as_array().expect("symbols");
    let names: Vec<&str> = symbols.iter().filter_map(|x| x["name"].as_str()).collect();
    assert_eq!(
        names,
        [
            "inverted_pendulum",
            "g",
            "m",
            "Mc",
            "l",
            "a",
            "beta",
            "theta",
            "omega",
            "u",
            "den",
            "A",
            "B",
            "s",
            "R1",
            "R2"
        ]
    );
    let premise = symbols
        .iter()
        .find(|x| x["name"] == "s")
        .expect("premise s");
    let sets: Vec<&str> = premise["children"]
        .as_array()
        .expect("sets")
        .iter()
        .filter_map(|x| x["name"].as_str())
        .collect();
    assert_eq!(sets, ["near", "far"]);

    // Formatting: nothing to do on the shipped (formatted) spec; one edit of
    // the whole document with `tsfc fmt`'s layout on a messy one; no edit when
    // the document does not parse.
    let format = |s: &mut Server| {
        s.request("textDocument/formatting", json!({ "textDocument": { "uri": URI }, "options": { "tabSize": 4, "insertSpaces": true } }))
    };
    let clean = format(&mut s);
    let want = tsf_lang::format::format_source(&text).expect("formats");
    if want == text {
        assert_eq!(clean["result"], json!([]), "{clean}");
    }
    let messy = text.replacen("const a = 1 / (m + Mc);", "const a =1/( m+Mc ) ;", 1);
    change(&mut s, &messy, 2);
    let edits = format(&mut s)["result"].as_array().cloned().expect("edits");
    assert_eq!(edits.len(), 1, "{edits:?}");
    assert_eq!(
        edits[0]["range"]["start"],
        json!({ "line": 0, "character": 0 })
    );
    assert_eq!(edits[0]["range"]["end"], position(&messy, messy.len()));
    assert_eq!(
        edits[0]["newText"].as_str(),
        tsf_lang::format::format_source(&messy).ok().as_deref()
    );
    change(&mut s, &messy.replacen("rule R1:", "rule R1", 1), 3);
    assert_eq!(format(&mut s)["result"], Value::Null);
    assert_eq!(s.stop(), Some(0));
}

/// Sends the whole new text and waits for its diagnostics.
fn change(s: &mut Server, text: &str, version: i32) -> Vec<Value> {
    s.notify(
        "textDocument/didChange",
        json!({ "textDocument": { "uri": URI, "version": version }, "contentChanges": [{ "text": text }] }),
    );
    s.diagnostics()
}

#[test]
fn hostile_documents_are_answered_within_bounds() {
    let mut s = Server::start();
    s.initialize();
    let cases = [
        (
            "nesting 100,000 deep",
            format!("const c = {}1{};", "(".repeat(100_000), ")".repeat(100_000)),
        ),
        (
            "4 MB of garbage (inside the size limit)",
            "@#(=; ".repeat(600_000),
        ),
        (
            "10 MB of garbage (over the size limit)",
            "x = ((]; ".repeat(1_200_000),
        ),
        ("1.3 million broken items", "1;\n".repeat(1_300_000)),
        (
            "100,000 functions with the same parameter names",
            "fn f(a, b) = a + b;\n".repeat(100_000),
        ),
        (
            "an unterminated block comment",
            format!("tsf 1; /* {}", "a".repeat(1_000_000)),
        ),
    ];
    for (what, text) in cases {
        let t = Instant::now();
        let diags = s.open(&text);
        let took = t.elapsed();
        println!(
            "{what}: {} bytes, {} diagnostics in {took:.2?}",
            text.len(),
            diags.len()
        );
        assert!(!diags.is_empty(), "{what}: no diagnostic");
        assert!(
            diags.len() <= tsf_lang::limits::MAX_DIAGNOSTICS + 1,
            "{what}: {}",
            diags.len()
        );
        assert!(took < Duration::from_secs(20), "{what}: {took:?}");
        // Every request on it is answered too.
        for method in [
            "textDocument/hover",
            "textDocument/definition",
            "textDocument/references",
            "textDocument/completion",
        ] {
            let t = Instant::now();
            let r = s.request(method, json!({ "textDocument": { "uri": URI }, "position": { "line": 0, "character": 12 }, "context": { "includeDeclaration": true } }));
            assert!(
                r.get("error").is_none() || r["error"]["code"] != -32603,
                "{what} {method}: {r}"
            );
            assert!(
                t.elapsed() < Duration::from_secs(10),
                "{what} {method}: {:?}",
                t.elapsed()
            );
        }
        let r = s.request(
            "textDocument/documentSymbol",
            json!({ "textDocument": { "uri": URI } }),
        );
        assert!(r["result"].is_array(), "{what}: {r}");
    }
    let over = s.open(&"x".repeat(5 << 20));
    assert_eq!(over.len(), 1);
    assert!(
        over[0]["message"]
            .as_str()
            .unwrap_or_default()
            .contains("larger than the limit of 4 MiB"),
        "{over:?}"
    );
    assert_eq!(s.stop(), Some(0));
}

#[test]
fn malformed_and_unknown_requests_get_errors() {
    let mut s = Server::start();
    // Before initialize.
    let early = s.request("textDocument/hover", json!({}));
    assert_eq!(early["error"]["code"], -32002, "{early}");
    s.initialize();
    // Not JSON: a parse error with id null; the server goes on.
    s.send_raw(b"{\"jsonrpc\": \"2.0\", \"id\": 5, \"method\": ");
    let parse = s.wait_for(|v| v.get("error").is_some());
    assert_eq!(parse["error"]["code"], -32700, "{parse}");
    assert_eq!(parse["id"], Value::Null);
    // JSON but not a message.
    s.send_raw(br#"{"jsonrpc": "2.0", "id": 6, "params": [1, 2]}"#);
    let invalid = s.wait_for(|v| v["id"] == 6);
    assert_eq!(invalid["error"]["code"], -32600, "{invalid}");
    s.send_raw(b"[1, 2, 3]");
    let array = s.wait_for(|v| v.get("error").is_some());
    assert_eq!(array["error"]["code"], -32600, "{array}");
    // Unknown method, missing parameters, a document that is not open.
    let unknown = s.request("textDocument/rename", json!({}));
    assert_eq!(unknown["error"]["code"], -32601, "{unknown}");
    let missing = s.request(
        "textDocument/hover",
        json!({ "textDocument": { "uri": URI } }),
    );
    assert_eq!(missing["error"]["code"], -32602, "{missing}");
    let closed = s.request("textDocument/hover", json!({ "textDocument": { "uri": "file:///nope.tsf" }, "position": { "line": 0, "character": 0 } }));
    assert_eq!(closed["error"]["code"], -32602, "{closed}");
    // Unknown notifications are ignored; the server still answers.
    s.notify("$/unknown", json!({ "x": 1 }));
    s.open("tsf 1;\ncontroller c;\n");
    let r = s.request(
        "textDocument/documentSymbol",
        json!({ "textDocument": { "uri": URI } }),
    );
    assert_eq!(r["result"][0]["name"], "c", "{r}");
    assert_eq!(s.stop(), Some(0));
}

#[test]
fn exit_without_shutdown_is_code_1() {
    let mut s = Server::start();
    s.initialize();
    s.notify("exit", Value::Null);
    let t = Instant::now();
    loop {
        if let Some(st) = s.child.try_wait().expect("wait") {
            assert_eq!(st.code(), Some(1));
            return;
        }
        assert!(t.elapsed() < ANSWER_LIMIT, "no exit");
        std::thread::sleep(Duration::from_millis(20));
    }
}
