//! The objective-family seam: the [`Objective`] trait every family in
//! [`super::objectives`] implements, and what a family sees while it builds
//! its conditions: the read-only [`Ctx`] (model, shared variables, a view of
//! the other objectives) and the growing problem [`Lmis`].

use super::achieved::{Achieved, Quantity};
use super::blocks::{initial_set_block, nonstrict_psd};
use super::objectives::{Decay, Linf, Saturation};
use super::reduction::Values;
use super::relaxation::Family;
use super::relaxations::Relaxer;
use super::solved::Solved;
use crate::model::TsModel;
use nalgebra::DMatrix;
use tsf_lang::spec::{InitialSet, ObjectiveKind, Target};
use tsf_lmi::{Expr, LmiError, Problem, Var};

/// A bound that is fixed, or minimized by the SDP.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bound {
    /// The SDP minimizes it (a decay rate: the bisection maximizes it).
    Minimize,
    /// A free variable: the objective's constraints stay, its value is not minimized.
    Free,
    /// Fixed value.
    Fixed(f64),
}

/// What the spec asks to optimize, if anything.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Goal {
    /// Feasibility only.
    Feasibility,
    /// Maximize the decay rate (bisection).
    MaxDecay,
    /// Minimize inside the SDP (hinf, linf, input/output norm).
    InSdp,
}

/// What a family needs to know of the other objectives of its plan.
pub trait PlanView {
    /// The level of V the state reaches from rest under a disturbance
    /// bounded by `tau` (`None` when no objective bounds it that way).
    fn reach_level(&self, tau: f64) -> Result<Option<f64>, BuildError>;
    /// An objective whose conditions cannot carry the sector (dead-zone) column.
    fn without_sector(&self) -> Option<ObjectiveKind>;
}

/// Cloning, implemented for every `Clone` objective.
pub trait ObjectiveBase {
    /// A boxed copy.
    fn clone_box(&self) -> Box<dyn Objective>;
}

impl<T: Objective + Clone + 'static> ObjectiveBase for T {
    fn clone_box(&self) -> Box<dyn Objective> {
        Box::new(self.clone())
    }
}

/// One objective family with its numbers.
pub trait Objective: ObjectiveBase + std::fmt::Debug + Send + Sync {
    /// The family.
    fn kind(&self) -> ObjectiveKind;

    /// Its bound: minimized (maximized for a decay rate), free or fixed.
    fn target(&self) -> Option<Bound> {
        None
    }

    /// Changes its bound (diagnosis optimizes one bound with the others kept).
    fn set_target(&mut self, _target: Bound) {}

    /// The fixed value that can conflict with other objectives, if any.
    fn fixed(&self) -> Option<f64> {
        match self.target() {
            Some(Bound::Fixed(v)) => Some(v),
            _ => None,
        }
    }

    /// How the driver optimizes it when its target is [`Bound::Minimize`].
    fn search(&self) -> Goal {
        Goal::InSdp
    }

    /// The bound in the spec's words (`hinf <= 0.5`).
    fn describe_bound(&self, v: f64) -> String {
        format!("{} <= {v}", self.kind())
    }

    /// The achieved quantity that answers "how good can this be".
    fn headline(&self) -> Option<Quantity> {
        None
    }

    /// Whether its conditions contain the Lyapunov decrease (then plain
    /// stability need not be imposed).
    fn implies_stability(&self) -> bool {
        false
    }

    /// The level of V its conditions keep the state below from rest under a
    /// disturbance bounded by `tau` (`None`: it does not bound it).
    fn reach_level(&self, _tau: f64) -> Option<Result<f64, BuildError>> {
        None
    }

    /// Whether its conditions can carry the sector column of saturation.
    fn supports_sector(&self) -> bool {
        true
    }

    /// Declares its variables.
    fn declare(&self, _model: &TsModel, _lmis: &mut Lmis<'_>) -> Result<(), BuildError> {
        Ok(())
    }

