//! The observer part of an observer-based design's tables: the measured
//! output map C, and every rule's fuzzy observer discretized exactly at the
//! controller's period.
//!
//! The continuous observer of rule i is
//! `xhat' = (A_i - L_i C) xhat + B_i u + L_i y`. With u and y held over one period T (zero-order hold, the
//! memberships frozen at the sample), its exact discretization is
//!
//!   Phi_i = expm(Ao_i T),  [Gu_i Gy_i] = int_0^T expm(Ao_i s) ds [B_i L_i],
//!
//! `Ao_i = A_i - L_i C`, both read off one matrix exponential of the
//! augmented block matrix `[[Ao_i, [B_i L_i]], [0, 0]] T` (C. F. Van Loan,
//! "Computing integrals involving the matrix exponential", IEEE TAC 23(3),
//! 1978), computed by the same zero-order-hold routine as the discrete-time
//! design route ([`crate::synth::objectives::discrete::zoh`]).
//!
//! [`ObserverTables::from_design`] is the seam: it takes the design as plain
//! continuous-time data (C, the gains L_i, the rules' A_i and B_i, the
//! period and where the premises come from).

use super::TablesError;
use crate::synth::observer::sampled::ObserverSteps;
use nalgebra::DMatrix;
use tsf_lang::spec::{Spec, Trigger};

/// Where the premises of an observer-based controller are computed from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PremiseFrom {
    /// From the measured output y: the observer and the controller blend
    /// with the plant's true memberships.
    Output,
    /// From the estimate xhat (unmeasured premises).
    Estimate,
}

/// The observer of an observer-based design, as generated code and the
/// simulator run it.
#[derive(Debug, Clone, PartialEq)]
pub struct ObserverTables {
    /// Measured outputs (rows of C).
    pub q: usize,
    /// The measured output y = C x (Q rows of N).
    pub c: Vec<Vec<f64>>,
    /// The controller's period T in seconds (the observer's step).
    pub period: f64,
    /// Where the premises are computed from.
    pub premise_from: PremiseFrom,
    /// With premises from the output: S (N rows of Q), the premises read the
    /// state-like vector S y (S = C' (C C')^-1 puts the measured components
    /// back in their places); `None` when the premises read the estimate.
    pub output_map: Option<Vec<Vec<f64>>>,
    /// The continuous observer gains L_i (R x N x Q), for headers.
    pub gains: Vec<Vec<Vec<f64>>>,
    /// Phi_i (R x N x N).
    pub phi: Vec<Vec<Vec<f64>>>,
    /// Gu_i (R x N x M).
    pub gu: Vec<Vec<Vec<f64>>>,
    /// Gy_i (R x N x Q).
    pub gy: Vec<Vec<Vec<f64>>>,
}

/// The rows of a matrix.
fn rows(m: &DMatrix<f64>) -> Vec<Vec<f64>> {
    crate::util::matrix::rows(m)
}

pub use crate::synth::observer::sampled::discretize;

/// The controller's period of a spec: `trigger periodic { every = T; }`.
/// Any other loop is refused (the observer runs at a fixed period).
pub fn period_of(spec: &Spec) -> Result<f64, TablesError> {
    match spec.trigger.as_ref().map(|t| &t.node) {
        Some(Trigger::Periodic { every }) => Ok(*every),
        _ => Err(TablesError::ObserverPeriod),
    }
}

/// The observer tables of a certified design: those of its sampled
/// observer loop's certificate (`None` without one).
pub fn of_design(
    model: &crate::model::TsModel,
    design: &crate::synth::Design,
) -> Result<Option<ObserverTables>, TablesError> {
    use crate::synth::observer::OutputFeedback;
    let (Some(s), Some(OutputFeedback::Observer(o))) =
        (design.loop_design.observer_sampled(), &design.output)
    else {
        return Ok(None);
    };
    let a: Vec<DMatrix<f64>> = model.rules.iter().map(|r| r.a.clone()).collect();
    let b: Vec<DMatrix<f64>> = model.rules.iter().map(|r| r.b.clone()).collect();
    ObserverTables::from_certified(
        &o.c,
        &o.gains,
        (&a, &b),
        &s.steps,
        s.period,
        PremiseFrom::Output,
    )
    .map(Some)
}

impl ObserverTables {
    /// The observer tables of a design given as continuous-time data: the
    /// measured output `c` (Q x N), the observer gains `l` (one N x Q per
    /// rule), the rules' `a` (N x N) and `b` (N x M), the controller's
    /// `period` and where the premises come from. Errors name the first
    /// inconsistent shape, a period that is not a positive number, a C
    /// without full row rank (premises from the output) or a non-finite
    /// discretized entry.
    pub fn from_design(
        c: &DMatrix<f64>,
        l: &[DMatrix<f64>],
        a: &[DMatrix<f64>],
        b: &[DMatrix<f64>],
        period: f64,
        premise_from: PremiseFrom,
    ) -> Result<Self, TablesError> {
        Self::build(c, l, (a, b), None, period, premise_from)
    }

    /// [`ObserverTables::from_design`] with the discrete observer `steps`
    /// the sampled loop's certificate was built from (the tables store
    /// exactly those numbers).
    pub fn from_certified(
        c: &DMatrix<f64>,
        l: &[DMatrix<f64>],
        (a, b): (&[DMatrix<f64>], &[DMatrix<f64>]),
        steps: &ObserverSteps,
        period: f64,
        premise_from: PremiseFrom,
    ) -> Result<Self, TablesError> {
        if steps.phi.len() != a.len() || steps.gu.len() != a.len() || steps.gy.len() != a.len() {
            return Err(TablesError::ObserverShape(format!(
                "{} discrete observers for {} rules",
                steps.phi.len(),
                a.len()
            )));
        }
        Self::build(c, l, (a, b), Some(steps), period, premise_from)
    }

