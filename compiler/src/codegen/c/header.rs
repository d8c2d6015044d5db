//! The controller's header `<name>.h`: dimensions, flag bits, the state
//! struct, the step functions and the trigger state machines' interface.
//! It includes only `stdint.h`; the implementation is `<name>.c` on top of
//! the runtime `tsf_runtime.c`.

use super::Gen;
use std::fmt::Write as _;
use tsf_lang::spec::Precision;

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

impl Gen<'_> {
    /// The controller header `<name>.h`: the interface, self-contained.
    pub(super) fn header(&self) -> String {
        let mut s = self.banner("C99 interface");
        self.header_top(&mut s);
        self.header_defines(&mut s);
        self.header_interface(&mut s);
        s
    }

    /// The header's opening: semantics, include guard, the real type and
    /// the dimensions.
    fn header_top(&self, s: &mut String) {
        let t = self.t;
        let u = &self.u;
        let real = format!("{u}REAL");
        let default_real = match t.precision {
            Precision::F64 => "double",
            Precision::F32 => "float",
        };
        let _ = write!(
            s,
            r#"//
// Semantics are those of tsf-runtime's `FactoredController::step` (runtime/README.md),
// computed with tsf_runtime.c's operations in its order: the step in this
// controller's .c either writes them out (`emit c(style = straight)`, bit for
// bit) or calls the runtime (`style = table`). Link tsf_runtime.c (written next
// to this file) once per image either way.
// Non-finite state or premise -> u = 0, h = 0 and a fault
// flag; no rule fired -> the nearest rule centre's gain alone and a flag;
// |u_s| <= u_max_s always; rules with h_j == 0 are skipped in the blend;
// each distinct premise term is evaluated once per step.
// The elementary functions (exp, sin, cos, sinc, exprel, atan, sqrt, fabs)
// are tsf-runtime's, bit for bit (tsf_runtime.c mirrors its arithmetic).
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
    }

    /// The sampling period or interval, the flag bits and the modes.
    fn header_defines(&self, s: &mut String) {
        let t = self.t;
        let u = &self.u;
        let note = crate::codegen::header::modal_sampling_note(t);
        match (t.header.sampling, note) {
            (Some((lo, hi)), Some(_)) if lo == hi => {
                let _ = writeln!(s, "#define {u}SAMPLE_PERIOD {} /* s: the certified sampling period; sample the state and call step once per period */", super::lit(hi));
            }
            (Some((lo, hi)), Some(_)) => {
                let _ = writeln!(s, "#define {u}SAMPLE_INTERVAL_MIN {} /* s: shortest interval between two samples of the state */", super::lit(lo));
                let _ = writeln!(s, "#define {u}SAMPLE_INTERVAL_MAX {} /* s: longest certified interval between two samples of the state */", super::lit(hi));
            }
            (Some((lo, hi)), None) if lo == hi => {
                let _ = writeln!(s, "#define {u}SAMPLE_PERIOD {} /* s: the certified sampling period; call step once per period and hold the command (the certificate covers this period only) */", super::lit(hi));
            }
            (Some((lo, hi)), None) => {
                let _ = writeln!(s, "#define {u}SAMPLE_INTERVAL_MIN {} /* s: shortest certified interval between two steps */", super::lit(lo));
                let _ = writeln!(s, "#define {u}SAMPLE_INTERVAL_MAX {} /* s: longest certified interval between two steps */", super::lit(hi));
            }
            (None, _) => {}
        }
        if let Some(note) = note {
            let _ = writeln!(s, "/* {note} */");
        }
        for (name, bit, doc) in FLAGS {
            let _ = writeln!(s, "#define {u}FLAG_{name} {bit}u /* {doc} */");
        }
        if let Some(mt) = &t.modes {
            let _ = writeln!(
                s,
                "#define {u}FLAG_MODE_OUT_OF_RANGE 32u /* the mode given to step was >= {u}K: mode 0's gains were used */"
            );
            let _ = writeln!(
                s,
                "\n#define {u}K {} /* Markov-switching modes (gain sets) */",
                mt.names.len()
            );
            for (a, name) in mt.names.iter().enumerate() {
                let _ = writeln!(
                    s,
                    "#define {u}MODE_{} {a} /* mode `{name}` */",
                    name.to_ascii_uppercase()
                );
            }
        }
    }

    /// The state struct, the step functions and the triggers' interface.
    fn header_interface(&self, s: &mut String) {
        let t = self.t;
        let (p, u) = (&self.p, &self.u);
        let real = format!("{u}REAL");
        let note = crate::codegen::header::modal_sampling_note(t);
        let (mode_param, mode_doc) = match t.modes {
            Some(_) => (
                "uint8_t mode, ",
                format!(" in mode `mode` (0 .. {u}K - 1, from fault detection; a mode >= {u}K uses mode 0's gains and sets {u}FLAG_MODE_OUT_OF_RANGE)"),
            ),
            None => ("", String::new()),
        };
        let sampled_doc = if note.is_some() {
            " Sampled: call it at each sample and at each mode change, with the last sample."
        } else {
            ""
        };
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
/* One control step{mode_doc}: z from x, then {p}step_with_premises.{sampled_doc} */
void {p}step({p}t *s, {mode_param}const {real} x[{u}N], {real} u[{u}M]);
/* One control step with premises z computed by the caller. */
void {p}step_with_premises({p}t *s, {mode_param}const {real} x[{u}N], const {real} z[], {real} u[{u}M]);
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
   nu = max(nu (1 - (2 mu1/pi) atan(mu2 (||x_new - x_k|| - mu3))), nu_min),
   kept below the real type's largest value. */
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
    }
}
