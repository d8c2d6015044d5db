//! The observer-based controller in C (output feedback): `<name>.h` declares
//! the caller-owned `<name>_state_t` (the estimate, the strengths, the
//! flags), its initial value `<name>_init` and `<name>_step(&s, y, u)`;
//! `<name>.c` holds the controller's tables, the discretized observer of
//! every rule and a thin step over the runtime's `tsf_observer_step`.
//! Table style only: `emit c(style = straight)` is refused for observers.

use super::{flat_rows, lit, Gen};
use crate::tables::ObserverTables;
use std::fmt::Write as _;
use tsf_lang::spec::Precision;

/// Flag bits of an observer step (tsf_runtime::Flags).
const FLAGS: [(&str, u8, &str); 6] = [
    ("NO_RULE_FIRED", 1, "no rule fired: the nearest rule alone"),
    ("STATE_NONFINITE", 2, "y or the estimate was NaN/inf: u = 0"),
    ("PREMISE_NONFINITE", 4, "a premise value was NaN/inf: u = 0"),
    ("COMMAND_NONFINITE", 8, "a blended command was NaN/inf"),
    ("SATURATED", 16, "at least one channel was clipped"),
    ("ESTIMATE_RESET", 64, "the estimate was NaN/inf: reset to 0"),
];

/// The blocks of one matrix per rule as one flat initializer.
fn blocks(o: &[Vec<Vec<f64>>], names: &[String]) -> String {
    let items: Vec<String> = o
        .iter()
        .zip(names)
        .map(|(m, name)| format!("    /* {name} */\n{}", flat_rows(m)))
        .collect();
    items.join(",\n")
}