    fn build(
        c: &DMatrix<f64>,
        l: &[DMatrix<f64>],
        (a, b): (&[DMatrix<f64>], &[DMatrix<f64>]),
        steps: Option<&ObserverSteps>,
        period: f64,
        premise_from: PremiseFrom,
    ) -> Result<Self, TablesError> {
        let (q, n) = c.shape();
        let shape = |what: String| Err(TablesError::ObserverShape(what));
        if !(period.is_finite() && period > 0.0) {
            return Err(TablesError::ObserverPeriod);
        }
        if q == 0 || n == 0 {
            return shape(format!("C is {q}x{n}: at least one output and one state"));
        }
        if l.len() != a.len() || b.len() != a.len() || a.is_empty() {
            return shape(format!(
                "{} observer gains, {} A_i and {} B_i: one of each per rule",
                l.len(),
                a.len(),
                b.len()
            ));
        }
        let m = b[0].ncols();
        for (i, ((li, ai), bi)) in l.iter().zip(a).zip(b).enumerate() {
            let expect = [(li, (n, q), "L"), (ai, (n, n), "A"), (bi, (n, m), "B")];
            for (mat, want, name) in expect {
                if mat.shape() != want {
                    let ((r, k), (wr, wk)) = (mat.shape(), want);
                    return shape(format!(
                        "rule {}: {name} is {r}x{k}, expected {wr}x{wk}",
                        i + 1
                    ));
                }
            }
        }
        let output_map = match premise_from {
            PremiseFrom::Estimate => None,
            PremiseFrom::Output => {
                let cct = c * c.transpose();
                let inv = cct
                    .try_inverse()
                    .filter(|i| i.iter().all(|v| v.is_finite()))
                    .ok_or_else(|| {
                        TablesError::ObserverShape(
                            "C has no full row rank: the premises cannot be read from y".into(),
                        )
                    })?;
                Some(rows(&(c.transpose() * inv)))
            }
        };
        let (mut phi, mut gu, mut gy) = (Vec::new(), Vec::new(), Vec::new());
        for (i, ((li, ai), bi)) in l.iter().zip(a).zip(b).enumerate() {
            let (p, u, y) = match steps {
                Some(s) => (s.phi[i].clone(), s.gu[i].clone(), s.gy[i].clone()),
                None => discretize(ai, bi, c, li, period),
            };
            if p.shape() != (n, n) || u.shape() != (n, m) || y.shape() != (n, q) {
                return shape(format!("rule {}: the discrete observer's shapes", i + 1));
            }
            if ![&p, &u, &y].iter().all(|m| m.iter().all(|v| v.is_finite())) {
                return Err(TablesError::ObserverNonFinite);
            }
            phi.push(rows(&p));
            gu.push(rows(&u));
            gy.push(rows(&y));
        }
        Ok(ObserverTables {
            q,
            c: rows(c),
            period,
            premise_from,
            output_map,
            gains: l.iter().map(rows).collect(),
            phi,
            gu,
            gy,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Scalar closed form: ao = a - l c, phi = e^{ao T},
    /// [gu gy] = (e^{ao T} - 1)/ao [b l].
    #[test]
    fn scalar_observer_matches_its_closed_form() {
        let (a, b, c, l, t) = (0.7, 1.3, 2.0, 1.1, 0.05);
        let m = |v: f64| DMatrix::from_element(1, 1, v);
        let (phi, gu, gy) = discretize(&m(a), &m(b), &m(c), &m(l), t);
        let ao = a - l * c;
        let e = (ao * t).exp();
        assert!((phi[(0, 0)] - e).abs() < 1e-15);
        assert!((gu[(0, 0)] - b * (e - 1.0) / ao).abs() < 1e-15);
        assert!((gy[(0, 0)] - l * (e - 1.0) / ao).abs() < 1e-15);
    }

    #[test]
    fn bad_designs_are_refused_with_their_reason() {
        let c = DMatrix::from_row_slice(1, 2, &[1.0, 0.0]);
        let a = vec![DMatrix::zeros(2, 2)];
        let b = vec![DMatrix::zeros(2, 1)];
        let l = vec![DMatrix::zeros(2, 1)];
        let ok =
            ObserverTables::from_design(&c, &l, &a, &b, 0.01, PremiseFrom::Output).expect("valid");
        assert_eq!(ok.output_map, Some(vec![vec![1.0], vec![0.0]]));
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let e = ObserverTables::from_design(&c, &l, &a, &b, bad, PremiseFrom::Output);
            assert_eq!(e, Err(TablesError::ObserverPeriod));
        }
        let l3 = vec![DMatrix::zeros(3, 1)];
        let e = ObserverTables::from_design(&c, &l3, &a, &b, 0.01, PremiseFrom::Estimate)
            .expect_err("shape");
        assert!(
            e.to_string().contains("rule 1: L is 3x1, expected 2x1"),
            "{e}"
        );
        let c0 = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 2.0, 0.0]);
        let l2 = vec![DMatrix::zeros(2, 2)];
        let e = ObserverTables::from_design(&c0, &l2, &a, &b, 0.01, PremiseFrom::Output)
            .expect_err("rank");
        assert!(e.to_string().contains("full row rank"), "{e}");
    }
}
