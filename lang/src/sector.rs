//! The checked `rules sector;` item: a T-S model the compiler builds by the
//! sector-nonlinearity construction (Ohtake, Tanaka and Wang, "Fuzzy modeling
//! via sector nonlinearity concept", 2001; Tanaka and Wang, "Fuzzy Control
//! Systems Design and Analysis", 2001, Section 2.2).
//!
//! Each sector premise z_k (a scalar premise with a range [lo_k, hi_k] and no
//! sets) gets the sets `max` (degree (z - lo)/(hi - lo)) and `min` (degree
//! (hi - z)/(hi - lo)), which sum to 1 on the range. The 2^p rules are their
//! products; the rule whose clauses pick `max`/`min` has the local model
//! A(x), B(x), D(x) with every z_k at hi_k/lo_k. The blend equals the model
//! exactly wherever the premises are in range when every entry of the model
//! is affine in each z_k (a multilinear function of z(x)): the checker
//! verifies that by a least-squares fit on sampled states and refuses the
//! spec otherwise, naming the entry.

use crate::span::Span;

/// Most sector premises (2^6 = 64 rules).
pub const MAX_SECTOR_PREMISES: usize = 6;

/// Relative residual of the multilinear fit above which an entry is not an
/// exact function of the sector premises: `max |fit - entry| / (1 + max |entry|)`
/// over the sampled states.
pub const FIT_TOLERANCE: f64 = 1e-8;

/// The sector construction of a spec's rules.
#[derive(Debug, Clone, PartialEq)]
pub struct SectorModel {
    /// The sector premises (indices into `Spec::premises`), in source order.
    pub premises: Vec<usize>,
    /// The box the states were sampled from for the fit, per state component:
    /// a state that is itself a sector premise spans its range, any other
    /// state [-1, 1] (an exact identity holds everywhere).
    pub sample_box: Vec<(f64, f64)>,
    /// Sampled states with a finite model (the fit's rows).
    pub samples: usize,
    /// Worst relative residual of the fit over every entry of A, B, D.
    pub residual: f64,
    /// Where `rules sector;` is.
    pub span: Span,
}
