//! Polya's relaxation (Sala & Arino, *Asymptotically necessary and sufficient
//! conditions for stability and performance in fuzzy control: Applications of
//! Polya's theorem*, 2007): on the simplex sum_k h_k = 1, so
//! sum_ij h_i h_j Q_ij = (sum_ij h_i h_j Q_ij) (sum_k h_k)^d, a homogeneous
//! polynomial of degree d + 2 in h. It is negative definite for every h >= 0,
//! h != 0, if each of its coefficients is:
//!
//!   C_alpha = sum_{i,j: alpha - e_i - e_j >= 0} d! / (alpha - e_i - e_j)! Q_ij < 0
//!
//! for every multi-index |alpha| = d + 2. d = 0 gives `basic`; raising d
//! never loses feasibility and converges to the exact double-sum condition.

use crate::synth::relaxation::{DoubleSum, Family, Sink};
use tsf_lmi::{Expr, LmiError};

/// Polya's relaxation of degree `d`.
pub struct Polya {
    /// Degree of the multiplier (sum_k h_k)^d.
    pub d: usize,
}

/// Every multi-index of `r` entries summing to `total`, in lexicographic order.
fn multi_indices(r: usize, total: usize) -> Vec<Vec<usize>> {
    if r == 0 {
        return Vec::new();
    }
    if r == 1 {
        return vec![vec![total]];
    }
    (0..=total)
        .rev()
        .flat_map(|first| {
            multi_indices(r - 1, total - first)
                .into_iter()
                .map(move |mut rest| {
                    rest.insert(0, first);
                    rest
                })
        })
        .collect()
}

/// d! / prod_k beta_k!: the multinomial coefficient of h^beta in (sum h)^d.
fn multinomial(beta: &[usize]) -> f64 {
    let fact = |n: usize| (1..=n).map(|k| k as f64).product::<f64>();
    fact(beta.iter().sum()) / beta.iter().map(|&b| fact(b)).product::<f64>()
}

impl DoubleSum for Polya {
    fn impose(&self, sink: &mut Sink<'_, '_>, fam: &Family<'_>) -> Result<(), LmiError> {
        let r = sink.r();
        if sink.pair_reduce {
            // Every rule shares B: sum_ij h_i h_j Q_ij = sum_i h_i Q_ii exactly,
            // so the vertex conditions are necessary and sufficient.
            for i in 0..r {
                sink.negative(&fam.name("Q", i, i), fam.q(i, i)?)?;
            }
            sink.dropped(fam, r * (r - 1) / 2);
            return Ok(());
        }
        for alpha in multi_indices(r, self.d + 2) {
            let mut sum: Option<Expr> = None;
            for i in 0..r {
                for j in 0..r {
                    let mut beta = alpha.clone();
                    if beta[i] == 0 {
                        continue;
                    }
                    beta[i] -= 1;
                    if beta[j] == 0 {
                        continue;
                    }
                    beta[j] -= 1;
                    let term = fam.q(i, j)?.scale(multinomial(&beta))?;
                    sum = Some(match sum {
                        Some(s) => s.add(term)?,
                        None => term,
                    });
                }
            }
            if let Some(c) = sum {
                let name = format!(
                    "{} polya[{}]",
                    fam.name,
                    alpha
                        .iter()
                        .map(|a| a.to_string())
                        .collect::<Vec<_>>()
                        .join(",")
                );
                sink.negative(&name, c)?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::{multi_indices, multinomial};

    #[test]
    fn multi_indices_count_and_sum() {
        // (r + t - 1 choose t) indices of r entries summing to t.
        assert_eq!(multi_indices(3, 4).len(), 15);
        assert_eq!(
            multi_indices(2, 2),
            vec![vec![2, 0], vec![1, 1], vec![0, 2]]
        );
        assert!(multi_indices(4, 3)
            .iter()
            .all(|a| a.iter().sum::<usize>() == 3));
        assert_eq!(
            multi_indices(5, 4).len(),
            tsf_lang::limits::polya_lmis(5, 2).expect("small") // ok: unit test
        );
    }

    #[test]
    fn multinomials_sum_to_the_power_of_the_count() {
        // sum over |beta| = d of d!/beta! = r^d.
        let total: f64 = multi_indices(3, 4).iter().map(|b| multinomial(b)).sum();
        assert_eq!(total, 81.0);
    }
}
