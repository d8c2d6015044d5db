//! Static output feedback u = sum_j h_j K_j y by the change of variables of
//! Crusius & Trofino (1999), "Sufficient LMI conditions for output feedback
//! control problems": for C of full row rank, M C = C X (M p x p) and
//! M_j = N_j C (N_j m x p) are added to the core problem (X = P^-1,
//! M_j = F_j X) as equalities (zero cones). Then M is invertible and
//! M_j = N_j M^-1 M C = K_j C X with K_j = N_j M^-1, so every condition of the
//! core problem holds for the state-feedback gains F_j = K_j C: the loop
//! A_i + B_i K_j C. The condition is sufficient, not necessary; an
//! infeasible one is refused with advice. The certificate rebuilds the core
//! conditions with M_j = K_j C X from the recovered K_j (the loop that ships).

use crate::model::TsModel;
use crate::synth::objective::GainTerm;
use nalgebra::DMatrix;
use tsf_lmi::{Expr, LmiError, Problem, Relation, Var};

/// M of the change of variables (p x p).
pub const M: &str = "M_sof";

/// N_j of rule `j` (0-based).
pub fn product(j: usize) -> String {
    format!("N{}_sof", j + 1)
}

/// The variables the coupling adds.
#[derive(Debug, Clone)]
pub struct Coupling {
    /// M.
    pub m: Var,
    /// N_j.
    pub n: Vec<Var>,
}

/// `e = 0`, entry by entry (zero cones), named `name[r,c]`.
fn equal_zero(problem: &mut Problem, name: &str, e: Expr) -> Result<(), LmiError> {
    let (rows, cols) = e.shape();
    for r in 0..rows {
        for c in 0..cols {
            let mut left = DMatrix::zeros(1, rows);
            left[(0, r)] = 1.0;
            let mut right = DMatrix::zeros(cols, 1);
            right[(c, 0)] = 1.0;
            let entry = e.clone().left_mul(&left)?.right_mul(&right)?;
            problem.add_scalar(
                &format!("{name}[{},{}]", r + 1, c + 1),
                entry,
                Relation::Eq,
                0.0,
            )?;
        }
    }
    Ok(())
}

/// Adds M C = C X and M_j = N_j C to the core problem (`x` is X, `m` the
/// gain products M_j, which must be variables).
pub fn couple(
    problem: &mut Problem,
    model: &TsModel,
    c: &DMatrix<f64>,
    x: Var,
    m: &[GainTerm],
) -> Result<Coupling, LmiError> {
    let p = c.nrows();
    let mv = problem.full(M, p, p)?;
    equal_zero(
        problem,
        "static output M C = C X",
        Expr::var(mv).right_mul(c)?.sub(Expr::var(x).left_mul(c)?)?,
    )?;
    let mut n = Vec::with_capacity(m.len());
    for (j, term) in m.iter().enumerate() {
        let GainTerm::Free(mj) = term else {
            return Err(LmiError::Variable {
                what: "static output feedback needs synthesized gains".into(),
            });
        };
        let nj = problem.full(&product(j), model.m, p)?;
        equal_zero(
            problem,
            &format!("static output M{} = N{} C", j + 1, j + 1),
            Expr::var(*mj).sub(Expr::var(nj).right_mul(c)?)?,
        )?;
        n.push(nj);
    }
    Ok(Coupling { m: mv, n })
}

/// K_j = N_j M^-1 from the solved values; `None` when M is singular.
pub fn recover(
    value: impl Fn(Var) -> Option<DMatrix<f64>>,
    coupling: &Coupling,
) -> Option<Vec<DMatrix<f64>>> {
    let m_inv = value(coupling.m)?.try_inverse()?;
    coupling
        .n
        .iter()
        .map(|v| value(*v).map(|n| n * &m_inv))
        .collect()
}

/// The coupling of a `control static_output` spec, added to `built` (the
/// core problem); `None` for every other kind.
pub fn coupled(
    model: &TsModel,
    built: &mut crate::synth::Built,
) -> Result<Option<Coupling>, LmiError> {
    let Some(c) = static_output_c(model) else {
        return Ok(None);
    };
    couple(&mut built.problem, model, c, built.x, &built.m).map(Some)
}

/// C of a `control static_output` spec.
fn static_output_c(model: &TsModel) -> Option<&DMatrix<f64>> {
    match (model.spec.control.kind, &model.spec.measure) {
        (super::ControlKind::StaticOutput, Some(m)) => Some(&m.c),
        _ => None,
    }
}

/// The shipped design of a solved coupled problem: K_j, the state-feedback
/// gains F_j = K_j C, and the values with M_j = F_j X (what the certificate
/// rebuilds: the loop A_i + B_i K_j C, not the solver's M_j). `None` when M
/// is singular.
pub fn finish(
    model: &TsModel,
    coupling: &Coupling,
    x: &DMatrix<f64>,
    value: impl Fn(Var) -> Option<DMatrix<f64>>,
    values: &mut [(String, DMatrix<f64>)],
) -> Option<(Vec<DMatrix<f64>>, super::StaticOutputDesign)> {
    let measured = model.spec.measure.as_ref()?;
    let k = recover(value, coupling)?;
    let f: Vec<DMatrix<f64>> = k.iter().map(|k| k * &measured.c).collect();
    for (j, fj) in f.iter().enumerate() {
        let name = crate::synth::solved::names::gain_product(j);
        if let Some((_, v)) = values.iter_mut().find(|(n, _)| *n == name) {
            *v = fj * x;
        }
    }
    let design = super::StaticOutputDesign {
        c: measured.c.clone(),
        output_names: measured.names.clone(),
        gains: k,
        premise_from_y: super::premise_from_y(&measured.c),
    };
    Some((f, design))
}

/// The advice an infeasible static output-feedback design adds to its
/// diagnosis (the condition is only sufficient).
pub const ADVICE: &str = "static output feedback (u = sum_j h_j K_j y) is infeasible under the sufficient condition M C = C X of Crusius & Trofino (1999): measure more states (`measure ..`) or use `control observer_based;`, which estimates the unmeasured states";

/// `e` with [`ADVICE`] for a `control static_output` spec whose design is infeasible.
pub fn advise(model: &TsModel, e: crate::synth::SynthError) -> crate::synth::SynthError {
    use crate::synth::SynthError;
    if static_output_c(model).is_none() {
        return e;
    }
    match e {
        SynthError::Infeasible {
            message,
            mut achievable,
        } => {
            achievable.insert(0, ADVICE.into());
            SynthError::Infeasible {
                message,
                achievable,
            }
        }
        SynthError::Solver {
            status,
            message,
            mut achievable,
        } => {
            achievable.insert(0, ADVICE.into());
            SynthError::Solver {
                status,
                message,
                achievable,
            }
        }
        e => e,
    }
}
