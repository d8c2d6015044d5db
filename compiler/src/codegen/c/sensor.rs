//! The sensor-side trigger in C99: `<name>_sensor.h` / `<name>_sensor.c`,
//! self-contained (they do not include the controller's files).
//!
//! The decision and the threshold update are the controller library's
//! trigger functions (the same generator text, `Gen::relative_decide_e_fn`
//! and `Gen::adaptive_update`) on a state struct holding only `last`,
//! `has_last` and `nu`, with the weight a `static const` table. Unlike the
//! controller library, which calls libm's `atan`, the sensor carries
//! tsf-runtime's `math::atan` operation by operation, so a build without
//! contraction across statements (`-ffp-contract=off`; one operation per
//! statement already rules out contraction within an expression) gives
//! decisions and thresholds bit-identical to `tsf_runtime::AdaptiveTrigger`.

use super::{lit, AdaptiveFields, CFiles, Gen};
use crate::codegen::header::{law_summary, marker, sensor_certificate, sensor_name};
use crate::codegen::CodegenError;
use crate::tables::{SensorLaw, SensorTables, Tables};
use std::fmt::Write as _;
use tsf_lang::spec::Precision;
use tsf_runtime::math::{ATAN_COMP_J16, ATAN_J16, ATAN_Q};

/// File names of the sensor module: `(<name>_sensor.h, <name>_sensor.c)`.
pub fn c_sensor_file_names(t: &Tables) -> (String, String) {
    let name = sensor_name(t);
    (format!("{name}.h"), format!("{name}.c"))
}

/// Generates the sensor module's header and source; errors if the design
/// has no aperiodic trigger.
pub fn emit_c_sensor(t: &Tables) -> Result<CFiles, CodegenError> {
    let s = t.trigger.as_ref().ok_or(CodegenError::NoSensor)?;
    let name = sensor_name(t);
    let g = Gen::with_prefix(
        t,
        format!("{name}_"),
        format!("{}_", name.to_ascii_uppercase()),
    );
    Ok(CFiles {
        header: sensor_header(&g, s),
        source: sensor_source(&g, s),
    })
}

/// The rows of a matrix as one flat initializer, one row per line.
fn flat_rows(rows: &[Vec<f64>]) -> String {
    let lines: Vec<String> = rows
        .iter()
        .map(|r| {
            let items: Vec<String> = r.iter().map(|v| lit(*v)).collect();
            format!("    {}", items.join(", "))
        })
        .collect();
    lines.join(",\n")
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
// (the runtime's own atan included): with contraction across statements off
// (GCC outside ISO modes: -ffp-contract=off) decisions and nu are bit-identical.
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
    let t = g.t;
    let (p, u) = (&g.p, &g.u);
    let real = format!("{u}REAL");
    let mut out = banner(g, s, "C99 implementation");
    let adaptive = matches!(s.law, SensorLaw::Adaptive(..));
    let _ = write!(
        out,
        r#"
#include "{name}.h"

#include <math.h>

#define {u}C(v) (({real})(v))
"#,
        name = sensor_name(t)
    );
    if adaptive {
        let _ = writeln!(out, "#define {u}FRAC_2_PI {u}C(0.6366197723675814)");
    }
    out.push('\n');
    if s.law != SensorLaw::EverySample {
        let _ = write!(
            out,
            "/* Trigger weight U ({u}N x {u}N, row-major, one row per line). */\nstatic const {real} {p}weight[{u}N * {u}N] = {{\n{}\n}};\n\n",
            flat_rows(&s.weight)
        );
    }
    if adaptive {
        out.push_str(&atan(g));
        out.push_str(&g.libm_wrapper("sqrt"));
    }
    if s.law != SensorLaw::EverySample {
        out.push_str(&g.dot_fn());
    }
    if adaptive {
        out.push_str(&g.norm_fn());
    }
    if s.law != SensorLaw::EverySample {
        out.push_str(&g.quad_form_fn());
        out.push_str(&g.relative_decide_e_fn(&format!("{p}t"), &format!("{p}weight")));
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
    let body = match s.law {
        SensorLaw::EverySample => format!(
            r#"    int i;
    for (i = 0; i < {u}N; i++) {{
        t->last[i] = x[i];
    }}
    t->has_last = 1;
"#
        ),
        SensorLaw::Relative => format!(
            r#"    {real} e[{u}N];
    int i;
    if (!{p}relative_decide_e(t, x, e)) {{
        return 0;
    }}
"#
        ),
        SensorLaw::Adaptive(..) => {
            let update = g.adaptive_update(
                &AdaptiveFields {
                    nu: "t->nu".into(),
                    mu1: format!("{u}C({u}MU1)"),
                    mu2: format!("{u}C({u}MU2)"),
                    mu3: format!("{u}C({u}MU3)"),
                    nu_min: format!("{u}C({u}NU_MIN)"),
                    nu_max: Some(format!("{u}C({u}NU_MAX)")),
                },
                "        ",
            );
            format!(
                r#"    {real} e[{u}N];
    const int first = !t->has_last;
    int i;
    if (!{p}relative_decide_e(t, x, e)) {{
        return 0;
    }}
    if (!first) {{
{update}    }}
"#
            )
        }
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
    return t->has_last ? t->last : 0;
}}
"#
    );
    out
}

