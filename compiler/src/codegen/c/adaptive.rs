//! The C99 module of an adaptive controller (docs/adaptive.md): `<name>.h`
//! declares the caller-owned `<name>_state_t` (estimates, reference-model
//! state, strengths, flags, status) and `<name>_init` / `<name>_step`;
//! `<name>.c` holds the const tables (premise map, rule terms and centres in
//! a `tsf_controller` with no commands, the law in a `tsf_mrac_law`, the
//! initial estimates) and thin wrappers over the runtime's
//! `tsf_step_with_premises` (the strengths only) and `tsf_mrac_step`, which
//! mirror `tsf_runtime::AdaptiveController` operation by operation. Double
//! only.

use super::{flat_rows, lit, CFiles, Gen};
use crate::codegen::header::generated_lines;
use crate::tables::AdaptiveTables;
use std::fmt::Write as _;
use tsf_runtime::Adaptation;

/// Generates the header and source of an adaptive controller.
pub fn emit_c_adaptive(at: &AdaptiveTables) -> CFiles {
    let g = Gen::new(&at.base);
    CFiles {
        header: header(&g, at),
        source: source(&g, at),
    }
}

/// The comment block both files start with.
fn banner(g: &Gen<'_>, at: &AdaptiveTables, what: &str) -> String {
    let t = g.t;
    let mut s = generated_lines(&t.header);
    let _ = writeln!(
        s,
        "// Precision f64: adaptive model-reference law, no LMI certificate (docs/adaptive.md).\n//\n// {what} of the adaptive T-S controller `{}`: {} states, {} inputs, {} premise components, {} rules.",
        t.name, t.n, t.m, t.p, t.r
    );
    let _ = writeln!(s, "// States: {}.", t.state_names.join(", "));
    let _ = writeln!(
        s,
        "// Inputs (and reference, error-signal components): {}.",
        t.input_names.join(", ")
    );
    let _ = writeln!(s, "// Rules: {}.", t.rule_names.join(", "));
    let _ = writeln!(
        s,
        "// Period {} s; {} adapted numbers.",
        lit(at.dt),
        adapted(at)
    );
    s
}

/// Adapted numbers (a quantity with rate 0 is not adapted).
fn adapted(at: &AdaptiveTables) -> usize {
    let d = &at.design;
    let count = |q: &Adaptation, len: usize| if q.rate > 0.0 { len } else { 0 };
    count(&d.a, d.a0.len()) + count(&d.b, d.b0.len()) + count(&d.d, 1)
}

