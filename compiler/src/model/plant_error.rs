//! The model error as the design sees it: norm bounds of A(x) - A_h(x) and
//! B(x) - B_h(x) over a state box (the region of the plant claim), and the
//! closed-form geometry of that box: which level sets E(P, c) = {x' P x <= c}
//! fit inside it, and the box scaled about the origin.

/// A box of states: per state component `[lo, hi]` (infinite where unbounded).
pub type StateBox = Vec<(f64, f64)>;

/// Upper bounds of the model error over a region: ||A(x) - A_h(x)|| <= a and
/// ||B(x) - B_h(x)|| <= b (spectral norms) for every x in the region, with how
/// the bound was found.
/// (Serialized as the report's `plant.error_bound`.)
#[derive(Debug, Clone, PartialEq, serde::Serialize, schemars::JsonSchema)]
pub struct PlantError {
    /// Bound of the spectral norm of A(x) - A_h(x).
    pub a: f64,
    /// Bound of the spectral norm of B(x) - B_h(x).
    pub b: f64,
    /// Bound of the spectral norm of D(x) - D_h(x), when the spec has disturbances.
    pub d: Option<f64>,
    /// Boxes the region was subdivided into.
    pub boxes: usize,
    /// Whether the subdivision stopped because the bound stopped improving.
    pub converged: bool,
    /// The largest errors of A and B found by sampling (lower bounds of the truth).
    pub sampled_max: (f64, f64),
}

impl PlantError {
    /// The error of a model that equals its plant (no subdivision needed).
    pub fn exact() -> Self {
        PlantError {
            a: 0.0,
            b: 0.0,
            d: None,
            boxes: 0,
            converged: true,
            sampled_max: (0.0, 0.0),
        }
    }

    /// Whether the bound is zero (then the robust conditions are the nominal ones).
    pub fn is_zero(&self) -> bool {
        self.a == 0.0 && self.b == 0.0
    }
}

/// The default region of the plant claim: where the rules were placed (from
/// the smallest to the largest operating-point coordinate, or the box a
/// sector model was fitted on); a component the rules do not spread over is
/// unbounded.
pub fn default_region(model: &super::TsModel) -> StateBox {
    super::consistency::bounds(&model.spec, &model.rules, model.n)
        .into_iter()
        .map(|(lo, hi)| {
            if hi > lo {
                (lo, hi)
            } else {
                (f64::NEG_INFINITY, f64::INFINITY)
            }
        })
        .collect()
}

/// `region` scaled about the origin by `s` (unbounded components stay unbounded).
pub fn scaled(region: &StateBox, s: f64) -> StateBox {
    region.iter().map(|&(lo, hi)| (lo * s, hi * s)).collect()
}

/// The largest level c with E(P, c) inside `region`, from `p_inv` = P^{-1}:
/// the ellipsoid's extent along x_k is sqrt(c (P^{-1})_kk), so
/// c = min_k d_k^2 / (P^{-1})_kk over the bounded components, d_k the
/// distance from the origin to the nearer face. `None` when the region does
/// not contain the origin in its interior; infinite when nothing is bounded.
pub fn level_inside(region: &StateBox, p_inv: &nalgebra::DMatrix<f64>) -> Option<f64> {
    let mut c = f64::INFINITY;
    for (k, &(lo, hi)) in region.iter().enumerate() {
        if !(lo < 0.0 && hi > 0.0) {
            return None;
        }
        let d = (-lo).min(hi);
        if d.is_finite() {
            c = c.min(d * d / p_inv[(k, k)]);
        }
    }
    Some(c)
}

/// The extents of E(P, c) along each state: sqrt(c (P^{-1})_kk).
pub fn extents(p_inv: &nalgebra::DMatrix<f64>, c: f64) -> Vec<f64> {
    (0..p_inv.nrows())
        .map(|k| (c * p_inv[(k, k)]).sqrt())
        .collect()
}

/// Slack of the nominal design against the model error, without a new
/// design: with M_ij = He(P (A_i + B_i F_j)) + 2 alpha P and
/// mu = min(min_i -lmax(M_ii), min_{i<j} -lmax((M_ij + M_ji) / 2)), every
/// blend sum h_i h_j M_ij <= -mu I (the weights sum to 1), and the error adds
/// at most 2 ||P|| (a + b max_j ||F_j||) to it (||dA|| <= a, ||dB|| <= b, the
/// blended gain's norm at most the largest F_j's). The returned slack
/// mu - 2 ||P|| (a + b max ||F_j||) - rounding is positive when the plant
/// x' = A(x) x + B(x) u with these gains decreases V = x'Px at rate alpha
/// wherever the error bound holds. `gains`: one per rule, or one common gain.
pub fn nominal_slack(
    rules: &[super::LocalModel],
    p: &nalgebra::DMatrix<f64>,
    gains: &[nalgebra::DMatrix<f64>],
    alpha: f64,
    error: &PlantError,
) -> Option<f64> {
    let r = rules.len();
    let gain = |j: usize| gains.get(if gains.len() == 1 { 0 } else { j });
    let m = |i: usize, j: usize| -> Option<nalgebra::DMatrix<f64>> {
        let acl = &rules[i].a + &rules[i].b * gain(j)?;
        let pa = p * acl;
        Some(&pa + pa.transpose() + p * (2.0 * alpha))
    };
    let lmax = |s: nalgebra::DMatrix<f64>| s.symmetric_eigenvalues().max();
    let mut mu = f64::INFINITY;
    let mut scale = 0.0f64;
    for i in 0..r {
        for j in i..r {
            let s = if i == j {
                m(i, i)?
            } else {
                (m(i, j)? + m(j, i)?) * 0.5
            };
            scale = scale.max(s.norm());
            mu = mu.min(-lmax(s));
        }
    }
    let p_norm = p.clone().singular_values().max();
    let f_norm = gains
        .iter()
        .map(|f| f.clone().singular_values().max())
        .fold(0.0, f64::max);
    // Rounding of the products and the eigenvalues, far above f64's.
    let rounding = 1e-9 * (1.0 + scale);
    let slack = mu - 2.0 * p_norm * (error.a + error.b * f_norm) - rounding;
    slack.is_finite().then_some(slack)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    #[test]
    fn level_is_set_by_the_nearer_face() {
        // P^{-1} = diag(4, 1): extents sqrt(4c), sqrt(c); faces 1 (nearer side of
        // [-1, 3]) and 2: c = min(1/4, 4/1) = 0.25.
        let p_inv = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![4.0, 1.0]));
        let c = level_inside(&vec![(-1.0, 3.0), (-2.0, 2.0)], &p_inv).unwrap();
        assert!((c - 0.25).abs() < 1e-15);
        let e = extents(&p_inv, c);
        assert!((e[0] - 1.0).abs() < 1e-15 && (e[1] - 0.5).abs() < 1e-15);
        assert_eq!(level_inside(&vec![(0.0, 1.0), (-1.0, 1.0)], &p_inv), None);
        let open = vec![(f64::NEG_INFINITY, f64::INFINITY); 2];
        assert_eq!(level_inside(&open, &p_inv), Some(f64::INFINITY));
    }
}
