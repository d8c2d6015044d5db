//! Large specs: the front end's work grows with the size of the spec, not
//! faster (issue 12, item 5). Each case is a scaled-down version of a spec that
//! used to take minutes or never finish; the tests check the answers, and the
//! counts (diagnostics, work) that bound the time, never the time itself.

mod common;

use common::{errors, SPEC};
use tsf_lang::check_source;
use tsf_lang::diag::render;
use tsf_lang::limits::{MAX_DIAGNOSTICS, MAX_ECHO_CHARS, MAX_EVAL_WORK, MAX_MATRIX_POWER};

/// `n` states with three sets each, and one rule per combination of sets
/// (`3^n` rules), each clause list rotated by the rule's number.
fn full_rule_base(n: usize) -> (String, Vec<String>) {
    let mut s = format!("tsf 1; controller c;\nstate s[{n}];\ninput u;\n");
    s.push_str(&format!("A = -eye({n}); B = ones({n}, 1);\n"));
    for i in 0..n {
        s.push_str(&format!(
            "premise p{i} = s[{i}] range -1 .. 1 {{ lo = trap(-1, -1, -1, 0); \
             mid = tri(-1, 0, 1); hi = trap(0, 1, 1, 1); }}\n"
        ));
    }
    let sets = ["lo", "mid", "hi"];
    let mut rules = Vec::new();
    for k in 0..3usize.pow(n as u32) {
        let mut clauses: Vec<String> = (0..n)
            .map(|i| format!("p{i} is {}", sets[k / 3usize.pow(i as u32) % 3]))
            .collect();
        clauses.rotate_left(k % n);
        rules.push(clauses.join(" and "));
    }
    (s, rules)
}

#[test]
fn a_full_rule_base_is_checked_and_a_reordered_duplicate_premise_is_found() {
    let (head, rules) = full_rule_base(7);
    let mut src = head;
    for (k, r) in rules.iter().enumerate() {
        src.push_str(&format!("rule R{k}: {r} => A = -2 * eye(7);\n"));
    }
    let (spec, diags) = check_source(&src);
    assert!(diags.is_empty(), "{diags:#?}");
    assert_eq!(spec.map(|s| s.rules.len()), Some(2187));
    // The premise of rule R1000, its clauses in another order.
    let mut clauses: Vec<&str> = rules[1000].split(" and ").collect();
    clauses.reverse();
    src.push_str(&format!(
        "rule Last: {} => A = -3 * eye(7);\n",
        clauses.join(" and ")
    ));
    let e = errors(&src);
    assert_eq!(e.len(), 1, "{e:#?}");
    assert_eq!(
        e[0].message,
        "rule `Last` has the same premise as rule `R1000`"
    );
}

#[test]
fn twenty_thousand_constants_are_checked() {
    let n = 20_000;
    let mut src = format!("{SPEC}const c0 = 1;\n");
    for i in 1..n {
        src.push_str(&format!("const c{i} = c{} + 1;\n", i - 1));
    }
    let (spec, diags) = check_source(&src);
    assert!(diags.is_empty(), "{diags:#?}");
    let spec = spec.expect("valid");
    assert_eq!(spec.consts[&format!("c{}", n - 1)][(0, 0)], n as f64);
    // The last one uses a state: one error, naming it.
    src.push_str("const bad = x1 + 1;\n");
    let e = errors(&src);
    assert_eq!(e.len(), 1, "{e:#?}");
    assert_eq!(e[0].message, "`x1` cannot be used here");
}

/// `fn f0(a) = a;` and `fn f_i(a) = f_{i-1}(a) + f_{i-1}(a);` up to `f_n`,
/// used once: evaluating `f_n` visits about `2^(n+1)` nodes.
fn self_doubling(n: usize) -> String {
    let mut s = format!("{SPEC}fn f0(a) = a;\n");
    for i in 1..=n {
        s.push_str(&format!("fn f{i}(a) = f{}(a) + f{}(a);\n", i - 1, i - 1));
    }
    s.push_str(&format!("const k = f{n}(1);\n"));
    s
}

