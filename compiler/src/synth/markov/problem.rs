//! The mode conditions in X variables, the SDP synthesis solves (see the
//! module documentation of [`super`] for the derivation).

use super::pairs::PairCondition;
use crate::model::TsModel;
use crate::synth::objective::BuildError;
use nalgebra::DMatrix;
use tsf_lang::modes::{ModeDesign, Modes};
use tsf_lmi::{Expr, Problem, Var};

/// The variables of one mode (shared by every mode when the design is
/// mode-independent).
#[derive(Debug, Clone)]
pub struct ModeVars {
    /// X_a = P_a^{-1}.
    pub x: Var,
    /// M_aj = F_aj X_a, one per rule.
    pub m: Vec<Var>,
    /// The relaxation's slack Y_a (tanaka), in X variables.
    pub y: Option<Var>,
}

/// The built problem.
#[derive(Debug)]
pub struct XProblem {
    /// The SDP.
    pub problem: Problem,
    /// Variables per mode, in mode order.
    pub modes: Vec<ModeVars>,
}

/// The input matrices B_ai of mode `a`, one per rule.
pub fn input_matrices(model: &TsModel, modes: &Modes, a: usize) -> Vec<DMatrix<f64>> {
    model
        .rules
        .iter()
        .map(|rule| modes.modes[a].actuator.input_matrix(&rule.b))
        .collect()
}

/// The condition's name for mode `name`.
pub fn condition_name(mode: &str, c: &PairCondition) -> String {
    format!("mode {mode} {}", c.label)
}

/// Builds the conditions of every mode for decay rate `alpha` (0: stability)
/// with strict margin `eps`.
pub fn build(
    model: &TsModel,
    modes: &Modes,
    conditions: &[PairCondition],
    slack: bool,
    alpha: f64,
    eps: f64,
) -> Result<XProblem, BuildError> {
    let (n, m, r) = (model.n, model.m, model.r());
    let mut problem = Problem::new();
    let dependent = modes.design == ModeDesign::Dependent;
    let mut vars: Vec<ModeVars> = Vec::new();
    for mode in &modes.modes {
        let suffix = if dependent {
            format!("_{}", mode.name)
        } else {
            String::new()
        };
        let shared = vars.first().filter(|_| !dependent);
        let x = match shared {
            Some(v) => v.x,
            None => problem.symmetric(&format!("X{suffix}"), n)?,
        };
        let mv = match shared {
            Some(v) => v.m.clone(),
            None => (0..r)
                .map(|j| problem.full(&format!("M{}{suffix}", j + 1), m, n))
                .collect::<Result<_, _>>()?,
        };
        let y = if slack {
            Some(problem.symmetric(&format!("Y_{}", mode.name), n)?)
        } else {
            None
        };
        vars.push(ModeVars { x, m: mv, y });
    }
    let id = DMatrix::identity(n, n);
    for (a, mode) in modes.modes.iter().enumerate() {
        let v = &vars[a];
        if dependent || a == 0 {
            let name = if dependent {
                format!("mode {}: X > 0", mode.name)
            } else {
                "X > 0".to_string()
            };
            problem.psd(&name, Expr::var(v.x), eps)?;
        }
        if let Some(y) = v.y {
            let name = format!("mode {} Y >= 0", mode.name);
            problem.psd(&name, Expr::var(y), eps)?;
        }
        let b = input_matrices(model, modes, a);
        // Coupling: the modes b != a reachable from a, with pi_ab > 0.
        let coupled: Vec<(usize, f64)> = if dependent {
            (0..modes.len())
                .filter(|&c| c != a && modes.rates[(a, c)] > 0.0)
                .map(|c| (c, modes.rates[(a, c)]))
                .collect()
        } else {
            Vec::new()
        };
        let diagonal = 2.0 * alpha + if dependent { modes.rates[(a, a)] } else { 0.0 };
        let phi = |i: usize, j: usize| -> Result<Expr, BuildError> {
            let ax = Expr::product(&model.rules[i].a, v.x, &id)?;
            let bm = Expr::product(&b[i], v.m[j], &id)?;
            Ok(ax.add(bm)?.he()?.add(Expr::var(v.x).scale(diagonal)?)?)
        };
        for c in conditions {
            let mut top = Expr::zeros(n, n);
            for &(i, j, w) in &c.terms {
                top = top.add(phi(i, j)?.scale(w)?)?;
            }
            if let (Some(y), true) = (v.y, c.slack != 0.0) {
                top = top.add(Expr::var(y).scale(c.slack)?)?;
            }
            let k = c.multiplicity();
            let e = if coupled.is_empty() {
                top
            } else {
                let len = coupled.len() + 1;
                let mut grid: Vec<Vec<Option<Expr>>> = vec![vec![None; len]; len];
                grid[0][0] = Some(top);
                for (s, &(bm, pi)) in coupled.iter().enumerate() {
                    grid[0][s + 1] = Some(Expr::var(v.x).scale(k)?);
                    grid[s + 1][s + 1] = Some(Expr::var(vars[bm].x).scale(-k / pi)?);
                }
                Expr::sym_blocks(grid)?
            };
            // Non-strict conditions are solved with the margin too.
            problem.nsd(&condition_name(&mode.name, c), e, eps)?;
        }
    }
    Ok(XProblem {
        problem,
        modes: vars,
    })
}
