//! The sensor-side trigger in C99: `<name>_sensor.h` / `<name>_sensor.c`,
//! independent of the controller's files.
//!
//! The decision and the threshold update are the runtime's
//! (`tsf_relative_decide`, `tsf_adaptive_decide` in `tsf_runtime.c`, the
//! functions the controller library's triggers call) on a state struct
//! holding only `last`, `has_last` and `nu`, with the weight and the
//! adaptive law `static const` tables. The runtime carries tsf-runtime's
//! `math::atan` operation by operation, so a build without contraction
//! across statements (`-ffp-contract=off`; one operation per statement
//! already rules out contraction within an expression) gives decisions and
//! thresholds bit-identical to `tsf_runtime::AdaptiveTrigger`.

use super::{flat_rows, lit, CFiles, Gen};
use crate::codegen::header::{law_summary, marker, sensor_certificate, sensor_name};
use crate::codegen::CodegenError;
use crate::tables::{SensorLaw, SensorTables, Tables};
use std::fmt::Write as _;
use tsf_lang::spec::Precision;

/// File names of the sensor module: `(<name>_sensor.h, <name>_sensor.c)`.
pub fn c_sensor_file_names(t: &Tables) -> (String, String) {
    let name = sensor_name(t);
    (format!("{name}.h"), format!("{name}.c"))
}

/// Generates the sensor module's header and source; errors if the design
/// has no aperiodic trigger.
pub fn emit_c_sensor(t: &Tables) -> Result<CFiles, CodegenError> {
    let s = t.sensor.aperiodic().ok_or(CodegenError::NoSensor)?;
    let g = Gen::sensor(t);
    Ok(CFiles {
        header: sensor_header(&g, s),
        source: sensor_source(&g, s),
    })
}

/// The comment block both sensor files start with.
fn banner(g: &Gen<'_>, s: &SensorTables, what: &str) -> String {
    let t = g.t;
    let mut out = marker(&t.header);
    let _ = writeln!(
        out,
        "// {what} of the sensor-side event trigger of controller `{}` ({} states): at each",
        t.name, t.n
    );
    let _ = writeln!(
        out,
        "// sampling instant (intervals in [{:?}, {:?}] s) it decides whether to transmit x; the",
        s.h_min, s.h_max
    );
    let _ = writeln!(
        out,
        "// controller module `{}` (.h/.c) is fed the transmitted x(t_k).",
        t.name
    );
    let _ = writeln!(out, "// States: {}.", t.state_names.join(", "));
    let _ = writeln!(out, "// Law: {}.", law_summary(s));
    let _ = writeln!(out, "// Weight U: {}.", s.weight_source);
    let _ = writeln!(out, "// Certificate: {}.", sensor_certificate(t, s));
    out
}

fn sensor_header(g: &Gen<'_>, s: &SensorTables) -> String {
    let t = g.t;
    let (p, u) = (&g.p, &g.u);
    let real = format!("{u}REAL");
    let ctl_real = format!("{}_REAL", t.name.to_ascii_uppercase());
    let default_real = match t.precision {
        Precision::F64 => "double",
        Precision::F32 => "float",
    };
    let runtime = match s.law {
        SensorLaw::EverySample => "every sample transmitted".to_string(),
        SensorLaw::Relative => "tsf-runtime's `RelativeTrigger::new(U, NU_MIN)`".to_string(),
        SensorLaw::Adaptive(..) => {
            "tsf-runtime's `AdaptiveTrigger::new(U, NU_MIN, MU1, MU2, MU3).with_max(NU_MAX)`"
                .to_string()
        }
    };
    let mut out = banner(g, s, "C99 interface");
    let _ = write!(
        out,
        r#"//
// Semantics are those of {runtime}, operation by operation
// (the runtime's own atan included), computed by tsf_runtime.c (written next to
// this file: compile and link it once per image): with contraction across
// statements off (GCC outside ISO modes: -ffp-contract=off) decisions and nu are
// bit-identical.
// The first sample is always transmitted; a comparison involving NaN transmits.

#ifndef {u}H
#define {u}H

/* Floating-point type of the sensor (define it before including this header
   to override; by default the controller's {ctl_real} if defined, so both
   modules share one type). */
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
#define {u}H_MIN {h_min} /* shortest sampling interval (s) */
#define {u}H_MAX {h_max} /* longest sampling interval (s) */
#define {u}NU_MIN {nu_min} /* lower bound and initial value nu(0) of the threshold */
#define {u}NU_MAX {nu_max} /* ceiling of the threshold: the value the loop is certified for */
"#,
        n = t.n,
        h_min = lit(s.h_min),
        h_max = lit(s.h_max),
        nu_min = lit(s.nu_min),
        nu_max = lit(s.nu_max),
    );
    if let SensorLaw::Adaptive(mu1, mu2, mu3) = s.law {
        let _ = writeln!(
            out,
            "#define {u}MU1 {} /* gain of the adaptive law */",
            lit(mu1)
        );
        let _ = writeln!(
            out,
            "#define {u}MU2 {} /* slope inside the atan */",
            lit(mu2)
        );
        let _ = writeln!(
            out,
            "#define {u}MU3 {} /* jump size at which nu stays constant */",
            lit(mu3)
        );
    }
    let law = match s.law {
        SensorLaw::EverySample => "Every sample is transmitted.".to_string(),
        SensorLaw::Relative => {
            "Transmit iff e'U e >= NU_MIN x_k'U x_k, e = x - x_k (x_k: last transmitted).".to_string()
        }
        SensorLaw::Adaptive(..) => format!(
            "Transmit iff e'U e >= nu x_k'U x_k, e = x - x_k (x_k: last transmitted);\n   after each transmission but the first\n   nu = min(max(nu (1 - (2 MU1/pi) atan(MU2 (||x - x_k|| - MU3))), NU_MIN), NU_MAX),\n   so nu(t_k) stays in [{u}NU_MIN, {u}NU_MAX]."
        ),
    };
    let _ = write!(
        out,
        r#"
/* Sensor state, owned by the caller (no hidden globals). */
typedef struct {p}t {{
    /* x(t_k): the last transmitted state */
    {real} last[{u}N];
    /* threshold nu(t_k) */
    {real} nu;
    /* nonzero once a state was transmitted */
    int has_last;
}} {p}t;

/* Nothing transmitted yet, nu = {u}NU_MIN. */
void {p}init({p}t *t);
/* Call at every sampling instant (intervals in [{u}H_MIN, {u}H_MAX] s).
   {law}
   Returns 1 and copies x into x_tx when x is transmitted now (feed x_tx to the
   controller), else 0 (x_tx untouched). */
int {p}sample({p}t *t, const {real} x[{u}N], {real} x_tx[{u}N]);
/* Current threshold nu(t_k). */
{real} {p}nu(const {p}t *t);
/* Last transmitted state x(t_k) ({u}N values), or a null pointer before the
   first transmission. */
const {real} *{p}last(const {p}t *t);

#ifdef __cplusplus
}}
#endif

