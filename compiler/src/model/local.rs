//! Local linear models: the model matrices evaluated at each rule's operating
//! point, with the rule's direct overrides.

use super::LocalModel;
use nalgebra::DMatrix;
use tsf_lang::eval::Mode;
use tsf_lang::spec::{ModelMatrix, Spec};
use tsf_lang::Diagnostic;

/// Evaluates A, B, D for every rule.
pub(super) fn local_models(spec: &Spec, diags: &mut Vec<Diagnostic>) -> Vec<LocalModel> {
    let (n, m, q) = (spec.n(), spec.m(), spec.q());
    let mut out = Vec::new();
    for rule in &spec.rules {
        let point = rule.at.as_ref().map(|(x, _)| x.clone());
        let x = point.clone().unwrap_or_else(|| vec![0.0; n]);
        let mut eval = |name: &str,
                        mm: &Option<ModelMatrix>,
                        rows: usize,
                        cols: usize|
         -> Option<DMatrix<f64>> {
            if let Some((_, v, _)) = rule.overrides.iter().find(|(k, _, _)| k == name) {
                return Some(v.clone());
            }
            let Some(mm) = mm else {
                return Some(DMatrix::zeros(rows, cols));
            };
            if mm.state_dependent && rule.at.is_none() {
                diags.push(
                    Diagnostic::error(
                        rule.span,
                        format!(
                            "rule {} has no operating point, but `{name}` depends on the state",
                            rule.name
                        ),
                    )
                    .with_secondary(mm.span, format!("`{name}(x)` defined here"))
                    .with_help(format!(
                        "add `at(...)` to the rule, or give `{name} = ...` in it"
                    )),
                );
                return None;
            }
            let env = spec.state_env(&x, Mode::Exact);
            match env.eval(&mm.expr) {
                Ok(v) if v.iter().all(|e| e.is_finite()) => Some(v),
                Ok(_) => {
                    let mut d = Diagnostic::error(
                        mm.expr.span,
                        format!(
                            "`{name}` is not finite at the operating point of rule {}",
                            rule.name
                        ),
                    )
                    .with_label("NaN or infinite entries");
                    if let Some((_, s)) = &rule.at {
                        d = d.with_secondary(*s, "evaluated at this operating point");
                    }
                    diags.push(d);
                    None
                }
                Err(d) => {
                    let d = match &rule.at {
                        Some((_, s)) => d.with_secondary(
                            *s,
                            format!("while evaluating `{name}` for rule {} here", rule.name),
                        ),
                        None => d,
                    };
                    diags.push(d);
                    None
                }
            }
        };
        let a = eval("A", &spec.a, n, n);
        let b = eval("B", &spec.b, n, m);
        let d = eval("D", &spec.d, n, q);
        if let (Some(a), Some(b), Some(d)) = (a, b, d) {
            out.push(LocalModel {
                name: rule.name.clone(),
                a,
                b,
                d,
                at: point,
            });
        }
    }
    out
}
