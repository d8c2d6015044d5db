//! Name resolution and shape checking: AST -> [`Spec`].
//!
//! Each item is checked on its own, so independent mistakes are all reported.
//! One module per item kind: [`decls`] (version, controller, functions,
//! constants, signals), [`model`] (outputs and the matrices A, B, D), named [`signals`],
//! [`premises`], [`rules`] (and their given [`gains`]), [`objectives`], [`relaxation`], [`trigger`],
//! [`targets`] (emit, precision), [`simulate`] and its [`dynamics`], [`monte_carlo`] and
//! [`sweep`], [`modes`]; premises
//! must be [`generatable`], and [`compat`] rejects valid items the
//! compiler cannot do together (one file per feature).
//! Environments and constant evaluation are shared by all of them
//! ([`env`], [`values`]).

mod adaptive;
mod compat;
mod decls;
mod dynamics;
mod env;
mod finite_time;
mod gains;
mod generatable;
mod lyapunov;
mod measure;
mod model;
mod modes;
mod monte_carlo;
mod objective_parts;
mod objectives;
mod plant_region;
mod precision;
mod premises;
mod relaxation;
mod rules;
mod sector;
mod signals;
mod simulate;
mod sweep;
mod targets;
mod trigger;
mod values;

pub use generatable::GENERATABLE_FUNCTIONS;

use crate::ast::*;
use crate::diag::Diagnostic;
use crate::eval::{Budget, FnDef, Mat, BUILTINS};
use crate::span::{Span, Spanned};
use crate::spec::*;
use std::collections::{HashMap, HashSet};

/// Kinds of declared names, for duplicate and misuse messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Const,
    Fn,
    State,
    Input,
    Disturbance,
    Output,
    Premise,
    Named,
    Measured,
}

impl Kind {
    fn word(self) -> &'static str {
        match self {
            Kind::Const => "constant",
            Kind::Fn => "function",
            Kind::State => "state",
            Kind::Input => "input",
            Kind::Disturbance => "disturbance",
            Kind::Output => "output",
            Kind::Premise => "premise",
            Kind::Named => "signal",
            Kind::Measured => "measured output",
        }
    }

    /// Whether a name of this kind is a signal (not a constant or function).
    fn is_signal(self) -> bool {
        !matches!(self, Kind::Const | Kind::Fn)
    }
}

/// The names of the state, input and disturbance items of `file`.
fn signal_items(file: &File) -> Vec<(String, Kind)> {
    let mut out = Vec::new();
    for it in &file.items {
        let (vars, kind): (&[VarDecl], Kind) = match &it.kind {
            ItemKind::State(v) => (v, Kind::State),
            ItemKind::Input(v, _) => (v, Kind::Input),
            ItemKind::Disturbance(v, _) => (v, Kind::Disturbance),
            _ => continue,
        };
        out.extend(vars.iter().map(|v| (v.name.node.clone(), kind)));
    }
    out
}

/// The signal dimensions: states n, inputs m, disturbances q.
#[derive(Debug, Clone, Copy)]
struct Dims {
    n: usize,
    m: usize,
    q: usize,
}

struct Checker<'a> {
    file: &'a File,
    diags: Vec<Diagnostic>,
    names: HashMap<String, (Kind, Span)>,
    /// The declared names that are signals (states, inputs, disturbances,
    /// outputs, premises), kept beside `names` so that building an
    /// environment does not go through every constant.
    signal_names: Vec<(String, Kind)>,
    /// The names of every state, input and disturbance item of the file,
    /// declared or not.
    signal_items: Vec<(String, Kind)>,
    consts: HashMap<String, Mat>,
    fns: HashMap<String, FnDef>,
    states: Vec<Signal>,
    inputs: Vec<Signal>,
    disturbances: Vec<Signal>,
    /// Names whose definitions failed: uses of them are not reported again.
    poisoned: HashSet<String>,
    /// Functions using a poisoned name (through any chain of calls).
    tainted: HashSet<String>,
    /// For each name, the functions whose bodies use it.
    users: HashMap<String, Vec<String>>,
    /// First words of items that failed to parse.
    broken_keywords: HashSet<String>,
    /// `paper = ...` of the L-inf objective (a source's reported gamma).
    linf_paper: Option<f64>,
    /// The evaluation work left for the whole check.
    budget: Budget,
    /// Whether running out of it was reported (it is reported once).
    budget_reported: bool,
    /// The `on = name;` of each expanded sweep scenario, in scenario order,
    /// resolved with the spec's own trigger once every signal is checked.
    sweep_on: Vec<Option<Ident>>,
}

