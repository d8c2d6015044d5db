//! Numbers in messages and printed specs, written short.

use std::fmt::{self, Display, Formatter};

/// A number as a spec would write it: shortest round-trip form, with an
/// exponent only for very small or very large magnitudes.
pub struct Num(pub f64);

impl Display for Num {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        let v = self.0;
        if v != 0.0 && v.is_finite() && !(1e-4..1e16).contains(&v.abs()) {
            write!(f, "{v:e}")
        } else {
            write!(f, "{v}")
        }
    }
}
