//! Disturbance signals `name(t) = expr` of the `simulate` block, evaluated
//! with the language's evaluator and `t` bound.

use super::source::SpecSource;
use super::SimError;
use tsf_lang::ast::Expr;
use tsf_lang::eval::{Env, Mode};
use tsf_lang::spec::Spec;

/// The disturbance vector `w(t)` (components without a signal are 0).
pub struct Signals<'a> {
    spec: &'a Spec,
    source: &'a SpecSource,
    /// `(offset, len, expr)` per defined signal.
    parts: Vec<(usize, usize, &'a Expr)>,
    q: usize,
}

impl<'a> Signals<'a> {
    /// The signals of `spec`'s scenario (evaluation errors point into `source`).
    pub fn new(spec: &'a Spec, source: &'a SpecSource) -> Self {
        let parts = spec
            .simulate
            .iter()
            .flat_map(|s| &s.signals)
            .filter_map(|(k, e)| spec.disturbances.get(*k).map(|d| (d.offset, d.len, e)))
            .collect();
        Signals {
            spec,
            source,
            parts,
            q: spec.q(),
        }
    }

    /// Total disturbance dimension q.
    pub fn len(&self) -> usize {
        self.q
    }

    /// `true` when there is no disturbance input.
    pub fn is_empty(&self) -> bool {
        self.q == 0
    }

    /// Writes `w(t)` into `w` (length q).
    pub fn eval(&self, t: f64, w: &mut [f64]) -> Result<(), SimError> {
        w.iter_mut().for_each(|v| *v = 0.0);
        if self.parts.is_empty() {
            return Ok(());
        }
        let env = Env {
            consts: &self.spec.consts,
            fns: &self.spec.fns,
            locals: vec![("t".to_string(), nalgebra::DMatrix::from_element(1, 1, t))],
            unavailable: Vec::new(),
            mode: Mode::Exact,
        };
        for &(offset, len, e) in &self.parts {
            let v = env
                .eval(e)
                .map_err(|d| self.source.eval_error("disturbance signal", t, d))?;
            if v.len() != len {
                return Err(self.source.error_at(
                    e.span,
                    format!(
                        "disturbance signal has {} components, expected {len}",
                        v.len()
                    ),
                    "give the signal as many components as the disturbance",
                ));
            }
            if let Some(dst) = w.get_mut(offset..offset + len) {
                dst.copy_from_slice(v.as_slice());
            }
        }
        Ok(())
    }
}
