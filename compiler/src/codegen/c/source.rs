//! The controller's source `<name>.c`: the const tables, the descriptor the
//! runtime's step reads, and the premise function (`z = L x` or
//! straight-line expression code). The step and trigger functions are thin
//! wrappers over the runtime ([`super::step`]).

use super::{flat_rows, list, lit, Gen};
use crate::model::TermSpec;
use crate::tables::sym::Sym;
use crate::tables::{PremiseCode, Tables};
use std::fmt::Write as _;
use tsf_lang::spec::SetShape;

impl Gen<'_> {
    /// The controller source `<name>.c`.
    pub(super) fn source(&self) -> String {
        let mut s = self.banner("C99 implementation");
        s.push_str(&self.prelude(&self.t.name));
        if super::straight::is_straight(self.t) {
            s.push_str(&self.straight_tables());
            s.push_str(&self.premises());
            s.push_str(&self.init());
            s.push_str(&self.straight_controller());
        } else {
            s.push_str(&self.tables());
            s.push_str(&self.premises());
            s.push_str(&self.init());
            s.push_str(&self.step());
        }
        s.push_str(&self.accessors());
        s.push_str(&self.triggers());
        s
    }

    /// The includes of a source file whose header is `<file>.h`, and the two
    /// macros it uses: `<NAME>_RT(f)`, the runtime's `f` of the real type,
    /// and `<NAME>_C(v)`, a constant of the real type.
    pub(super) fn prelude(&self, file: &str) -> String {
        let u = &self.u;
        format!(
            r#"
#include "{file}.h"
#include "tsf_runtime.h"

#include <math.h>

/* The runtime's functions and types of the real type (tsf_<f> for double,
   tsf_<f>f for float), and a constant of the real type. */
#define {u}RT(f) TSF_REAL_FN({u}REAL, f)
#define {u}C(v) (({u}REAL)(v))

"#
        )
    }

    /// The const tables: premise map, centres, gains, levels, terms, and the
    /// descriptor `<name>_tables` pointing at them.
    fn tables(&self) -> String {
        let mut s = self.gain_tables();
        s.push_str(&self.term_tables());
        let _ = writeln!(s, "{}", self.descriptor(self.t.factored.terms.len()));
        s
    }

    /// The const tables the straight-line step reads at constant indices:
    /// premise map, centres, gains and levels (the terms' parameters are
    /// constants in its code).
    fn straight_tables(&self) -> String {
        self.gain_tables()
    }

    /// Premise map, centres, gains and saturation levels.
    pub(super) fn gain_tables(&self) -> String {
        let t = self.t;
        let (p, u) = (&self.p, &self.u);
        let real = format!("{u}REAL");
        let mut s = self.premise_tables();
        let mut gains = Vec::new();
        match &t.modes {
            Some(mt) => {
                for (set, mode) in mt.gains.iter().zip(&mt.names) {
                    for (f, name) in set.iter().zip(&t.rule_names) {
                        gains.push(format!("    /* mode {mode}, {name} */\n{}", flat_rows(f)));
                    }
                }
                let _ = writeln!(
                    s,
                    "/* PDC gains F_aj ({u}M x {u}N, row-major): per mode, one block per rule. */\nstatic const {real} {p}gains[{u}K * {u}R * {u}M * {u}N] = {{\n{}\n}};\n",
                    gains.join(",\n")
                );
            }
            None => {
                for (f, name) in t.gains.iter().zip(&t.rule_names) {
                    gains.push(format!("    /* {name} */\n{}", flat_rows(f)));
                }
                let _ = writeln!(
                    s,
                    "/* PDC gains F_j ({u}M x {u}N, row-major), one block per rule. */\nstatic const {real} {p}gains[{u}R * {u}M * {u}N] = {{\n{}\n}};\n",
                    gains.join(",\n")
                );
            }
        }
        let _ = writeln!(
            s,
            "/* Saturation levels (INFINITY = unlimited). */\nstatic const {real} {p}u_max[{u}M] = {};\n",
            list(&t.u_max)
        );
        s
    }

    /// The premise map `z = L x` (linear premises only) and the rule centres.
    pub(super) fn premise_tables(&self) -> String {
        let t = self.t;
        let (p, u) = (&self.p, &self.u);
        let real = format!("{u}REAL");
        let pd = self.pd;
        let mut s = String::new();
        if let PremiseCode::Linear(l) = &t.premise {
            let _ = writeln!(
                s,
                "/* Premise map z = L x ({pd} rows of {u}N, row-major, one row per line). */\nstatic const {real} {p}premise_map[{pd} * {u}N] = {{\n{}\n}};\n",
                flat_rows(&padded(l, t.n))
            );
        }
        let _ = writeln!(
            s,
            "/* Rule centres in premise space ({u}R rows of {pd}; nearest-rule fallback). */\nstatic const {real} {p}centres[{u}R * {pd}] = {{\n{}\n}};\n",
            flat_rows(&padded(&t.centres, pd))
        );
        s
    }

    /// The distinct premise terms, the rules' factor lists and the `about`
    /// points (every table a descriptor's rule part points at).
    pub(super) fn term_tables(&self) -> String {
        let t = self.t;
        let (p, u) = (&self.p, &self.u);
        let real = format!("{u}REAL");
        let mut s = String::new();
        let f = &t.factored;
        let mut points: Vec<f64> = Vec::new();
        let mut terms: Vec<String> = f
            .terms
            .iter()
            .enumerate()
            .map(|(k, term)| term_entry(term, &users(t, k), &mut points))
            .collect();
        if terms.is_empty() {
            terms.push("    {TSF_TERM_TRAP, 0, 0, 0, {0.0, 0.0, 0.0, 0.0}} /* unused */".into());
        }
        if points.is_empty() {
            points.push(0.0);
        }
        let mut factors: Vec<String> = Vec::new();
        let mut firsts = vec!["0".to_string()];
        for rule in &f.rules {
            factors.extend(rule.iter().map(usize::to_string));
            firsts.push(factors.len().to_string());
        }
        if factors.is_empty() {
            factors.push("0".into());
        }
        let _ = write!(
            s,
            r#"/* The distinct rule-premise terms (tsf_term in tsf_runtime.h), each
   evaluated once per step. */
static const {u}RT(tsf_term) {p}terms[{nt}] = {{
{terms}
}};

/* Every rule's premise as indices into {p}terms, rule after rule (the
   weight is the product of the degrees, in this order). */
static const int {p}factors[{nf}] = {{{factors}}};

/* Terms of rule i: {p}factors[{p}rule_factors[i] .. {p}rule_factors[i + 1]]. */
static const int {p}rule_factors[{u}R + 1] = {{{firsts}}};

/* Operating points of `about` terms. */
static const {real} {p}about_points[{np}] = {pts};

"#,
            nt = terms.len(),
            terms = terms.join(",\n"),
            nf = factors.len(),
            factors = factors.join(", "),
            firsts = firsts.join(", "),
            np = points.len(),
            pts = list(&points),
        );
        s
    }

    /// The descriptor(s) the runtime's step reads: `<name>_tables`, or one
    /// per mode `<name>_tables[K]` (each pointing at its mode's gains).
    fn descriptor(&self, d: usize) -> String {
        let (p, u) = (&self.p, &self.u);
        let entry = |gains: String| {
            self.descriptor_entry(d, &format!("{u}M"), &gains, &format!("{p}u_max"))
        };
        match &self.t.modes {
            Some(mt) => {
                let entries: Vec<String> = (0..mt.names.len())
                    .map(|a| entry(format!("&{p}gains[{a} * {u}R * {u}M * {u}N]")))
                    .collect();
                format!(
                    "/* Everything the runtime's step reads, per mode (its gains). */\nstatic const {u}RT(tsf_controller) {p}tables[{u}K] = {{\n{}\n}};\n",
                    entries.join(",\n")
                )
            }
            None => format!(
                "/* Everything the runtime's step reads. */\nstatic const {u}RT(tsf_controller) {p}tables = {};\n",
                entry(format!("{p}gains"))
            ),
        }
    }

    /// One `tsf_controller` initializer over this module's rule tables with
    /// `m` commands, the given gains and saturation levels.
    pub(super) fn descriptor_entry(&self, d: usize, m: &str, gains: &str, u_max: &str) -> String {
        let (p, u) = (&self.p, &self.u);
        format!(
            "{{\n    {u}N, {m}, {u}P, {u}R, {d},\n    {p}terms, {p}factors, {p}rule_factors, {p}about_points,\n    {p}centres, {gains}, {u_max}\n}}"
        )
    }

    /// `name_premises`: `z = L x` or straight-line premise expressions.
    pub(super) fn premises(&self) -> String {
        let (p, u) = (&self.p, &self.u);
        let real = format!("{u}REAL");
        let mut body = String::new();
        match &self.t.premise {
            PremiseCode::Linear(_) => {
                let _ = write!(
                    body,
                    "    int k;\n    for (k = 0; k < {u}P; k++) {{\n        z[k] = {u}RT(tsf_dot)(&{p}premise_map[k * {u}N], x, {u}N);\n    }}\n"
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
    pub(super) fn expr(&self, e: &Sym, out: &mut String, next: &mut usize) -> String {
        let u = &self.u;
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
                        Sym::Call(f, _) => format!(
                            "{u}RT(tsf_{})({})",
                            f.name(),
                            vals.pop().unwrap_or_default()
                        ),
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
}

/// `rows` with every row padded with zeros (or cut) to `width` entries,
/// and at least one row (C has no empty arrays).
fn padded(rows: &[Vec<f64>], width: usize) -> Vec<Vec<f64>> {
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

/// The rules using distinct term `k`, for the term table's comments.
fn users(t: &Tables, k: usize) -> String {
    let names: Vec<&str> = t
        .factored
        .rules
        .iter()
        .zip(&t.rule_names)
        .filter(|(rule, _)| rule.contains(&k))
        .map(|(_, name)| name.as_str())
        .collect();
    names.join(", ")
}

/// One entry of the term table (a `tsf_term` initializer) with a comment
/// naming the rules that use it; `about` points are appended to `points`.
fn term_entry(term: &TermSpec, rules: &str, points: &mut Vec<f64>) -> String {
    let (kind, var, len, point, prm) = match term {
        TermSpec::Is { var, set } => {
            let (kind, prm) = match *set {
                SetShape::Tri(a, b, c) => ("TRAP", [a, b, b, c]),
                SetShape::Trap(a, b, c, d) => ("TRAP", [a, b, c, d]),
                SetShape::Gauss(c, sg) => ("GAUSS", [c, sg, 0.0, 0.0]),
                SetShape::Sigmoid(k, c) => ("SIGMOID", [k, c, 0.0, 0.0]),
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
            ("ABOUT", *first, point.len(), at, [*sigma, 0.0, 0.0, 0.0])
        }
    };
    format!(
        "    {{TSF_TERM_{kind}, {var}, {len}, {point}, {}}} /* {rules} */",
        list(&prm)
    )
}
