//! The checked specification: names resolved, shapes checked, constants
//! evaluated. This is what the compiler's model stage consumes.

use crate::ast::Expr;
use crate::eval::{Env, FnDef, Mat, Mode};
use crate::span::{Span, Spanned};
use std::collections::HashMap;

/// A declared signal (state, input or disturbance) and its place in the vector.
#[derive(Debug, Clone, PartialEq)]
pub struct Signal {
    /// The name.
    pub name: String,
    /// Number of components (1 for a scalar).
    pub len: usize,
    /// Whether it was declared as a vector (`w[3]`) rather than a scalar.
    pub is_vector: bool,
    /// Index of its first component in the stacked vector.
    pub offset: usize,
    /// Where it was declared.
    pub span: Span,
}

impl Signal {
    /// Names of its components in order: `w[0]`, `w[1]`, .. for a vector,
    /// the name itself for a scalar.
    pub fn component_names(&self) -> impl Iterator<Item = String> + '_ {
        (0..self.len).map(move |k| {
            if self.is_vector {
                format!("{}[{k}]", self.name)
            } else {
                self.name.clone()
            }
        })
    }

    /// The component names of a list of signals, in order (the states'
    /// `w[0], w[1], w[2], rho[0], ..`).
    pub fn names_of(signals: &[Signal]) -> Vec<String> {
        signals.iter().flat_map(Signal::component_names).collect()
    }
}

/// A performance output `y = C x + E u + G w`, linear by construction.
#[derive(Debug, Clone, PartialEq)]
pub struct Output {
    /// The name.
    pub name: String,
    /// p x n.
    pub c: Mat,
    /// p x m.
    pub e: Mat,
    /// p x q.
    pub g: Mat,
    /// Where it was declared.
    pub span: Span,
}

/// What the controller reads and how it is built (`control ..;`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ControlKind {
    /// `control state_feedback;` (the default): u = sum_j h_j F_j x.
    #[default]
    StateFeedback,
    /// `control observer_based;`: a fuzzy observer estimates x from y = C x
    /// and the PDC gains act on the estimate.
    ObserverBased,
    /// `control static_output;`: u = sum_j h_j K_j y.
    StaticOutput,
}

impl ControlKind {
    /// The keyword of the kind.
    pub fn keyword(self) -> &'static str {
        match self {
            ControlKind::StateFeedback => "state_feedback",
            ControlKind::ObserverBased => "observer_based",
            ControlKind::StaticOutput => "static_output",
        }
    }
}

/// The checked `control ..;` item.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Control {
    /// The kind.
    pub kind: ControlKind,
    /// `observer_based(decay = a)`: the observer's decay rate, if given.
    pub observer_decay: Option<f64>,
    /// Where the item is (empty when not written).
    pub span: Span,
}

/// The measured outputs y = C x of every `measure` item, stacked.
#[derive(Debug, Clone, PartialEq)]
pub struct Measured {
    /// p x n.
    pub c: Mat,
    /// One name per row (`y`, or `y[0]`, `y[1]`, .. for a vector item).
    pub names: Vec<String>,
    /// Per row: the `noise <= bound` of its item, if given.
    pub noise: Vec<Option<f64>>,
    /// Where the first `measure` item is.
    pub span: Span,
}

/// A model matrix `A`, `B` or `D`, constant or state-dependent.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelMatrix {
    /// The defining expression.
    pub expr: Expr,
    /// `true` for `A(x) = ...`.
    pub state_dependent: bool,
    /// The whole definition.
    pub span: Span,
}

/// The shape of a scalar fuzzy set.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SetShape {
    /// Triangle with feet `a`, `c` and peak `b`.
    Tri(f64, f64, f64),
    /// Trapezoid with feet `a`, `d` and plateau `b..c`.
    Trap(f64, f64, f64, f64),
    /// Gaussian `exp(-0.5 ((z - c) / sigma)^2)`: (center, sigma).
    Gauss(f64, f64),
    /// Logistic `1 / (1 + exp(-slope (z - center)))`: (slope, center).
    Sigmoid(f64, f64),
}

