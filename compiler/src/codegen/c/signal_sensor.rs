//! The sensor-side mixed trigger on a named signal in C99:
//! `<name>_sensor.h` / `<name>_sensor.c`, independent of the controller's files.
//! The signal is computed one operation per statement (the premises'
//! generator), the decision is the runtime's `tsf_mixed_decide` (the same
//! operations as tsf-runtime's `MixedTrigger`), and the transmitted, held
//! value is the state x(t_i).

use super::{lit, CFiles, Gen};
use crate::codegen::header::{marker, sensor_name};
use crate::codegen::CodegenError;
use crate::tables::{SignalSensorTables, Tables};
use std::fmt::Write as _;
use tsf_lang::spec::Precision;

/// Generates the header and source; errors if the design has no such trigger.
pub fn emit_c_signal_sensor(t: &Tables) -> Result<CFiles, CodegenError> {
    let s = t.sensor.mixed().ok_or(CodegenError::NoSensor)?;
    let g = Gen::sensor(t);
    Ok(CFiles {
        header: header(&g, s),
        source: source(&g, s),
    })
}

/// The comment block both files start with.
fn banner(g: &Gen<'_>, s: &SignalSensorTables, what: &str) -> String {
    let t = g.t;
    let mut out = marker(&t.header);
    let _ = writeln!(
        out,
        "// {what} of the sensor-side mixed trigger of controller `{}` ({} states) on the signal",
        t.name, t.n
    );
    let _ = writeln!(
        out,
        "// `{}` ({} components, monitor = {}): transmits x when ||s(x(t_i)) - s(x)|| >= BETA ||s(x)|| + RHO;",
        s.signal,
        s.exprs.len(),
        s.monitor
    );
    let _ = writeln!(
        out,
        "// the controller module `{}` (.h/.c) is fed the transmitted x(t_i).",
        t.name
    );
    let _ = writeln!(out, "// States: {}.", t.state_names.join(", "));
    let _ = writeln!(out, "// Certificate: {}.", s.certificate);
    out
}

fn header(g: &Gen<'_>, s: &SignalSensorTables) -> String {
    let t = g.t;
    let (p, u) = (&g.p, &g.u);
    let real = format!("{u}REAL");
    let ctl_real = format!("{}_REAL", t.name.to_ascii_uppercase());
    let default_real = match t.precision {
        Precision::F64 => "double",
        Precision::F32 => "float",
    };
    let mut out = banner(g, s, "C99 interface");
    let _ = write!(
        out,
        r#"//
// Semantics are those of tsf-runtime's `SignalTrigger::new(BETA, RHO)` on `signal(x)`,
// computed by tsf_runtime.c (written next to this file). The first call always
// transmits; a comparison involving NaN transmits.

#ifndef {u}H
#define {u}H

/* Floating-point type of the sensor (define it before including this header
   to override; by default the controller's {ctl_real} if defined). */
#ifndef {real}
#ifdef {ctl_real}
#define {real} {ctl_real}
#else
#define {real} {default_real}
#endif
#endif

#ifdef __cplusplus
extern "C" {{
#endif

#define {u}N {n} /* states */
#define {u}K {k} /* components of the monitored signal */
#define {u}BETA {beta} /* relative coefficient of the law */
#define {u}RHO {rho} /* absolute offset of the law */

/* Sensor state, owned by the caller (no hidden globals). */
typedef struct {p}t {{
    /* s(x(t_i)): the signal at the last transmitted state */
    {real} last_signal[{u}K];
    /* x(t_i): the last transmitted state */
    {real} last[{u}N];
    /* nonzero once a state was transmitted */
    int has_last;
}} {p}t;

/* Nothing transmitted yet. */
void {p}init({p}t *t);
/* The monitored signal s(x) ({u}K values). */
void {p}signal(const {real} x[{u}N], {real} s[{u}K]);
/* Call at every control step: returns 1 and copies x into x_tx when x is
   transmitted now (feed x_tx to the controller), else 0 (x_tx untouched). */
int {p}sample({p}t *t, const {real} x[{u}N], {real} x_tx[{u}N]);
/* Last transmitted state x(t_i) ({u}N values), or a null pointer before the
   first transmission. */
const {real} *{p}last(const {p}t *t);

#ifdef __cplusplus
}}
#endif

#endif /* {u}H */
"#,
        n = t.n,
        k = s.exprs.len(),
        beta = lit(s.beta),
        rho = lit(s.rho),
    );
    out
}

fn source(g: &Gen<'_>, s: &SignalSensorTables) -> String {
    let (p, u) = (&g.p, &g.u);
    let real = format!("{u}REAL");
    let mut out = banner(g, s, "C99 implementation");
    out.push_str(&g.prelude(&sensor_name(g.t)));
    let mut body = String::new();
    let mut next = 0usize;
    for (k, e) in s.exprs.iter().enumerate() {
        let v = g.expr(e, &mut body, &mut next);
        let _ = writeln!(body, "    s[{k}] = {v};");
    }
    let _ = write!(
        out,
        r#"void {p}init({p}t *t) {{
    int i;
    for (i = 0; i < {u}K; i++) {{
        t->last_signal[i] = {u}C(0);
    }}
    for (i = 0; i < {u}N; i++) {{
        t->last[i] = {u}C(0);
    }}
    t->has_last = 0;
}}

void {p}signal(const {real} x[{u}N], {real} s[{u}K]) {{
    (void)x;
{body}}}

int {p}sample({p}t *t, const {real} x[{u}N], {real} x_tx[{u}N]) {{
    {real} s[{u}K];
    {real} d[{u}K];
    int i;
    {p}signal(x, s);
    if ({u}RT(tsf_mixed_decide)({u}C({u}BETA), {u}C({u}RHO), t->last_signal, &t->has_last, s, d, {u}K) == 0) {{
        return 0;
    }}
    for (i = 0; i < {u}N; i++) {{
        t->last[i] = x[i];
        x_tx[i] = x[i];
    }}
    return 1;
}}

const {real} *{p}last(const {p}t *t) {{
    return (t->has_last != 0) ? t->last : NULL;
}}
"#
    );
    out
}