/// tsf-runtime's `math::atan` in C (binary64, one operation per statement)
/// and `name_atan`, which rounds it once to the real type (as `atanf`).
fn atan(g: &Gen<'_>) -> String {
    let (p, u) = (&g.p, &g.u);
    let real = format!("{u}REAL");
    let pairs = |tab: &[(f64, f64)]| -> String {
        let items: Vec<String> = tab
            .iter()
            .map(|(hi, lo)| format!("    {{{}, {}}}", lit(*hi), lit(*lo)))
            .collect();
        items.join(",\n")
    };
    let q: Vec<String> = ATAN_Q.iter().map(|v| format!("    {}", lit(*v))).collect();
    format!(
        r#"/* tsf-runtime's math::atan, operation by operation (binary64). */

/* (atan(j/16) high, low), j = 0..39. */
static const double {p}atan_j16[40][2] = {{
{j16}
}};

/* (pi/2 - atan(j/16)) high, low, j = 0..7. */
static const double {p}atan_comp_j16[8][2] = {{
{comp}
}};

/* Taylor coefficients of atan(t)/t - 1 = s Q(s), s = t^2: -1/3, 1/5, ..., -1/23. */
static const double {p}atan_q[11] = {{
{q}
}};

/* atan(t) - t for |t| <= 1/8: t (s Q(s)), Horner innermost first. */
static double {p}atan_tail(double t) {{
    const double s = t * t;
    double acc = 0.0;
    int k;
    for (k = 10; k >= 0; k--) {{
        const double m = s * acc;
        acc = {p}atan_q[k] + m;
    }}
    {{
        const double sq = s * acc;
        return t * sq;
    }}
}}

/* Arc tangent on a = |x| (sign restored at the end): a < 2^-27 -> x;
   a > 2^66 -> pi/2; a < 1/8 -> a + tail(a); a <= 39/16 -> j = trunc(16a + 1/2),
   c = j/16, t = (a - c)/(1 + a c), atan(j/16) + t + tail(t); else
   j = trunc(16/a + 1/2), t = (1 - a c)/(a + c), pi/2 - atan(j/16) - (t + tail(t)). */
static double {p}atan_f64(double x) {{
    double a;
    double r;
    if (isnan(x)) {{
        return x;
    }}
    a = fabs(x);
    if (a < 7.450580596923828e-09) {{
        return x;
    }}
    if (a > 7.378697629483821e19) {{
        r = {p}atan_comp_j16[0][0] + {p}atan_comp_j16[0][1];
    }} else if (a < 0.125) {{
        const double tl = {p}atan_tail(a);
        r = a + tl;
    }} else if (a <= 2.4375) {{
        const double a16 = a * 16.0;
        const int j = (int)(a16 + 0.5);
        const double c = (double)j * 0.0625;
        const double num = a - c;
        const double ac = a * c;
        const double den = 1.0 + ac;
        const double t = num / den;
        const double tl = {p}atan_tail(t);
        const double tt = t + tl;
        const double hi = j >= 0 && j < 40 ? {p}atan_j16[j][0] : 0.0;
        const double lo = j >= 0 && j < 40 ? {p}atan_j16[j][1] : 0.0;
        const double lt = lo + tt;
        r = hi + lt;
    }} else {{
        const double q16 = 16.0 / a;
        const int j = (int)(q16 + 0.5);
        const double c = (double)j * 0.0625;
        const double ac = a * c;
        const double num = 1.0 - ac;
        const double den = a + c;
        const double t = num / den;
        const double tl = {p}atan_tail(t);
        const double tt = t + tl;
        const double hi = j >= 0 && j < 8 ? {p}atan_comp_j16[j][0] : 0.0;
        const double lo = j >= 0 && j < 8 ? {p}atan_comp_j16[j][1] : 0.0;
        const double lt = lo - tt;
        r = hi + lt;
    }}
    return signbit(x) ? -r : r;
}}

static {real} {p}atan({real} v) {{
    return {u}C({p}atan_f64((double)v));
}}

"#,
        j16 = pairs(&ATAN_J16),
        comp = pairs(&ATAN_COMP_J16),
        q = q.join(",\n"),
    )
}