impl SetShape {
    /// The finite breakpoints of the shape (used by the coverage check).
    pub fn breakpoints(&self) -> Vec<f64> {
        match *self {
            SetShape::Tri(a, b, c) => vec![a, b, c],
            SetShape::Trap(a, b, c, d) => vec![a, b, c, d],
            SetShape::Gauss(c, _) => vec![c],
            SetShape::Sigmoid(_, c) => vec![c],
        }
    }
}

/// A named fuzzy set of a premise.
#[derive(Debug, Clone, PartialEq)]
pub struct FuzzySet {
    /// The set's name.
    pub name: String,
    /// Its shape.
    pub shape: SetShape,
    /// Where it was defined.
    pub span: Span,
}

/// A premise variable z (scalar or vector), a function of the state.
#[derive(Debug, Clone, PartialEq)]
pub struct Premise {
    /// The name used in rules.
    pub name: String,
    /// The expression of the state it is bound to.
    pub expr: Expr,
    /// For `premise a, b = v`: which component of `expr` this premise is.
    pub component: Option<usize>,
    /// Number of components (1 for scalar premises).
    pub dim: usize,
    /// Operating range per component (lo, hi), if known.
    pub range: Option<(f64, f64)>,
    /// Width of `about` sets, if given.
    pub sigma: Option<f64>,
    /// Named sets.
    pub sets: Vec<FuzzySet>,
    /// Where it was declared.
    pub span: Span,
}

/// The set of a rule clause.
#[derive(Debug, Clone, PartialEq)]
pub enum ClauseSet {
    /// Index into the premise's `sets`.
    Named(usize),
    /// An `about` point (length = premise dim).
    About(Vec<f64>),
}

/// One clause `premise is set` of a rule.
#[derive(Debug, Clone, PartialEq)]
pub struct RuleClause {
    /// Index into [`Spec::premises`].
    pub premise: usize,
    /// The set.
    pub set: ClauseSet,
    /// Where the clause is.
    pub span: Span,
}

/// A rule of the T-S model.
#[derive(Debug, Clone, PartialEq)]
pub struct RuleSpec {
    /// The rule's name.
    pub name: String,
    /// The premise (product t-norm over clauses).
    pub clauses: Vec<RuleClause>,
    /// Operating point (full state vector) and the span of `at(...)`.
    pub at: Option<(Vec<f64>, Span)>,
    /// Direct matrices given in the rule, by name (`A`, `B`, `D`), with spans.
    pub overrides: Vec<(String, Mat, Span)>,
    /// The rule's given PDC gain `F = ...` (m x n), with the span of its value:
    /// the compiler then analyzes these gains instead of synthesizing them.
    pub gain: Option<(Mat, Span)>,
    /// Where the rule is.
    pub span: Span,
}

/// Whether a bound is fixed, or optimized.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Target {
    /// Minimize (gains) or maximize (decay rate).
    Optimize,
    /// `<= v` or `>= v`.
    Fixed(f64),
}

/// Initial condition of a norm objective.
#[derive(Debug, Clone, PartialEq)]
pub enum InitialSet {
    /// A single x0.
    Point(Vec<f64>),
    /// The ellipsoid {x : x' R x <= 1}.
    Ellipsoid(Mat),
}