fn header(g: &Gen<'_>, at: &AdaptiveTables) -> String {
    let t = g.t;
    let (p, u) = (&g.p, &g.u);
    let mut s = banner(g, at, "C99 interface");
    let _ = write!(
        s,
        r#"//
// Semantics are those of tsf-runtime's `AdaptiveController::step` (runtime/src/adaptive.rs),
// computed by tsf_runtime.c (written next to this file: compile and link it once per
// image): with s = C x and p = P (s - s_m),
//   u_k = ((A_m (s - r))_k - sum_i h_i a_ik'x - d sat(p_k / phi)) / sum_i h_i b_ik,
// then the estimates a, b, d and the reference model s_m advance by {u}SAMPLE_PERIOD
// (explicit Euler) and every estimate is projected onto its box. A NaN or infinite
// state, premise, reference or command gives u = 0, a nonzero status and leaves the
// estimates and s_m unchanged; when no rule fires, the nearest rule centre's strength
// is 1. Every sum starts from +0 in index order, one product per statement: with
// -ffp-contract=off the results are the Rust runtime's, bit for bit.

#ifndef {u}H
#define {u}H

#include <stdint.h>

/* Floating-point type of the controller: the adaptive law is double only. */
#define {u}REAL double

#ifdef __cplusplus
extern "C" {{
#endif

#define {u}N {n} /* states */
#define {u}M {m} /* inputs = error-signal components */
#define {u}P {np} /* premise components */
#define {u}R {r} /* rules */
#define {u}SAMPLE_PERIOD {dt} /* s: call step once per period and hold the command; the update laws are integrated over it */
#define {u}FLAG_NO_RULE_FIRED 1u /* no rule fired: the nearest rule's strength is 1 */
#define {u}FLAG_STATE_NONFINITE 2u /* a state component was NaN/inf: u = 0, state held */
#define {u}FLAG_PREMISE_NONFINITE 4u /* a premise value was NaN/inf: u = 0, state held */
#define {u}STATUS_OK 0 /* the step was taken */
#define {u}STATUS_SHAPE 1 /* a dimension out of the runtime's range: u = 0, state held */
#define {u}STATUS_NONFINITE 2 /* a NaN/inf state, premise, reference or command: u = 0, state held */

/* Controller state, owned by the caller (no hidden globals). */
typedef struct {p}state_t {{
    double a_hat[{u}R * {u}M * {u}N]; /* state-coefficient estimates a_ik (rule, input, state) */
    double b_hat[{u}R * {u}M];        /* input-gain estimates b_ik (rule, input) */
    double d_hat;                     /* disturbance-bound estimate d */
    double s_m[{u}M];                 /* reference-model state */
    double h[{u}R];                   /* normalised firing strengths of the last step */
    double work[2 * {u}M];            /* scratch space of the step */
    uint8_t flags;                    /* {u}FLAG_* bits of the last step */
    int status;                       /* {u}STATUS_* of the last step */
}} {p}state_t;

/* The spec's initial estimates, s_m = 0, no step taken. */
void {p}init({p}state_t *s);
/* Premise vector z of state x ({u}P components). */
void {p}premises(const double x[{u}N], double z[]);
/* One control step at state x with reference r (the spec's r(t), evaluated by the
   caller; zeros to regulate): writes the command u and advances the state. */
void {p}step({p}state_t *s, const double x[{u}N], const double r[{u}M], double u[{u}M]);
/* One control step with premises z computed by the caller. */
void {p}step_with_premises({p}state_t *s, const double x[{u}N], const double z[],
    const double r[{u}M], double u[{u}M]);
/* {u}STATUS_* of the last step. */
int {p}status(const {p}state_t *s);
/* Flags of the last step. */
uint8_t {p}flags(const {p}state_t *s);
/* Nonzero if the last step was refused (u = 0, state held). */
int {p}is_fault(const {p}state_t *s);
/* Firing strengths used by the last step ({u}R values). */
const double *{p}strengths(const {p}state_t *s);

#ifdef __cplusplus
}}
#endif

#endif /* {u}H */
"#,
        n = t.n,
        m = t.m,
        np = t.p,
        r = t.r,
        dt = lit(at.dt),
    );
    s
}

/// `{rate, lo, hi}`.
fn adaptation(q: &Adaptation) -> String {
    format!("{{{}, {}, {}}}", lit(q.rate), lit(q.lo), lit(q.hi))
}

/// `values` as rows of `width` (one per line).
fn rows(values: &[f64], width: usize) -> String {
    let rows: Vec<Vec<f64>> = values.chunks(width.max(1)).map(<[f64]>::to_vec).collect();
    flat_rows(&rows)
}

