//! The C99 backend: a header `<name>.h` and a source `<name>.c` per
//! controller, a sensor module `<name>_sensor.h/.c` for an aperiodic event
//! trigger, and the fixed runtime `tsf_runtime.h/.c` they include.
//!
//! The runtime (`runtime/c` in the repository, embedded here by
//! [`runtime`]) does every computation of `tsf_runtime::FactoredController::step` and
//! of the trigger state machines, operation by operation; generated files
//! hold only what depends on the spec: dimensions, const tables, the premise
//! function and the step. The step has two styles (`emit c(style = ..)`,
//! [`is_straight`]): `table`, a thin wrapper passing the tables to the
//! runtime's step, and `straight` (the default up to
//! [`STRAIGHT_MAX_GAINS`] gain entries), the runtime's step written out for
//! the controller with every dimension a constant (`straight.rs`), bit for
//! bit the same results.
//!
//! Conventions (runtime/README.md): no `malloc`, no recursion, no global
//! mutable state (the caller owns `<name>_t`), only standard headers
//! (`stdint.h`, `math.h`, `float.h`), `const` tables, every external symbol
//! prefixed `<name>_` and every macro `<NAME>_` so several controllers link
//! into one image (the runtime's are `tsf_` and `TSF_`), a float-type macro
//! `<NAME>_REAL` (default `double`, or `float` when the spec asks for
//! `precision f32`) that selects the runtime's double or float functions,
//! include guards and `extern "C"` guards.
//!
//! Floating-point fidelity: every arithmetic step is the runtime's, in the
//! runtime's order (sums accumulated from 0 in index order, products in
//! their own statements so that a compiler allowed to contract `a*b + c`
//! within an expression, like clang's default `-ffp-contract=on`, cannot
//! fuse them). The elementary functions are the Rust runtime's, bit for bit,
//! in both precisions: `tsf_runtime.c` mirrors `math::exp`, `sin`, `cos`,
//! `sinc`, `exprel`, `atan` (binary64) and their binary32 `f` variants
//! operation by operation (no libm call); `sqrt` and `fabs` are C's (correctly
//! rounded and exact, so the same bits).

use super::header::marker;
use super::{Backend, CodegenError, GeneratedFile};
use crate::tables::{AdaptiveTables, Sensor, Tables};
use std::fmt::Write as _;
use tsf_lang::spec::Emit;

mod adaptive;
mod header;
mod observer;
pub mod runtime;
mod sensor;
mod signal_sensor;
mod source;
mod step;
mod straight;

pub use adaptive::emit_c_adaptive;
pub use sensor::{c_sensor_file_names, emit_c_sensor};
pub use signal_sensor::emit_c_signal_sensor;
pub use straight::{is_straight, STRAIGHT_MAX_GAINS};

/// The C99 backend: `<name>.h` and `<name>.c`, `<name>_sensor.h` and
/// `<name>_sensor.c` for an aperiodic event trigger, and the runtime
/// `tsf_runtime.h` and `tsf_runtime.c`.
#[derive(Debug, Clone, Copy)]
pub struct CBackend;

impl Backend for CBackend {
    fn target(&self) -> Emit {
        Emit::C
    }

    fn controller(&self, t: &Tables) -> Result<Vec<GeneratedFile>, CodegenError> {
        check_name(&t.name)?;
        if t.observer.is_some() {
            super::observer_supported(t)?;
            if t.c_style == tsf_lang::spec::CStyle::Straight {
                return Err(CodegenError::ObserverStraight);
            }
            let g = Gen::new(t);
            let files = CFiles {
                header: g.observer_header(),
                source: g.observer_source(),
            };
            return Ok(files.named(c_file_names(t)));
        }
        Ok(emit_c(t).named(c_file_names(t)))
    }

    fn sensor(&self, t: &Tables) -> Result<Vec<GeneratedFile>, CodegenError> {
        let files = match &t.sensor {
            Sensor::None => return Ok(Vec::new()),
            Sensor::Aperiodic(_) => emit_c_sensor(t)?,
            Sensor::Mixed(_) => emit_c_signal_sensor(t)?,
        };
        Ok(files.named(c_sensor_file_names(t)))
    }

    fn adaptive(&self, at: &AdaptiveTables) -> Result<Vec<GeneratedFile>, CodegenError> {
        check_name(&at.base.name)?;
        Ok(emit_c_adaptive(at).named(c_file_names(&at.base)))
    }

    fn support(&self) -> Vec<GeneratedFile> {
        runtime::files()
    }
}

/// Controller names whose C symbols would collide with the runtime's
/// (`tsf`, `tsf_...` in any case) are refused.
pub(super) fn check_name(name: &str) -> Result<(), CodegenError> {
    let lower = name.to_ascii_lowercase();
    if lower == "tsf" || lower.starts_with("tsf_") {
        return Err(CodegenError::ReservedName {
            name: name.to_string(),
            language: "C",
        });
    }
    Ok(())
}

/// The two generated files.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CFiles {
    /// Contents of `<name>.h`.
    pub header: String,
    /// Contents of `<name>.c` (includes `"<name>.h"` and `"tsf_runtime.h"`).
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

/// The spec-dependent text of one C module, under its symbol prefixes.
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

    /// The generator of the sensor module (`<name>_sensor_` symbols).
    fn sensor(t: &'a Tables) -> Self {
        let name = super::header::sensor_name(t);
        Self::with_prefix(
            t,
            format!("{name}_"),
            format!("{}_", name.to_ascii_uppercase()),
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
        if t.sensor.aperiodic().is_some() {
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
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn controller_names_of_the_runtime_are_refused() {
        for bad in ["tsf", "TSF", "tsf_relative", "Tsf_x"] {
            let e = check_name(bad).expect_err(bad);
            assert!(e.to_string().contains(bad), "{e}");
        }
        for ok in ["tsfc", "my_tsf", "zhang", "tsfx"] {
            assert!(check_name(ok).is_ok(), "{ok}");
        }
    }

    #[test]
    fn literals_are_shortest_round_trip_and_c_constants() {
        assert_eq!(lit(0.1), "0.1");
        assert_eq!(lit(-2.5e-300), "-2.5e-300");
        assert_eq!(lit(f64::INFINITY), "INFINITY");
        assert_eq!(lit(f64::NEG_INFINITY), "-INFINITY");
        assert_eq!(lit(f64::NAN), "NAN");
        assert_eq!(list(&[1.0, -0.5]), "{1.0, -0.5}");
        assert_eq!(
            flat_rows(&[vec![1.0, 2.0], vec![3.0, 4.0]]),
            "    1.0, 2.0,\n    3.0, 4.0"
        );
    }
}
