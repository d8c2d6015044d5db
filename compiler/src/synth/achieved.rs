//! What a design achieved: a keyed list of certified values that the report,
//! the generated headers and the diagnosis iterate (no per-objective fields).

use tsf_lang::spec::ObjectiveKind;

/// A quantity a design achieves. The order is the order of reports and
/// generated headers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Quantity {
    /// Certified H-inf bound gamma.
    HinfGamma,
    /// Certified peak-to-peak bound gamma.
    LinfGamma,
    /// Certified decay rate alpha.
    DecayRate,
    /// Certified bound on ||u(t)||.
    InputNormBound,
    /// Certified bound on ||y(t)||.
    OutputNormBound,
    /// Certified finite-time bound c2 on x(t)' R x(t) over [0, T].
    FiniteTimeC2,
    /// phi used by the L-inf objective (a parameter, not a bound).
    LinfPhi,
    /// xi used by the L-inf objective (a parameter, not a bound).
    LinfXi,
}

impl Quantity {
    /// The key in the report's `objectives` section and generated headers.
    pub fn key(self) -> &'static str {
        match self {
            Quantity::HinfGamma => "hinf_gamma",
            Quantity::LinfGamma => "linf_gamma",
            Quantity::DecayRate => "decay_rate",
            Quantity::InputNormBound => "input_norm_bound",
            Quantity::OutputNormBound => "output_norm_bound",
            Quantity::FiniteTimeC2 => "finite_time_c2",
            Quantity::LinfPhi => "linf_phi",
            Quantity::LinfXi => "linf_xi",
        }
    }

    /// Whether this is a certified objective value (listed in generated
    /// headers), rather than a parameter of the conditions.
    pub fn is_bound(self) -> bool {
        !matches!(self, Quantity::LinfPhi | Quantity::LinfXi)
    }

    /// The objective family it belongs to.
    pub fn objective(self) -> ObjectiveKind {
        match self {
            Quantity::HinfGamma => ObjectiveKind::Hinf,
            Quantity::LinfGamma | Quantity::LinfPhi | Quantity::LinfXi => ObjectiveKind::Linf,
            Quantity::DecayRate => ObjectiveKind::DecayRate,
            Quantity::InputNormBound => ObjectiveKind::InputNorm,
            Quantity::OutputNormBound => ObjectiveKind::OutputNorm,
            Quantity::FiniteTimeC2 => ObjectiveKind::FiniteTime,
        }
    }
}

impl std::fmt::Display for Quantity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.key())
    }
}

/// Values achieved by a design, kept sorted by [`Quantity`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Achieved {
    values: Vec<(Quantity, f64)>,
    /// Bracket of the maximal decay rate (feasible, infeasible), when it was
    /// maximized by bisection.
    pub decay_bracket: Option<(f64, f64)>,
}

impl Achieved {
    /// Sets (or replaces) a value.
    pub fn set(&mut self, q: Quantity, v: f64) {
        match self.values.binary_search_by(|(k, _)| k.cmp(&q)) {
            Ok(i) => self.values[i].1 = v,
            Err(i) => self.values.insert(i, (q, v)),
        }
    }

    /// The value of `q`, if achieved.
    pub fn get(&self, q: Quantity) -> Option<f64> {
        self.values
            .binary_search_by(|(k, _)| k.cmp(&q))
            .ok()
            .map(|i| self.values[i].1)
    }

    /// Every value, in [`Quantity`] order.
    pub fn iter(&self) -> impl Iterator<Item = (Quantity, f64)> + '_ {
        self.values.iter().copied()
    }

    /// The certified objective values only (no parameters), in order.
    pub fn bounds(&self) -> impl Iterator<Item = (Quantity, f64)> + '_ {
        self.iter().filter(|(q, _)| q.is_bound())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_stay_sorted_and_replace() {
        let mut a = Achieved::default();
        a.set(Quantity::LinfXi, 3.0);
        a.set(Quantity::HinfGamma, 1.0);
        a.set(Quantity::DecayRate, 2.0);
        a.set(Quantity::HinfGamma, 1.5);
        let keys: Vec<_> = a.iter().map(|(q, _)| q.key()).collect();
        assert_eq!(keys, ["hinf_gamma", "decay_rate", "linf_xi"]);
        assert_eq!(a.get(Quantity::HinfGamma), Some(1.5));
        assert_eq!(a.get(Quantity::LinfGamma), None);
        assert_eq!(a.bounds().count(), 2);
    }
}