#endif /* {u}H */
"#
    );
    out
}

fn sensor_source(g: &Gen<'_>, s: &SensorTables) -> String {
    let (p, u) = (&g.p, &g.u);
    let real = format!("{u}REAL");
    let mut out = banner(g, s, "C99 implementation");
    out.push_str(&g.prelude(&sensor_name(g.t)));
    if s.law != SensorLaw::EverySample {
        let _ = write!(
            out,
            "/* Trigger weight U ({u}N x {u}N, row-major, one row per line). */\nstatic const {real} {p}weight[{u}N * {u}N] = {{\n{}\n}};\n\n",
            flat_rows(&s.weight)
        );
    }
    if let SensorLaw::Adaptive(..) = s.law {
        let _ = write!(
            out,
            "/* The adaptive law, nu(t_k) in [NU_MIN, NU_MAX]. */\nstatic const {u}RT(tsf_adaptive_law) {p}law = {{\n    {u}C({u}MU1),\n    {u}C({u}MU2),\n    {u}C({u}MU3),\n    {u}C({u}NU_MIN),\n    {u}C({u}NU_MAX)\n}};\n\n"
        );
    }
    let _ = write!(
        out,
        r#"void {p}init({p}t *t) {{
    int i;
    for (i = 0; i < {u}N; i++) {{
        t->last[i] = {u}C(0);
    }}
    t->nu = {u}C({u}NU_MIN);
    t->has_last = 0;
}}

"#
    );
    let decide = match s.law {
        SensorLaw::EverySample => None,
        SensorLaw::Relative => Some(format!(
            "{u}RT(tsf_relative_decide)({p}weight, t->nu, t->last, &t->has_last, x, e, {u}N)"
        )),
        SensorLaw::Adaptive(..) => Some(format!(
            "{u}RT(tsf_adaptive_decide)(&{p}law, {p}weight, &t->nu, t->last, &t->has_last, x, e, {u}N)"
        )),
    };
    let body = match decide {
        None => format!(
            r#"    int i;
    for (i = 0; i < {u}N; i++) {{
        t->last[i] = x[i];
    }}
    t->has_last = 1;
"#
        ),
        Some(call) => format!(
            r#"    {real} e[{u}N];
    int i;
    if (!{call}) {{
        return 0;
    }}
"#
        ),
    };
    let _ = write!(
        out,
        r#"int {p}sample({p}t *t, const {real} x[{u}N], {real} x_tx[{u}N]) {{
{body}    for (i = 0; i < {u}N; i++) {{
        x_tx[i] = x[i];
    }}
    return 1;
}}

{real} {p}nu(const {p}t *t) {{
    return t->nu;
}}

const {real} *{p}last(const {p}t *t) {{
    return (t->has_last != 0) ? t->last : NULL;
}}
"#
    );
    out
}