/// A performance objective.
#[derive(Debug, Clone, PartialEq)]
pub enum Objective {
    /// Closed-loop (quadratic) stability.
    Stability,
    /// Decay rate alpha.
    DecayRate(Target),
    /// H-inf gain from a disturbance (index into disturbances) to an output.
    Hinf {
        /// Disturbance index.
        from: usize,
        /// Output index.
        to: usize,
        /// Bound or minimize.
        target: Target,
    },
    /// Peak-to-peak gain.
    Linf {
        /// Disturbance index.
        from: usize,
        /// Output index.
        to: usize,
        /// Bound or minimize.
        target: Target,
        /// Fixed xi, if given.
        xi: Option<f64>,
        /// Fixed phi, if given (else line search).
        phi: Option<f64>,
    },
    /// ||u(t)|| <= bound.
    InputNorm {
        /// The bound (or minimize).
        target: Target,
        /// x0 set.
        initial: InitialSet,
    },
    /// ||y(t)|| <= bound.
    OutputNorm {
        /// Output index.
        output: usize,
        /// The bound (or minimize).
        target: Target,
        /// x0 set.
        initial: InitialSet,
    },
    /// Actuator saturation with an estimated region of attraction.
    SaturationRegion {
        /// Initial states the region must contain (`for x0 = ...` / `in ellipsoid(R)`).
        contain: Option<InitialSet>,
    },
    /// Finite-time boundedness (Amato et al.): x(0)' R x(0) <= c1 and the
    /// disturbance energy at most w2 imply x(t)' R x(t) < c2 for t in [0, T]
    /// (in the mean-square sense under Markov modes).
    FiniteTime(FiniteTime),
}

/// The numbers of a finite-time boundedness objective
/// (`objective finite_time minimize with c1 = .., T = .., alpha = .., R = ..;`).
#[derive(Debug, Clone, PartialEq)]
pub struct FiniteTime {
    /// c2: bounded or minimized.
    pub target: Target,
    /// c1 > 0: the initial set x(0)' R x(0) <= c1.
    pub c1: f64,
    /// The horizon T > 0.
    pub horizon: f64,
    /// The growth rate alpha >= 0 of the Lyapunov function, if fixed (else a
    /// fixed grid, `ALPHA_GRID_STEPS`).
    pub alpha: Option<f64>,
    /// The weight R (n x n, symmetric positive definite).
    pub r: Mat,
}

/// An objective with its span.
pub type SpannedObjective = Spanned<Objective>;

/// The family of an objective: the one name that the checker, synthesis,
/// report and generated headers share (no raw strings across crates).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum ObjectiveKind {
    /// Closed-loop stability (a common quadratic Lyapunov function).
    Stability,
    /// Decay rate alpha.
    DecayRate,
    /// H-inf gain.
    Hinf,
    /// Peak-to-peak (L-inf) gain.
    Linf,
    /// Bound on ||u(t)||.
    InputNorm,
    /// Bound on ||y(t)||.
    OutputNorm,
    /// Saturation region (generalized sector condition).
    SaturationRegion,
    /// Finite-time boundedness.
    FiniteTime,
}

impl ObjectiveKind {
    /// Every kind, in the order the language documents them.
    pub const ALL: [ObjectiveKind; 8] = [
        ObjectiveKind::Stability,
        ObjectiveKind::DecayRate,
        ObjectiveKind::Hinf,
        ObjectiveKind::Linf,
        ObjectiveKind::InputNorm,
        ObjectiveKind::OutputNorm,
        ObjectiveKind::SaturationRegion,
        ObjectiveKind::FiniteTime,
    ];

    /// The kind written as `keyword` after `objective`.
    pub fn from_keyword(keyword: &str) -> Option<ObjectiveKind> {
        Self::ALL.into_iter().find(|k| k.keyword() == keyword)
    }

    /// The keyword of the language (`decay_rate`, `hinf`, `saturation`, ...).
    pub fn keyword(self) -> &'static str {
        match self {
            ObjectiveKind::Stability => "stability",
            ObjectiveKind::DecayRate => "decay_rate",
            ObjectiveKind::Hinf => "hinf",
            ObjectiveKind::Linf => "linf",
            ObjectiveKind::InputNorm => "input_norm",
            ObjectiveKind::OutputNorm => "output_norm",
            ObjectiveKind::SaturationRegion => "saturation",
            ObjectiveKind::FiniteTime => "finite_time",
        }
    }
}

impl std::fmt::Display for ObjectiveKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.keyword())
    }
}

