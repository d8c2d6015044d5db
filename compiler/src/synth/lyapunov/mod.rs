//! Lyapunov functions other than the quadratic V = x' P x of the objective
//! families: [`fuzzy`] (membership-dependent, V = x' (sum_k h_k P_k) x, its
//! LMIs and gain recovery) and [`region`] (the a posteriori check of its
//! membership-derivative assumption on a level set).

pub mod fuzzy;
pub mod region;

pub use fuzzy::FuzzyDesign;
pub use region::Region;
