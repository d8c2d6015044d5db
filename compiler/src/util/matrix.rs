//! Matrices as plain rows (JSON reports and report sections).

use nalgebra::DMatrix;

/// Rows of a matrix, for JSON.
pub fn rows(m: &DMatrix<f64>) -> Vec<Vec<f64>> {
    (0..m.nrows())
        .map(|i| m.row(i).iter().copied().collect())
        .collect()
}
