//! The premise region: the product of the premise variables' operating ranges
//! (declared with `range lo .. hi`, else the hull of their sets). The design's
//! guarantees hold only while the premise vector `z(x)` stays inside it, so a
//! run that leaves it is reported (and `tsfc simulate` exits 4).

use crate::model::TsModel;
use crate::tables::{PremiseCode, Tables};

/// Tells whether a state's premise vector lies in the premise region.
pub struct Region<'a> {
    premise: &'a PremiseCode,
    /// Per premise component: `(lo, hi)` widened by a relative 1e-9.
    bounds: Vec<(f64, f64)>,
}

impl<'a> Region<'a> {
    /// The region of `model`, evaluated with the premise code of `tables`.
    pub fn new(model: &TsModel, tables: &'a Tables) -> Self {
        let bounds = model
            .premises
            .slots
            .iter()
            .flat_map(|s| {
                let slack = 1e-9 * (s.range.1 - s.range.0).abs().max(f64::MIN_POSITIVE);
                std::iter::repeat_n((s.range.0 - slack, s.range.1 + slack), s.dim)
            })
            .collect();
        Region {
            premise: &tables.premise,
            bounds,
        }
    }

    /// `true` when every premise component of the controller state `x` is
    /// finite and within its range.
    pub fn contains(&self, x: &[f64]) -> bool {
        let inside = |p: usize, (lo, hi): (f64, f64)| {
            let z = match self.premise {
                PremiseCode::Linear(rows) => rows
                    .get(p)
                    .map_or(0.0, |row| row.iter().zip(x).map(|(l, v)| l * v).sum()),
                PremiseCode::Exprs(e) => e.get(p).map_or(0.0, |s| s.eval(x)),
            };
            z >= lo && z <= hi
        };
        self.bounds.iter().enumerate().all(|(p, &b)| inside(p, b))
    }

    /// `true` when every component of the premise vector `z` is finite and
    /// within its range.
    pub fn contains_premises(&self, z: &[f64]) -> bool {
        self.bounds.iter().enumerate().all(|(p, &(lo, hi))| {
            let v = z.get(p).copied().unwrap_or(0.0);
            v >= lo && v <= hi
        })
    }
}