fn source(g: &Gen<'_>, at: &AdaptiveTables) -> String {
    let t = g.t;
    let d = &at.design;
    let (p, u) = (&g.p, &g.u);
    let mut s = banner(g, at, "C99 implementation");
    s.push_str(&g.prelude(&t.name));
    s.push_str(&g.premise_tables());
    s.push_str(&g.term_tables());
    let dd = t.factored.terms.len();
    let _ = write!(
        s,
        r#"/* The rule part of the runtime's controller descriptor: no commands (m = 0),
   so its step computes the strengths and flags only (no gains, no saturation). */
static const tsf_controller {p}rules = {rules};

/* The error signal s = C x ({u}M x {u}N, row-major). */
static const double {p}error_map[{u}M * {u}N] = {{
{c}
}};

/* The reference model A_m ({u}M x {u}M, row-major). */
static const double {p}reference_model[{u}M * {u}M] = {{
{a_m}
}};

/* P with A_m'P + P A_m = -Q ({u}M x {u}M, row-major). */
static const double {p}lyapunov[{u}M * {u}M] = {{
{p_mat}
}};

/* Initial a_ik: one line per rule and input. */
static const double {p}a_hat_0[{u}R * {u}M * {u}N] = {{
{a0}
}};

/* Initial b_ik: one line per rule. */
static const double {p}b_hat_0[{u}R * {u}M] = {{
{b0}
}};

/* The law: dimensions, tables, {{rate, lo, hi}} of a, b, d (rate 0: not
   adapted), boundary layer. */
static const tsf_mrac_law {p}law = {{
    {u}N, {u}M, {u}R,
    {p}error_map, {p}reference_model, {p}lyapunov,
    {ra}, {rb}, {rd},
    {layer}
}};

"#,
        rules = g.descriptor_entry(dd, "0", "NULL", "NULL"),
        c = rows(&d.c, t.n),
        a_m = rows(&d.a_m, t.m),
        p_mat = rows(&d.p, t.m),
        a0 = rows(&d.a0, t.n),
        b0 = rows(&d.b0, t.m),
        ra = adaptation(&d.a),
        rb = adaptation(&d.b),
        rd = adaptation(&d.d),
        layer = lit(d.layer),
    );
    s.push_str(&g.premises());
    let pd = g.pd;
    let dd = dd.max(1);
    let _ = write!(
        s,
        r#"void {p}init({p}state_t *s) {{
    int k;
    for (k = 0; k < {u}R * {u}M * {u}N; k++) {{
        s->a_hat[k] = {p}a_hat_0[k];
    }}
    for (k = 0; k < {u}R * {u}M; k++) {{
        s->b_hat[k] = {p}b_hat_0[k];
    }}
    s->d_hat = {d0};
    for (k = 0; k < {u}M; k++) {{
        s->s_m[k] = 0.0;
    }}
    for (k = 0; k < {u}R; k++) {{
        s->h[k] = 0.0;
    }}
    s->flags = 0u;
    s->status = {u}STATUS_OK;
}}

void {p}step_with_premises({p}state_t *s, const double x[{u}N], const double z[],
    const double r[{u}M], double u[{u}M]) {{
    double deg[{dd}]; /* degrees of the distinct premise terms */
    s->flags = tsf_step_with_premises(&{p}rules, x, z, deg, s->h, u);
    if ((s->flags & ({u}FLAG_STATE_NONFINITE | {u}FLAG_PREMISE_NONFINITE)) != 0u) {{
        int k;
        for (k = 0; k < {u}M; k++) {{
            u[k] = 0.0;
        }}
        s->status = {u}STATUS_NONFINITE;
        return;
    }}
    s->status = tsf_mrac_step(&{p}law, s->a_hat, s->b_hat, &s->d_hat, s->s_m, x, s->h, r,
        {u}SAMPLE_PERIOD, u, s->work);
}}

void {p}step({p}state_t *s, const double x[{u}N], const double r[{u}M], double u[{u}M]) {{
    double z[{pd}];
    {p}premises(x, z);
    {p}step_with_premises(s, x, z, r, u);
}}

int {p}status(const {p}state_t *s) {{
    return s->status;
}}

uint8_t {p}flags(const {p}state_t *s) {{
    return s->flags;
}}

int {p}is_fault(const {p}state_t *s) {{
    return s->status != {u}STATUS_OK;
}}

const double *{p}strengths(const {p}state_t *s) {{
    return s->h;
}}
"#,
        d0 = lit(d.d0),
    );
    s
}
