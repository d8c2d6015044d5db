//! The checkers on synthetic sources: each must flag what it is for and
//! nothing in strings, comments or tests.

use super::items::{functions, length_violations, undocumented};
use super::stages::stage_violations;

/// Asserts that violation `k` of `v` starts with `prefix`.
fn starts(v: &[String], k: usize, prefix: &str) {
    assert!(
        v.get(k).is_some_and(|m| m.starts_with(prefix)),
        "violation {k} should start with {prefix:?}: {v:#?}"
    );
}

/// A small crate: (path under compiler/src, text).
fn krate(files: &[(&str, &str)]) -> Vec<(String, String)> {
    let mut base = vec![
        ("lib.rs", "pub mod model; pub mod synth; pub mod certify;\npub use certify::{Certificate, Verdict as V};\n"),
        ("model/mod.rs", "pub struct TsModel;\n"),
        ("synth/mod.rs", "use crate::model::TsModel;\n"),
        ("certify/mod.rs", "use crate::{model::TsModel, synth};\npub struct Certificate;\n"),
    ];
    base.retain(|(p, _)| !files.iter().any(|(q, _)| q == p));
    base.iter()
        .chain(files)
        .map(|(p, t)| (p.to_string(), t.to_string()))
        .collect()
}

#[test]
fn tidy_stage_checker_accepts_paths_down_the_order() {
    assert_eq!(stage_violations(&krate(&[])), Vec::<String>::new());
}

#[test]
fn tidy_stage_checker_flags_a_crate_path_up_the_order() {
    let files = krate(&[("synth/a.rs", "//! A.\n\nuse crate::certify;\n")]);
    let v = stage_violations(&files);
    starts(
        &v,
        0,
        "compiler/src/synth/a.rs:3: synth (rank 2) uses certify (rank 3",
    );
    assert!(v[0].ends_with("`use crate::certify;`"), "{v:?}");
    // synth -> certify -> synth closes a cycle.
    starts(&v, 1, "cycle certify -> synth -> certify: ");
    assert!(
        v[1].contains("synth -> certify at compiler/src/synth/a.rs:3"),
        "{v:?}"
    );
    assert_eq!(v.len(), 2, "{v:?}");
}

#[test]
fn tidy_stage_checker_flags_one_member_of_a_group() {
    let src = "use crate::{\n    model::TsModel,\n    certify::{self, Certificate},\n};\n";
    let v = stage_violations(&krate(&[("synth/a.rs", src)]));
    starts(
        &v,
        0,
        "compiler/src/synth/a.rs:3: synth (rank 2) uses certify",
    );
    assert!(!v.iter().any(|m| m.contains("uses model")), "{v:?}");
}

#[test]
fn tidy_stage_checker_follows_re_exports_of_the_crate_root() {
    let v = stage_violations(&krate(&[("model/a.rs", "fn f(_: crate::V) {}\n")]));
    starts(
        &v,
        0,
        "compiler/src/model/a.rs:1: model (rank 1) uses certify",
    );
    let v = stage_violations(&krate(&[("model/a.rs", "use crate::helper;\n")]));
    assert!(
        v[0].contains("model (rank 1) uses (crate root) (rank 8"),
        "{v:?}"
    );
}

#[test]
fn tidy_stage_checker_flags_super_paths_that_leave_the_stage() {
    // From synth/a.rs (module synth::a), super::super is the crate root.
    let v = stage_violations(&krate(&[("synth/a.rs", "use super::super::certify::X;\n")]));
    starts(
        &v,
        0,
        "compiler/src/synth/a.rs:1: synth (rank 2) uses certify",
    );
    // From synth/a/b.rs (synth::a::b) it takes three; two stay in synth.
    let three = "use super::super::super::{certify, model};\n";
    let v = stage_violations(&krate(&[("synth/a/b.rs", three)]));
    starts(
        &v,
        0,
        "compiler/src/synth/a/b.rs:1: synth (rank 2) uses certify",
    );
    let two = "use super::super::certify;\n";
    assert_eq!(
        stage_violations(&krate(&[("synth/a/b.rs", two)])),
        Vec::<String>::new()
    );
    // An inline module is one more level.
    let inline = "mod inner {\n    use super::super::super::certify;\n}\nuse super::super::y;\n";
    let v = stage_violations(&krate(&[("synth/a.rs", inline)]));
    starts(&v, 0, "compiler/src/synth/a.rs:2: synth");
    starts(
        &v,
        1,
        "compiler/src/synth/a.rs:4: synth (rank 2) uses (crate root)",
    );
}

