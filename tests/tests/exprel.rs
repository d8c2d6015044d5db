//! Issue 33, premises that are 0/0 at the equilibrium: a CSTR whose sector
//! premise is written as the quotient `(exp(x2s + e2) - exp(x2s)) / e2` is
//! refused at check with the span on the division and `exprel` as the fix
//! (`tests/bad/premise_zero_over_zero.tsf`); the same model written with
//! `exprel` (`tests/specs/cstr_exprel.tsf`) certifies, and its generated C
//! gives, at e2 = 0, the limit of the control law computed here from the
//! report's gains and the analytic memberships at q = exp(x2s). The generated
//! Rust is checked the same way in `tests/flight_example/tests/exprel.rs`.

use crate::c_codegen::{build, c_compiler, run_driver, work_dir, write_files, write_runtime};
use crate::common::errors_of;
use std::path::Path;
use tsfc::driver::compile::Status;

fn read(rel: &str) -> (String, String) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(rel);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{rel}: {e}"));
    (rel.to_string(), text)
}

#[test]
fn zero_over_zero_premise_is_refused_at_the_division_with_exprel_as_the_fix() {
    let (name, text) = read("bad/premise_zero_over_zero.tsf");
    let errors = errors_of(&name, &text);
    assert_eq!(errors.len(), 1, "{errors:?}");
    let d = &errors[0];
    assert_eq!(d.message, "premise `s` is not finite at x = 0 (0/0)");
    assert_eq!(
        &text[d.span.start..d.span.end],
        "exp(x2s + e2) - exp(x2s)) / e2",
        "the span is the division (its left operand's parentheses excluded)"
    );
    let help = d.help.as_deref().unwrap_or_default();
    assert!(help.contains("`exprel`") && help.contains("sinc"), "{help}");
    assert!(
        d.secondary
            .iter()
            .any(|l| &text[l.span.start..l.span.end] == "q(e2)"),
        "the premise's expression is labelled: {:?}",
        d.secondary
    );
}

/// x1s, x2s = 1 and the membership of the upper vertex of each sector
/// premise at e2 = 0, from the spec's constants (Da = 0.072): p = e^x2 in
/// [1, e^2] and s = e exprel(e2) in [e - 1, e (e - 1)], both e at e2 = 0.
fn upper_memberships_at_e2_zero() -> (f64, f64) {
    let e = std::f64::consts::E;
    let p = (e - 1.0) / (e * e - 1.0);
    let s = (e - (e - 1.0)) / (e * (e - 1.0) - (e - 1.0));
    (p, s)
}

#[test]
fn exprel_model_certifies_and_its_c_gives_the_limit_at_e2_zero() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("specs/cstr_exprel.tsf");
    let shown = "tests/specs/cstr_exprel.tsf";
    let (model, c, sha) = crate::common::compile_path(&path, shown).expect("checks clean");
    assert_eq!(c.status, Status::Certified);
    // The limit: u = sum_j h_j F_j x with h the products of the sector
    // memberships at p = s = e (e2 = 0), from the report's gains.
    let (mp, ms) = upper_memberships_at_e2_zero();
    let h = |rule: &str| {
        let p = if rule.contains("p_max") { mp } else { 1.0 - mp };
        let s = if rule.contains("s_max") { ms } else { 1.0 - ms };
        p * s
    };
    assert_eq!(c.report.gains.len(), 4);
    let e1 = 0.3;
    let limit: f64 = c
        .report
        .gains
        .iter()
        .map(|g| h(&g.rule) * g.f[0][0] * e1)
        .sum();
    let (design, cert) = c.outcome.expect("a design");
    let t = tsfc::tables::tables(&model, &design, &cert, shown, &sha).expect("tables");
    let files = tsfc::codegen::c::emit_c(&t);
    let dir = work_dir("exprel_cstr");
    let sources = [write_files(&dir, &t, &files), write_runtime(&dir)];
    let drv = dir.join("drive.c");
    std::fs::write(
        &drv,
        r#"#include "cstr_exprel.h"
#include <stdio.h>

int main(void) {
    double e2;
    while (scanf("%lf", &e2) == 1) {
        cstr_exprel_t s;
        double x[2], u[1];
        x[0] = 0.3;
        x[1] = e2;
        cstr_exprel_init(&s);
        cstr_exprel_step(&s, x, u);
        printf("%.17g %u\n", u[0], (unsigned)cstr_exprel_flags(&s));
    }
    return 0;
}
"#,
    )
    .expect("write driver");
    let input = dir.join("e2.txt");
    std::fs::write(&input, "0\n-0\n1e-9\n").expect("write input");
    let cc = c_compiler();
    let exe = dir.join("drive");
    let mut all = vec![drv];
    all.extend(sources);
    build(&cc, &all, &exe, &["-O2", "-ffp-contract=off"]);
    let out = run_driver(&exe, &input);
    let rows: Vec<(f64, u32)> = out
        .lines()
        .map(|l| {
            let (u, f) = l.split_once(' ').expect("u flags");
            (u.parse().expect("u"), f.parse().expect("flags"))
        })
        .collect();
    assert_eq!(rows.len(), 3, "{out}");
    println!(
        "C: u(e2 = 0) = {:.17e}, limit {limit:.17e}, u(e2 = 1e-9) = {:.17e}",
        rows[0].0, rows[2].0
    );
    for (u, flags) in &rows[..2] {
        assert_eq!(*flags, 0, "no flag at e2 = 0");
        assert!(
            (u - limit).abs() <= 1e-12 * limit.abs().max(1.0),
            "u = {u} at e2 = 0, limit {limit}"
        );
    }
    assert!((rows[2].0 - rows[0].0).abs() <= 1e-6, "{rows:?}");
}
