//! Typed syntax tree of a `.tsf` file. Every node carries its source span.

use crate::span::{Span, Spanned};

/// An identifier with its span.
pub type Ident = Spanned<String>;

/// A binary operator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BinOp {
    /// `+`
    Add,
    /// `-`
    Sub,
    /// `*` (matrix product, scalar broadcast)
    Mul,
    /// `.*` (element-wise product)
    EMul,
    /// `/` (division by a scalar)
    Div,
    /// `^` (power)
    Pow,
}

/// One index of an indexing expression.
#[derive(Debug, Clone, PartialEq)]
pub enum IndexArg {
    /// `..`: the whole dimension.
    Full,
    /// `i`: one element.
    One(Expr),
    /// `i..j`: half-open range.
    Range(Expr, Expr),
}

/// An argument of a call, positional or named.
#[derive(Debug, Clone, PartialEq)]
pub struct Arg {
    /// The name for `name = value` arguments.
    pub name: Option<Ident>,
    /// The value.
    pub value: Expr,
}

/// An expression node.
#[derive(Debug, Clone, PartialEq)]
pub enum ExprKind {
    /// A number literal (already parsed; `text` kept for messages).
    Number(f64),
    /// A name.
    Name(String),
    /// `[a, b; c, d]`: rows of elements (block concatenation).
    Matrix(Vec<Vec<Expr>>),
    /// `-e`
    Neg(Box<Expr>),
    /// `e'`
    Transpose(Box<Expr>),
    /// `a op b`
    Binary(BinOp, Box<Expr>, Box<Expr>),
    /// `e[i]` or `e[i, j]`
    Index(Box<Expr>, Vec<IndexArg>),
    /// `f(args)`
    Call(Ident, Vec<Arg>),
}

/// An expression with its span.
#[derive(Debug, Clone, PartialEq)]
pub struct Expr {
    /// What the expression is.
    pub kind: ExprKind,
    /// Where it is.
    pub span: Span,
}

/// A declared signal (`w[3]` or `theta`).
#[derive(Debug, Clone, PartialEq)]
pub struct VarDecl {
    /// The name.
    pub name: Ident,
    /// The declared length (`None` for a scalar), with the span of the number.
    pub len: Option<Spanned<f64>>,
}

/// `name = expr` (named argument or setting).
#[derive(Debug, Clone, PartialEq)]
pub struct NamedArg {
    /// The name.
    pub name: Ident,
    /// The value.
    pub value: Expr,
}

/// One bound of `plant region`: `x = lo .. hi` (every component of a
/// vector state) or `x[k] = lo .. hi` (its component k, 0-based).
#[derive(Debug, Clone, PartialEq)]
pub struct PlantBound {
    /// The state's name.
    pub name: Ident,
    /// The component index as written (0-based), if any.
    pub index: Option<Spanned<f64>>,
    /// The lower bound.
    pub lo: Expr,
    /// The upper bound.
    pub hi: Expr,
}

/// One target of `emit`: `c` or `c(style = table)`.
#[derive(Debug, Clone, PartialEq)]
pub struct EmitTarget {
    /// The target's name.
    pub name: Ident,
    /// Its options (`style = ..` for `c`).
    pub args: Vec<NamedArg>,
}

/// A fuzzy-set definition inside a premise block: `neg = tri(-1, -1, 0);`.
#[derive(Debug, Clone, PartialEq)]
pub struct SetDef {
    /// The set's name.
    pub name: Ident,
    /// The shape function (`tri`, `trap`, `gauss`, `sigmoid`).
    pub shape: Ident,
    /// Its arguments.
    pub args: Vec<Arg>,
    /// Span of the whole definition.
    pub span: Span,
}

/// The right-hand side of a rule clause.
#[derive(Debug, Clone, PartialEq)]
pub enum SetRef {
    /// A named set of the premise.
    Named(Ident),
    /// `about <point>`.
    About(Expr),
}

/// One clause of a rule's premise: `premise is set`.
#[derive(Debug, Clone, PartialEq)]
pub struct Clause {
    /// The premise variable.
    pub premise: Ident,
    /// The set.
    pub set: SetRef,
    /// Span of the clause.
    pub span: Span,
}

/// A value in a setting: an expression or a range `a .. b [step h]`.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// An expression.
    Expr(Expr),
    /// A range with an optional step.
    Range(Expr, Expr, Option<Expr>),
}

/// A modifier after a setting value: `adaptive(mu1 = 10, ...)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Modifier {
    /// Its name.
    pub name: Ident,
    /// Its named arguments.
    pub args: Vec<NamedArg>,
}

/// `key [qualifier] = value [modifiers];` inside `trigger` and `simulate` blocks.
#[derive(Debug, Clone, PartialEq)]
pub struct Setting {
    /// The key (e.g. `threshold`).
    pub key: Ident,
    /// An optional second word (e.g. `nu` in `threshold nu = 0.2`).
    pub qualifier: Option<Ident>,
    /// The value.
    pub value: Value,
    /// Modifiers.
    pub modifiers: Vec<Modifier>,
    /// Span of the whole setting.
    pub span: Span,
}