#[test]
fn tidy_stage_checker_ignores_strings_comments_and_tests() {
    let src = r##"
// use crate::certify;
/* crate::certify /* nested */ crate::certify */
/// See [`crate::certify`].
const A: &str = "crate::certify";
const B: &str = r#"crate::certify "quoted""#;
const C: char = '"'; const D: &str = "use crate::certify;";
fn f<'a>(x: &'a str) -> &'a str { x }
#[cfg(test)]
mod tests {
    use crate::certify::Certificate;
}
#[cfg(test)]
use crate::certify;
"##;
    assert_eq!(
        stage_violations(&krate(&[("synth/a.rs", src)])),
        Vec::<String>::new()
    );
}

#[test]
fn tidy_stage_checker_keeps_code_compiled_outside_tests() {
    let src =
        "#[cfg(any(test, unix))]\nuse crate::certify;\n#[cfg(not(test))]\nuse crate::certify::X;\n";
    let v = stage_violations(&krate(&[("synth/a.rs", src)]));
    starts(
        &v,
        0,
        "compiler/src/synth/a.rs:2: synth (rank 2) uses certify",
    );
    starts(
        &v,
        1,
        "compiler/src/synth/a.rs:4: synth (rank 2) uses certify",
    );
}

#[test]
fn tidy_stage_checker_requires_every_stage_in_the_table() {
    let v = stage_violations(&krate(&[
        ("helpers.rs", "use crate::model;\n"),
        ("gui/mod.rs", ""),
    ]));
    starts(
        &v,
        0,
        "compiler/src/gui/: stage `gui` is not in the rank table",
    );
    starts(&v, 1, "compiler/src/helpers.rs: stage `helpers`");
    assert_eq!(v.len(), 2, "{v:?}");
}

#[test]
fn tidy_stage_checker_reads_the_binaries_paths_into_the_library() {
    // The binaries are the top: they use any stage; their own `crate::`
    // paths name the binary's modules, not the library's.
    let main = "use tsfc::certify;\nmod exit {}\nfn main() { crate::exit::run() }\n";
    let files = krate(&[
        ("main.rs", main),
        ("bin/bench.rs", "use tsfc::{model, synth};\n"),
    ]);
    assert_eq!(stage_violations(&files), Vec::<String>::new());
}

#[test]
fn tidy_same_rank_stages_do_not_use_each_other() {
    let files = krate(&[
        ("sim/mod.rs", "use crate::codegen::x;\n"),
        ("codegen/mod.rs", "pub fn x() {}\n"),
    ]);
    let v = stage_violations(&files);
    assert!(
        v[0].contains("sim (rank 5) uses codegen (rank 5, same rank)"),
        "{v:?}"
    );
}

#[test]
fn tidy_function_lengths_skip_strings_chars_lifetimes_and_comments() {
    let src = r##"fn a<'a>(x: &'a str) -> &'a str {
    let _ = '{';
    let _ = "}}}";
    let _ = r#"}"#;
    let _ = b'}';
    // }
    /* } */
    x
}
fn pointer(f: fn(u8) -> u8) -> u8 { f(1) }
trait T { fn declared(&self); }
#[cfg(test)]
mod tests {
    fn hidden() {}
}
fn b() {
    let c = '\'';
    let _ = |x: &[u8; 2]| { x[0] };
}
"##;
    let expected = [("a", 1, 9), ("pointer", 10, 1), ("b", 16, 4)];
    let got = functions(src);
    let got: Vec<_> = got
        .iter()
        .map(|f| (f.name.as_str(), f.line, f.lines))
        .collect();
    assert_eq!(got, expected);
}

#[test]
fn tidy_length_checker_reports_file_line_name_and_length() {
    let body = "    let _ = 1;\n".repeat(150);
    let src = format!("fn short() {{}}\n\nfn long() {{\n{body}}}\n");
    let v = length_violations("x/src", &[("a.rs".into(), src)]);
    assert_eq!(v, ["x/src/a.rs:3: fn long is 152 lines (limit 150)"]);
    let big = "// filler\n".repeat(1001);
    let v = length_violations("x/src", &[("b.rs".into(), big)]);
    assert_eq!(
        v,
        ["x/src/b.rs: 1001 lines (limit 1000): split it by domain"]
    );
}

#[test]
fn tidy_doc_checker_sees_doc_comments_and_attributes() {
    let src = r#"
/// Documented.
#[derive(Debug)]
pub struct A;
#[doc = "Documented too."]
pub fn b() {}
pub(crate) fn internal() {}
/// Documented.
pub mod m {
    pub enum Bare { X }
}
fn private() { quote! { pub fn generated() {} }; }
pub trait T {}
"#;
    assert_eq!(
        undocumented(src),
        [(10, "Bare".to_string()), (13, "T".to_string())]
    );
}