    /// Imposes its conditions.
    fn impose(&self, ctx: &Ctx<'_>, lmis: &mut Lmis<'_>) -> Result<(), BuildError>;

    /// Reads what it achieved from the solved variables.
    fn achieved(&self, _values: &Values, _out: &mut Achieved) {}

    /// The certified saturation region it declares (the saturation family),
    /// read by the searches, the loop certificates and the report.
    fn saturation_region(&self) -> Option<&Saturation> {
        None
    }

    /// Its rounded saturation levels changed (the certificate of stored numbers).
    fn saturation_region_mut(&mut self) -> Option<&mut Saturation> {
        None
    }

    /// The peak-to-peak bound with its level parameters phi and xi (the
    /// L-inf family), which the xi and phi searches move.
    fn peak_bound(&self) -> Option<&Linf> {
        None
    }

    /// The same, for the searches to set xi, its bound or phi.
    fn peak_bound_mut(&mut self) -> Option<&mut Linf> {
        None
    }

    /// The decay rate it imposes (the decay family).
    fn decay_rate(&self) -> Option<&Decay> {
        None
    }

    /// The same, for the bisection to move alpha.
    fn decay_rate_mut(&mut self) -> Option<&mut Decay> {
        None
    }
}

impl Clone for Box<dyn Objective> {
    fn clone(&self) -> Self {
        self.clone_box()
    }
}

/// A bound of the spec as a plan bound.
pub fn bound(t: Target) -> Bound {
    match t {
        Target::Optimize => Bound::Minimize,
        Target::Fixed(v) => Bound::Fixed(v),
    }
}

/// The value of a scalar variable, by name.
pub fn scalar(values: &Values, name: &str) -> Option<f64> {
    values.value(name).map(|v| v[(0, 0)])
}

/// The value of a bound: the fixed number, or `read()` of the solved variable.
pub fn bound_value(target: Bound, read: impl FnOnce() -> f64) -> f64 {
    match target {
        Bound::Fixed(v) => v,
        _ => read(),
    }
}

/// Why a problem could not be built.
#[derive(Debug, Clone, PartialEq)]
pub enum BuildError {
    /// The objectives of the plan cannot be combined (the checker should
    /// have said so with a span; this is the last line of defence).
    Unsupported(String),
    /// An LMI expression was malformed: a bug in tsfc.
    Lmi(LmiError),
}

impl From<LmiError> for BuildError {
    fn from(e: LmiError) -> Self {
        BuildError::Lmi(e)
    }
}

impl std::fmt::Display for BuildError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BuildError::Unsupported(m) => f.write_str(m),
            BuildError::Lmi(e) => write!(f, "internal LMI construction error: {e}"),
        }
    }
}

/// S = T^{-1} (diagonal, m x m) and Z_j = G_j X (m x n) of the generalized
/// sector condition for actuator saturation.
#[derive(Debug, Clone)]
pub struct Sector {
    /// S.
    pub s: Var,
    /// Z_j, one per rule.
    pub z: Vec<Var>,
}

/// M_j = F_j X of one rule: a decision variable when the gains are
/// synthesized, or the given gain F_j (then M_j = F_j X is linear in X and
/// every condition stays an LMI with F_j X substituted for M_j).
#[derive(Debug, Clone, PartialEq)]
pub enum GainTerm {
    /// M_j, a decision variable (m x n).
    Free(Var),
    /// F_j, given (m x n).
    Given(DMatrix<f64>),
}

impl GainTerm {
    /// L M_j as an expression (rows of L by n): L M_j for a variable,
    /// (L F_j) X for a given gain.
    pub fn times(&self, left: &DMatrix<f64>, x: Var, n: usize) -> Result<Expr, LmiError> {
        let id = DMatrix::identity(n, n);
        match self {
            GainTerm::Free(m) => Expr::product(left, *m, &id),
            GainTerm::Given(f) => Expr::product(&(left * f), x, &id),
        }
    }

    /// M_j itself (`m` rows).
    pub fn expr(&self, x: Var, m: usize, n: usize) -> Result<Expr, LmiError> {
        self.times(&DMatrix::identity(m, m), x, n)
    }
}