impl Objective {
    /// The family of this objective.
    pub fn kind(&self) -> ObjectiveKind {
        match self {
            Objective::Stability => ObjectiveKind::Stability,
            Objective::DecayRate(_) => ObjectiveKind::DecayRate,
            Objective::Hinf { .. } => ObjectiveKind::Hinf,
            Objective::Linf { .. } => ObjectiveKind::Linf,
            Objective::InputNorm { .. } => ObjectiveKind::InputNorm,
            Objective::OutputNorm { .. } => ObjectiveKind::OutputNorm,
            Objective::SaturationRegion { .. } => ObjectiveKind::SaturationRegion,
            Objective::FiniteTime(_) => ObjectiveKind::FiniteTime,
        }
    }
}

/// The double-sum relaxation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Relaxation {
    /// Tanaka & Wang.
    Basic,
    /// At most `s` rules fire at once.
    Tanaka {
        /// s.
        s: usize,
    },
    /// Tuan et al. 2001.
    Tuan,
    /// Polya's theorem (Sala & Arino 2007): the double sum times (sum_k h_k)^d
    /// has every coefficient negative definite (d = 0 is `basic`).
    Polya {
        /// Degree d of the multiplier.
        d: usize,
    },
    /// Controller memberships evaluated at sampling instants.
    MembershipMismatch {
        /// Mismatch bound.
        kappa: f64,
    },
}

/// The Lyapunov function of the design (`lyapunov quadratic | fuzzy(phi = ..);`).
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Lyapunov {
    /// V = x' P x (the default).
    #[default]
    Quadratic,
    /// V = x' (sum_k h_k P_k) x, certified under the assumption
    /// |dh_k/dt| <= phi_k on the closed loop (Tanaka, Hori & Wang 2003).
    Fuzzy {
        /// The bound phi_k of each rule's membership derivative, in rule order.
        phi: Vec<f64>,
    },
}

/// Threshold of an event trigger.
#[derive(Debug, Clone, PartialEq)]
pub struct Threshold {
    /// Initial / static threshold nu.
    pub nu: f64,
    /// Adaptive law parameters (mu1, mu2, mu3), if adaptive.
    pub adaptive: Option<(f64, f64, f64)>,
    /// Ceiling of the adaptive law (`adaptive(.., max = ..)`): the threshold the
    /// event-triggered loop is certified for; `nu` itself when absent.
    pub max: Option<f64>,
}

impl Threshold {
    /// The largest threshold nu(t_k) the trigger may use: the certified one.
    pub fn ceiling(&self) -> f64 {
        self.max.unwrap_or(self.nu)
    }
}

/// Trigger weight: given, or synthesized.
#[derive(Debug, Clone, PartialEq)]
pub enum Weight {
    /// Synthesized with the gains.
    Synthesize,
    /// Given n x n matrix.
    Given(Mat),
}

/// How a synthesized trigger weight is designed
/// (`weight = synthesize two_step;` or `weight = synthesize theorem2(...);`).
#[derive(Debug, Clone, PartialEq)]
pub enum TriggerSynthesis {
    /// Gains first (the spec's objectives), then the weight and the largest
    /// threshold for those gains.
    TwoStep,
    /// Xu & Huang (2020) Theorem 2, LMIs (37)-(41), co-designing gains and weight.
    Theorem2 {
        /// Slack scalars eps_1, eps_2, eps_3 (Q_k = eps_k Q).
        eps: [f64; 3],
        /// xi, if given here (else the L-inf objective's).
        xi: Option<f64>,
        /// OCR reading (1, 2 or 3; docs/event_trigger.md).
        reading: u8,
    },
    /// Gains and weight co-designed by alternating a trigger step (gains
    /// fixed) and a gain step (Lyapunov matrices fixed), starting from the
    /// two-step design (docs/event_trigger.md).
    Codesign {
        /// Largest number of (gain step, trigger step) rounds, 1 ..= 30.
        rounds: u32,
    },
    /// A design for few transmissions (`weight = synthesize transmissions(points = ..);`):
    /// gains as soft as the L-inf bound allows, found by co-design rounds whose gain step
    /// minimizes the gains' stiffness; every round is a point of the reported trade-off
    /// (docs/event_trigger.md).
    Transmissions {
        /// Points of the search (gain step + trigger step each), 1 ..= 12.
        points: u32,
        /// The bound on the event-triggered L-inf gamma every point keeps
        /// (`gamma = ..`); without it, the two-step design's gamma.
        gamma: Option<f64>,
    },
}

