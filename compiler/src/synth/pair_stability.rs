//! Stability of every plant/controller rule pair: A_i + B_i F_j for plant
//! rule i under the gain of controller rule j.
//!
//! A loop whose controller memberships may differ from the plant's (a
//! sampled or event-triggered loop holds the memberships of the last
//! sample) is certified by conditions on every pair with one common P. As
//! the interval shrinks to 0 each pair's condition tends to
//! He(P (A_i + B_i F_j)) < 0, which needs A_i + B_i F_j Hurwitz: one pair
//! with an eigenvalue in the closed right half-plane proves that no
//! sampling interval certifies those gains. Refusals name that pair and the
//! eigenvalue; the failed report lists every pair.

use super::adaptive::lyapunov::eigenvalue_real_parts;
use crate::model::TsModel;
use nalgebra::DMatrix;

/// The spectral abscissa of one plant/controller pair.
#[derive(Debug, Clone, PartialEq)]
pub struct PairAbscissa {
    /// Plant rule i (0-based).
    pub plant: usize,
    /// Controller rule j (0-based).
    pub controller: usize,
    /// The largest real part of the eigenvalues of A_i + B_i F_j (NaN when
    /// the eigenvalues did not converge).
    pub abscissa: f64,
}

/// Every pair (i, j), plant rule major, for the gains `gains` (F_j, m x n).
pub fn abscissae(model: &TsModel, gains: &[DMatrix<f64>]) -> Vec<PairAbscissa> {
    let mut out = Vec::with_capacity(model.r() * gains.len());
    for (i, rule) in model.rules.iter().enumerate() {
        for (j, f) in gains.iter().enumerate() {
            let closed = &rule.a + &rule.b * f;
            let abscissa = eigenvalue_real_parts(&closed)
                .and_then(|re| re.last().copied())
                .unwrap_or(f64::NAN);
            out.push(PairAbscissa {
                plant: i,
                controller: j,
                abscissa,
            });
        }
    }
    out
}

/// The least stable pair (largest abscissa; NaN first), if there are pairs.
pub fn worst(model: &TsModel, gains: &[DMatrix<f64>]) -> Option<PairAbscissa> {
    abscissae(model, gains).into_iter().max_by(|a, b| {
        let key = |p: &PairAbscissa| {
            if p.abscissa.is_nan() {
                f64::INFINITY
            } else {
                p.abscissa
            }
        };
        key(a).total_cmp(&key(b))
    })
}

impl PairAbscissa {
    /// "plant rule `R2` under the gain of rule `R1` (A + B F has an
    /// eigenvalue with real part +0.26)", with the spec's rule names.
    pub fn describe(&self, model: &TsModel) -> String {
        let name = |k: usize| model.rules.get(k).map_or("?", |r| r.name.as_str());
        let eig = if self.abscissa.is_nan() {
            "eigenvalues that did not converge".to_string()
        } else {
            format!("an eigenvalue with real part {:+.4}", self.abscissa)
        };
        if self.plant == self.controller {
            format!(
                "rule `{}` under its own gain (A + B F has {eig})",
                name(self.plant)
            )
        } else {
            format!(
                "plant rule `{}` under the gain of rule `{}` (A + B F has {eig})",
                name(self.plant),
                name(self.controller)
            )
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sector model of z' = -z * z + u on |z| <= 1: rules z_max (A = -1)
    /// and z_min (A = 1), b = 1; gains 0 and -2 give the pairs' closed
    /// loops -1, -3, 1, -1 (by hand).
    #[test]
    fn the_unstable_pair_is_found_with_its_eigenvalue() {
        let model = crate::model::scalar_sector_model(1.0);
        let gains = vec![DMatrix::zeros(1, 1), DMatrix::from_element(1, 1, -2.0)];
        let got: Vec<f64> = abscissae(&model, &gains)
            .iter()
            .map(|p| p.abscissa)
            .collect();
        assert_eq!(got.len(), 4);
        for (g, want) in got.iter().zip([-1.0, -3.0, 1.0, -1.0]) {
            assert!((g - want).abs() < 1e-12, "{got:?}");
        }
        let w = worst(&model, &gains).expect("pairs"); // ok: unit test
        assert_eq!((w.plant, w.controller), (1, 0));
        let text = w.describe(&model);
        assert!(
            text.contains("plant rule `z_min` under the gain of rule `z_max`")
                && text.contains("+1.0000"),
            "{text}"
        );
    }
}
