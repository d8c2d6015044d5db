//! The C99 generator: a header `<name>.h` and a source `<name>.c` that mirror
//! `tsf_runtime::Controller::step` operation by operation.
//!
//! Conventions (see `/work/shared/design/notes.md`): no `malloc`, no
//! recursion, no global mutable state (the caller owns `<name>_t`), only
//! standard headers (`stdint.h`, `math.h`, `float.h`), `const` tables, every
//! external symbol prefixed `<name>_` and every macro `<NAME>_` so several
//! controllers link into one image, a float-type macro `<NAME>_REAL`
//! (default `double`, or `float` when the spec asks for `precision f32`),
//! include guards and `extern "C"` guards.
//!
//! Floating-point fidelity: every arithmetic step is the runtime's, in the
//! runtime's order (sums accumulated from 0 in index order, products in
//! their own statements so that a compiler allowed to contract `a*b + c`
//! within an expression, like clang's default `-ffp-contract=on`, cannot
//! fuse them). The elementary functions are libm's (`exp`, `atan`, `sqrt`,
//! `sin`, `cos`, `fabs`), always evaluated in `double` and rounded once to
//! `<NAME>_REAL`, exactly like the runtime's `f32` functions; libm and the
//! runtime differ by a few ulp per call, `sqrt` and `fabs` not at all.

use super::header::marker;
use super::{Backend, CodegenError, GeneratedFile};
use crate::model::TermSpec;
use crate::tables::sym::{Func, Sym};
use crate::tables::{PremiseCode, Tables};
use std::fmt::Write as _;
use tsf_lang::spec::{Emit, Precision, SetShape};

mod sensor;
pub use sensor::{c_sensor_file_names, emit_c_sensor};

/// The C99 backend: `<name>.h` and `<name>.c`, and `<name>_sensor.h` and
/// `<name>_sensor.c` for an aperiodic event trigger.
#[derive(Debug, Clone, Copy)]
pub struct CBackend;

impl Backend for CBackend {
    fn target(&self) -> Emit {
        Emit::C
    }

    fn files(&self, t: &Tables) -> Result<Vec<GeneratedFile>, CodegenError> {
        let mut out = emit_c(t).named(c_file_names(t));
        if t.trigger.is_some() {
            out.extend(emit_c_sensor(t)?.named(c_sensor_file_names(t)));
        }
        Ok(out)
    }
}

/// The two generated files.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CFiles {
    /// Contents of `<name>.h`.
    pub header: String,
    /// Contents of `<name>.c` (includes `"<name>.h"`).
    pub source: String,
}

impl CFiles {
    /// The pair as generated files named `(header, source)`.
    fn named(self, (h, c): (String, String)) -> Vec<GeneratedFile> {
        vec![
            GeneratedFile {
                name: h,
                text: self.header,
            },
            GeneratedFile {
                name: c,
                text: self.source,
            },
        ]
    }
}

/// File names of the generated header and source: `(<name>.h, <name>.c)`.
pub fn c_file_names(t: &Tables) -> (String, String) {
    (format!("{}.h", t.name), format!("{}.c", t.name))
}

/// Flag bits, identical to `tsf_runtime::Flags`.
const FLAGS: [(&str, u8, &str); 5] = [
    (
        "NO_RULE_FIRED",
        1,
        "no rule fired: the nearest rule's gain was used alone",
    ),
    (
        "STATE_NONFINITE",
        2,
        "a state component was NaN/inf: u = 0, h = 0",
    ),
    (
        "PREMISE_NONFINITE",
        4,
        "a premise value was NaN/inf: u = 0, h = 0",
    ),
    (
        "COMMAND_NONFINITE",
        8,
        "a blended command was NaN/inf (NaN -> 0, +-inf -> +-u_max)",
    ),
    (
        "SATURATED",
        16,
        "at least one channel was clipped to its level",
    ),
];

/// Term kinds of the generated term table.
const KIND_TRAP: &str = "TERM_TRAP";
const KIND_GAUSS: &str = "TERM_GAUSS";
const KIND_SIGMOID: &str = "TERM_SIGMOID";
const KIND_ABOUT: &str = "TERM_ABOUT";

/// Generates the header and source of a controller.
pub fn emit_c(t: &Tables) -> CFiles {
    let g = Gen::new(t);
    CFiles {
        header: g.header(),
        source: g.source(),
    }
}

/// A C double literal (shortest round-trip form; `INFINITY`/`NAN` for the
/// non-finite values), converted to the real type where it is used.
fn lit(v: f64) -> String {
    if v.is_nan() {
        "NAN".into()
    } else if v.is_infinite() {
        if v > 0.0 { "INFINITY" } else { "-INFINITY" }.into()
    } else {
        format!("{v:?}")
    }
}

/// `{a, b, c}` of literals.
fn list(values: &[f64]) -> String {
    let items: Vec<String> = values.iter().map(|v| lit(*v)).collect();
    format!("{{{}}}", items.join(", "))
}

/// Rows of literals, one per line, each preceded by `indent`.
fn rows(rows: &[Vec<f64>], indent: &str) -> String {
    let items: Vec<String> = rows
        .iter()
        .map(|r| format!("{indent}{}", list(r)))
        .collect();
    items.join(",\n")
}