/// What the pass over the model, objective and setting items collects.
#[derive(Default)]
struct Draft<'a> {
    outputs: Vec<Output>,
    a: Option<ModelMatrix>,
    b: Option<ModelMatrix>,
    d: Option<ModelMatrix>,
    /// Checked after the pass, once every signal and matrix is known.
    premise_items: Vec<&'a Item>,
    rule_items: Vec<&'a Item>,
    /// `rules sector;` items.
    rules_items: Vec<&'a Item>,
    objective_items: Vec<&'a Item>,
    relaxation: Option<Spanned<Relaxation>>,
    /// `lyapunov ..;`: the kind and its phi value (settled once the rules are known).
    lyapunov: Option<Spanned<lyapunov::Draft>>,
    trigger: Option<Spanned<Trigger>>,
    /// Where the trigger's kind and settings are written.
    trigger_spans: compat::TriggerSpans,
    /// The `on = name;` of a mixed trigger, resolved once every signal is checked.
    trigger_on: Option<Ident>,
    /// Named signals (`signal name = expr;`).
    signals: Vec<NamedSignal>,
    trigger_synthesis: Option<TriggerSynthesis>,
    /// `region z = lo .. hi;` settings of an aperiodic trigger (premises checked later).
    trigger_region: Vec<crate::spec::RegionBound>,
    /// `design = ..` of a periodic trigger.
    periodic_design: Option<Spanned<crate::spec::PeriodicDesign>>,
    /// Where a synthesized trigger weight is asked for (when its design method checked).
    weight_span: Option<Span>,
    emit: Vec<Emit>,
    c_style: CStyle,
    emit_seen: Option<Span>,
    precision: Option<Precision>,
    precision_seen: Option<Span>,
    simulate: Option<Simulation>,
    simulate_seen: Option<Span>,
    /// `plant region ..;` and where it is written.
    plant_region: Option<Spanned<Vec<(f64, f64)>>>,
    /// The stacked `measure` items.
    measure: Option<Measured>,
    /// `control ..;`.
    control: Option<Control>,
}

/// Checks a parsed file. Returns the spec when there is no error, and all diagnostics.
pub fn check(file: &File) -> (Option<Spec>, Vec<Diagnostic>) {
    let mut c = Checker {
        file,
        diags: Vec::new(),
        names: HashMap::new(),
        signal_names: Vec::new(),
        signal_items: signal_items(file),
        consts: HashMap::new(),
        fns: HashMap::new(),
        states: Vec::new(),
        inputs: Vec::new(),
        disturbances: Vec::new(),
        poisoned: file
            .broken
            .iter()
            .flat_map(|b| b.names.iter().cloned())
            .collect(),
        tainted: HashSet::new(),
        users: HashMap::new(),
        broken_keywords: file.broken.iter().map(|b| b.keyword.clone()).collect(),
        linf_paper: None,
        budget: Budget::check(),
        budget_reported: false,
        sweep_on: Vec::new(),
    };
    let spec = c.run();
    let has_error = c.diags.iter().any(Diagnostic::is_error);
    (if has_error { None } else { spec }, c.diags)
}

