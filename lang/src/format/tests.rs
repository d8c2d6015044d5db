use super::*;

fn fmt(s: &str) -> String {
    let once = format_source(s).expect("formats");
    assert_eq!(
        format_source(&once).as_deref(),
        Ok(once.as_str()),
        "idempotent"
    );
    assert_eq!(lex::token_texts(s), lex::token_texts(&once), "same tokens");
    once
}

#[test]
fn spacing_is_canonical() {
    assert_eq!(
        fmt("const  a=-1+2*x' ;  A(x)=[1,2;3 ,4];"),
        "const a = -1 + 2 * x';\nA(x) = [1, 2; 3, 4];\n"
    );
    assert_eq!(
        fmt("const b = a - -c[1] .* (d+e)^2;fn f(x,y)=x/ y;"),
        "const b = a - -c[1] .* (d + e) ^ 2;\nfn f(x, y) = x / y;\n"
    );
    assert_eq!(
        fmt("rule R1:w is about[0,0] and q is near=>at(w=[0,0]),F=-[1,2];"),
        "rule R1: w is about [0, 0] and q is near => at(w = [0, 0]), F = -[1, 2];\n"
    );
    assert_eq!(
        fmt("objective hinf ( w->z ) minimize;state w[3],q [3];"),
        "objective hinf(w -> z) minimize;\nstate w[3], q[3];\n"
    );
}

#[test]
fn blocks_are_indented_one_statement_per_line() {
    assert_eq!(
        fmt("simulate{x0=[1,0];time=0..5 step 0.1; dynamics { x' = -x; } }"),
        "simulate {\n    x0 = [1, 0];\n    time = 0 .. 5 step 0.1;\n    dynamics { x' = -x; }\n}\n"
    );
    assert_eq!(
        fmt("simulate{x0=[1,0];xhat0=[0 ,-0.5];time=0..5 step 0.1;}"),
        "simulate {\n    x0 = [1, 0];\n    xhat0 = [0, -0.5];\n    time = 0 .. 5 step 0.1;\n}\n"
    );
    assert_eq!(
        fmt("modes {\n  mode a   { }\n mode b {k = 1; j = 2;}\n}"),
        "modes {\n    mode a { }\n    mode b {\n        k = 1;\n        j = 2;\n    }\n}\n"
    );
    assert_eq!(
        fmt("adaptive {\nconverged  | x |<=1e-3 by 40;\n}"),
        "adaptive {\n    converged |x| <= 1e-3 by 40;\n}\n"
    );
}

#[test]
fn comments_and_blank_lines_are_kept() {
    let src = "// head\n\n\n\ntsf 1; // one\ncontroller c;   // two\n\n/* block */ state x; /* inline */\n\
               premise p {\n\n  // inside\n  a = tri(0, 1, 2);\n\n}\n\n\n";
    assert_eq!(
        fmt(src),
        "// head\n\ntsf 1;         // one\ncontroller c;  // two\n\n/* block */ state x; /* inline */\n\
         premise p {\n    // inside\n    a = tri(0, 1, 2);\n}\n"
    );
}

#[test]
fn continuation_lines_keep_the_authors_breaks() {
    // Matrix rows align after `[`; outside brackets a continuation is indented once.
    assert_eq!(
        fmt("A = [1, 2;\n3, 4];\nrule R: p is a => at(x = 0),\n      A = 1;"),
        "A = [1, 2;\n     3, 4];\nrule R: p is a => at(x = 0),\n    A = 1;\n"
    );
    // A bracket that ends its line indents its contents one level.
    assert_eq!(
        fmt("const k = f(\n1,\n  2\n  );"),
        "const k = f(\n    1,\n    2\n);\n"
    );
}

#[test]
fn a_source_that_does_not_parse_is_refused_with_its_position() {
    let e = format_source("tsf 1;\nconst a = ;\n").expect_err("syntax error");
    assert_eq!((e.line, e.column), (2, 11));
    assert!(e.to_string().starts_with("2:11: "), "{e}");
    assert!(format_source("const a = (1;").is_err());
    assert!(format_source("/* open").is_err());
}

#[test]
fn too_deep_nesting_is_an_error_not_a_crash() {
    let deep = format!("const a = {}1{};", "(".repeat(5000), ")".repeat(5000));
    let e = format_source(&deep).expect_err("too deep");
    assert!(e.to_string().contains("nesting deeper than"), "{e}");
    let signs = format!("const a = {}1;", "-".repeat(100_000));
    assert!(format_source(&signs).is_err());
}

#[test]
fn crlf_and_bom_sources() {
    assert_eq!(
        fmt("tsf 1;\r\n\r\n\r\ncontroller c;\r\n"),
        "tsf 1;\n\ncontroller c;\n"
    );
    assert_eq!(fmt("\u{feff}tsf  1;"), "\u{feff}tsf 1;\n");
    assert_eq!(fmt(""), "");
    assert_eq!(fmt("\n\n// only\n\n"), "// only\n");
}