/// The sampling intervals [h - j, h + j] of `trigger jittered { every = h; jitter = j; }`.
pub fn jittered_intervals(every: f64, jitter: f64) -> (f64, f64) {
    (every - jitter, every + jitter)
}

/// A triggering law.
#[derive(Debug, Clone, PartialEq)]
pub enum Trigger {
    /// Control updated at every integration step.
    Continuous,
    /// Every h seconds.
    Periodic {
        /// The period.
        every: f64,
    },
    /// Nominally every h seconds, each instant within j/2 of the nominal
    /// grid, so every interval lies in [h - j, h + j] (0 <= j < h); every
    /// sample transmitted, the command held.
    Jittered {
        /// The nominal period h.
        every: f64,
        /// The jitter j: how far an interval may differ from h.
        jitter: f64,
    },
    /// Aperiodic sampling with a relative event trigger.
    Aperiodic {
        /// h_min, h_max.
        sampling: (f64, f64),
        /// Threshold, if any (else every sample is sent).
        threshold: Option<Threshold>,
        /// Weight U.
        weight: Weight,
    },
    /// ||sigma(t_i) - sigma|| >= beta ||sigma|| + rho (Amrr et al. 2019).
    Mixed {
        /// Where the law is checked.
        monitor: Monitor,
        /// beta >= 0.
        beta: f64,
        /// rho >= 0.
        rho: f64,
        /// The monitored signal (`on = name;`); `None`: the state.
        on: Option<NamedSignal>,
    },
}

/// One `region z = lo .. hi;` of an aperiodic trigger: every component of
/// premise `z` stays in `[lo, hi]` on the certified set (lo < 0 < hi, inside
/// the premise's range). When `z` names a state rather than a premise
/// variable, the box bounds that state's components and tsfc encloses the
/// premises that read it (docs/language.md).
#[derive(Debug, Clone, PartialEq)]
pub struct RegionBound {
    /// The premise variable (or the state, when [`RegionBound::state`] is set).
    pub premise: String,
    /// `Some((offset, len))` when the name is a state and no premise
    /// variable: its components x[offset .. offset + len] are bounded.
    pub state: Option<(usize, usize)>,
    /// Bounds of each of its components (for `region z = auto;`: the seed
    /// box, the premise's range times [`crate::limits::REGION_AUTO_SEED`]).
    pub range: (f64, f64),
    /// `region z = auto;`: tsfc grows the box from the seed to the largest
    /// one on which the design certifies (docs/event_trigger.md).
    pub auto: bool,
    /// The setting.
    pub span: Span,
}

/// How the gains of a `trigger periodic` loop are designed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PeriodicDesign {
    /// `design = emulation` (default): continuous-time design, then the
    /// sampled-loop certificate for the period.
    Emulation,
    /// `design = discrete`: discrete-time PDC design on the exact zero-order-hold
    /// discretization of each local model, then the same sampled-loop certificate.
    Discrete,
}

/// When a `trigger mixed` checks its law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Monitor {
    /// `sampling = h_min .. h_max;`: at aperiodic sampling instants.
    Sampling(f64, f64),
    /// `monitor = step;`: at every integration step (the controller rate).
    Step,
    /// `monitor = continuous;`: continuously (the simulator locates each crossing).
    Continuous,
}

impl Monitor {
    /// The sampling interval bounds, for `Sampling`.
    pub fn sampling(&self) -> Option<(f64, f64)> {
        match *self {
            Monitor::Sampling(lo, hi) => Some((lo, hi)),
            _ => None,
        }
    }
}