impl<'a> Checker<'a> {
    /// The passes, in the order their diagnostics must come (equal spans keep it).
    fn run(&mut self) -> Option<Spec> {
        let file: &'a File = self.file;
        let items = &file.items;
        let controller = self.header(items);
        self.functions(items);
        self.index_function_uses();
        let limits = self.declarations(items);
        self.check_fn_bodies();
        self.require_signals();
        let dims = self.dims();
        let saturate_span = limits.saturate.map(|e| e.span);
        let saturation = limits
            .saturate
            .and_then(|e| self.saturation_levels(e, dims.m));
        let disturbance_bound = limits
            .bound
            .and_then(|e| self.positive(e, "the disturbance bound"));
        let energy_given = limits.energy.is_some();
        let disturbance_energy = limits
            .energy
            .and_then(|e| self.positive(e, "the disturbance energy bound"));
        let mut draft = Draft::default();
        for it in items {
            self.item(it, dims, &mut draft);
        }
        self.resolve_trigger_signal(&mut draft);
        self.resolve_sweep_signals(&mut draft);
        self.check_model(&draft, dims);
        let mut premises = self.premises(&draft.premise_items, &draft.rule_items);
        let trigger_region = self.trigger_region(&draft.trigger_region, &premises);
        let matrices = [
            ("A", draft.a.as_ref(), dims.n, dims.n),
            ("B", draft.b.as_ref(), dims.n, dims.m),
            ("D", draft.d.as_ref(), dims.n, dims.q),
        ];
        let (rules, sector) = match self.sector_rules(
            &draft.rules_items,
            &draft.rule_items,
            &mut premises,
            matrices,
            dims,
        ) {
            sector::Built::NotAsked => (self.rules(&draft.rule_items, &premises, dims), None),
            sector::Built::Sector(model, rules) => (rules, Some(*model)),
            sector::Built::Failed => (Vec::new(), None),
        };
        self.gains_all_or_none(&draft.rule_items);
        let objectives = self.objectives(&draft.objective_items, dims.n, &draft.outputs);
        let relaxation =
            self.settle_relaxation(draft.relaxation.take(), &rules, draft.rule_items.len());
        let modes_span = items
            .iter()
            .find(|it| matches!(it.kind, ItemKind::Modes(_)))
            .map(|it| it.span);
        self.compatibility(
            &draft,
            &compat::Around {
                controller: controller.as_ref(),
                objectives: &objectives,
                objectives_complete: objectives.len() == draft.objective_items.len(),
                levels: saturation.as_deref(),
                saturate: limits.saturate.map(|e| e.span),
                first_input: self.inputs.first().map(|s| s.span),
                disturbance_bound,
                trigger_region: &trigger_region,
                modes: modes_span,
            },
        );
        let modes = self.modes_block(
            items,
            &draft,
            dims,
            modes::Around {
                objectives: &objectives,
                relaxation: &relaxation,
                rules: &rules,
                saturated: saturation.is_some(),
            },
        );
        self.finite_time_fits(
            &objectives,
            modes_span,
            dims.q,
            disturbance_energy,
            energy_given && disturbance_energy.is_none(),
        );
        self.simulate_modes(modes.as_ref(), draft.simulate.as_ref());
        self.discrete_design_fits(
            draft.periodic_design.as_ref(),
            &objectives,
            saturation.is_some(),
            &rules,
        );
        let adaptive = self.adaptive_block(items, &draft, dims, &objectives, &rules);
        let lyapunov = self.settle_lyapunov(
            draft.lyapunov.take(),
            lyapunov::Around {
                trigger: draft.trigger.as_ref().map(|t| &t.node),
                rules: &rules,
                rule_items: draft.rule_items.len(),
                objectives: &objectives,
                relaxation: &relaxation,
                saturated: saturation.is_some(),
                modes: modes_span,
                adaptive: adaptive.is_some(),
            },
        );
        let controller = controller?;
        let spec = Spec {
            controller,
            consts: self.consts.clone(),
            fns: self.fns.clone(),
            states: self.states.clone(),
            inputs: self.inputs.clone(),
            saturation,
            disturbances: self.disturbances.clone(),
            disturbance_bound,
            disturbance_energy,
            outputs: draft.outputs,
            a: draft.a,
            b: draft.b,
            d: draft.d,
            premises,
            rules,
            objectives,
            relaxation,
            lyapunov,
            signals: draft.signals,
            trigger: draft.trigger,
            trigger_synthesis: draft.trigger_synthesis,
            trigger_region,
            linf_paper: self.linf_paper,
            emit: draft.emit,
            c_style: draft.c_style,
            precision: draft.precision.unwrap_or(Precision::F64),
            simulate: draft.simulate,
            modes,
            periodic_design: draft.periodic_design,
            sector,
            adaptive,
            plant_region: draft.plant_region.map(|r| r.node),
            measure: draft.measure,
            control: draft.control.unwrap_or_default(),
        };
        self.f32_storable(&spec, saturate_span);
        self.output_feedback_fits(&spec);
        self.simulate_estimate(&spec);
        Some(spec)
    }

