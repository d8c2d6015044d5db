//! Source text that used to be misread or echoed unsafely (issue 12, item 10):
//! a byte-order mark, CR-only line ends, control bytes, one broken
//! declaration, and values whose messages must stay short and exact.

mod common;

use common::{errors, SPEC};
use tsf_lang::check_source;
use tsf_lang::diag::render;

/// The rendered errors of `src` (as `tsfc check` prints them).
fn shown(src: &str) -> String {
    render("p.tsf", src, &errors(src), false)
}

#[test]
fn a_byte_order_mark_is_skipped_and_takes_no_column() {
    let src = format!("\u{feff}{SPEC}");
    let (spec, diags) = check_source(&src);
    assert!(diags.is_empty(), "{diags:#?}");
    assert!(spec.is_some());
    let out = shown(&format!("\u{feff}const k = q;\n{SPEC}"));
    assert!(out.contains("--> p.tsf:1:11"), "{out}");
    assert!(!out.contains('\u{feff}'), "{out}");
}

#[test]
fn a_lone_carriage_return_ends_a_line() {
    let src = format!("{SPEC}const k = q;\n").replace('\n', "\r");
    let out = shown(&src);
    assert!(out.contains("--> p.tsf:4:11"), "{out}");
    assert!(!out.contains('\r'), "{out}");
    // Mixed line ends: `\r\n` counts once.
    let src = format!("{SPEC}\r\nconst k = q;\r\n");
    assert!(shown(&src).contains("--> p.tsf:5:11"));
}

#[test]
fn control_bytes_are_never_echoed() {
    for bad in ["\u{1b}[2J", "\u{0}", "\u{7}", "\u{9b}31m", "\u{202e}"] {
        for src in [
            format!("{SPEC}const k{bad} = 1;\n"),
            format!("{SPEC}const k = q{bad};\n"),
            format!("{SPEC}const k = 1; {bad}\n"),
            format!("{SPEC}rule S: x1 is all{bad} => A = -3;\n"),
        ] {
            let out = shown(&src);
            assert!(!out.is_empty(), "{src:?}");
            let bad_char = bad.chars().next().unwrap_or_default();
            assert!(!out.contains(bad_char), "{src:?}:\n{out}");
            let escaped = format!("\\u{{{:x}}}", bad_char as u32);
            assert!(out.contains(&escaped), "{src:?}:\n{out}");
        }
    }
}

#[test]
fn a_broken_declaration_hides_its_follow_on_errors() {
    // Only the syntax error: no "not a state", "unknown premise" or shape errors.
    let src = "tsf 1; controller c; state x1, x2 @; input u; A = -eye(2); B = [1; 1];\n\
        premise x1 range -1 .. 1 { all = trap(-1, -1, 1, 1); }\n\
        premise z = x1 + x2 range -1 .. 1 { all = trap(-1, -1, 1, 1); }\n\
        rule R: x1 is all and z is all => at(x2 = 0.1), A = -2 * eye(2);\n\
        output y = x1 + x2;\n\
        objective stability;\n\
        simulate { x0 = [0.1, 0]; time = 0 .. 1 step 0.01; }\n";
    let e = errors(src);
    assert_eq!(e.len(), 1, "{e:#?}");
    assert!(e[0].message.starts_with("syntax error"), "{e:#?}");
}

#[test]
fn a_mixed_trigger_rejects_negative_beta_and_rho() {
    let trigger = |beta: &str, rho: &str| {
        errors(&format!(
            "{SPEC}trigger mixed {{ monitor = continuous; beta = {beta}; rho = {rho}; }}"
        ))
    };
    assert!(trigger("0.1", "0.001").is_empty());
    assert!(trigger("0", "0").is_empty());
    let e = trigger("-0.1", "-1e-300");
    let found: Vec<(&str, &str)> = e.iter().map(|d| (&*d.message, &*d.label)).collect();
    assert_eq!(
        found,
        [
            ("`beta` must not be negative", "this is -0.1"),
            ("`rho` must not be negative", "this is -1e-300"),
        ]
    );
}

#[test]
fn tiny_and_huge_numbers_are_printed_short() {
    let cases = [
        (
            "trigger periodic { every = -1e-300; }",
            "the period must be positive",
        ),
        (
            "relaxation membership_mismatch(kappa = -1e-300);",
            "`kappa` must be in [0, 1], found -1e-300",
        ),
        (
            "trigger aperiodic { sampling = 1e-300 .. 1e-301; }",
            "`sampling` needs 0 <= lo < hi, found 1e-300 .. 1e-301",
        ),
        (
            "const k = [1, 2] ^ 1e-300;",
            "shape mismatch in `^`: 1x2 and a scalar",
        ),
        (
            "const k = eye(2) ^ 1e-300;",
            "matrix power exponent 1e-300 is not allowed",
        ),
        (
            "const k = abs(1e-300, 2);",
            "`abs` takes 1 argument, 2 given",
        ),
    ];
    for (item, message) in cases {
        let src = format!("{SPEC}{item}");
        let e = errors(&src);
        assert_eq!(e.len(), 1, "{item}: {e:#?}");
        assert_eq!(e[0].message, message, "{item}");
        let out = shown(&src);
        assert!(!out.contains("0000000000"), "{item}:\n{out}");
    }
}