/// The n x n block `e` in the top-left corner of a k x k zero matrix.
fn pad_square(e: Expr, k: usize) -> Result<Expr, LmiError> {
    let n = e.shape().0;
    if k == n {
        return Ok(e);
    }
    Expr::blocks(vec![
        vec![Some(e), None],
        vec![None, Some(Expr::zeros(k - n, k - n))],
    ])
}

/// Read-only context of the conditions: model, plan and the shared variables.
pub struct Ctx<'a> {
    /// The model.
    pub model: &'a TsModel,
    /// The other objectives of the plan.
    pub plan: &'a dyn PlanView,
    /// X = P^{-1}.
    pub x: Var,
    /// M_j = F_j X, one per rule.
    pub m: Vec<GainTerm>,
    /// The sector variables, if the saturation objective declared them.
    pub sector: Option<Sector>,
    /// The multiplier of the model error, when the model carries a nonzero one.
    pub model_error: Option<ModelError>,
}

/// The model error as norm-bounded uncertainty: ||dA|| <= a, ||dB|| <= b
/// (and ||dD|| <= d in the blocks of a disturbance), with the S-procedure
/// multipliers of the decrease block (Petersen 1987; Tanaka & Wang 2001,
/// ch. 8); the H-inf and L-inf blocks declare their own
/// ([`declare_model_error`]).
#[derive(Debug, Clone, Copy)]
pub struct ModelError {
    /// The multipliers of the decrease block (none when the plan imposes no
    /// decrease block of its own).
    pub eps: Multipliers,
    /// a^2.
    pub a2: f64,
    /// b^2.
    pub b2: f64,
    /// d^2 (0 when D is not state-dependent or the spec has no disturbance).
    pub d2: f64,
}

/// One block's multipliers eps > 0, one per uncertain term (declared only
/// where its bound is nonzero): separate multipliers bound
/// He(dA X) + He(dB M_j) by 2 a ||X|| + 2 b ||M_j|| at best, where one
/// common multiplier gives 2 sqrt(a^2 + b^2) sqrt(||X||^2 + ||M_j||^2).
#[derive(Debug, Clone, Copy, Default)]
pub struct Multipliers {
    /// Of dA X.
    pub a: Option<Var>,
    /// Of dB M_j.
    pub b: Option<Var>,
    /// Of dD w.
    pub d: Option<Var>,
}

/// Declares the model-error multipliers `{prefix}_a`, `_b` (and `_d` with
/// `with_d`) of one block for the nonzero bounds of the model's error (none
/// without one: the nominal problem, bit for bit), and returns them.
pub fn declare_model_error(
    model: &TsModel,
    lmis: &mut Lmis<'_>,
    prefix: &str,
    with_d: bool,
) -> Result<Multipliers, LmiError> {
    let Some(e) = model.plant_error.as_ref().filter(|e| !e.is_zero()) else {
        return Ok(Multipliers::default());
    };
    let mut one = |bound: f64, tag: &str| -> Result<Option<Var>, LmiError> {
        match bound > 0.0 {
            true => lmis.scalar(&format!("{prefix}_{tag}")).map(Some),
            false => Ok(None),
        }
    };
    Ok(Multipliers {
        a: one(e.a, "a")?,
        b: one(e.b, "b")?,
        d: match with_d {
            true => one(e.d.unwrap_or(0.0), "d")?,
            false => None,
        },
    })
}

/// The multipliers [`declare_model_error`] declared under `prefix`.
pub fn model_error_multipliers(lmis: &Lmis<'_>, prefix: &str) -> Multipliers {
    Multipliers {
        a: lmis.var(&format!("{prefix}_a")),
        b: lmis.var(&format!("{prefix}_b")),
        d: lmis.var(&format!("{prefix}_d")),
    }
}

