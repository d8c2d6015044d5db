//! The variables one module declares and another reads, by role: their names
//! in the solved problem are formatted here only, and a solved problem's
//! values ([`super::reduction::Values`]) are read through [`Solved`], so no
//! module looks a variable up by a name it spelled itself.

use super::design::SynthError;
use nalgebra::DMatrix;

/// The names of the shared variables.
pub mod names {
    /// X = P^{-1} of the continuous design (G of the fuzzy Lyapunov form).
    pub const X: &str = "X";
    /// The trigger weight Upsilon of an event-triggered loop.
    pub const TRIGGER_WEIGHT: &str = "Upsilon";
    /// P of the sampled loop's looped functional.
    pub const LOOP_P: &str = "Ptr";
    /// Y of the sampled loop's looped functional (the integral term).
    pub const LOOP_Y: &str = "Ytr";
    /// The free matrix L1 of the looped functional's term.
    pub const LOOP_L1: &str = "L1";
    /// The free matrix L2 of the looped functional's term.
    pub const LOOP_L2: &str = "L2";
    /// T, the sector multiplier of the sampled loop (diagonal).
    pub const LOOP_SECTOR: &str = "T";
    /// Prefix of the unknown sector gains of the loop, `G_sector{q}` per
    /// controller vertex q (1-based), when the multiplier T is known.
    pub const LOOP_SECTOR_GAIN: &str = "G_sector";
    /// gamma of the sampled loop's L-inf bound.
    pub const LOOP_GAMMA: &str = "gamma_tr";
    /// xi of the sampled loop's L-inf bound.
    pub const LOOP_XI: &str = "xi_tr";
    /// g = gamma^2 of the sampled loop's H-inf bound.
    pub const LOOP_HINF: &str = "g_tr";
    /// The prefix of the model-error multipliers of the decrease block
    /// (`eps_model_a`, `eps_model_b`: robust conditions).
    pub const MODEL_ERROR: &str = "eps_model";
    /// The prefix of the model-error multipliers of the H-inf block.
    pub const MODEL_ERROR_HINF: &str = "eps_model_hinf";
    /// The prefix of the model-error multipliers of the L-inf decrease block.
    pub const MODEL_ERROR_LINF: &str = "eps_model_linf";

    /// M_j = F_j X of rule `j` (0-based).
    pub fn gain_product(j: usize) -> String {
        format!("M{}", j + 1)
    }

    /// Z_j = G_j X of the generalized sector condition, rule `j` (0-based).
    pub fn sector_product(j: usize) -> String {
        format!("Z{}", j + 1)
    }
}

/// Typed reads of a solved problem's values.
pub trait Solved {
    /// The value of variable `name`, if the problem had it.
    fn value(&self, name: &str) -> Option<&DMatrix<f64>>;

    /// The same, mutably.
    fn value_mut(&mut self, name: &str) -> Option<&mut DMatrix<f64>>;

    /// The value of `name`, or an internal error (a variable the builder
    /// always declares).
    fn required(&self, name: &str) -> Result<DMatrix<f64>, SynthError> {
        self.value(name)
            .cloned()
            .ok_or_else(|| SynthError::Internal(format!("internal error: `{name}` has no value")))
    }

    /// X = P^{-1}.
    fn x(&self) -> Option<&DMatrix<f64>> {
        self.value(names::X)
    }

    /// M_j = F_j X of rule `j`.
    fn gain_product_mut(&mut self, j: usize) -> Option<&mut DMatrix<f64>> {
        self.value_mut(&names::gain_product(j))
    }

    /// Z_j = G_j X of rule `j` (saturation's sector condition).
    fn sector_product(&self, j: usize) -> Option<&DMatrix<f64>> {
        self.value(&names::sector_product(j))
    }

    /// The trigger weight Upsilon, mutably (the certificate of stored numbers).
    fn trigger_weight_mut(&mut self) -> Option<&mut DMatrix<f64>> {
        self.value_mut(names::TRIGGER_WEIGHT)
    }
}

impl Solved for [(String, DMatrix<f64>)] {
    fn value(&self, name: &str) -> Option<&DMatrix<f64>> {
        self.iter().find(|(n, _)| n == name).map(|(_, v)| v)
    }

    fn value_mut(&mut self, name: &str) -> Option<&mut DMatrix<f64>> {
        self.iter_mut().find(|(n, _)| n == name).map(|(_, v)| v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_are_read_by_role() {
        let mut v: Vec<(String, DMatrix<f64>)> = vec![
            (names::X.into(), DMatrix::identity(2, 2)),
            (names::sector_product(1), DMatrix::from_element(1, 2, 3.0)),
            (names::gain_product(0), DMatrix::zeros(1, 2)),
        ];
        assert_eq!(v.x(), Some(&DMatrix::identity(2, 2)));
        assert_eq!(v.sector_product(1).map(|z| z[(0, 1)]), Some(3.0));
        assert!(v.sector_product(0).is_none());
        *v.gain_product_mut(0).expect("M1") += DMatrix::from_element(1, 2, 1.0); // ok: test
        assert_eq!(v.value("M1").map(|m| m[(0, 0)]), Some(1.0));
        assert!(v.required(names::TRIGGER_WEIGHT).is_err());
    }
}
