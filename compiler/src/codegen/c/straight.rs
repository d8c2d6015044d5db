//! The straight-line controller step (`emit c(style = straight)`, the
//! default for controllers up to [`STRAIGHT_MAX_GAINS`] gain entries): the
//! runtime's `tsf_step_with_premises` written out for this controller, with
//! every dimension a compile-time constant. Memberships of the distinct
//! premise terms carry their parameters as constants; rule weights,
//! normalisation, the blend (one branch per rule, skipped when its strength
//! is 0) and the saturation are unrolled; the gains and levels are read from
//! the const tables at constant indices (the mode's block under modes).
//!
//! Every arithmetic operation is the runtime's, in the runtime's order, one
//! product per statement (see the [`super`] module documentation), so the
//! command, strengths and flags are the runtime's bit for bit. The
//! exceptions change no output bit: with linear premises `<name>_step`
//! computes `z = L x` without `L`'s exact-zero coefficients (see
//! `fused_premises`), the sum of the weights starts from the first weight,
//! and the strengths are stored as soon as they are normalised (the blend
//! reads them back; fewer values live in registers). The rare nearest-rule
//! fallback is a small loop over the rule centres, the runtime's
//! `tsf_nearest_rule`; `exp` is the runtime's `tsf_exp`.

use super::{lit, Gen};
use crate::model::TermSpec;
use crate::tables::{PremiseCode, Tables};
use std::fmt::Write as _;
use tsf_lang::spec::{CStyle, SetShape};

/// Largest controller (rules x inputs x states, the gain entries the blend
/// multiplies) whose step `style = auto` writes straight-line; larger ones
/// get the table-driven step. Zhang & Zeng (162 entries) is measured within
/// the flight audit's Cortex-M4 text budgets (bench/RESULTS.md, issue 37);
/// 256 allows a little more, the code growing with rules x inputs (one row
/// call each at `-Os`).
pub const STRAIGHT_MAX_GAINS: usize = 256;

/// Whether the controller's step is generated straight-line: the spec's
/// `style`, or for `auto` whether its gain tables (one mode's) have at most
/// [`STRAIGHT_MAX_GAINS`] entries.
pub fn is_straight(t: &Tables) -> bool {
    match t.c_style {
        CStyle::Straight => true,
        CStyle::Table => false,
        CStyle::Auto => t.r * t.m * t.n <= STRAIGHT_MAX_GAINS,
    }
}