/// A named signal `signal name = expr;`: a vector expression of the state.
#[derive(Debug, Clone, PartialEq)]
pub struct NamedSignal {
    /// Its name.
    pub name: String,
    /// The expression of the state.
    pub expr: Expr,
    /// Its length.
    pub dim: usize,
    /// Where it is declared.
    pub span: Span,
}

impl NamedSignal {
    /// The signal at the state `x`, or `None` when it cannot be evaluated.
    pub fn eval(&self, spec: &Spec, x: &[f64]) -> Option<Vec<f64>> {
        let v = spec.state_env(x, Mode::Exact).eval(&self.expr).ok()?;
        Some(v.iter().copied().collect())
    }
}

/// Code targets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Emit {
    /// Rust.
    Rust,
    /// C99.
    C,
}

/// How generated C writes a controller's step (`emit c(style = ..)`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CStyle {
    /// Straight-line up to a size, table-driven beyond it (the default).
    #[default]
    Auto,
    /// Straight-line: memberships, rules, blend and saturation written out
    /// with the tables' numbers at compile-time indices.
    Straight,
    /// Table-driven: dimensions and tables handed to the runtime's step.
    Table,
}

/// Floating-point precision of generated code.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Precision {
    /// f64 / double.
    F64,
    /// f32 / float.
    F32,
}

/// Integrator for the simulation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Integrator {
    /// Fixed-step RK4.
    Rk4,
    /// Adaptive Dormand-Prince 5(4).
    Dopri5,
}

/// The truth plant of a simulation.
#[derive(Debug, Clone, PartialEq)]
pub struct Dynamics {
    /// States the controller does not see.
    pub extra_states: Vec<Signal>,
    /// Local constants.
    pub consts: Vec<(String, Mat)>,
    /// Derivatives by state name (declared states first, then extra states).
    pub derivatives: Vec<(String, Expr)>,
    /// Where the block is.
    pub span: Span,
}

/// The `simulate` scenario.
#[derive(Debug, Clone, PartialEq)]
pub struct Simulation {
    /// Initial state.
    pub x0: Vec<f64>,
    /// Initial estimate of an observer-based controller (`xhat0 = [..];`,
    /// n components; the generated `INIT`, 0, when not given).
    pub xhat0: Option<crate::span::Spanned<Vec<f64>>>,
    /// Start, end, step.
    pub time: (f64, f64, f64),
    /// Disturbance signals: (disturbance index, expression of t).
    pub signals: Vec<(usize, Expr)>,
    /// Seed for random sampling patterns.
    pub seed: u64,
    /// Initial Markov mode (`mode0 = name;`, a mode of the `modes` block;
    /// the first mode when not given).
    pub mode0: Option<crate::span::Spanned<String>>,
    /// Seed of the Markov mode process (`mode_seed = k;`; `seed` when not given).
    pub mode_seed: Option<u64>,
    /// Integrator.
    pub integrator: Integrator,
    /// Truth dynamics, if given.
    pub dynamics: Option<Dynamics>,
    /// Declared uncertainty for Monte Carlo campaigns, if given.
    pub monte_carlo: Option<MonteCarlo>,
    /// Scenarios of `tsfc simulate --sweep`, if given.
    pub sweep: Option<Sweep>,
    /// Where the block is.
    pub span: Span,
}

/// One scenario of a `sweep`: a triggering law, checked by the same checker
/// as the top-level `trigger` item.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepScenario {
    /// Its name in the table: the law's kind and the expanded values
    /// (`periodic every = 2`).
    pub name: String,
    /// The law.
    pub trigger: Trigger,
    /// The design method of a synthesized trigger weight, as for the item.
    pub trigger_synthesis: Option<TriggerSynthesis>,
    /// How to write the scenario as a `trigger` item of the spec's text: the
    /// sweep statement's span, and for each expanded field the span of its
    /// list and of the element that replaces it.
    pub source: (Span, Vec<(Span, Span)>),
}