#[test]
fn self_doubling_functions_run_out_of_work_with_one_error() {
    let (spec, diags) = check_source(&self_doubling(10));
    assert!(diags.is_empty(), "{diags:#?}");
    assert_eq!(spec.expect("valid").consts["k"][(0, 0)], 1024.0);
    for n in [40, 60] {
        let e = errors(&self_doubling(n));
        assert_eq!(e.len(), 1, "{e:#?}");
        assert_eq!(
            e[0].message,
            format!("evaluation takes too much work: more than {MAX_EVAL_WORK} operations")
        );
        assert!(e[0]
            .help
            .as_deref()
            .is_some_and(|h| h.contains("MAX_EVAL_WORK")));
    }
}

/// The value of the constant `expr`, or the message of its only error.
fn constant(expr: &str) -> Result<Vec<f64>, String> {
    let (spec, diags) = check_source(&format!("{SPEC}const v = {expr};"));
    match diags.iter().find(|d| d.is_error()) {
        Some(e) => Err(e.message.clone()),
        None => Ok(spec.expect("valid").consts["v"].iter().copied().collect()),
    }
}

#[test]
fn a_matrix_power_is_exact_up_to_the_limit_and_an_error_past_it() {
    // [1 1; 0 1]^k = [1 k; 0 1] exactly (stored by columns).
    let k = MAX_MATRIX_POWER;
    assert_eq!(
        constant(&format!("[1, 1; 0, 1] ^ {k}")),
        Ok(vec![1.0, 0.0, k, 1.0])
    );
    assert_eq!(constant("[1, 1; 0, 1] ^ 13"), Ok(vec![1.0, 0.0, 13.0, 1.0]));
    assert_eq!(constant("[2, 0; 0, 3] ^ 0"), Ok(vec![1.0, 0.0, 0.0, 1.0]));
    assert!(constant(&format!("(eye(100) * 0.5) ^ {k}")).is_ok());
    for bad in ["1000001", "1e300", "2.5", "-1"] {
        let e = constant(&format!("(eye(3) * 0.5) ^ {bad}")).unwrap_err();
        assert!(e.starts_with("matrix power exponent"), "{bad}: {e}");
        assert!(e.ends_with("is not allowed"), "{bad}: {e}");
    }
    let (_, diags) = check_source(&format!("{SPEC}const v = eye(2) ^ 1e300;"));
    assert!(diags[0]
        .help
        .as_deref()
        .is_some_and(|h| h.contains("MAX_MATRIX_POWER")));
    assert_eq!(
        diags[0].message,
        "matrix power exponent 1e300 is not allowed"
    );
}

#[test]
fn many_syntax_errors_are_capped_with_one_line_counting_the_rest() {
    let n = 10_000;
    let src = format!("{SPEC}{}", "@;".repeat(n));
    let (spec, diags) = check_source(&src);
    assert!(spec.is_none());
    assert_eq!(diags.len(), MAX_DIAGNOSTICS + 1);
    let last = &diags[MAX_DIAGNOSTICS];
    assert_eq!(last.omitted, n - MAX_DIAGNOSTICS);
    assert_eq!(
        last.message,
        format!("{} more errors not shown", n - MAX_DIAGNOSTICS)
    );
    let shown = render("p.tsf", &src, &diags, false);
    assert_eq!(
        shown.matches("error: syntax error").count(),
        MAX_DIAGNOSTICS
    );
    assert!(
        shown.ends_with("error: 9800 more errors not shown\n\n"),
        "{shown}"
    );
}

#[test]
fn a_huge_number_is_echoed_shortened() {
    let digits = "9".repeat(100_000);
    let src = format!("{SPEC}const k = {digits} + [1, 2];\n");
    let e = errors(&src);
    assert_eq!(e.len(), 1, "{e:#?}");
    assert!(
        e[0].message.len() < 2 * MAX_ECHO_CHARS + 40,
        "{}",
        e[0].message
    );
    let shown = render("p.tsf", &src, &e, false);
    assert!(shown.len() < 1_000, "{shown}");
    assert!(shown.contains("out of range"), "{shown}");
}