    /// One item of the main pass, handed to the module of its kind.
    fn item(&mut self, it: &'a Item, dims: Dims, draft: &mut Draft<'a>) {
        match &it.kind {
            ItemKind::Output(name, e) => self.output_item(name, e, dims, draft),
            ItemKind::Signal(name, e) => self.signal_item(name, e, draft),
            ItemKind::Matrix { name, param, value } => {
                self.matrix_item(it, name, param.as_ref(), value, draft)
            }
            ItemKind::Premise { .. } => draft.premise_items.push(it),
            ItemKind::Rule { .. } => draft.rule_items.push(it),
            ItemKind::Rules(_) => draft.rules_items.push(it),
            ItemKind::Objective { .. } => draft.objective_items.push(it),
            ItemKind::Relaxation(name, args) => self.relaxation_item(it, name, args, draft),
            ItemKind::Lyapunov(name, args) => self.lyapunov_item(it, name, args, draft),
            ItemKind::PlantRegion(bounds) => self.plant_region_item(it, bounds, dims.n, draft),
            ItemKind::Measure { name, value, noise } => {
                self.measure_item(name, value, noise.as_ref(), dims, draft)
            }
            ItemKind::Control(kind, args) => self.control_item(it, kind, args, draft),
            ItemKind::Trigger(kind, settings) => {
                self.trigger_item(it, kind, settings, dims.n, draft)
            }
            ItemKind::Emit(targets) => self.emit_item(it, targets, draft),
            ItemKind::Precision(p) => self.precision_item(it, p, draft),
            ItemKind::Simulate(stmts) => self.simulate_item(it, stmts, dims.n, draft),
            _ => {}
        }
    }

    fn dims(&self) -> Dims {
        let total = |s: &[Signal]| s.iter().map(|s| s.len).sum();
        Dims {
            n: total(&self.states),
            m: total(&self.inputs),
            q: total(&self.disturbances),
        }
    }

    fn err(&mut self, d: Diagnostic) {
        if self.budget.is_spent() {
            // Every evaluation after the check ran out of work fails the same way.
            if self.budget_reported {
                return;
            }
            self.budget_reported = true;
        }
        self.diags.push(d);
    }

    fn declare(&mut self, name: &Ident, kind: Kind) -> bool {
        if matches!(name.node.as_str(), "x" | "t") {
            let what = if name.node == "x" {
                "the whole state vector"
            } else {
                "time in `simulate`"
            };
            self.err(
                Diagnostic::error(name.span, format!("`{}` is a reserved name", name.node))
                    .with_label(format!("`{}` means {what}", name.node))
                    .with_help("choose another name"),
            );
            return false;
        }
        if BUILTINS.contains(&name.node.as_str()) {
            self.err(
                Diagnostic::error(
                    name.span,
                    format!("`{}` is the name of a built-in function", name.node),
                )
                .with_help("choose another name"),
            );
            return false;
        }
        if let Some((k, s)) = self.names.get(&name.node) {
            let d = Diagnostic::error(name.span, format!("`{}` is declared twice", name.node))
                .with_label(format!("redeclared here as a {}", kind.word()))
                .with_secondary(*s, format!("first declared here as a {}", k.word()));
            self.err(d);
            return false;
        }
        self.names.insert(name.node.clone(), (kind, name.span));
        if kind.is_signal() {
            self.signal_names.push((name.node.clone(), kind));
        }
        true
    }

    /// Whether a missing-declaration error would only repeat a syntax error.
    fn broken(&self, keyword: &str) -> bool {
        self.broken_keywords.contains(keyword)
    }

    /// Reports `d`, a value of the wrong size for the declared dimensions,
    /// unless a state, input or disturbance item failed to parse: the
    /// dimensions are unknown then, and the error would repeat that one.
    fn shape_err(&mut self, d: Diagnostic) {
        if !["state", "input", "disturbance"]
            .iter()
            .any(|k| self.broken(k))
        {
            self.err(d);
        }
    }

