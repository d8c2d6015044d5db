//! `precision f32`: every number the spec gives that generated code stores
//! (membership parameters, `about` points and widths, given gains, trigger
//! weights and sampling, thresholds, saturation levels) must be a finite f32.
//! Past `f32::MAX` the stored value would be infinite: a spec error at the
//! number's item, never a table of infinities or a panic in code generation.

use super::Checker;
use crate::diag::Diagnostic;
use crate::num::Num;
use crate::span::Span;
use crate::spec::{ClauseSet, Precision, SetShape, Spec, Trigger, Weight};

/// Whether `v` survives `v as f32` as a finite number.
fn fits(v: f64) -> bool {
    (v as f32).is_finite() || !v.is_finite()
}

impl Checker<'_> {
    /// With `precision f32`, one error per item whose stored numbers do not
    /// fit an f32 (`saturate` points at the input's `saturate` value).
    pub(super) fn f32_storable(&mut self, spec: &Spec, saturate: Option<Span>) {
        if spec.precision != Precision::F32 {
            return;
        }
        let mut found: Vec<(Span, String, f64)> = Vec::new();
        let mut check = |span: Span, what: String, values: Vec<f64>| {
            if let Some(v) = values.into_iter().find(|v| !fits(*v)) {
                found.push((span, what, v));
            }
        };
        for p in &spec.premises {
            for set in &p.sets {
                let params = match set.shape {
                    SetShape::Tri(a, b, c) => vec![a, b, c],
                    SetShape::Trap(a, b, c, d) => vec![a, b, c, d],
                    SetShape::Gauss(a, b) | SetShape::Sigmoid(a, b) => vec![a, b],
                };
                let what = format!("a parameter of the set `{}` of `{}`", set.name, p.name);
                check(set.span, what, params);
            }
            if let Some(sigma) = p.sigma {
                let what = format!("the `about` width of `{}`", p.name);
                check(p.span, what, vec![sigma]);
            }
        }
        for r in &spec.rules {
            for c in &r.clauses {
                if let ClauseSet::About(point) = &c.set {
                    let what = format!("an `about` point of rule `{}`", r.name);
                    check(c.span, what, point.clone());
                }
            }
            if let Some((f, span)) = &r.gain {
                let what = format!("an entry of the gain of rule `{}`", r.name);
                check(*span, what, f.iter().copied().collect());
            }
        }
        if let (Some(levels), Some(span)) = (&spec.saturation, saturate) {
            check(span, "a saturation level".into(), levels.clone());
        }
        if let Some(t) = &spec.trigger {
            let values: Vec<f64> = match &t.node {
                Trigger::Continuous => Vec::new(),
                Trigger::Periodic { every } => vec![*every],
                Trigger::Jittered { every, jitter } => vec![*every, *jitter],
                Trigger::Aperiodic {
                    sampling,
                    threshold,
                    weight,
                } => {
                    let mut v = vec![sampling.0, sampling.1];
                    if let Some(th) = threshold {
                        v.extend([th.nu, th.ceiling()]);
                        v.extend(th.adaptive.iter().flat_map(|(a, b, c)| [*a, *b, *c]));
                    }
                    if let Weight::Given(w) = weight {
                        v.extend(w.iter().copied());
                    }
                    v
                }
                Trigger::Mixed {
                    monitor, beta, rho, ..
                } => {
                    let mut v = vec![*beta, *rho];
                    v.extend(monitor.sampling().iter().flat_map(|(a, b)| [*a, *b]));
                    v
                }
            };
            check(t.span, "a value of the trigger".into(), values);
        }
        for (span, what, v) in found {
            self.err(
                Diagnostic::error(span, format!("{what} does not fit `precision f32`"))
                    .with_label(format!(
                        "{} is beyond the largest f32, {:e}: generated code would store infinity",
                        Num(v),
                        f32::MAX
                    ))
                    .with_help("scale the value into the f32 range, or write `precision f64;`"),
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::check::testing::only_error_of as only_error;

    const BASE: &str =
        "tsf 1; controller c; state x1; input u saturate 2; A = 1; B = 1;\nprecision f32;\n";

    #[test]
    fn every_stored_parameter_must_fit_an_f32() {
        let cases = [
            (
                "premise x1 range -2 .. 2 { a = gauss(-1e39, 0.6); b = gauss(1, 0.6); }\nrule R1: x1 is a => A = 1;\nrule R2: x1 is b => A = 1;",
                "a parameter of the set `a` of `x1` does not fit `precision f32`",
                "a = gauss(-1e39, 0.6);",
            ),
            (
                "premise x1 range -2 .. 2 { a = trap(-2, -2, 2, 2); }\nrule R1: x1 is a => A = 1, F = -1e41;",
                "an entry of the gain of rule `R1` does not fit `precision f32`",
                "-1e41",
            ),
            (
                "premise x1 range -2 .. 2 { a = trap(-2, -2, 2, 2); }\nrule R1: x1 is a => A = 1;\ntrigger mixed { beta = 0.1; rho = 1e39; monitor = continuous; }",
                "a value of the trigger does not fit `precision f32`",
                "trigger mixed { beta = 0.1; rho = 1e39; monitor = continuous; }",
            ),
        ];
        for (tail, message, at) in cases {
            // The mixed trigger is refused with saturation (its own check), so
            // its case runs on the unsaturated input.
            let base = if tail.contains("mixed") {
                BASE.replace(" saturate 2", "")
            } else {
                BASE.to_string()
            };
            let (m, span) = only_error(&format!("{base}{tail}"));
            assert_eq!(m, message);
            assert_eq!(span, at);
        }
        let (m, span) = only_error(&format!(
            "{}premise x1 range -2 .. 2 {{ a = trap(-2, -2, 2, 2); }}\nrule R1: x1 is a => A = 1;",
            BASE.replace("saturate 2", "saturate 1e39")
        ));
        assert_eq!(m, "a saturation level does not fit `precision f32`");
        assert_eq!(span, "1e39");
    }
}
