//! Problem reductions: constraints or variables left out of the solved SDP
//! because they are provably implied. Each is an object the certificate
//! inverts (restoring the variables the reduced problem did not have), so the
//! certificate always checks the original, unreduced conditions.

use nalgebra::DMatrix;

/// Values of named variables, as kept in a design.
pub type Values = Vec<(String, DMatrix<f64>)>;

/// One reduction applied to a solved problem.
#[derive(Debug, Clone, PartialEq)]
pub enum Reduction {
    /// Pair LMIs of a family dropped: every rule shares B, so each equals a
    /// sum of vertex LMIs (Q_ij + Q_ji = Q_ii + Q_jj) and is implied.
    PairsDropped {
        /// The objective family.
        family: String,
        /// How many LMIs.
        count: usize,
    },
    /// Conditions left out of the solved problem because others imply them
    /// (the sentence says which and why); the certificate checks them.
    Implied(String),
    /// Tanaka's slack Y of a family fixed to 0 and its pair LMIs dropped:
    /// every rule shares B, so (Q_ij + Q_ji)/2 = (Q_ii + Q_jj)/2 < 0 <= Y is
    /// implied by the vertex LMIs.
    TanakaSlackZero {
        /// The objective family.
        family: String,
        /// Pair LMIs dropped.
        pairs: usize,
        /// Name of the slack variable of the full problem.
        var: String,
        /// Its size.
        size: usize,
    },
}

impl Reduction {
    /// Restores, in `values`, the variables the reduced problem did not have.
    pub fn invert(&self, values: &mut Values) {
        match self {
            Reduction::PairsDropped { .. } | Reduction::Implied(_) => {}
            Reduction::TanakaSlackZero { var, size, .. } => {
                if !values.iter().any(|(n, _)| n == var) {
                    values.push((var.clone(), DMatrix::zeros(*size, *size)));
                }
            }
        }
    }
}

impl std::fmt::Display for Reduction {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Reduction::PairsDropped { family, count } => write!(
                f,
                "{family}: {count} pair LMIs dropped: every rule shares B, so each equals a sum of vertex LMIs (Q_ij + Q_ji = Q_ii + Q_jj) and is implied; the certificate still checks them"
            ),
            Reduction::Implied(what) => f.write_str(what),
            Reduction::TanakaSlackZero { family, pairs, .. } => write!(
                f,
                "{family}: tanaka slack Y = 0 and {pairs} pair LMIs dropped: every rule shares B, so (Q_ij + Q_ji)/2 = (Q_ii + Q_jj)/2 < 0 <= Y is implied by the vertex LMIs; the certificate checks the original conditions with Y = 0"
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tanaka_inversion_restores_a_zero_slack_once() {
        let r = Reduction::TanakaSlackZero {
            family: "decay".into(),
            pairs: 3,
            var: "Y_decay".into(),
            size: 2,
        };
        let mut v = Values::new();
        r.invert(&mut v);
        r.invert(&mut v);
        assert_eq!(v.len(), 1);
        assert_eq!(v[0].0, "Y_decay");
        assert_eq!(v[0].1, DMatrix::zeros(2, 2));
        let mut w = Values::new();
        Reduction::PairsDropped {
            family: "hinf".into(),
            count: 4,
        }
        .invert(&mut w);
        assert!(w.is_empty());
    }
}
