//! Detectability of every local pair (A_i, C) of an output-feedback spec
//! (`control observer_based` or `static_output`), by the Popov-Belevitch-Hautus
//! test: for each eigenvalue lambda of A_i with Re lambda >= -[`UNSTABLE_TOL`]
//! (unstable or critically stable), [lambda I - A_i; C] must have full column
//! rank, i.e. its smallest singular value must exceed [`RANK_TOL`] times
//! max(1, ||A_i||, ||C||). A pair that fails is a spec error naming the rule:
//! no observer (and no output feedback) can recover that mode from y.

use super::LocalModel;
use nalgebra::{Complex, DMatrix};
use tsf_lang::spec::{ControlKind, Spec};
use tsf_lang::Diagnostic;

/// Eigenvalues with real part at least minus this (relative to max(1, ||A||))
/// count as unstable or critically stable.
pub const UNSTABLE_TOL: f64 = 1e-9;

/// Relative rank tolerance of the PBH matrix (its smallest singular value
/// against max(1, ||A_i||, ||C||)).
pub const RANK_TOL: f64 = 1e-8;

/// One undetectable mode: the eigenvalue and the smallest singular value of
/// the PBH matrix.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Undetectable {
    /// The eigenvalue of A_i.
    pub eigenvalue: Complex<f64>,
    /// sigma_min([lambda I - A_i; C]).
    pub sigma_min: f64,
}

/// The first undetectable mode of (a, c), if any (`None` also when the
/// shapes do not match; the checker has refused those).
pub fn undetectable(a: &DMatrix<f64>, c: &DMatrix<f64>) -> Option<Undetectable> {
    let n = a.nrows();
    if a.ncols() != n || c.ncols() != n {
        return None;
    }
    let scale = 1f64.max(a.norm()).max(c.norm());
    let eig = a
        .clone()
        .try_schur(1e-14, 10_000)
        .map(|s| s.complex_eigenvalues())?;
    let p = c.nrows();
    for lambda in eig.iter() {
        if lambda.re < -UNSTABLE_TOL * 1f64.max(a.norm()) {
            continue;
        }
        let mut pbh = DMatrix::<Complex<f64>>::zeros(n + p, n);
        for r in 0..n {
            for k in 0..n {
                let diag = if r == k {
                    *lambda
                } else {
                    Complex::new(0.0, 0.0)
                };
                pbh[(r, k)] = diag - Complex::new(a[(r, k)], 0.0);
            }
        }
        for r in 0..p {
            for k in 0..n {
                pbh[(n + r, k)] = Complex::new(c[(r, k)], 0.0);
            }
        }
        let sigma_min = pbh
            .svd(false, false)
            .singular_values
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        if sigma_min.is_nan() || sigma_min <= RANK_TOL * scale {
            return Some(Undetectable {
                eigenvalue: *lambda,
                sigma_min,
            });
        }
    }
    None
}

/// Spec errors for the rules whose pair (A_i, C) is not detectable (output
/// feedback only).
pub fn check(spec: &Spec, rules: &[LocalModel], diags: &mut Vec<Diagnostic>) {
    if spec.control.kind == ControlKind::StateFeedback {
        return;
    }
    let Some(measured) = &spec.measure else {
        return;
    };
    for (rule, local) in spec.rules.iter().zip(rules) {
        let Some(u) = undetectable(&local.a, &measured.c) else {
            continue;
        };
        diags.push(
            Diagnostic::error(
                rule.span,
                format!(
                    "the pair (A, C) of rule {} is not detectable: the mode at eigenvalue {:.6}{:+.6}i is not seen by the measured outputs",
                    rule.name, u.eigenvalue.re, u.eigenvalue.im
                ),
            )
            .with_label(format!(
                "PBH test: sigma_min([lambda I - A; C]) = {:.3e} (tolerance {RANK_TOL:.0e} relative)",
                u.sigma_min
            ))
            .with_secondary(measured.span, "the measured outputs y = C x")
            .with_help("measure a state this mode moves (add a row to `measure`), or change the rule's model: no observer can estimate an unstable mode y does not see"),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pbh_test_finds_the_hidden_unstable_mode() {
        // x1' = x1 (unstable) measured, x2' = x2 hidden: undetectable.
        let a = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 2.0]);
        let c = DMatrix::from_row_slice(1, 2, &[1.0, 0.0]);
        let u = undetectable(&a, &c).expect("x2 is hidden"); // ok: unit test
        assert!((u.eigenvalue.re - 2.0).abs() < 1e-12);
        // A hidden stable mode is detectable.
        let a = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, -2.0]);
        assert!(undetectable(&a, &c).is_none());
        // The double integrator measured by position is observable.
        let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 0.0, 0.0]);
        assert!(undetectable(&a, &c).is_none());
        // ... by velocity it is not (the position mode at 0 is hidden).
        let c = DMatrix::from_row_slice(1, 2, &[0.0, 1.0]);
        assert!(undetectable(&a, &c).is_some());
    }
}
