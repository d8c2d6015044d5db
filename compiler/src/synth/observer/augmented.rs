//! The certificate of an observer-based loop on the augmented state
//! (x, e), e = x - x_hat:
//!
//! ```text
//! x' = sum_ij h_i h_j ((A_i + B_i F_j) x - B_i F_j e)
//! e' = sum_i  h_i (A_i - L_i C) e
//! ```
//!
//! so (x, e)' = sum_ij h_i h_j G_ij (x, e) with
//! G_ij = [A_i + B_i F_j, -B_i F_j; 0, A_i - L_i C]. An analysis SDP in
//! P_aug = diag(P1, Pe) imposes Q_ij = He(P_aug G_ij) + 2 alpha P_aug under
//! the spec's relaxation: then V = x'P1 x + e'Pe e decays like e^{-2 alpha t}
//! along the loop that ships (the gains F_j and L_i are data, not variables).

use crate::model::TsModel;
use crate::synth::relaxation::Family;
use crate::synth::relaxations::Relaxer;
use crate::synth::{Reduction, Runner, SynthError};
use nalgebra::DMatrix;
use tsf_lmi::{Expr, LmiError, Problem, SolveStatus, Var};

/// P1 of the augmented Lyapunov function (the state block).
pub const P1: &str = "P1_aug";
/// Pe of the augmented Lyapunov function (the estimation-error block).
pub const PE: &str = "Pe_aug";

/// The solved augmented certificate.
#[derive(Debug, Clone, PartialEq)]
pub struct AugmentedDesign {
    /// The decay rate alpha imposed on the augmented loop.
    pub alpha: f64,
    /// P_aug (2n x 2n): diag(P1, Pe), or full with input bounds or the
    /// saturation region ([`super::bounded`], P_aug = X^-1).
    pub p: DMatrix<f64>,
    /// Values of every variable of the solved problem.
    pub values: Vec<(String, DMatrix<f64>)>,
    /// Reductions applied to the solved problem.
    pub reductions: Vec<Reduction>,
    /// The certified H-inf gain from (w, v) to the objective's output, with
    /// an H-inf objective ([`super::hinf`]).
    pub hinf_gamma: Option<f64>,
    /// The input bound and saturation region's certificate, when the spec
    /// asks for them ([`super::bounded`]).
    pub bounded: Option<Box<super::bounded::BoundedDesign>>,
}

/// The augmented problem and what the certificate needs of it.
pub struct AugmentedProblem {
    /// The problem.
    pub problem: Problem,
    /// P1.
    pub p1: Var,
    /// Pe.
    pub pe: Var,
    /// Reductions the relaxation applied.
    pub reductions: Vec<Reduction>,
    /// Constraints non-strict in the theory.
    pub nonstrict: Vec<String>,
}

/// G_ij of plant rule i under controller rule j.
pub fn closed_loop(
    model: &TsModel,
    f: &[DMatrix<f64>],
    l: &[DMatrix<f64>],
    c: &DMatrix<f64>,
    i: usize,
    j: usize,
) -> DMatrix<f64> {
    let n = model.n;
    let rule = &model.rules[i];
    let bf = &rule.b * &f[j];
    let mut g = DMatrix::zeros(2 * n, 2 * n);
    g.view_mut((0, 0), (n, n)).copy_from(&(&rule.a + &bf));
    g.view_mut((0, n), (n, n)).copy_from(&(-&bf));
    g.view_mut((n, n), (n, n)).copy_from(&(&rule.a - &l[i] * c));
    g
}

/// The blocks of G_ij: state-state, state-error, error-error.
pub struct Split {
    /// A_i + B_i F_j.
    pub xx: DMatrix<f64>,
    /// -B_i F_j.
    pub xe: DMatrix<f64>,
    /// A_i - L_i C.
    pub ee: DMatrix<f64>,
}

impl Split {
    /// The blocks of `g` (2n x 2n).
    pub fn of(g: &DMatrix<f64>, n: usize) -> Split {
        Split {
            xx: g.view((0, 0), (n, n)).into_owned(),
            xe: g.view((0, n), (n, n)).into_owned(),
            ee: g.view((n, n), (n, n)).into_owned(),
        }
    }
}