impl Ctx<'_> {
    /// Q_ij of the decrease with the model error (Petersen's lemma), with the
    /// decrease block's multipliers ([`Ctx::with_model_error_by`]).
    pub fn with_model_error(&self, j: usize, q: Expr) -> Result<Expr, LmiError> {
        let eps = self.model_error.map(|me| me.eps).unwrap_or_default();
        self.with_model_error_by(&eps, j, q, None)
    }

    /// A block `q` (state rows first) with the model error as norm-bounded
    /// uncertainty under the multipliers `eps` (Petersen's lemma): in
    /// X = P^{-1} coordinates He(dA X) <= eps_a a^2 I + eps_a^{-1} X X and
    /// He(dB M_j) <= eps_b b^2 I + eps_b^{-1} M_j' M_j for every ||dA|| <= a,
    /// ||dB|| <= b (and with saturation, |sat(u)| <= |u| bounds dB sat(u) the
    /// same way), so `q` becomes, by a Schur complement,
    /// [[q + (eps_a a^2 + eps_b b^2) I, X, M_j'], [*, -eps_a I, 0], [*, *, -eps_b I]]
    /// (a column left out when its bound is 0). With `w_rows` (the first
    /// row of the disturbance block in `q`) and ||dD|| <= d, the term
    /// He(e_x dD e_w') <= eps_d d^2 e_x e_x' + eps_d^{-1} e_w e_w' adds
    /// eps_d d^2 to the state diagonal and the column e_w. Unchanged without
    /// a model error.
    pub fn with_model_error_by(
        &self,
        eps: &Multipliers,
        j: usize,
        q: Expr,
        w_rows: Option<usize>,
    ) -> Result<Expr, LmiError> {
        let Some(me) = self.model_error else {
            return Ok(q);
        };
        let (n, m) = (self.model.n, self.model.m);
        let k = q.shape().0;
        let pad = |e: Expr, at: usize| -> Result<Expr, LmiError> {
            let (h, w) = e.shape();
            if at == 0 && h == k {
                return Ok(e);
            }
            let mut rows = Vec::new();
            if at > 0 {
                rows.push(vec![Some(Expr::zeros(at, w))]);
            }
            rows.push(vec![Some(e)]);
            if k > at + h {
                rows.push(vec![Some(Expr::zeros(k - at - h, w))]);
            }
            Expr::blocks(rows)
        };
        // (multiplier, bound^2, column, its width)
        let mut terms = Vec::new();
        if let (Some(v), true) = (eps.a, me.a2 > 0.0) {
            terms.push((v, me.a2, pad(Expr::var(self.x), 0)?, n));
        }
        if let (Some(v), true) = (eps.b, me.b2 > 0.0) {
            let col = pad(self.m[j].expr(self.x, m, n)?.transpose(), 0)?;
            terms.push((v, me.b2, col, m));
        }
        if let (Some(v), Some(at), true) = (eps.d, w_rows, me.d2 > 0.0) {
            let q_w = self.model.q;
            terms.push((v, me.d2, pad(Expr::identity(q_w), at)?, q_w));
        }
        if terms.is_empty() {
            return Ok(q);
        }
        let mut top = q;
        for (v, bound2, _, _) in &terms {
            let diag = Expr::scaled(*v, &(DMatrix::identity(n, n) * *bound2))?;
            top = top.add(pad_square(diag, k)?)?;
        }
        let size = terms.len() + 1;
        let mut grid: Vec<Vec<Option<Expr>>> = vec![vec![Some(top)]];
        grid[0].resize(size, None);
        for (c, (v, _, col, width)) in terms.into_iter().enumerate() {
            grid[0][c + 1] = Some(col);
            let mut row = vec![None; size];
            row[c + 1] = Some(Expr::scaled(v, &(-DMatrix::identity(width, width)))?);
            grid.push(row);
        }
        Expr::sym_blocks(grid)
    }

    /// Upsilon_ij = He(A_i X + B_i M_j) (+ shift * X).
    pub fn upsilon(&self, i: usize, j: usize, shift: f64) -> Result<Expr, LmiError> {
        let n = self.model.n;
        let (a, b) = (&self.model.rules[i].a, &self.model.rules[i].b);
        let ax = Expr::product(a, self.x, &DMatrix::identity(n, n))?;
        let bm = self.m[j].times(b, self.x, n)?;
        let he = ax.add(bm)?.he()?;
        if shift == 0.0 {
            Ok(he)
        } else {
            he.add(Expr::var(self.x).scale(shift)?)
        }
    }

    /// Adds the dead-zone signal psi of the generalized sector condition to a
    /// block: [[U, -B_i S + Z_j', (W)], [*, -2S, 0], [*, *, (-xi I)]], or
    /// returns `[[U, W], [*, -xi I]]` / `U` unchanged without saturation.
    pub fn with_sector(
        &self,
        i: usize,
        j: usize,
        ups: Expr,
        w: Option<(Expr, Expr)>,
    ) -> Result<Expr, LmiError> {
        let Some(sector) = &self.sector else {
            return match w {
                Some((d, xi)) => {
                    Expr::sym_blocks(vec![vec![Some(ups), Some(d)], vec![None, Some(xi)]])
                }
                None => Ok(ups),
            };
        };
        let m = self.model.m;
        let b = &self.model.rules[i].b;
        let cross = Expr::product(b, sector.s, &DMatrix::identity(m, m))?
            .scale(-1.0)?
            .add(Expr::var(sector.z[j]).transpose())?;
        let psi = Expr::var(sector.s).scale(-2.0)?;
        match w {
            Some((d, xi)) => Expr::sym_blocks(vec![
                vec![Some(ups), Some(cross), Some(d)],
                vec![None, Some(psi), None],
                vec![None, None, Some(xi)],
            ]),
            None => Expr::sym_blocks(vec![vec![Some(ups), Some(cross)], vec![None, Some(psi)]]),
        }
    }
}

