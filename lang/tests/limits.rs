//! The front end's limits: every input past one is a spec error naming the
//! limit, and every input within them is checked without exhausting a test
//! thread's stack (run explicitly on a 2 MiB thread, the smallest a test gets).

use tsf_lang::limits::{MAX_EXPR_DEPTH, MAX_EXPR_NODES, MAX_NESTING};
use tsf_lang::{check_source, Diagnostic};

/// A valid spec to which items are appended.
const SPEC: &str = "tsf 1; controller c; state x1; input u; A = -1; B = 1;\n\
    premise x1 range -1 .. 1 { all = trap(-1, -1, 1, 1); }\n\
    rule R: x1 is all => A = -2;\n";

/// Runs `f` on a thread with a 2 MiB stack (a test thread's default).
fn on_small_stack<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    std::thread::Builder::new()
        .stack_size(2 << 20)
        .spawn(f)
        .expect("thread starts")
        .join()
        .expect("no stack overflow")
}

/// The errors of `SPEC` followed by `items`, checked on a 2 MiB stack.
fn errors(items: String) -> Vec<Diagnostic> {
    on_small_stack(move || {
        let (spec, diags) = check_source(&format!("{SPEC}{items}"));
        let errors: Vec<_> = diags.into_iter().filter(Diagnostic::is_error).collect();
        assert_eq!(spec.is_none(), !errors.is_empty());
        errors
    })
}

/// `open` repeated `n` times around `inner`, closed by `close`.
fn nest(open: &str, inner: &str, close: &str, n: usize) -> String {
    format!("{}{inner}{}", open.repeat(n), close.repeat(n))
}

/// Every way of nesting, `n` levels deep (each item's own brackets count too).
fn nestings(n: usize) -> Vec<String> {
    vec![
        format!("const k = {};", nest("(", "1", ")", n)),
        format!("const k = {};", nest("[", "1", "]", n)),
        format!("const k = {};", nest("abs(", "1", ")", n)),
        format!("const k = {}1;", "-".repeat(n)),
        format!("const k = 1{};", "^1".repeat(n)),
        // A unary sign and a `^` per repetition: two levels each.
        format!("const k = {};", nest("- 1 ^ ", "1", "", n.div_ceil(2))),
        format!("const v = [0];\nconst k = {};", nest("v[", "0", "]", n)),
        format!("fn f(a) = {};\nconst k = f(1);", nest("(", "a", ")", n)),
        format!("fn g(a) = {};", nest("sin(", "a", ")", n)),
    ]
}

#[test]
fn nesting_at_the_limit_is_checked_and_one_more_level_is_an_error() {
    for item in nestings(MAX_NESTING - 1) {
        let e = errors(item.clone());
        assert!(e.is_empty(), "{item}: {e:#?}");
    }
    for item in nestings(MAX_NESTING + 1) {
        let e = errors(item.clone());
        assert_eq!(e.len(), 1, "{item}: {e:#?}");
        assert_eq!(
            e[0].message,
            format!("nesting deeper than {MAX_NESTING} levels")
        );
        assert!(e[0]
            .help
            .as_deref()
            .is_some_and(|h| h.contains("MAX_NESTING")));
    }
}

#[test]
fn thousands_of_levels_are_one_error_at_the_first_level_too_many() {
    for (open, close, level) in [
        ("(", ")", '('),
        ("[", "]", '['),
        ("abs(", ")", '('),
        ("-", "", '-'),
    ] {
        let item = format!("const k = {};", nest(open, "1", close, 10_000));
        let e = errors(item.clone());
        assert_eq!(e.len(), 1, "{open}: {e:#?}");
        let at = e[0].span.start - SPEC.len();
        assert_eq!(e[0].span.end - e[0].span.start, 1);
        assert_eq!(item[at..].chars().next(), Some(level));
        assert_eq!(item[..at].matches(level).count(), MAX_NESTING, "{open}");
    }
}

#[test]
fn a_flat_chain_past_the_depth_limit_is_an_error_not_a_crash() {
    let sum = |n: usize| vec!["1"; n].join(" + ");
    assert!(errors(format!("const k = {};", sum(MAX_EXPR_DEPTH))).is_empty());
    for n in [MAX_EXPR_DEPTH + 1, 20_000] {
        let e = errors(format!("const k = {};", sum(n)));
        assert_eq!(e.len(), 1, "{e:#?}");
        assert_eq!(
            e[0].message,
            format!("expression nested too deeply: more than {MAX_EXPR_DEPTH} levels")
        );
        assert!(e[0]
            .help
            .as_deref()
            .is_some_and(|h| h.contains("MAX_EXPR_DEPTH")));
        // The whole expression is marked.
        assert_eq!(e[0].span.end - e[0].span.start, sum(n).len());
    }
    // Postfix chains and products count the same way.
    let transposes = format!("const k = 1{};", "'".repeat(MAX_EXPR_DEPTH));
    assert_eq!(errors(transposes).len(), 1);
    let products = format!("const k = {};", vec!["1"; 5_000].join(" * "));
    assert_eq!(errors(products).len(), 1);
}

#[test]
fn an_expression_past_the_size_limit_is_an_error() {
    let row = |n: usize| format!("const k = [{}];", vec!["1"; n].join(", "));
    assert!(errors(row(MAX_EXPR_NODES - 1)).is_empty());
    let e = errors(row(MAX_EXPR_NODES + 1));
    assert_eq!(e.len(), 1, "{e:#?}");
    assert_eq!(
        e[0].message,
        format!("expression too large: more than {MAX_EXPR_NODES} terms")
    );
    assert!(e[0]
        .help
        .as_deref()
        .is_some_and(|h| h.contains("MAX_EXPR_NODES")));
}

#[test]
fn evaluation_through_functions_stays_within_the_depth_limit() {
    // Each function adds a chain of 40 levels: 10 of them nest 400 levels.
    let chain = |arg: &str| format!("{arg}{}", " + 1".repeat(39));
    let mut fns = format!("fn f0(a) = {};\n", chain("a"));
    for i in 1..10 {
        fns.push_str(&format!(
            "fn f{i}(a) = {};\n",
            chain(&format!("f{}(a)", i - 1))
        ));
    }
    let e = errors(format!("{fns}const k = f9(1);"));
    assert_eq!(e.len(), 1, "{e:#?}");
    assert_eq!(
        e[0].message,
        format!("evaluation nested too deeply: more than {MAX_EXPR_DEPTH} levels")
    );
    // Five of them (200 levels) evaluate.
    let e = errors(format!("{fns}const k = f4(1);"));
    assert!(e.is_empty(), "{e:#?}");
}

#[test]
fn the_deepest_accepted_inputs_fit_a_small_stack() {
    // Each kind of nesting at the limit, inside a chain at the depth limit,
    // through functions: parsing, checking, evaluating and dropping it fits.
    let deep = MAX_NESTING - 2;
    let fns = format!(
        "fn f(a) = {};\nfn g(a) = [{}];\nfn h(a) = {};\n",
        nest("abs(", "a", ")", deep),
        nest("[", "a", "]", deep - 1),
        nest("-a^", "1", "", deep / 2),
    );
    let chain = vec!["f(1)"; MAX_EXPR_DEPTH / 4].join(" + ");
    let items = format!(
        "{fns}const k = {chain};\nconst m = g(2) + h(1);\nconst v = [0];\nconst i = {};",
        nest("v[", "0", "]", deep)
    );
    let e = errors(items);
    assert!(e.is_empty(), "{e:#?}");
}
