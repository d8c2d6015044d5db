//! Paper-specific conditions kept for study, outside the main synthesis path:
//! they are reported, never emitted.

pub mod theorem2;