/// The goal of an objective.
#[derive(Debug, Clone, PartialEq)]
pub enum Goal {
    /// `<= e`
    AtMost(Expr),
    /// `>= e`
    AtLeast(Expr),
    /// A word: `minimize`, `maximize`, `region`.
    Word(Ident),
}

/// `for x0 = e` or `for x0 in e`.
#[derive(Debug, Clone, PartialEq)]
pub struct ObjectiveFor {
    /// The bound name (`x0`).
    pub name: Ident,
    /// `true` for `in`, `false` for `=`.
    pub is_in: bool,
    /// The value.
    pub value: Expr,
}

/// A statement inside `simulate { dynamics { ... } }`.
#[derive(Debug, Clone, PartialEq)]
pub enum DynStmt {
    /// `state eta[4];`
    State(Vec<VarDecl>),
    /// `const k = ...;`
    Const(Ident, Expr),
    /// `w' = ...;`
    Derivative(Ident, Expr),
}

/// A statement inside `simulate { ... }`.
#[derive(Debug, Clone, PartialEq)]
pub enum SimStmt {
    /// `key = value;`
    Setting(Setting),
    /// `d(t) = expr;`
    Signal {
        /// The signal name.
        name: Ident,
        /// The time parameter name.
        param: Ident,
        /// The expression.
        value: Expr,
    },
    /// `dynamics { ... }`
    Dynamics(Vec<Spanned<DynStmt>>, Span),
    /// `monte_carlo { ... }`
    MonteCarlo(Vec<McStmt>, Span),
    /// `sweep { ... }`
    Sweep(Vec<SweepStmt>, Span),
}

/// A statement inside `sweep { ... }`.
#[derive(Debug, Clone, PartialEq)]
pub enum SweepStmt {
    /// `trigger kind { settings }`: a triggering law whose list-valued fields expand.
    Trigger {
        /// The law's kind.
        kind: Ident,
        /// Its settings as written.
        settings: Vec<Setting>,
        /// The whole statement.
        span: Span,
    },
    /// `columns { name = state; ... }`, with the block's span.
    Columns(Vec<(Ident, Ident)>, Span),
    /// `key = value;` (`window`).
    Setting(Box<Setting>),
}

/// How a `monte_carlo` statement perturbs its target.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Vary {
    /// `name scale dist;`: the nominal value times a factor drawn per run.
    Scale,
    /// `name offset dist;`: the nominal value plus an offset drawn per run.
    Offset,
    /// `name in dist;`: a value drawn per run (the nominal one is not used).
    In,
}

/// A statement inside `monte_carlo { ... }`.
#[derive(Debug, Clone, PartialEq)]
pub enum McStmt {
    /// `key = value;` (`runs`).
    Setting(Setting),
    /// `name scale|offset|in uniform(lo, hi);`
    Vary {
        /// The perturbed constant, `x0` or disturbance.
        name: Ident,
        /// How.
        how: Spanned<Vary>,
        /// The distribution (a call such as `uniform(lo, hi)`).
        dist: Expr,
        /// The whole statement.
        span: Span,
    },
    /// `converged |x| <= tol by t;`
    Converged {
        /// `x` or a state name.
        signal: Ident,
        /// The norm bound.
        tol: Expr,
        /// The time by which the bound must hold for good.
        by: Expr,
        /// The whole statement.
        span: Span,
    },
}