/// The growing problem: constraints, relaxation and bookkeeping.
pub struct Lmis<'m> {
    /// The LMI problem.
    pub problem: Problem,
    /// Margin of strict LMIs.
    pub eps: f64,
    /// Sector variables (declared by the saturation objective).
    pub sector: Option<Sector>,
    pub(super) relaxer: Relaxer<'m>,
    pub(super) named: Vec<(String, Var)>,
    pub(super) initial_sets: Vec<InitialSet>,
}

impl Lmis<'_> {
    /// Declares a scalar variable owned by an objective.
    pub fn scalar(&mut self, name: &str) -> Result<Var, LmiError> {
        let v = self.problem.scalar(name)?;
        self.named.push((name.to_string(), v));
        Ok(v)
    }

    /// A variable declared by [`Lmis::scalar`], by name.
    pub fn var(&self, name: &str) -> Option<Var> {
        self.named.iter().find(|(n, _)| n == name).map(|(_, v)| *v)
    }

    /// `e > 0`, strict (solved as `e >= eps I`).
    pub fn strict(&mut self, name: &str, e: Expr) -> Result<(), LmiError> {
        self.problem.psd(name, e, self.eps)?;
        Ok(())
    }

    /// `e >= 0`, non-strict in the theory (solved with the margin too).
    pub fn nonstrict(&mut self, name: &str, e: Expr) -> Result<(), LmiError> {
        nonstrict_psd(
            &mut self.problem,
            &mut self.relaxer.nonstrict,
            name,
            e,
            self.eps,
        )
    }

    /// Imposes `sum_ij h_i h_j Q_ij < 0` under the spec's relaxation.
    pub fn impose(&mut self, fam: &Family<'_>) -> Result<(), LmiError> {
        self.relaxer.impose(&mut self.problem, fam)
    }

    /// Puts `init` inside E(P, 1) (once per distinct initial set).
    pub fn contain(&mut self, x: Var, init: &InitialSet, what: &str) -> Result<(), LmiError> {
        if self.initial_sets.contains(init) {
            return Ok(());
        }
        self.initial_sets.push(init.clone());
        let (name, e) = initial_set_block(x, init)?;
        self.nonstrict(&format!("{what}: {name}"), e)
    }
}