/// C expressions of an adaptive trigger's fields (see `Gen::adaptive_update`).
struct AdaptiveFields {
    nu: String,
    mu1: String,
    mu2: String,
    mu3: String,
    nu_min: String,
    nu_max: Option<String>,
}

struct Gen<'a> {
    t: &'a Tables,
    /// Lowercase prefix `name_`.
    p: String,
    /// Uppercase prefix `NAME_`.
    u: String,
    /// Array extent of premise vectors (`max(P, 1)`: C has no empty arrays).
    pd: usize,
}

impl<'a> Gen<'a> {
    fn new(t: &'a Tables) -> Self {
        Self::with_prefix(
            t,
            format!("{}_", t.name),
            format!("{}_", t.name.to_ascii_uppercase()),
        )
    }

    /// A generator whose symbols start with `p` and macros with `u`.
    fn with_prefix(t: &'a Tables, p: String, u: String) -> Self {
        Gen {
            t,
            p,
            u,
            pd: t.p.max(1),
        }
    }

    /// The comment block both files start with.
    fn banner(&self, what: &str) -> String {
        let t = self.t;
        let h = &t.header;
        let mut s = marker(h);
        let _ = writeln!(
            s,
            "// {what} of the T-S PDC controller `{}`: {} states, {} inputs, {} premise components, {} rules.",
            t.name, t.n, t.m, t.p, t.r
        );
        if t.trigger.is_some() {
            let _ = writeln!(
                s,
                "// Controller-side role of the event-triggered loop: {p}step is fed the received x(t_k),\n// the last state transmitted by the sensor module `{p}sensor` (.h/.c); memberships and\n// feedback are evaluated at x(t_k) and the command is held between transmissions.",
                p = self.p
            );
        }
        let _ = writeln!(s, "// States: {}.", t.state_names.join(", "));
        let _ = writeln!(s, "// Inputs: {}.", t.input_names.join(", "));
        let _ = writeln!(s, "// Rules: {}.", t.rule_names.join(", "));
        if h.objectives.is_empty() {
            let _ = writeln!(s, "// Objectives: stability.");
        } else {
            let objs: Vec<String> = h
                .objectives
                .iter()
                .map(|(k, v)| format!("{k} = {v}"))
                .collect();
            let _ = writeln!(s, "// Objectives achieved: {}.", objs.join(", "));
        }
        let _ = writeln!(
            s,
            "// Certificate: minimum LMI margin {:e} (relaxation {}).",
            h.min_margin, h.relaxation
        );
        s
    }