/// One top-level item.
#[derive(Debug, Clone, PartialEq)]
pub enum ItemKind {
    /// `tsf 1;`
    Version(Spanned<f64>),
    /// `controller name;`
    Controller(Ident),
    /// `const name = expr;`
    Const(Ident, Expr),
    /// `fn name(params) = expr;`
    Fn(Ident, Vec<Ident>, Expr),
    /// `state ...;`
    State(Vec<VarDecl>),
    /// `input ... [saturate e];`
    Input(Vec<VarDecl>, Option<Expr>),
    /// `disturbance ... [bound e | energy e];`
    Disturbance(Vec<VarDecl>, Option<DisturbanceLimit>),
    /// `output name = expr;`
    Output(Ident, Expr),
    /// `signal name = expr;` (a named vector expression of the state)
    Signal(Ident, Expr),
    /// `A(x) = expr;` or `B = expr;`
    Matrix {
        /// Matrix name.
        name: Ident,
        /// The state parameter for state-dependent matrices.
        param: Option<Ident>,
        /// The expression.
        value: Expr,
    },
    /// `premise names [= expr] [range a .. b] [sigma s] { sets } | ;`
    Premise {
        /// The premise names.
        names: Vec<Ident>,
        /// The bound expression.
        expr: Option<Expr>,
        /// The declared operating range.
        range: Option<(Expr, Expr)>,
        /// The `about` width.
        sigma: Option<Expr>,
        /// The fuzzy sets.
        sets: Vec<SetDef>,
    },
    /// `rule name: clauses => consequent;`
    Rule {
        /// Rule name.
        name: Ident,
        /// Premise clauses.
        clauses: Vec<Clause>,
        /// `at(...)` assignments, with the span of `at(...)`.
        at: Option<(Vec<NamedArg>, Span)>,
        /// Direct matrix assignments.
        matrices: Vec<NamedArg>,
    },
    /// `objective name[(a -> b)] [goal] [for ...] [with ...];`
    Objective {
        /// Objective kind.
        name: Ident,
        /// Signals `(from -> to)` or `(signal)`.
        signals: Vec<Ident>,
        /// Goal.
        goal: Option<Goal>,
        /// `for` clause.
        for_: Option<ObjectiveFor>,
        /// `with` parameters.
        with: Vec<NamedArg>,
    },
    /// `relaxation name[(args)];`
    Relaxation(Ident, Vec<NamedArg>),
    /// `lyapunov kind[(args)];`
    Lyapunov(Ident, Vec<NamedArg>),
    /// `plant region x1 = lo .. hi, ..;`: the region of the plant claim.
    PlantRegion(Vec<PlantBound>),
    /// `measure name = expr [noise <= e];`: a measured output y = C x.
    Measure {
        /// The output's name.
        name: Ident,
        /// Its expression (linear in the state).
        value: Expr,
        /// The noise bound `noise <= e`, if given.
        noise: Option<Expr>,
    },
    /// `control kind[(args)];`: state feedback, observer-based or static output feedback.
    Control(Ident, Vec<NamedArg>),
    /// `rules kind;`: rules the compiler builds (`rules sector;`).
    Rules(Ident),
    /// `trigger kind { settings }`
    Trigger(Ident, Vec<Setting>),
    /// `emit targets;`
    Emit(Vec<EmitTarget>),
    /// `precision f64;`
    Precision(Ident),
    /// `simulate { ... }`
    Simulate(Vec<SimStmt>),
    /// `modes { mode name { settings } ... settings }`
    Modes(Vec<ModesStmt>),
    /// `adaptive { ... }`
    Adaptive(Vec<AdaptiveStmt>),
}

/// A statement inside `adaptive { ... }`.
#[derive(Debug, Clone, PartialEq)]
#[allow(clippy::large_enum_variant)] // a handful per spec, parsed once
pub enum AdaptiveStmt {
    /// `key = value;` (`error`, `reference`, `Q`).
    Setting(Box<Setting>),
    /// `estimate name rate g bounds lo .. hi [init v];` or
    /// `robust name rate g bounds lo .. hi [init v] layer phi;`
    Estimate {
        /// `true` for `robust`.
        robust: bool,
        /// The estimated quantity (`a`, `b`, `d`).
        name: Ident,
        /// Adaptation rate.
        rate: Expr,
        /// Projection bounds.
        lo: Expr,
        /// Projection bounds.
        hi: Expr,
        /// Initial value (default: the design model's value, or `lo` for `d`).
        init: Option<Expr>,
        /// Boundary-layer width.
        layer: Option<Expr>,
        /// The whole statement.
        span: Span,
    },
    /// `r(t) = expr;`
    Signal {
        /// The signal name.
        name: Ident,
        /// The time parameter.
        param: Ident,
        /// The expression.
        value: Expr,
        /// The whole statement.
        span: Span,
    },
    /// `converged |signal| <= tol by t;`
    Converged {
        /// `x` or a state name.
        signal: Ident,
        /// The norm bound.
        tol: Expr,
        /// The time by which the bound holds for good.
        by: Expr,
        /// The whole statement.
        span: Span,
    },
}

/// A statement inside `modes { ... }`.
#[derive(Debug, Clone, PartialEq)]
pub enum ModesStmt {
    /// `mode name { key = value; ... }`
    Mode {
        /// The mode's name.
        name: Ident,
        /// Its settings.
        settings: Vec<Setting>,
        /// The whole definition.
        span: Span,
    },
    /// `key = value;` (`rates`, `design`).
    Setting(Box<Setting>),
}

/// A top-level item with its span.
#[derive(Debug, Clone, PartialEq)]
pub struct Item {
    /// What it is.
    pub kind: ItemKind,
    /// Where it is (the whole item).
    pub span: Span,
}

/// An item that could not be parsed: what it seems to declare, so that the
/// checker does not report every later use of those names as unknown.
#[derive(Debug, Clone, PartialEq)]
pub struct BrokenItem {
    /// Its first word (`const`, `state`, `rule`, a matrix name, ...).
    pub keyword: String,
    /// The names it seems to declare.
    pub names: Vec<String>,
    /// Where it is.
    pub span: Span,
}

/// A parsed file: the items that parsed, and what the broken ones seem to declare.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct File {
    /// The items in source order.
    pub items: Vec<Item>,
    /// Items with syntax errors (reported separately).
    pub broken: Vec<BrokenItem>,
}

/// The limit a `disturbance` declaration gives.
#[derive(Debug, Clone, PartialEq)]
pub enum DisturbanceLimit {
    /// `bound e`: ||w(t)|| <= e at every t.
    Bound(Expr),
    /// `energy e`: the integral of w(t)'w(t) over the horizon is at most e.
    Energy(Expr),
}