/// A column of the sweep table: the largest Euclidean norm of a state group
/// over the steady-state window.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepColumn {
    /// The column's name.
    pub name: String,
    /// The state group as written (`x`, a state, or an extra state of `dynamics`).
    pub group: String,
    /// `(offset, len)` of the group in the plant state (controller states, then extra states).
    pub at: (usize, usize),
}

/// The `sweep { }` block of the scenario.
#[derive(Debug, Clone, PartialEq)]
pub struct Sweep {
    /// The expanded scenarios, in source order (at most
    /// [`crate::limits::MAX_SWEEP_SCENARIOS`]).
    pub scenarios: Vec<SweepScenario>,
    /// The steady-state window `(start, end)` of the norm columns (default: the whole span).
    pub window: Option<(f64, f64)>,
    /// The norm columns.
    pub columns: Vec<SweepColumn>,
    /// Where the block is.
    pub span: Span,
}

/// What a `monte_carlo` statement perturbs (always the truth plant).
#[derive(Debug, Clone, PartialEq)]
pub enum McTarget {
    /// A constant of the spec (`local` false) or of the `dynamics` block.
    Const {
        /// Its name.
        name: String,
        /// Whether it is a constant of the `dynamics` block.
        local: bool,
    },
    /// The initial state (its `n` controller states).
    InitialState,
    /// A disturbance signal's amplitude (index into [`Spec::disturbances`]).
    Disturbance(usize),
}

/// One uncertain quantity: drawn per run uniformly in `[lo, hi]` (per component).
#[derive(Debug, Clone, PartialEq)]
pub struct Uncertain {
    /// What is perturbed.
    pub target: McTarget,
    /// How the draw acts on the nominal value.
    pub how: crate::ast::Vary,
    /// Lower bounds (one per component; a scalar for constants and disturbances).
    pub lo: Vec<f64>,
    /// Upper bounds (`lo <= hi`, both finite).
    pub hi: Vec<f64>,
    /// The statement.
    pub span: Span,
}

/// `converged |x| <= tol by t`: a run converged when the Euclidean norm of the
/// signal stays at most `tol` from some time `<= by` to the end.
#[derive(Debug, Clone, PartialEq)]
pub struct Convergence {
    /// The signal's `(offset, len)` in the state (`x`: `(0, n)`).
    pub signal: (usize, usize),
    /// Its name as written.
    pub name: String,
    /// The norm bound.
    pub tol: f64,
    /// The time by which the bound holds for good.
    pub by: f64,
    /// The statement.
    pub span: Span,
}

/// The `monte_carlo { }` block of the scenario.
#[derive(Debug, Clone, PartialEq)]
pub struct MonteCarlo {
    /// Default run count.
    pub runs: Option<u64>,
    /// The uncertain quantities, in source order.
    pub uncertain: Vec<Uncertain>,
    /// What "converged" means.
    pub converged: Convergence,
    /// Where the block is.
    pub span: Span,
}