impl Gen<'_> {
    /// The observer tables of the design (callers check it has them).
    fn observer_tables(&self) -> Option<&ObserverTables> {
        self.t.observer.as_ref()
    }

    /// `<name>.h` of an observer-based controller.
    pub(super) fn observer_header(&self) -> String {
        let t = self.t;
        let Some(o) = self.observer_tables() else {
            return String::new();
        };
        let (p, u) = (&self.p, &self.u);
        let real = format!("{u}REAL");
        let default_real = match t.precision {
            Precision::F64 => "double",
            Precision::F32 => "float",
        };
        let mut s = self.banner("C99 interface");
        let _ = write!(
            s,
            r#"// Observer-based controller (output feedback): semantics of tsf-runtime's
// `Observer::step_with_premises` (runtime/README.md), computed by tsf_runtime.c's
// tsf_observer_step in its order. Every {u}SAMPLE_PERIOD seconds: sample the
// measured output y, call {p}step, apply u until the next call (zero-order hold).
// The step blends the controller on the estimate, u = sat(sum_j h_j F_j xhat),
// and advances the estimate with the rules' observers discretized exactly at the
// period: xhat+ = sum_i h_i (Phi_i xhat + Gu_i u + Gy_i y). Premises are read
// {premises}.
// Non-finite y or estimate -> u = 0, h = 0 and a fault flag (a non-finite
// estimate is reset to 0). Link tsf_runtime.c once per image.

#ifndef {u}H
#define {u}H

#include <stdint.h>

/* Floating-point type of the controller (define it before including this
   header to override; the tables are rounded once to it). */
#ifndef {real}
#define {real} {default_real}
#endif

#ifdef __cplusplus
extern "C" {{
#endif

#define {u}N {n} /* states (estimated) */
#define {u}M {m} /* inputs */
#define {u}Q {q} /* measured outputs y = C x */
#define {u}P {np} /* premise components */
#define {u}R {r} /* rules */
#define {u}SAMPLE_PERIOD {period} /* s: call {p}step once per period */
"#,
            premises = match o.output_map {
                Some(_) => "from the measured output",
                None => "from the estimate",
            },
            n = t.n,
            m = t.m,
            q = o.q,
            np = t.p,
            r = t.r,
            period = lit(o.period),
        );
        for (name, bit, doc) in FLAGS {
            let _ = writeln!(s, "#define {u}FLAG_{name} {bit}u /* {doc} */");
        }
        let _ = write!(
            s,
            r#"
/* Controller state, owned by the caller (no hidden globals). */
typedef struct {p}state_t {{
    {real} xhat[{u}N]; /* the state estimate */
    {real} h[{u}R];    /* normalised firing strengths of the last step */
    uint8_t flags;     /* {u}FLAG_* bits of the last step */
}} {p}state_t;

/* The initial state: estimate 0, no step taken. */
extern const {p}state_t {p}init;
/* Premise vector z ({u}P components) of the state-like vector x. */
void {p}premises(const {real} x[{u}N], {real} z[]);
/* One step: the command u for the measured output y; advances s->xhat. */
void {p}step({p}state_t *s, const {real} y[{u}Q], {real} u[{u}M]);

#ifdef __cplusplus
}}
#endif

#endif /* {u}H */
"#
        );
        s
    }

    /// `<name>.c` of an observer-based controller.
    pub(super) fn observer_source(&self) -> String {
        let t = self.t;
        let Some(o) = self.observer_tables() else {
            return String::new();
        };
        let (p, u) = (&self.p, &self.u);
        let real = format!("{u}REAL");
        let mut s = self.banner("C99 implementation");
        s.push_str(&self.prelude(&t.name));
        s.push_str(&self.observer_controller_tables());
        let rules = &t.rule_names;
        let map = match &o.output_map {
            Some(rows) => {
                let _ = writeln!(
                    s,
                    "/* Premises read v = S y ({u}N rows of {u}Q). */\nstatic const {real} {p}output_map[{u}N * {u}Q] = {{\n{}\n}};\n",
                    flat_rows(rows)
                );
                format!("{p}output_map")
            }
            None => "NULL".into(),
        };
        let md = t.m.max(1);
        let gu: Vec<Vec<Vec<f64>>> =
            o.gu.iter()
                .map(|g| g.iter().map(|r| padded_row(r, md)).collect())
                .collect();
        let _ = write!(
            s,
            r#"/* Phi_i = expm((A_i - L_i C) T) ({u}N x {u}N), one block per rule. */
static const {real} {p}phi[{u}R * {u}N * {u}N] = {{
{phi}
}};

/* Gu_i = int_0^T expm((A_i - L_i C) s) ds B_i ({u}N x {u}M), one block per rule. */
static const {real} {p}gu[{u}R * {u}N * {md}] = {{
{gu}
}};

/* Gy_i = int_0^T expm((A_i - L_i C) s) ds L_i ({u}N x {u}Q), one block per rule. */
static const {real} {p}gy[{u}R * {u}N * {u}Q] = {{
{gy}
}};

/* Everything the runtime's observer step reads. */
static const {u}RT(tsf_observer) {p}observer = {{
    &{p}tables, {u}Q, {map}, {p}phi, {p}gu, {p}gy
}};

"#,
            phi = blocks(&o.phi, rules),
            gu = blocks(&gu, rules),
            gy = blocks(&o.gy, rules),
        );
        s.push_str(&self.premises());
        let pd = self.pd;
        let dd = t.factored.terms.len().max(1);
        let _ = write!(
            s,
            r#"const {p}state_t {p}init = {{{{0}}, {{0}}, 0u}};

void {p}step({p}state_t *s, const {real} y[{u}Q], {real} u[{u}M]) {{
    {real} v[{u}N];
    {real} z[{pd}];
    {real} deg[{dd}]; /* degrees of the distinct premise terms */
    {real} next[{u}N];
    {u}RT(tsf_observer_premise_state)(&{p}observer, s->xhat, y, v);
    {p}premises(v, z);
    s->flags = {u}RT(tsf_observer_step)(&{p}observer, s->xhat, y, z, deg, s->h, u, next);
}}
"#
        );
        s
    }

    /// The controller's tables and its descriptor `<name>_tables`.
    fn observer_controller_tables(&self) -> String {
        let mut s = self.gain_tables();
        s.push_str(&self.term_tables());
        let (p, u) = (&self.p, &self.u);
        let d = self.t.factored.terms.len();
        let entry = self.descriptor_entry(
            d,
            &format!("{u}M"),
            &format!("{p}gains"),
            &format!("{p}u_max"),
        );
        let _ = writeln!(
            s,
            "/* Everything the runtime's controller step reads. */\nstatic const {u}RT(tsf_controller) {p}tables = {entry};\n"
        );
        s
    }
}

/// `row` padded with zeros to `width` entries.
fn padded_row(row: &[f64], width: usize) -> Vec<f64> {
    let mut r = row.to_vec();
    r.resize(width, 0.0);
    r
}