/// Builds the augmented analysis problem for the gains `f`, `l` (with the
/// spec's H-inf objective, its augmented block too: [`super::hinf`]).
pub fn problem(
    model: &TsModel,
    f: &[DMatrix<f64>],
    l: &[DMatrix<f64>],
    c: &DMatrix<f64>,
    alpha: f64,
    eps: f64,
) -> Result<AugmentedProblem, LmiError> {
    let n = model.n;
    let mut problem = Problem::new();
    let p1 = problem.symmetric(P1, n)?;
    let pe = problem.symmetric(PE, n)?;
    problem.psd("augmented P1 > 0", Expr::var(p1), eps)?;
    problem.psd("augmented Pe > 0", Expr::var(pe), eps)?;
    let mut relaxer = Relaxer::new(model, model.spec.relaxation.node, eps, false);
    let fam = Family {
        name: "augmented".into(),
        q: Box::new(|i, j| {
            let Split {
                xx: gxx,
                xe: gxe,
                ee: gee,
            } = Split::of(&closed_loop(model, f, l, c, i, j), n);
            let xx = Expr::var(p1)
                .right_mul(&gxx)?
                .he()?
                .add(Expr::var(p1).scale(2.0 * alpha)?)?;
            let xe = Expr::var(p1).right_mul(&gxe)?;
            let ee = Expr::var(pe)
                .right_mul(&gee)?
                .he()?
                .add(Expr::var(pe).scale(2.0 * alpha)?)?;
            Expr::sym_blocks(vec![vec![Some(xx), Some(xe)], vec![None, Some(ee)]])
        }),
    };
    relaxer.impose(&mut problem, &fam)?;
    if let Some(h) = super::hinf::objective(model) {
        super::hinf::impose(&mut problem, &mut relaxer, model, (f, l), c, (p1, pe), h)?;
    }
    Ok(AugmentedProblem {
        problem,
        p1,
        pe,
        reductions: relaxer.reductions,
        nonstrict: relaxer.nonstrict,
    })
}

/// Solves the augmented analysis SDP; refused (not certified) when infeasible.
pub fn solve(
    runner: &mut Runner<'_>,
    f: &[DMatrix<f64>],
    l: &[DMatrix<f64>],
    c: &DMatrix<f64>,
    alpha: f64,
) -> Result<AugmentedDesign, SynthError> {
    let model = runner.model;
    let built = problem(model, f, l, c, alpha, runner.settings.eps)
        .map_err(|e| SynthError::Internal(format!("internal error: augmented problem: {e}")))?;
    let sol = runner.solve(&built.problem, "augmented observer-loop problem")?;
    if sol.status != SolveStatus::Solved {
        return Err(SynthError::Infeasible {
            message: format!(
                "the observer-based loop is not certified: the augmented (x, e) conditions at decay rate {alpha}{} are {} for the controller and observer gains",
                match super::hinf::objective(model) {
                    Some((_, _, Some(g))) => format!(" with the H-inf gain from (w, v) at most {g}"),
                    Some((_, _, None)) => " with an H-inf block".into(),
                    None => String::new(),
                },
                sol.status.describe()
            ),
            achievable: vec![
                "raise the observer's decay rate (`control observer_based(decay = ..)`) or lower the controller's `decay_rate`".into(),
            ],
        });
    }
    let values = super::SolvedVars::read(&built.problem, &sol)?;
    let get = |name: &str| values.get(name);
    let (p1, pe) = (get(P1)?, get(PE)?);
    let hinf_gamma = super::hinf::objective(model).map(|(_, _, fixed)| match fixed {
        Some(gamma) => Ok(gamma),
        None => get(super::hinf::G_AUG).map(|g| g[(0, 0)].max(0.0).sqrt()),
    });
    let hinf_gamma = hinf_gamma.transpose()?;
    let n = model.n;
    let mut p = DMatrix::zeros(2 * n, 2 * n);
    p.view_mut((0, 0), (n, n)).copy_from(&p1);
    p.view_mut((n, n), (n, n)).copy_from(&pe);
    Ok(AugmentedDesign {
        alpha,
        p,
        values: values.0,
        reductions: built.reductions,
        hinf_gamma,
        bounded: None,
    })
}
