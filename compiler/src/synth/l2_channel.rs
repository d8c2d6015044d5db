//! The H-inf (L2-gain) channel of a sampled loop's looped functional: the
//! disturbance w enters psi = [x(t); x(t_k); ..; w], and every block gains
//! the constant z'z and -g w'w, so W' + phi V + z'z - g w'w < 0 between
//! samples; integrated from rest over whole periods (the looped terms
//! vanish at the samples), ||z||_2^2 <= g ||w||_2^2 ([`super::trigger`]).

use super::trigger::{pick, Factor};
use nalgebra::DMatrix;
use tsf_lmi::LmiError;

/// The H-inf channel of a sampled loop: with z = `c` x(t) + `e` u_k +
/// `g` tau(t), u_k the held command (the first `e.ncols()` rows of the
/// loop's gain times the held state), every Lambda gains the constant z'z
/// block and -g tau'tau (g = gamma^2 the loop's unknown [`names`]
/// `LOOP_HINF`).
///
/// [`names`]: crate::synth::solved::names
#[derive(Debug, Clone, PartialEq)]
pub struct L2Channel {
    /// C of z (rows of z x the loop's states).
    pub c: DMatrix<f64>,
    /// E of z (rows of z x inputs u).
    pub e: DMatrix<f64>,
    /// G of z (rows of z x disturbance columns).
    pub g: DMatrix<f64>,
    /// The bound on gamma (g <= gamma^2 is imposed).
    pub gamma: f64,
    /// Whether g is minimized under the bound (else a feasibility problem).
    pub minimize: bool,
}

/// z'z of the channel `ch` as a quadratic form in psi (of length `k`, the
/// disturbance at `tau` = (offset, columns)): z = C E_x psi + E (F x(t_k)) +
/// G E_tau psi, F's first `ch.e.ncols()` rows the held command u_k (the
/// augmented observer loop's gain also holds the estimate's slope below
/// them). Constant: the gains must be known (an unknown F would need the
/// Schur complement; the co-design's gain step has no H-inf channel).
pub(super) fn output_energy(
    ch: &L2Channel,
    (tau, k): (Option<(usize, usize)>, usize),
    ex: &DMatrix<f64>,
    xk: &DMatrix<f64>,
    f: Factor<'_>,
) -> Result<DMatrix<f64>, LmiError> {
    let Factor::Val(f) = f else {
        return Err(LmiError::Variable {
            what: "the sampled loop's H-inf channel needs known gains".into(),
        });
    };
    let mut z = &ch.c * ex + &ch.e * f.rows(0, ch.e.ncols()) * xk;
    if let Some((at, q)) = tau {
        z += &ch.g * pick(q, at, k);
    }
    Ok(z.transpose() * z)
}