impl Gen<'_> {
    /// The statements of `<name>_step_core` giving, for `<name>_step`, its
    /// premise vector `z = L x` with the exact-zero coefficients of `L` left
    /// out, or `None` when the premises are expressions (or `z` is empty):
    /// then `<name>_step` calls `<name>_premises`, the runtime's `tsf_dot`
    /// rows, and `<name>_step_with_premises`.
    ///
    /// Why the step's commands, strengths and flags stay the runtime's bit
    /// for bit: for a finite `x`, a product `0 * x_j` is `+-0` and adding it
    /// leaves every non-zero sum as it was, so each `z_k` has the runtime's
    /// value but possibly the other sign of zero, which no membership, weight
    /// or nearest-rule distance can see (`z - a` and `(z - a)^2` are equal
    /// for `z = +-0` unless `a = +-0`, where the degree's `+ 0` or the
    /// square erases the sign; see `degree`). For a NaN or infinite `x_j` the
    /// runtime's `z` is NaN or infinite in every row (`0 * inf = NaN`); a
    /// column of `L` that has a non-zero entry keeps that product, so some
    /// `z_k` is non-finite too and the premise flag is set as the runtime
    /// sets it; an all-zero column keeps all its products, as the runtime.
    pub(super) fn fused_premises(&self) -> Option<String> {
        let p = &self.p;
        let t = self.t;
        let real = format!("{}REAL", self.u);
        let PremiseCode::Linear(l) = &t.premise else {
            return None;
        };
        if t.p == 0 || t.n == 0 {
            return None;
        }
        let column_used = |j: usize| l.iter().any(|row| row.get(j).is_some_and(|v| *v != 0.0));
        let mut b = String::from(
            "    /* z = L x, the exact-zero coefficients of L left out (see above). */\n",
        );
        for (k, row) in l.iter().enumerate().take(t.p) {
            let kept: Vec<usize> = (0..t.n)
                .filter(|&j| row.get(j).is_some_and(|v| *v != 0.0) || !column_used(j))
                .collect();
            let Some((&first, rest)) = kept.split_first() else {
                let _ = writeln!(b, "    z[{k}] = {}C(0); /* an all-zero row */", self.u);
                continue;
            };
            let _ = writeln!(
                b,
                "    {{\n        {real} acc = {p}premise_map[{}] * x[{first}];",
                k * t.n + first
            );
            if !rest.is_empty() {
                let _ = writeln!(b, "        {real} t;");
            }
            for &j in rest {
                let _ = writeln!(
                    b,
                    "        t = {p}premise_map[{}] * x[{j}];\n        acc = acc + t;",
                    k * t.n + j
                );
            }
            let _ = writeln!(b, "        z[{k}] = acc;\n    }}");
        }
        Some(b)
    }

    /// The helpers of the straight-line step (the runtime's `tsf_clamp01`,
    /// `tsf_edge_ratio` and nearest-rule search, on this controller's
    /// centres) and the step itself, then the accessors.
    pub(super) fn straight_controller(&self) -> String {
        let (p, u) = (&self.p, &self.u);
        let t = self.t;
        let real = format!("{u}REAL");
        let pd = self.pd;
        let mut s = String::new();
        s.push_str(&self.straight_helpers());
        let inner = if t.p == 0 {
            "    (void)z;\n    (void)scale;\n".to_string()
        } else {
            format!(
                r#"        for (k = 0; k < {u}P; k++) {{
            const {real} a = z[k] * scale;
            const {real} b = {p}centres[i * {pd} + k] * scale;
            const {real} e = a - b;
            const {real} e2 = e * e;
            d = d + e2;
        }}
"#
            )
        };
        let (decl_k, void_lead, inner_loop) = if t.p == 0 {
            (String::new(), inner, String::new())
        } else {
            ("    int k;\n".to_string(), String::new(), inner)
        };
        let tiny_f64 = lit(f64::powi(2.0, -520));
        let tiny_f32 = lit(f64::powi(2.0, -70));
        let _ = write!(
            s,
            r#"/* Scale of the second search when a distance overflows (the runtime's
   TSF_TINY_SCALE: 2^-520 in double, 2^-70 in float). */
#define {u}TINY_double {tiny_f64}
#define {u}TINY_float {tiny_f32}
#define {u}TINY TSF_PASTE({u}TINY_, {u}REAL)

/* Nearest rule centre with operands scaled by `scale`; *found is 0 if every
   distance was NaN. Ties and NaN go to the lowest index. */
static int {p}nearest_scaled(const {real} z[], {real} scale, {real} *best_d, int *found) {{
    int best = 0;
    int i;
{decl_k}{void_lead}    *found = 0;
    for (i = 0; i < {u}R; i++) {{
        {real} d = {u}C(0);
        int better = 0;
{inner_loop}        if (*found != 0) {{
            if (d < *best_d) {{
                better = 1;
            }}
        }} else {{
            if (isnan(d) == 0) {{
                better = 1;
            }}
        }}
        if (better != 0) {{
            best = i;
            *best_d = d;
            *found = 1;
        }}
    }}
    return best;
}}

/* Index of the nearest rule centre (the rare path of a step where no rule
   fires); overflowing distances are recomputed with scaled operands. */