    fn header(&self) -> String {
        let t = self.t;
        let (p, u) = (&self.p, &self.u);
        let real = format!("{u}REAL");
        let default_real = match t.precision {
            Precision::F64 => "double",
            Precision::F32 => "float",
        };
        let mut s = self.banner("C99 interface");
        let _ = write!(
            s,
            r#"//
// Semantics are those of tsf-runtime's `Controller::step` (runtime/README.md):
// non-finite state or premise -> u = 0, h = 0 and a fault flag; no rule fired
// -> the nearest rule centre's gain alone and a flag; |u_s| <= u_max_s always;
// rules with h_j == 0 are skipped in the blend. The elementary functions come
// from libm here and from tsf-runtime in Rust: results agree to ~1e-15
// relative (a few ulp per call; tested to 1e-12).
//
// Products are separate statements, so contraction within an expression
// (clang's default) cannot fuse them; for bit-exact runtime order also avoid
// contraction across statements (GCC outside ISO modes: -ffp-contract=off).

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

#define {u}N {n} /* states */
#define {u}M {m} /* inputs */
#define {u}P {np} /* premise components */
#define {u}R {r} /* rules */

"#,
            n = t.n,
            m = t.m,
            np = t.p,
            r = t.r,
        );
        for (name, bit, doc) in FLAGS {
            let _ = writeln!(s, "#define {u}FLAG_{name} {bit}u /* {doc} */");
        }
        let _ = write!(
            s,
            r#"
/* Controller state, owned by the caller (no hidden globals). */
typedef struct {p}t {{
    {real} h[{u}R];   /* normalised firing strengths of the last step */
    uint8_t flags;    /* {u}FLAG_* bits of the last step */
}} {p}t;

/* Clears the state (h = 0, no flags). */
void {p}init({p}t *s);
/* Premise vector z of state x ({u}P components). */
void {p}premises(const {real} x[{u}N], {real} z[]);
/* One control step: z from x, then {p}step_with_premises. */
void {p}step({p}t *s, const {real} x[{u}N], {real} u[{u}M]);
/* One control step with premises z computed by the caller. */
void {p}step_with_premises({p}t *s, const {real} x[{u}N], const {real} z[], {real} u[{u}M]);
/* Flags of the last step. */
uint8_t {p}flags(const {p}t *s);
/* Nonzero if the last command was forced to zero by a non-finite input. */
int {p}is_fault(const {p}t *s);
/* Nonzero if no rule fired in the last step. */
int {p}no_rule_fired(const {p}t *s);
/* Nonzero if a channel was clipped in the last step. */
int {p}saturated(const {p}t *s);
/* Firing strengths used by the last step ({u}R values). */
const {real} *{p}strengths(const {p}t *s);

/* Triggers (tsf-runtime's trigger module). The first decision transmits;
   comparisons involving NaN transmit. Weights are row-major {u}N x {u}N. */

/* Transmit on the first tick and then every `every` ticks (0 acts as 1). */
typedef struct {p}periodic_t {{
    uint32_t every;
    uint32_t count;
}} {p}periodic_t;
void {p}periodic_init({p}periodic_t *t, uint32_t every);
int {p}periodic_decide({p}periodic_t *t);

/* Relative trigger: transmit iff e'Ue >= nu x_k'U x_k, e = x - x_k. */
typedef struct {p}relative_t {{
    {real} weight[{u}N * {u}N];
    {real} nu;
    {real} last[{u}N];
    int has_last;
}} {p}relative_t;
void {p}relative_init({p}relative_t *t, const {real} *weight, {real} nu);
int {p}relative_decide({p}relative_t *t, const {real} x[{u}N]);

/* Adaptive threshold (Xu & Huang 2020): after each transmission
   nu = max(nu (1 - (2 mu1/pi) atan(mu2 (||x_new - x_k|| - mu3))), nu_min). */
typedef struct {p}adaptive_t {{
    {p}relative_t inner;
    {real} mu1;
    {real} mu2;
    {real} mu3;
    {real} nu_min;
}} {p}adaptive_t;
void {p}adaptive_init({p}adaptive_t *t, const {real} *weight, {real} nu_min, {real} mu1, {real} mu2, {real} mu3);
int {p}adaptive_decide({p}adaptive_t *t, const {real} x[{u}N]);
{real} {p}adaptive_nu(const {p}adaptive_t *t);

/* Mixed trigger (Amrr et al. 2019): transmit iff
   ||sigma_k - sigma|| >= beta ||sigma|| + rho. */
typedef struct {p}mixed_t {{
    {real} beta;
    {real} rho;
    {real} last[{u}N];
    int has_last;
}} {p}mixed_t;
void {p}mixed_init({p}mixed_t *t, {real} beta, {real} rho);
int {p}mixed_decide({p}mixed_t *t, const {real} sigma[{u}N]);

#ifdef __cplusplus
}}
#endif

#endif /* {u}H */
"#
        );
        s
    }

    fn source(&self) -> String {
        let mut s = self.banner("C99 implementation");
        let u = &self.u;
        let _ = write!(
            s,
            r#"
#include "{name}.h"

#include <float.h>
#include <math.h>

#define {u}C(v) (({u}REAL)(v))
#define {u}TINY_SCALE {u}C(sizeof({u}REAL) < sizeof(double) ? 0x1p-70 : 0x1p-520)
#define {u}REAL_MAX {u}C(sizeof({u}REAL) < sizeof(double) ? (double)FLT_MAX : DBL_MAX)
#define {u}FRAC_2_PI {u}C(0.6366197723675814)
#define {u}FAULT ({u}FLAG_STATE_NONFINITE | {u}FLAG_PREMISE_NONFINITE)

"#,
            name = self.t.name
        );
        s.push_str(&self.tables());
        s.push_str(&self.math());
        s.push_str(&self.premises());
        s.push_str(&self.controller());
        s.push_str(&self.triggers());
        s
    }

    /// The const tables: premise map, centres, gains, levels, terms.
    fn tables(&self) -> String {
        let t = self.t;
        let (p, u) = (&self.p, &self.u);
        let real = format!("{u}REAL");
        let mut s = String::new();
        if let PremiseCode::Linear(l) = &t.premise {
            let _ = writeln!(
                s,
                "/* Premise map z = L x ({u}P x {u}N). */\nstatic const {real} {p}premise_map[{}][{u}N] = {{\n{}\n}};\n",
                self.pd,
                rows(&self.padded(l, t.n), "    ")
            );
        }
        let _ = writeln!(
            s,
            "/* Rule centres in premise space (nearest-rule fallback). */\nstatic const {real} {p}centres[{u}R][{}] = {{\n{}\n}};\n",
            self.pd,
            rows(&self.padded(&t.centres, self.pd), "    ")
        );
        let _ = writeln!(
            s,
            "/* PDC gains F_j ({u}M x {u}N, row-major), one per rule. */\nstatic const {real} {p}gains[{u}R][{u}M][{u}N] = {{"
        );
        let gains: Vec<String> = t
            .gains
            .iter()
            .zip(&t.rule_names)
            .map(|(f, name)| format!("    /* {name} */ {{\n{}\n    }}", rows(f, "        ")))
            .collect();
        let _ = writeln!(s, "{}\n}};\n", gains.join(",\n"));
        let _ = writeln!(
            s,
            "/* Saturation levels (INFINITY = unlimited). */\nstatic const {real} {p}u_max[{u}M] = {};\n",
            list(&t.u_max)
        );
        // Rule terms.
        let mut terms = Vec::new();
        let mut firsts = vec![0usize];
        let mut points: Vec<f64> = Vec::new();
        for (rule, name) in t.terms.iter().zip(&t.rule_names) {
            for term in rule {
                terms.push(self.term(term, name, &mut points));
            }
            firsts.push(terms.len());
        }
        if terms.is_empty() {
            terms.push(format!(
                "    {{{u}{KIND_TRAP}, 0, 0, 0, {{0.0, 0.0, 0.0, 0.0}}}} /* unused */"
            ));
        }
        if points.is_empty() {
            points.push(0.0);
        }
        let firsts: Vec<String> = firsts.iter().map(|f| f.to_string()).collect();
        let _ = write!(
            s,
            r#"enum {{ {u}{KIND_TRAP}, {u}{KIND_GAUSS}, {u}{KIND_SIGMOID}, {u}{KIND_ABOUT} }};

/* One conjunct of a rule premise: trap(a, b, c, d) (tri(a, b, c) is
   trap(a, b, b, c)), gauss(center, sigma), sigmoid(slope, center) on z[var],
   or `about` the point about_points[point .. point + len] with width prm[0]
   on z[var .. var + len]. */
typedef struct {p}term_t {{
    int kind;
    int var;
    int len;
    int point;
    {real} prm[4];
}} {p}term_t;

static const {p}term_t {p}terms[{nt}] = {{
{terms}
}};

/* Terms of rule i: {p}terms[{p}rule_terms[i] .. {p}rule_terms[i + 1]]. */
static const int {p}rule_terms[{u}R + 1] = {{{firsts}}};

/* Operating points of `about` terms. */
static const {real} {p}about_points[{np}] = {pts};

"#,
            nt = terms.len(),
            terms = terms.join(",\n"),
            firsts = firsts.join(", "),
            np = points.len(),
            pts = list(&points),
        );
        s
    }

    /// `rows` with every row padded with zeros (or cut) to `width` entries,
    /// and at least one row (C has no empty arrays).
    fn padded(&self, rows: &[Vec<f64>], width: usize) -> Vec<Vec<f64>> {
        let mut out: Vec<Vec<f64>> = rows
            .iter()
            .map(|r| {
                let mut r = r.clone();
                r.resize(width, 0.0);
                r
            })
            .collect();
        if out.is_empty() {
            out.push(vec![0.0; width]);
        }
        out
    }

    /// One term-table entry.
    fn term(&self, term: &TermSpec, rule: &str, points: &mut Vec<f64>) -> String {
        let u = &self.u;
        let (kind, var, len, point, prm) = match term {
            TermSpec::Is { var, set } => {
                let (kind, prm) = match *set {
                    SetShape::Tri(a, b, c) => (KIND_TRAP, [a, b, b, c]),
                    SetShape::Trap(a, b, c, d) => (KIND_TRAP, [a, b, c, d]),
                    SetShape::Gauss(c, sg) => (KIND_GAUSS, [c, sg, 0.0, 0.0]),
                    SetShape::Sigmoid(k, c) => (KIND_SIGMOID, [k, c, 0.0, 0.0]),
                };
                (kind, *var, 1, 0, prm)
            }
            TermSpec::About {
                first,
                point,
                sigma,
            } => {
                let at = points.len();
                points.extend_from_slice(point);
                (KIND_ABOUT, *first, point.len(), at, [*sigma, 0.0, 0.0, 0.0])
            }
        };
        format!(
            "    {{{u}{kind}, {var}, {len}, {point}, {}}} /* {rule} */",
            list(&prm)
        )
    }

    /// Helpers: libm wrappers, dot product, memberships.
    fn math(&self) -> String {
        let (p, u) = (&self.p, &self.u);
        let real = format!("{u}REAL");
        let mut s = String::new();
        // libm wrappers: evaluate in double, round once (as the runtime's f32
        // functions). Only the ones the code calls are emitted.
        let mut funcs = vec![("exp", "exp"), ("sqrt", "sqrt"), ("atan", "atan")];
        for f in self.t.functions() {
            let pair = match f {
                Func::Sin => ("sin", "sin"),
                Func::Cos => ("cos", "cos"),
                Func::Abs => ("fabs", "fabs"),
                Func::Sinc => ("sinc", "sinc"),
                Func::Exp | Func::Sqrt | Func::Atan => continue,
            };
            funcs.push(pair);
        }
        for (name, _) in &funcs {
            if *name == "sinc" {
                let _ = write!(
                    s,
                    r#"/* sin(v)/v with the runtime's small-argument branch (|v| < 2^-13:
   1 - v*v/6, truncation error < 2^-59), evaluated in double. */
static {real} {p}sinc({real} v) {{
    const double d = (double)v;
    if (fabs(d) < 0x1p-13) {{
        const double d2 = d * d;
        return {u}C(1.0 - d2 / 6.0);
    }}
    return {u}C(sin(d) / d);
}}

"#
                );
            } else {
                s.push_str(&self.libm_wrapper(name));
            }
        }
        s.push_str(&self.dot_fn());
        let _ = write!(
            s,
            r#"/* Maps into [0, 1]; NaN -> 0. */
static {real} {p}clamp01({real} v) {{
    if (v >= {u}C(1)) {{
        return {u}C(1);
    }}
    if (v > {u}C(0)) {{
        return v;
    }}
    return {u}C(0);
}}

/* (p - q)/(r - s); if r - s overflows, every operand is halved first. */
static {real} {p}edge_ratio({real} p, {real} q, {real} r, {real} s) {{
    const {real} den = r - s;
    if (isfinite(den)) {{
        return (p - q) / den;
    }} else {{
        const {real} ph = p * {u}C(0.5);
        const {real} qh = q * {u}C(0.5);
        const {real} rh = r * {u}C(0.5);
        const {real} sh = s * {u}C(0.5);
        return (ph - qh) / (rh - sh);
    }}
}}

/* Degree of one term at premise vector z, in [0, 1], never NaN. */
static {real} {p}degree(const {p}term_t *t, const {real} z[]) {{
    {real} v;
    if (t->var < 0 || t->len < 0 || t->var + t->len > {u}P) {{
        return {u}C(0);
    }}
    switch (t->kind) {{
    case {u}{KIND_TRAP}: {{
        const {real} x = z[t->var];
        const {real} a = t->prm[0], b = t->prm[1], c = t->prm[2], d = t->prm[3];
        if (!(x >= a && x <= d)) {{
            v = {u}C(0);
        }} else if (x >= b && x <= c) {{
            v = {u}C(1);
        }} else if (x < b) {{
            v = {p}edge_ratio(x, a, b, a);
        }} else {{
            v = {p}edge_ratio(d, x, d, c);
        }}
        break;
    }}
    case {u}{KIND_GAUSS}: {{
        const {real} w = (z[t->var] - t->prm[0]) / t->prm[1];
        const {real} w2 = w * w;
        const {real} e = {u}C(0.5) * w2;
        v = {p}exp(-e);
        break;
    }}
    case {u}{KIND_SIGMOID}: {{
        const {real} d = z[t->var] - t->prm[1];
        const {real} k = t->prm[0] * d;
        const {real} e = {p}exp(-k);
        v = {u}C(1) / ({u}C(1) + e);
        break;
    }}
    default: {{
        {real} d2 = {u}C(0);
        int k;
        for (k = 0; k < t->len; k++) {{
            const {real} d = z[t->var + k] - {p}about_points[t->point + k];
            const {real} dd = d * d;
            d2 = d2 + dd;
        }}
        {{
            const {real} s2 = t->prm[0] * t->prm[0];
            const {real} e = {u}C(0.5) * (d2 / s2);
            v = {p}exp(-e);
        }}
        break;
    }}
    }}
    return {p}clamp01(v);
}}

"#
        );
        s.push_str(&self.norm_fn());
        s
    }

    /// `name_f(v)`: libm's `f` evaluated in double, rounded once to the real type.
    fn libm_wrapper(&self, name: &str) -> String {
        let (p, u) = (&self.p, &self.u);
        format!(
            "static {u}REAL {p}{name}({u}REAL v) {{\n    return {u}C({name}((double)v));\n}}\n\n"
        )
    }

    /// `name_dot`: the runtime's dot product (from 0, index order).
    fn dot_fn(&self) -> String {
        let (p, u) = (&self.p, &self.u);
        let real = format!("{u}REAL");
        format!(
            r#"/* sum_k a[k] b[k], accumulated from 0 in index order. */
static {real} {p}dot(const {real} *a, const {real} *b, int n) {{
    {real} acc = {u}C(0);
    int k;
    for (k = 0; k < n; k++) {{
        const {real} t = a[k] * b[k];
        acc = acc + t;
    }}
    return acc;
}}

"#
        )
    }

    /// `name_norm` (uses `name_sqrt` and `name_dot`).
    fn norm_fn(&self) -> String {
        let (p, u) = (&self.p, &self.u);
        let real = format!("{u}REAL");
        format!(
            r#"/* sqrt(sum v_k^2), no rescaling. */
static {real} {p}norm(const {real} *v, int n) {{
    return {p}sqrt({p}dot(v, v, n));
}}

"#
        )
    }

    /// `name_premises`: `z = L x` or straight-line premise expressions.
    fn premises(&self) -> String {
        let (p, u) = (&self.p, &self.u);
        let real = format!("{u}REAL");
        let mut body = String::new();
        match &self.t.premise {
            PremiseCode::Linear(_) => {
                let _ = write!(
                    body,
                    "    int k;\n    for (k = 0; k < {u}P; k++) {{\n        z[k] = {p}dot({p}premise_map[k], x, {u}N);\n    }}\n"
                );
                if self.t.p == 0 {
                    body.push_str("    (void)z;\n");
                }
                body.push_str("    (void)x;\n");
            }
            PremiseCode::Exprs(exprs) => {
                body.push_str("    (void)x;\n");
                let mut next = 0usize;
                for (k, e) in exprs.iter().enumerate() {
                    let v = self.expr(e, &mut body, &mut next);
                    let _ = writeln!(body, "    z[{k}] = {v};");
                }
            }
        }
        format!(
            "/* Premise vector z of state x. */\nvoid {p}premises(const {real} x[{u}N], {real} z[]) {{\n{body}}}\n\n"
        )
    }

    /// Emits the statements computing `e` (one operation per statement, in
    /// the runtime evaluator's order: left operand first) and returns the
    /// operand naming its value. Iterative post-order walk (no recursion in
    /// the generator either: expressions can be deep).
    fn expr(&self, e: &Sym, out: &mut String, next: &mut usize) -> String {
        let (p, u) = (&self.p, &self.u);
        enum Job<'s> {
            Visit(&'s Sym),
            Emit(&'s Sym),
        }
        let mut jobs = vec![Job::Visit(e)];
        let mut vals: Vec<String> = Vec::new();
        while let Some(job) = jobs.pop() {
            match job {
                Job::Visit(s) => match s {
                    Sym::Const(v) => vals.push(format!("{u}C({})", lit(*v))),
                    Sym::X(k) => vals.push(format!("x[{k}]")),
                    Sym::Add(a, b) | Sym::Mul(a, b) | Sym::Div(a, b) => {
                        jobs.push(Job::Emit(s));
                        jobs.push(Job::Visit(b));
                        jobs.push(Job::Visit(a));
                    }
                    Sym::Neg(a) | Sym::Call(_, a) => {
                        jobs.push(Job::Emit(s));
                        jobs.push(Job::Visit(a));
                    }
                },
                Job::Emit(s) => {
                    let rhs = match s {
                        Sym::Add(..) | Sym::Mul(..) | Sym::Div(..) => {
                            let b = vals.pop().unwrap_or_default();
                            let a = vals.pop().unwrap_or_default();
                            let op = match s {
                                Sym::Add(..) => "+",
                                Sym::Mul(..) => "*",
                                _ => "/",
                            };
                            format!("{a} {op} {b}")
                        }
                        Sym::Neg(_) => format!("-{}", vals.pop().unwrap_or_default()),
                        Sym::Call(f, _) => {
                            format!("{p}{}({})", f.name(), vals.pop().unwrap_or_default())
                        }
                        Sym::Const(_) | Sym::X(_) => String::new(),
                    };
                    let name = format!("t{next}");
                    *next += 1;
                    let _ = writeln!(out, "    const {u}REAL {name} = {rhs};");
                    vals.push(name);
                }
            }
        }
        vals.pop().unwrap_or_else(|| format!("{u}C(0)"))
    }

    /// Strengths, blend, saturation, step, accessors.
    fn controller(&self) -> String {
        let (p, u) = (&self.p, &self.u);
        let real = format!("{u}REAL");
        let pd = self.pd;
        format!(
            r#"/* Rule weight (product t-norm): ((1 * d_1) * d_2) * ... */
static {real} {p}rule_weight(int i, const {real} z[]) {{
    {real} w = {u}C(1);
    int k;
    for (k = {p}rule_terms[i]; k < {p}rule_terms[i + 1]; k++) {{
        w = w * {p}degree(&{p}terms[k], z);
    }}
    return w;
}}

/* h_i = w_i / sum w (weights NaN or <= 0 count as 0); 0 if no rule fires. */
static int {p}normalize(const {real} w[{u}R], {real} h[{u}R]) {{
    {real} s = {u}C(0);
    int i;
    for (i = 0; i < {u}R; i++) {{
        h[i] = w[i] > {u}C(0) ? w[i] : {u}C(0);
    }}
    for (i = 0; i < {u}R; i++) {{
        s = s + h[i];
    }}
    if (!(s > {u}C(0) && isfinite(s))) {{
        return 0;
    }}
    for (i = 0; i < {u}R; i++) {{
        h[i] = h[i] / s;
    }}
    return 1;
}}

/* Nearest rule centre with operands scaled by `scale`; *found is 0 if every
   distance was NaN. Ties and NaN go to the lowest index. */
static int {p}nearest_scaled(const {real} z[], {real} scale, {real} *best_d, int *found) {{
    int best = 0, i, k;
    *found = 0;
    for (i = 0; i < {u}R; i++) {{
        {real} d = {u}C(0);
        int better;
        for (k = 0; k < {u}P; k++) {{
            const {real} a = z[k] * scale;
            const {real} b = {p}centres[i][k] * scale;
            const {real} e = a - b;
            const {real} e2 = e * e;
            d = d + e2;
        }}
        better = *found ? d < *best_d : !isnan(d);
        if (better) {{
            best = i;
            *best_d = d;
            *found = 1;
        }}
    }}
    return best;
}}

/* Index of the nearest rule centre; overflowing distances are recomputed
   with operands scaled by {u}TINY_SCALE. */
static int {p}nearest_rule(const {real} z[]) {{
    {real} d = {u}C(0);
    int found;
    int best = {p}nearest_scaled(z, {u}C(1), &d, &found);
    if (found && !isfinite(d)) {{
        best = {p}nearest_scaled(z, {u}TINY_SCALE, &d, &found);
    }}
    return best;
}}

/* u = sum_j h_j (F_j x), rules with h_j == 0 skipped. */
static void {p}blend(const {real} h[{u}R], const {real} x[{u}N], {real} u[{u}M]) {{
    int j, s;
    for (s = 0; s < {u}M; s++) {{
        u[s] = {u}C(0);
    }}
    for (j = 0; j < {u}R; j++) {{
        if (h[j] == {u}C(0)) {{
            continue;
        }}
        for (s = 0; s < {u}M; s++) {{
            const {real} f = {p}dot({p}gains[j][s], x, {u}N);
            const {real} t = h[j] * f;
            u[s] = u[s] + t;
        }}
    }}
}}

/* |u_s| <= b_s, b_s = u_max_s if u_max_s >= 0 else 0; NaN -> 0,
   +-inf -> +-b_s (0 if b_s is infinite). */
static uint8_t {p}saturate(const {real} raw[{u}M], {real} u[{u}M]) {{
    uint8_t flags = 0;
    int s;
    for (s = 0; s < {u}M; s++) {{
        const {real} b = {p}u_max[s] >= {u}C(0) ? {p}u_max[s] : {u}C(0);
        {real} v = raw[s];
        if (!isfinite(v)) {{
            flags |= {u}FLAG_COMMAND_NONFINITE;
            if (isnan(v) || !isfinite(b)) {{
                v = {u}C(0);
            }}
        }}
        if (v > b) {{
            flags |= {u}FLAG_SATURATED;
            u[s] = b;
        }} else if (v < -b) {{
            flags |= {u}FLAG_SATURATED;
            u[s] = -b;
        }} else {{
            u[s] = v;
        }}
    }}
    return flags;
}}

void {p}init({p}t *s) {{
    int i;
    for (i = 0; i < {u}R; i++) {{
        s->h[i] = {u}C(0);
    }}
    s->flags = 0;
}}

void {p}step_with_premises({p}t *s, const {real} x[{u}N], const {real} z[], {real} u[{u}M]) {{
    {real} w[{u}R];
    {real} raw[{u}M];
    uint8_t flags = 0;
    int i;
    for (i = 0; i < {u}N; i++) {{
        if (!isfinite(x[i])) {{
            flags |= {u}FLAG_STATE_NONFINITE;
        }}
    }}
    for (i = 0; i < {u}P; i++) {{
        if (!isfinite(z[i])) {{
            flags |= {u}FLAG_PREMISE_NONFINITE;
        }}
    }}
    if (flags & {u}FAULT) {{
        for (i = 0; i < {u}R; i++) {{
            s->h[i] = {u}C(0);
        }}
        for (i = 0; i < {u}M; i++) {{
            u[i] = {u}C(0);
        }}
        s->flags = flags;
        return;
    }}
    for (i = 0; i < {u}R; i++) {{
        w[i] = {p}rule_weight(i, z);
    }}
    if (!{p}normalize(w, s->h)) {{
        for (i = 0; i < {u}R; i++) {{
            s->h[i] = {u}C(0);
        }}
        s->h[{p}nearest_rule(z)] = {u}C(1);
        flags |= {u}FLAG_NO_RULE_FIRED;
    }}
    {p}blend(s->h, x, raw);
    flags |= {p}saturate(raw, u);
    s->flags = flags;
}}

void {p}step({p}t *s, const {real} x[{u}N], {real} u[{u}M]) {{
    {real} z[{pd}];
    {p}premises(x, z);
    {p}step_with_premises(s, x, z, u);
}}

uint8_t {p}flags(const {p}t *s) {{
    return s->flags;
}}

int {p}is_fault(const {p}t *s) {{
    return (s->flags & {u}FAULT) != 0;
}}

int {p}no_rule_fired(const {p}t *s) {{
    return (s->flags & {u}FLAG_NO_RULE_FIRED) != 0;
}}

int {p}saturated(const {p}t *s) {{
    return (s->flags & {u}FLAG_SATURATED) != 0;
}}

const {real} *{p}strengths(const {p}t *s) {{
    return s->h;
}}

"#
        )
    }

    /// Trigger state machines (tsf-runtime's `trigger` module).
    fn triggers(&self) -> String {
        let (p, u) = (&self.p, &self.u);
        let real = format!("{u}REAL");
        let quad_form = self.quad_form_fn();
        let decide_e = self.relative_decide_e_fn(&format!("{p}relative_t"), "t->weight");
        let update = self.adaptive_update(
            &AdaptiveFields {
                nu: "t->inner.nu".into(),
                mu1: "t->mu1".into(),
                mu2: "t->mu2".into(),
                mu3: "t->mu3".into(),
                nu_min: "t->nu_min".into(),
                nu_max: None,
            },
            "        ",
        );
        format!(
            r#"void {p}periodic_init({p}periodic_t *t, uint32_t every) {{
    t->every = every;
    t->count = 0;
}}

int {p}periodic_decide({p}periodic_t *t) {{
    const int fire = t->count == 0;
    if (t->count != UINT32_MAX) {{
        t->count = t->count + 1u;
    }}
    if (t->count >= t->every) {{
        t->count = 0;
    }}
    return fire;
}}

{quad_form}void {p}relative_init({p}relative_t *t, const {real} *weight, {real} nu) {{
    int k;
    for (k = 0; k < {u}N * {u}N; k++) {{
        t->weight[k] = weight[k];
    }}
    for (k = 0; k < {u}N; k++) {{
        t->last[k] = {u}C(0);
    }}
    t->nu = nu;
    t->has_last = 0;
}}

{decide_e}int {p}relative_decide({p}relative_t *t, const {real} x[{u}N]) {{
    {real} e[{u}N];
    return {p}relative_decide_e(t, x, e);
}}

void {p}adaptive_init({p}adaptive_t *t, const {real} *weight, {real} nu_min, {real} mu1, {real} mu2, {real} mu3) {{
    {p}relative_init(&t->inner, weight, nu_min);
    t->mu1 = mu1;
    t->mu2 = mu2;
    t->mu3 = mu3;
    t->nu_min = nu_min;
}}

int {p}adaptive_decide({p}adaptive_t *t, const {real} x[{u}N]) {{
    {real} e[{u}N];
    const int first = !t->inner.has_last;
    if (!{p}relative_decide_e(&t->inner, x, e)) {{
        return 0;
    }}
    if (!first) {{
{update}    }}
    return 1;
}}

{real} {p}adaptive_nu(const {p}adaptive_t *t) {{
    return t->inner.nu;
}}

void {p}mixed_init({p}mixed_t *t, {real} beta, {real} rho) {{
    int k;
    t->beta = beta;
    t->rho = rho;
    for (k = 0; k < {u}N; k++) {{
        t->last[k] = {u}C(0);
    }}
    t->has_last = 0;
}}

int {p}mixed_decide({p}mixed_t *t, const {real} sigma[{u}N]) {{
    int k;
    if (t->has_last) {{
        {real} d[{u}N];
        for (k = 0; k < {u}N; k++) {{
            d[k] = t->last[k] - sigma[k];
        }}
        {{
            const {real} xi = {p}norm(d, {u}N);
            const {real} bs = t->beta * {p}norm(sigma, {u}N);
            const {real} threshold = bs + t->rho;
            if (xi < threshold) {{
                return 0;
            }}
        }}
    }}
    for (k = 0; k < {u}N; k++) {{
        t->last[k] = sigma[k];
    }}
    t->has_last = 1;
    return 1;
}}
"#
        )
    }

    /// `name_quad_form`: `v'Uv = sum_i v_i (sum_j U_ij v_j)`, U row-major
    /// (tsf-runtime's `quad_form`; uses `name_dot`).
    fn quad_form_fn(&self) -> String {
        let (p, u) = (&self.p, &self.u);
        let real = format!("{u}REAL");
        format!(
            r#"/* v'Uv = sum_i v_i (sum_j U_ij v_j). */
static {real} {p}quad_form(const {real} *w, const {real} v[{u}N]) {{
    {real} acc = {u}C(0);
    int i;
    for (i = 0; i < {u}N; i++) {{
        const {real} r = {p}dot(&w[i * {u}N], v, {u}N);
        const {real} t = v[i] * r;
        acc = acc + t;
    }}
    return acc;
}}

"#
        )
    }

    /// `name_relative_decide_e`: tsf-runtime's `RelativeTrigger` decision on
    /// a state `t` of type `state` with fields `last`, `has_last`, `nu`, and
    /// the row-major weight `weight` (an expression).
    fn relative_decide_e_fn(&self, state: &str, weight: &str) -> String {
        let (p, u) = (&self.p, &self.u);
        let real = format!("{u}REAL");
        format!(
            r#"/* Decision (10) with the jump e = x - x_k (zeros on the first call). */
static int {p}relative_decide_e({state} *t, const {real} x[{u}N], {real} e[{u}N]) {{
    int k;
    if (!t->has_last) {{
        for (k = 0; k < {u}N; k++) {{
            t->last[k] = x[k];
            e[k] = {u}C(0);
        }}
        t->has_last = 1;
        return 1;
    }}
    for (k = 0; k < {u}N; k++) {{
        e[k] = x[k] - t->last[k];
    }}
    {{
        const {real} lhs = {p}quad_form({weight}, e);
        const {real} q = {p}quad_form({weight}, t->last);
        const {real} rhs = t->nu * q;
        if (lhs < rhs) {{
            return 0;
        }}
    }}
    for (k = 0; k < {u}N; k++) {{
        t->last[k] = x[k];
    }}
    return 1;
}}

"#
        )
    }

    /// Statements of tsf-runtime's `AdaptiveTrigger` threshold update after a
    /// (non-first) transmission with jump `e`, each line indented by `indent`:
    /// `g = (mu1 * (2/pi)) * atan(mu2 * (||e|| - mu3))`, `cand = nu * (1 - g)`,
    /// then the bounds (`nu_max` absent: the real type's largest value).
    fn adaptive_update(&self, f: &AdaptiveFields, indent: &str) -> String {
        let (p, u) = (&self.p, &self.u);
        let real = format!("{u}REAL");
        let AdaptiveFields {
            nu,
            mu1,
            mu2,
            mu3,
            nu_min,
            nu_max,
        } = f;
        let clamp = match nu_max {
            None => format!("{indent}    {nu} = cand > {u}REAL_MAX ? {u}REAL_MAX : cand;\n"),
            Some(max) => format!(
                "{indent}    if (cand > {max}) {{\n\
                 {indent}        {nu} = {max} >= {nu_min} ? {max} : {nu_min};\n\
                 {indent}    }} else {{\n\
                 {indent}        {nu} = cand;\n\
                 {indent}    }}\n"
            ),
        };
        format!(
            "{indent}const {real} a = {p}norm(e, {u}N) - {mu3};\n\
             {indent}const {real} b = {mu2} * a;\n\
             {indent}const {real} k = {mu1} * {u}FRAC_2_PI;\n\
             {indent}const {real} g = k * {p}atan(b);\n\
             {indent}const {real} cand = {nu} * ({u}C(1) - g);\n\
             {indent}if (cand >= {nu_min}) {{\n\
             {clamp}\
             {indent}}} else {{\n\
             {indent}    {nu} = {nu_min};\n\
             {indent}}}\n"
        )
    }
}