/// A checked specification.
#[derive(Debug, Clone)]
pub struct Spec {
    /// The controller name.
    pub controller: Spanned<String>,
    /// Evaluated constants.
    pub consts: HashMap<String, Mat>,
    /// User functions.
    pub fns: HashMap<String, FnDef>,
    /// States in order.
    pub states: Vec<Signal>,
    /// Inputs in order.
    pub inputs: Vec<Signal>,
    /// Per-channel saturation levels (length m), if given.
    pub saturation: Option<Vec<f64>>,
    /// Disturbances in order.
    pub disturbances: Vec<Signal>,
    /// Bound on ||w(t)||, if given.
    pub disturbance_bound: Option<f64>,
    /// Bound w2 on the energy of w over the horizon (integral of w'w), if given
    /// (`disturbance d energy w2;`).
    pub disturbance_energy: Option<f64>,
    /// Performance outputs.
    pub outputs: Vec<Output>,
    /// `A`.
    pub a: Option<ModelMatrix>,
    /// `B`.
    pub b: Option<ModelMatrix>,
    /// `D`.
    pub d: Option<ModelMatrix>,
    /// Premise variables.
    pub premises: Vec<Premise>,
    /// Rules.
    pub rules: Vec<RuleSpec>,
    /// Objectives.
    pub objectives: Vec<SpannedObjective>,
    /// Relaxation (default basic).
    pub relaxation: Spanned<Relaxation>,
    /// Lyapunov function (default quadratic).
    pub lyapunov: Spanned<Lyapunov>,
    /// Named signals (`signal name = expr;`), in source order.
    pub signals: Vec<NamedSignal>,
    /// Trigger (default continuous).
    pub trigger: Option<Spanned<Trigger>>,
    /// How a synthesized trigger weight is designed (aperiodic trigger with
    /// `weight = synthesize`; None otherwise).
    pub trigger_synthesis: Option<TriggerSynthesis>,
    /// `region z = lo .. hi;` of an aperiodic trigger: the premise box the
    /// event-triggered certificate is local to (empty: the whole premise range).
    pub trigger_region: Vec<RegionBound>,
    /// The L-inf gamma a source reports (`with paper = ...`), echoed in the
    /// report as `objectives.linf_gamma_paper`; not used by synthesis.
    pub linf_paper: Option<f64>,
    /// Code targets.
    pub emit: Vec<Emit>,
    /// Style of the generated C step (`emit c(style = ..)`).
    pub c_style: CStyle,
    /// Precision.
    pub precision: Precision,
    /// Scenario.
    pub simulate: Option<Simulation>,
    /// Markov-switching modes, if any.
    pub modes: Option<crate::modes::Modes>,
    /// How a periodic loop's gains are designed (`trigger periodic { design = ..; }`),
    /// with the span of the setting; `None` is emulation.
    pub periodic_design: Option<Spanned<PeriodicDesign>>,
    /// The sector construction that built the rules (`rules sector;`), if any.
    pub sector: Option<crate::sector::SectorModel>,
    /// The adaptive controller (`adaptive { ... }`), if the spec is one.
    pub adaptive: Option<crate::adaptive::Adaptive>,
    /// `plant region ..;`: the region the plant claim is asked for, per state
    /// `[lo, hi]` (infinite where not written); `None`: the default region.
    pub plant_region: Option<Vec<(f64, f64)>>,
    /// The measured outputs (`measure ..;` items, stacked in source order), if any.
    pub measure: Option<Measured>,
    /// The controller kind (`control ..;`; default state feedback).
    pub control: Control,
}

impl Spec {
    /// n: total state dimension.
    pub fn n(&self) -> usize {
        self.states.iter().map(|s| s.len).sum()
    }

    /// m: total input dimension.
    pub fn m(&self) -> usize {
        self.inputs.iter().map(|s| s.len).sum()
    }

    /// q: total disturbance dimension.
    pub fn q(&self) -> usize {
        self.disturbances.iter().map(|s| s.len).sum()
    }

    /// The given PDC gains F_j in rule order, when the rules give them (the
    /// checker makes every rule give one or none): the compiler then analyzes
    /// these gains instead of synthesizing them.
    pub fn given_gains(&self) -> Option<Vec<Mat>> {
        self.rules
            .iter()
            .map(|r| r.gain.as_ref().map(|(f, _)| f.clone()))
            .collect::<Option<Vec<_>>>()
            .filter(|g| !g.is_empty())
    }

    /// An environment in which the states are bound to the components of `x`
    /// (and `x` to the whole vector).
    pub fn state_env(&self, x: &[f64], mode: Mode) -> Env<'_> {
        let mut locals = Vec::with_capacity(self.states.len() + 1);
        locals.push(("x".to_string(), Mat::from_column_slice(x.len(), 1, x)));
        for s in &self.states {
            let v = x.get(s.offset..s.offset + s.len).unwrap_or(&[]);
            locals.push((s.name.clone(), Mat::from_column_slice(v.len(), 1, v)));
        }
        Env {
            consts: &self.consts,
            fns: &self.fns,
            locals,
            unavailable: Vec::new(),
            mode,
        }
    }
}