static int {p}nearest_rule(const {real} z[]) {{
    {real} d = {u}C(0);
    int found;
    int best = {p}nearest_scaled(z, {u}C(1), &d, &found);
    if ((found != 0) && (isfinite(d) == 0)) {{
        best = {p}nearest_scaled(z, {u}C({u}TINY), &d, &found);
    }}
    return best;
}}

"#
        );
        if t.n > 0 && t.m > 0 {
            let mut body = format!("    {real} acc = row[0] * x[0];\n");
            if t.n > 1 {
                let _ = writeln!(body, "    {real} t;");
            }
            for k in 1..t.n {
                let _ = writeln!(body, "    t = row[{k}] * x[{k}];\n    acc = acc + t;");
            }
            let _ = write!(
                s,
                r#"/* F_j row . x (tsf_row_dot): from the first product, in index order. Inline:
   written out where it is used when optimising for speed, one copy when for size. */
static inline {real} {p}row_dot(const {real} row[{u}N], const {real} x[{u}N]) {{
{body}    return acc;
}}

"#
            );
        }
        s.push_str(&self.straight_step());
        s
    }

    /// The runtime's `tsf_clamp01` (for the sets whose degree needs it) and
    /// `tsf_edge_ratio` (for trapezoids with a sloped edge), as this
    /// controller uses them.
    fn straight_helpers(&self) -> String {
        let (p, u) = (&self.p, &self.u);
        let t = self.t;
        let real = format!("{u}REAL");
        let mut s = String::new();
        let uses_trap = t.factored.terms.iter().any(|term| match term {
            TermSpec::Is {
                set: SetShape::Tri(a, b, c),
                ..
            } => a != b || b != c,
            TermSpec::Is {
                set: SetShape::Trap(a, b, c, d),
                ..
            } => a != b || c != d,
            _ => false,
        });
        s.push_str("/* The runtime's operations on this controller, written out: tsf_clamp01,\n   tsf_edge_ratio and tsf_nearest_rule of tsf_runtime.c. */\n\n");
        // Trapezoid degrees need no clamp (see `degree`): clamp01 serves the other sets.
        let uses_clamp = t.factored.terms.iter().any(|term| {
            !matches!(
                term,
                TermSpec::Is {
                    set: SetShape::Tri(..) | SetShape::Trap(..),
                    ..
                }
            )
        });
        if uses_clamp {
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

"#
            );
        }
        if uses_trap {
            let _ = write!(
                s,
                r#"/* (p - q)/(r - s); if r - s overflows, every operand is halved first. */
static {real} {p}edge_ratio({real} p, {real} q, {real} r, {real} s) {{
    const {real} den = r - s;
    if (isfinite(den) != 0) {{
        return (p - q) / den;
    }} else {{
        const {real} ph = p * {u}C(0.5);
        const {real} qh = q * {u}C(0.5);
        const {real} rh = r * {u}C(0.5);
        const {real} sh = s * {u}C(0.5);
        return (ph - qh) / (rh - sh);
    }}
}}

"#
            );
        }
        s
    }

    /// The step's test for a NaN or infinite state or premise: one test of
    /// the sum of all values, the runtime's one-by-one tests behind it.
    /// With `fused` (the statements of [`Self::fused_premises`]) the test
    /// is the one of `<name>_step_core`: `z` from `zin` (then the sum of x and
    /// z is tested) or, when `zin` is NULL, from `x` (then the sum of z alone
    /// is: every `x_j` reaches some `z_k`, so the z are all finite only when x is).
    fn straight_fault_check(&self, fused: Option<&str>) -> String {
        let u = &self.u;
        let t = self.t;
        let real = format!("{u}REAL");
        let n = t.n;
        let mut b = String::new();
        let set_flag = |b: &mut String, ind: &str, flag: &str| {
            let _ = writeln!(b, "{ind}flags = (uint8_t)(flags | {u}FLAG_{flag});");
        };
        // Fault checks: one test of all values at once: their sum is finite
        // when every value is (or overflows, rarely), and NaN or infinite
        // when one is not (v - v is +0 only for a finite v), so `all - all`
        // is 0 only when the runtime's one-by-one isfinite tests would find
        // nothing. Those tests follow on the rare path, as loops (small code).
        let mut all = Vec::new();
        let mut checks = String::new();
        for (vec, len, dim, flag) in [
            ("x", n, format!("{u}N"), "STATE_NONFINITE"),
            ("z", t.p, format!("{u}P"), "PREMISE_NONFINITE"),
        ] {
            if len == 0 {
                continue;
            }
            all.extend((0..len).map(|i| format!("{vec}[{i}]")));
            let _ = writeln!(
                checks,
                "            for (i = 0; i < {dim}; i++) {{\n                if (isfinite({vec}[i]) == 0) {{"
            );
            set_flag(&mut checks, "                    ", flag);
            checks.push_str("                }\n            }\n");
        }
        let comment = "    /* A NaN or infinite state or premise: u = 0, h = 0. The sum of every value is\n       finite when they all are (v - v is 0 only for a finite v); otherwise, or when the\n       sum overflows, they are tested one by one. */\n";
        match fused {
            None if !all.is_empty() => {
                let _ = writeln!(
                    b,
                    "{comment}    {{\n        const {real} all = {};\n        if (all - all != {u}C(0)) {{\n            int i;\n{checks}        }}\n    }}",
                    all.join(" + ")
                );
            }
            None => {}
            Some(zs) => {
                let zs: String = zs.lines().map(|l| format!("        {l}\n")).collect();
                let zsum: Vec<String> = (0..t.p).map(|k| format!("z[{k}]")).collect();
                let copy: String = (0..t.p)
                    .map(|k| format!("            z[{k}] = zin[{k}];\n"))
                    .collect();
                let _ = writeln!(
                    b,
                    "{comment}    {{\n        {real} all;\n        if (zin == NULL) {{\n{zs}            all = {}; /* every x_j reaches some z_k */\n        }} else {{\n{copy}            all = {};\n        }}\n        if (all - all != {u}C(0)) {{\n            int i;\n{checks}        }}\n    }}",
                    zsum.join(" + "),
                    all.join(" + ")
                );
            }
        }
        b
    }

    /// `<name>_step_with_premises` written out, then `<name>_step`.
    fn straight_step(&self) -> String {
        let (p, u) = (&self.p, &self.u);
        let t = self.t;
        let real = format!("{u}REAL");
        let (m, r) = (t.m, t.r);
        let mut b = String::new();
        let set_flag = |b: &mut String, ind: &str, flag: &str| {
            let _ = writeln!(b, "{ind}flags = (uint8_t)(flags | {u}FLAG_{flag});");
        };
        let fused = self.fused_premises();
        let pd = self.pd;
        if fused.is_some() {
            let _ = writeln!(b, "    {real} z[{pd}];");
        }
        b.push_str("    uint8_t flags = 0u;\n");
        match t.modes {
            Some(_) => {
                let _ = writeln!(
                    b,
                    "    /* The gains of the mode (mode 0 and a flag when it is out of range). */\n    const {real} *g = &{p}gains[tsf_select_mode(mode, {u}K, &flags) * ({u}R * {u}M * {u}N)];"
                );
            }
            None => {
                let _ = writeln!(b, "    const {real} *g = {p}gains;");
            }
        }
        b.push_str(&self.straight_fault_check(fused.as_deref()));
        if t.p == 0 {
            b.push_str("    (void)z;\n");
        }
        let _ = writeln!(
            b,
            "    if ((flags & ({u}FLAG_STATE_NONFINITE | {u}FLAG_PREMISE_NONFINITE)) != 0u) {{"
        );
        for i in 0..r {
            let _ = writeln!(b, "        s->h[{i}] = {u}C(0);");
        }
        for i in 0..m {
            let _ = writeln!(b, "        u[{i}] = {u}C(0);");
        }
        b.push_str("        s->flags = flags;\n        return;\n    }\n");
        b.push_str("    {\n");
        // Degrees.
        let d = t.factored.terms.len();
        if d > 0 {
            let names: Vec<String> = (0..d).map(|k| format!("deg{k}")).collect();
            let _ = writeln!(
                b,
                "        /* Degrees of the distinct premise terms. */\n        {real} {};",
                names.join(", ")
            );
            for (k, term) in t.factored.terms.iter().enumerate() {
                self.degree(&mut b, k, term);
            }
        }
        // Weights.
        if r > 0 {
            let hs: Vec<String> = (0..r).map(|i| format!("h{i}")).collect();
            let _ = writeln!(
                b,
                "        /* Rule weights (product t-norm, from 1 in the rule's term order), then\n           normalised. Degrees are +0 or in (0, 1], so weights are too: the runtime's\n           clamp of weights not > 0 and its finite test of the sum (<= {u}R) hold, and\n           the sum may start from the first weight (0 + h0 is h0). */\n        {real} {};\n        {real} sum;",
                hs.join(", ")
            );
            for (i, rule) in t.factored.rules.iter().enumerate() {
                let mut e = format!("{u}C(1)");
                for &f in rule {
                    if f < d {
                        let _ = write!(e, " * deg{f}");
                    } else {
                        let _ = write!(e, " * {u}C(0)");
                    }
                }
                let _ = writeln!(b, "        h{i} = {e};");
            }
            // The runtime's clamp (weights not > 0 count as 0) and its test
            // that the sum is finite are identities here: every degree is
            // +0 or in (0, 1], so every weight is too and the sum is at most R.
            let _ = writeln!(b, "        sum = h0;");
            for i in 1..r {
                let _ = writeln!(b, "        sum = sum + h{i};");
            }
            let _ = writeln!(b, "        if (!(sum > {u}C(0))) {{");
            b.push_str("            /* No rule fired: the nearest rule centre's gain alone. The strengths are\n               stored as soon as they are known; the blend reads them back. */\n");
            let _ = writeln!(b, "            const int best = {p}nearest_rule(z);");
            for i in 0..r {
                let _ = writeln!(
                    b,
                    "            s->h[{i}] = (best == {i}) ? {u}C(1) : {u}C(0);"
                );
            }
            set_flag(&mut b, "            ", "NO_RULE_FIRED");
            b.push_str("        } else {\n");
            for i in 0..r {
                let _ = writeln!(b, "            s->h[{i}] = h{i} / sum;");
            }
            b.push_str("        }\n");
        } else {
            let _ = writeln!(
                b,
                "        /* No rules: no rule fires. */\n        (void){p}nearest_rule(z);"
            );
            set_flag(&mut b, "        ", "NO_RULE_FIRED");
        }
        self.straight_blend(&mut b);
        b.push_str("    }\n    s->flags = flags;\n");
        self.step_functions(&b, fused.is_some())
    }

    /// The step functions around body `b` (of the runtime's step): with
    /// `fused` a `static` `<name>_step_core` both steps call, else
    /// `<name>_step_with_premises` and a `<name>_step` calling it.
    fn step_functions(&self, b: &str, fused: bool) -> String {
        let (p, u) = (&self.p, &self.u);
        let real = format!("{u}REAL");
        let pd = self.pd;
        let (mode_param, mode_arg) = match self.t.modes {
            Some(_) => ("uint8_t mode, ", "mode, "),
            None => ("", ""),
        };
        let head = "/* One control step at x with premises z: the runtime's tsf_step_with_premises,\n   operation by operation, written out for this controller.";
        if fused {
            format!(
                r#"{head} {p}step and
   {p}step_with_premises share it: z is zin, or when zin is NULL
   z = L x computed here without L's exact-zero coefficients. For a finite x each z_k
   is then the runtime's (tsf_dot's) value up to the sign of a zero, which no degree,
   weight or distance sees; a NaN or infinite x_j still makes some z_k non-finite (an
   all-zero column of L keeps its products), so the flags are the runtime's too. */
static void {p}step_core({p}t *s, {mode_param}const {real} x[{u}N], const {real} *zin, {real} u[{u}M]) {{
{b}}}

void {p}step_with_premises({p}t *s, {mode_param}const {real} x[{u}N], const {real} z[], {real} u[{u}M]) {{
    {p}step_core(s, {mode_arg}x, z, u);
}}

void {p}step({p}t *s, {mode_param}const {real} x[{u}N], {real} u[{u}M]) {{
    {p}step_core(s, {mode_arg}x, NULL, u);
}}

"#
            )
        } else {
            format!(
                r#"{head} */
void {p}step_with_premises({p}t *s, {mode_param}const {real} x[{u}N], const {real} z[], {real} u[{u}M]) {{
{b}}}

void {p}step({p}t *s, {mode_param}const {real} x[{u}N], {real} u[{u}M]) {{
    {real} z[{pd}];
    {p}premises(x, z);
    {p}step_with_premises(s, {mode_arg}x, z, u);
}}

"#
            )
        }
    }

    /// The blend (one branch per rule, skipped when its strength is not
    /// > 0) and the saturation of every channel, into `b`.
    fn straight_blend(&self, b: &mut String) {
        let (p, u) = (&self.p, &self.u);
        let t = self.t;
        let real = format!("{u}REAL");
        let (n, m, r) = (t.n, t.m, t.r);
        let set_flag = |b: &mut String, ind: &str, flag: &str| {
            let _ = writeln!(b, "{ind}flags = (uint8_t)(flags | {u}FLAG_{flag});");
        };
        // Blend.
        if m > 0 {
            let us: Vec<String> = (0..m).map(|s| format!("u{s} = {u}C(0)")).collect();
            let _ = writeln!(
                b,
                "        {{\n            /* u = sum_j h_j (F_j x), rules whose h_j is not > 0 skipped. */\n            {real} {};",
                us.join(", ")
            );
            if n > 0 {
                for j in 0..r {
                    let _ = writeln!(
                        b,
                        "            if (s->h[{j}] > {u}C(0)) {{\n                {real} f, t;"
                    );
                    for s in 0..m {
                        let row = (j * m + s) * n;
                        let _ = writeln!(b, "                f = {p}row_dot(&g[{row}], x);");
                        let _ = writeln!(
                            b,
                            "                t = s->h[{j}] * f;\n                u{s} = u{s} + t;"
                        );
                    }
                    b.push_str("            }\n");
                }
            } else {
                b.push_str("            (void)g;\n            (void)x;\n");
            }
            b.push_str("            /* Saturation: |u_s| <= max(u_max_s, 0); NaN -> 0, +-inf -> +-level. */\n");
            let unlimited = t.u_max.iter().all(|v| *v == f64::INFINITY);
            let mut sat = String::new();
            for s in 0..m {
                if t.u_max.get(s).is_some_and(|v| *v == f64::INFINITY) {
                    // An unlimited channel (level +inf in either real type):
                    // the runtime's tests leave a finite v and zero the rest.
                    let _ = writeln!(
                        sat,
                        "            if (isfinite(u{s}) == 0) {{ /* unlimited channel */"
                    );
                    set_flag(&mut sat, "                ", "COMMAND_NONFINITE");
                    let _ = writeln!(sat, "                u[{s}] = {u}C(0);\n            }} else {{\n                u[{s}] = u{s};\n            }}");
                    continue;
                }
                let _ = writeln!(
                    sat,
                    "            {{\n                const {real} b = {p}u_max[{s}] >= {u}C(0) ? {p}u_max[{s}] : {u}C(0);\n                {real} v = u{s};\n                if (isfinite(v) == 0) {{"
                );
                set_flag(&mut sat, "                    ", "COMMAND_NONFINITE");
                let _ = writeln!(
                    sat,
                    "                    if ((isnan(v) != 0) || (isfinite(b) == 0)) {{\n                        v = {u}C(0);\n                    }}\n                }}\n                if (v > b) {{"
                );
                set_flag(&mut sat, "                    ", "SATURATED");
                let _ = writeln!(
                    sat,
                    "                    u[{s}] = b;\n                }} else if (v < -b) {{"
                );
                set_flag(&mut sat, "                    ", "SATURATED");
                let _ = writeln!(
                    sat,
                    "                    u[{s}] = -b;\n                }} else {{\n                    u[{s}] = v;\n                }}\n            }}"
                );
            }
            if unlimited {
                // Every channel unlimited: the runtime keeps each finite value,
                // so one test of their sum (finite when all are, or overflowing
                // rarely) comes first, the channel-by-channel tests after it.
                let us: Vec<String> = (0..m).map(|s| format!("u{s}")).collect();
                let _ = writeln!(
                    b,
                    "            (void){p}u_max; /* every channel unlimited */\n            {{\n                const {real} all = {};\n                if (all - all == {u}C(0)) {{",
                    us.join(" + ")
                );
                for s in 0..m {
                    let _ = writeln!(b, "                    u[{s}] = u{s};");
                }
                b.push_str("                } else {\n");
                for line in sat.lines() {
                    let _ = writeln!(b, "        {line}");
                }
                b.push_str("                }\n            }\n");
            } else {
                b.push_str(&sat);
            }
            b.push_str("        }\n");
        } else {
            b.push_str("        (void)g;\n        (void)x;\n        (void)u;\n");
        }
    }

    /// The statements giving `deg<k>`, the degree of distinct term `term`
    /// (the runtime's `tsf_degree` with this term's parameters).
    fn degree(&self, b: &mut String, k: usize, term: &TermSpec) {
        let (p, u) = (&self.p, &self.u);
        let real = format!("{u}REAL");
        let c = |v: f64| format!("{u}C({})", lit(v));
        let pn = self.t.p;
        let (var, len) = match term {
            TermSpec::Is { var, .. } => (*var, 1),
            TermSpec::About { first, point, .. } => (*first, point.len()),
        };
        if var.checked_add(len).is_none_or(|end| end > pn) {
            let _ = writeln!(
                b,
                "        deg{k} = {u}C(0); /* premise component out of range */"
            );
            return;
        }
        match term {
            TermSpec::Is { var, set } => {
                let _ = writeln!(
                    b,
                    "        {{\n            const {real} zv = z[{var}];\n            {real} v;"
                );
                match *set {
                    SetShape::Tri(..) | SetShape::Trap(..) => {
                        let (ta, tb, tc, td) = match *set {
                            SetShape::Tri(a, bb, cc) => (a, bb, bb, cc),
                            SetShape::Trap(a, bb, cc, dd) => (a, bb, cc, dd),
                            _ => unreachable!("trap shapes only"),
                        };
                        let (a, bb, cc, dd) = (c(ta), c(tb), c(tc), c(td));
                        let _ = writeln!(
                            b,
                            "            if (!((zv >= {a}) && (zv <= {dd}))) {{\n                v = {u}C(0);"
                        );
                        // A shoulder (a = b or c = d, equal in either real
                        // type) has no rising or falling edge: within [a, d]
                        // the runtime's tests reduce to one comparison.
                        let rising = format!("v = {p}edge_ratio(zv, {a}, {bb}, {a});");
                        let falling = format!("v = {p}edge_ratio({dd}, zv, {dd}, {cc});");
                        let one = format!("v = {u}C(1);");
                        let tail = match (ta == tb, tc == td) {
                            (true, true) => format!("}} else {{\n                {one}\n            }}"),
                            (true, false) => format!("}} else if (zv <= {cc}) {{\n                {one}\n            }} else {{\n                {falling}\n            }}"),
                            (false, true) => format!("}} else if (zv >= {bb}) {{\n                {one}\n            }} else {{\n                {rising}\n            }}"),
                            // Within [a, d] (z is not NaN here) the runtime's
                            // plateau test, then z < b, is z < b, then z > c.
                            (false, false) => format!("}} else if (zv < {bb}) {{\n                {rising}\n            }} else if (zv > {cc}) {{\n                {falling}\n            }} else {{\n                {one}\n            }}"),
                        };
                        let _ = writeln!(b, "            {tail}");
                    }
                    SetShape::Gauss(ctr, sg) => {
                        let _ = writeln!(
                            b,
                            "            const {real} w = (zv - {}) / {};\n            const {real} w2 = w * w;\n            const {real} e = {u}C(0.5) * w2;\n            v = {u}RT(tsf_exp)(-e);",
                            c(ctr),
                            c(sg)
                        );
                    }
                    SetShape::Sigmoid(slope, ctr) => {
                        let _ = writeln!(
                            b,
                            "            const {real} dz = zv - {};\n            const {real} kz = {} * dz;\n            const {real} e = {u}RT(tsf_exp)(-kz);\n            v = {u}C(1) / ({u}C(1) + e);",
                            c(ctr),
                            c(slope)
                        );
                    }
                }
                if let Some(signed_zero) = trap_signed_zero(*set) {
                    // The runtime's clamp is an identity here but for the sign of
                    // zero: within a <= z < b, 0 <= fl(z - a) <= fl(b - a) (rounding
                    // is monotone), so the ratio is in [0, 1]; likewise on the
                    // falling edge; the other branches give +0 and 1. The ratio is
                    // -0 only for z = -0 on an edge from a = +0 (or to d = -0),
                    // where the clamp gives +0: then `v + 0` does the same.
                    let fix = if signed_zero {
                        format!(" + {u}C(0)")
                    } else {
                        String::new()
                    };
                    let _ = writeln!(b, "            deg{k} = v{fix};\n        }}");
                } else {
                    let _ = writeln!(b, "            deg{k} = {p}clamp01(v);\n        }}");
                }
            }
            TermSpec::About {
                first,
                point,
                sigma,
            } => {
                let _ = writeln!(
                    b,
                    "        {{\n            {real} dsq = {u}C(0);\n            {real} v;"
                );
                for (j, pt) in point.iter().enumerate() {
                    let _ = writeln!(
                        b,
                        "            {{\n                const {real} dz = z[{}] - {};\n                const {real} dd = dz * dz;\n                dsq = dsq + dd;\n            }}",
                        first + j,
                        c(*pt)
                    );
                }
                let sg = c(*sigma);
                let _ = writeln!(
                    b,
                    "            {{\n                const {real} s2 = {sg} * {sg};\n                const {real} e = {u}C(0.5) * (dsq / s2);\n                v = {u}RT(tsf_exp)(-e);\n            }}\n            deg{k} = {p}clamp01(v);\n        }}"
                );
            }
        }
    }
}

/// For a trapezoid (or triangle) set: whether its degree can come out as -0
/// from a sloped edge (`Some`), or `None` for other sets. `z - a` is -0 only
/// for `z = -0`, `a = +0`; `d - z` only for `d = -0`, `z = +0` (round to
/// nearest); a vertical edge has no ratio. Judged on the f32 rounding of the
/// corners, which is +-0 whenever the f64 value is (the C may be built with
/// either real type).
fn trap_signed_zero(set: SetShape) -> Option<bool> {
    let (a, b, c, d) = match set {
        SetShape::Tri(a, b, c) => (a, b, b, c),
        SetShape::Trap(a, b, c, d) => (a, b, c, d),
        SetShape::Gauss(..) | SetShape::Sigmoid(..) => return None,
    };
    let zero =
        |v: f64, positive: bool| (v as f32) == 0.0 && (v as f32).is_sign_positive() == positive;
    Some((a != b && zero(a, true)) || (c != d && zero(d, false)))
}