    fn singleton(&mut self, found: &mut Option<Span>, span: Span, what: &str) -> bool {
        if let Some(first) = *found {
            self.err(
                Diagnostic::error(span, format!("{what} is given twice"))
                    .with_label("second definition")
                    .with_secondary(first, "first definition here")
                    .with_help("keep only one"),
            );
            return false;
        }
        *found = Some(span);
        true
    }
}

/// "unknown <what> `word`" with the valid choices and a "did you mean" hint.
fn unknown_choice(
    span: Span,
    what: &str,
    plural: &str,
    word: &str,
    choices: &[&str],
) -> Diagnostic {
    Diagnostic::error(span, format!("unknown {what} `{word}`"))
        .with_label(format!("{plural}: {}", choices.join(", ")))
        .with_suggestion(word, choices.iter().copied())
}

/// Small specs for the unit tests of every checker module.
#[cfg(test)]
pub(crate) mod testing {
    use crate::diag::Diagnostic;
    use crate::spec::Spec;

    /// A valid one-state spec; tests append or replace items.
    pub const BASE: &str = "tsf 1; controller c; state x1; input u; A = -1; B = 1;\n\
        premise x1 range -1 .. 1 { all = trap(-1, -1, 1, 1); }\n\
        rule R: x1 is all => A = -2;\n";

    /// `BASE` with `old` replaced by `new`.
    pub fn base_with(old: &str, new: &str) -> String {
        assert!(BASE.contains(old), "{old}");
        BASE.replace(old, new)
    }

    /// The spec of `src`, which must be valid.
    pub fn valid(src: &str) -> Spec {
        let (spec, diags) = crate::check_source(src);
        assert!(diags.iter().all(|d| !d.is_error()), "{diags:#?}");
        spec.expect("a valid spec") // ok: unit test
    }

    /// The only error of `src`: its message and the text under its span.
    pub fn only_error_of(src: &str) -> (String, String) {
        let e = errors(src);
        assert_eq!(e.len(), 1, "{e:#?}");
        (e[0].0.message.clone(), e[0].1.clone())
    }

    /// The spec of `BASE` followed by `extra`, which must be valid.
    pub fn spec_with(extra: &str) -> Spec {
        valid(&format!("{BASE}{extra}"))
    }

    /// The errors of `src`, each with the text its span covers.
    pub fn errors(src: &str) -> Vec<(Diagnostic, String)> {
        let (spec, diags) = crate::check_source(src);
        let errors: Vec<_> = diags
            .into_iter()
            .filter(Diagnostic::is_error)
            .map(|d| {
                let text = src.get(d.span.start..d.span.end).unwrap_or("").to_string();
                (d, text)
            })
            .collect();
        assert!(spec.is_none() || errors.is_empty());
        errors
    }

    /// The only error of `BASE` + `extra`: its message and the text under its span.
    pub fn only_error(extra: &str) -> (String, String) {
        only_error_of(&format!("{BASE}{extra}"))
    }
}

#[cfg(test)]
mod tests {
    use super::testing::*;

    #[test]
    fn base_spec_is_valid() {
        let spec = spec_with("");
        assert_eq!(spec.controller.node, "c");
        assert_eq!((spec.n(), spec.m(), spec.q()), (1, 1, 0));
        assert_eq!(spec.rules.len(), 1);
    }

    #[test]
    fn reserved_and_builtin_names_cannot_be_declared() {
        let (m, at) = only_error("const x = 1;");
        assert_eq!(m, "`x` is a reserved name");
        assert_eq!(at, "x");
        let (m, at) = only_error("const sinc = 1;");
        assert_eq!(m, "`sinc` is the name of a built-in function");
        assert_eq!(at, "sinc");
    }

    #[test]
    fn a_name_declared_twice_points_at_the_second() {
        let e = errors(&format!("{BASE}const k = 1;\nconst k = 2;"));
        assert_eq!(e.len(), 1);
        assert_eq!(e[0].0.message, "`k` is declared twice");
        assert_eq!(e[0].0.secondary.len(), 1);
        assert!(e[0].0.span.start > e[0].0.secondary[0].span.start);
    }

    #[test]
    fn a_singleton_item_given_twice_is_one_error() {
        let (m, at) = only_error("precision f64;\nprecision f32;");
        assert_eq!(m, "the precision is given twice");
        assert_eq!(at, "precision f32;");
    }
}
