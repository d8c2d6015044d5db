//! The editor packaging (`editors/`): the VS Code extension's manifest and
//! TextMate grammar, and the Neovim syntax file, stay in step with the
//! language: every keyword of the grammar (`lang/src/tsf.pest`), every
//! built-in function and every membership shape is highlighted.

use serde_json::Value;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn read(rel: &str) -> String {
    std::fs::read_to_string(root().join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

fn json(rel: &str) -> Value {
    serde_json::from_str(&read(rel)).unwrap_or_else(|e| panic!("{rel} is not JSON: {e}"))
}

/// The words the grammar spells literally (`"controller"`, `"is"`, ...).
fn grammar_keywords() -> BTreeSet<String> {
    let pest = read("lang/src/tsf.pest");
    let mut words = BTreeSet::new();
    for (k, chunk) in pest.split('"').enumerate() {
        let quoted = k % 2 == 1;
        let is_word = chunk.len() >= 2 && chunk.chars().all(|c| c.is_ascii_lowercase() || c == '_');
        if quoted && is_word {
            words.insert(chunk.to_string());
        }
    }
    words
}

/// The names of the built-in functions, read from their table in the evaluator.
fn builtins() -> BTreeSet<String> {
    let src = read("lang/src/eval/builtins.rs");
    let start = src
        .find("BUILTINS: &[&str] = &[")
        .expect("the BUILTINS table");
    let end = start + src[start..].find("];").expect("the end of BUILTINS");
    src[start..end]
        .split('"')
        .skip(1)
        .step_by(2)
        .map(String::from)
        .collect()
}

/// The membership shapes the checker accepts.
fn shapes() -> BTreeSet<String> {
    let src = read("lang/src/check/premises.rs");
    ["tri", "trap", "gauss", "sigmoid"]
        .into_iter()
        .inspect(|s| {
            assert!(
                src.contains(&format!("\"{s}\"")),
                "shape {s} left the checker"
            )
        })
        .map(String::from)
        .collect()
}

/// Every `\b(?:a|b|c)\b` alternative in the TextMate grammar's patterns.
fn textmate_words(v: &Value, out: &mut BTreeSet<String>) {
    match v {
        Value::Object(m) => {
            if let Some(Value::String(re)) = m.get("match") {
                for group in re.split("(?:").skip(1).chain(re.split("\\b(").skip(1)) {
                    let body = group.split(')').next().unwrap_or("");
                    out.extend(body.split('|').map(String::from));
                }
            }
            m.values().for_each(|x| textmate_words(x, out));
        }
        Value::Array(a) => a.iter().for_each(|x| textmate_words(x, out)),
        _ => {}
    }
}

/// Every word of a `syn keyword` line of the Vim syntax file.
fn vim_words() -> BTreeSet<String> {
    read("editors/nvim/syntax/tsf.vim")
        .lines()
        .filter_map(|l| l.strip_prefix("syn keyword "))
        .flat_map(|l| l.split_whitespace().skip(1).map(String::from))
        .collect()
}

#[test]
fn editor_grammars_know_every_keyword() {
    let mut want = grammar_keywords();
    assert!(
        want.contains("premise") && want.contains("rule") && want.contains("monte_carlo"),
        "keyword extraction broke: {want:?}"
    );
    want.extend(builtins());
    want.extend(shapes());
    let mut textmate = BTreeSet::new();
    textmate_words(
        &json("editors/vscode/syntaxes/tsf.tmLanguage.json"),
        &mut textmate,
    );
    let vim = vim_words();
    let missing_tm: Vec<_> = want.difference(&textmate).collect();
    let missing_vim: Vec<_> = want.difference(&vim).collect();
    assert!(
        missing_tm.is_empty(),
        "editors/vscode/syntaxes/tsf.tmLanguage.json does not highlight {missing_tm:?}"
    );
    assert!(
        missing_vim.is_empty(),
        "editors/nvim/syntax/tsf.vim does not highlight {missing_vim:?}"
    );
}

#[test]
fn vscode_extension_manifest_is_consistent() {
    let pkg = json("editors/vscode/package.json");
    let contributes = &pkg["contributes"];
    let lang = &contributes["languages"][0];
    assert_eq!(lang["id"], "tsf");
    assert_eq!(lang["extensions"][0], ".tsf");
    let grammar = &contributes["grammars"][0];
    assert_eq!(grammar["language"], "tsf");
    let grammar_path = grammar["path"].as_str().expect("grammar path");
    let tm = json(&format!(
        "editors/vscode/{}",
        grammar_path.trim_start_matches("./")
    ));
    assert_eq!(tm["scopeName"], grammar["scopeName"]);
    let config = lang["configuration"]
        .as_str()
        .expect("language configuration");
    json(&format!(
        "editors/vscode/{}",
        config.trim_start_matches("./")
    ));
    let main = pkg["main"].as_str().expect("main");
    let client = read(&format!("editors/vscode/{}", main.trim_start_matches("./")));
    assert!(
        client.contains("'lsp'") && client.contains("vscode-languageclient"),
        "the client must start `tsfc lsp` through vscode-languageclient"
    );
    assert!(pkg["dependencies"]["vscode-languageclient"].is_string());
    assert_eq!(pkg["activationEvents"][0], "onLanguage:tsf");
}
