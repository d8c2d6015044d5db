//! Name resolution and shape checking: AST -> [`Spec`].
//!
//! Each item is checked on its own, so independent mistakes are all reported.

use crate::ast::*;
use crate::diag::Diagnostic;
use crate::eval::{suggest, Env, FnDef, Mat, Mode, BUILTINS};
use crate::span::{Span, Spanned};
use crate::spec::*;
use std::collections::{HashMap, HashSet};

/// The language versions this checker reads.
pub const SUPPORTED_VERSION: f64 = 1.0;

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
        }
    }
}

struct Checker<'a> {
    file: &'a File,
    diags: Vec<Diagnostic>,
    names: HashMap<String, (Kind, Span)>,
    consts: HashMap<String, Mat>,
    fns: HashMap<String, FnDef>,
    states: Vec<Signal>,
    inputs: Vec<Signal>,
    disturbances: Vec<Signal>,
    /// Names whose definitions failed: uses of them are not reported again.
    poisoned: HashSet<String>,
    /// First words of items that failed to parse.
    broken_keywords: HashSet<String>,
    /// `paper = ...` of the L-inf objective (a source's reported gamma).
    linf_paper: Option<f64>,
}

/// Checks a parsed file. Returns the spec when there is no error, and all diagnostics.
pub fn check(file: &File) -> (Option<Spec>, Vec<Diagnostic>) {
    let mut c = Checker {
        file,
        diags: Vec::new(),
        names: HashMap::new(),
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
        broken_keywords: file.broken.iter().map(|b| b.keyword.clone()).collect(),
        linf_paper: None,
    };
    let spec = c.run();
    let has_error = c.diags.iter().any(Diagnostic::is_error);
    (if has_error { None } else { spec }, c.diags)
}

fn num_span(e: &Expr) -> Span {
    e.span
}

impl<'a> Checker<'a> {
    fn err(&mut self, d: Diagnostic) {
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
        true
    }

    fn const_env(&self) -> Env<'_> {
        let mut unavailable = Vec::new();
        for (n, (k, _)) in &self.names {
            if matches!(
                k,
                Kind::State | Kind::Input | Kind::Disturbance | Kind::Output | Kind::Premise
            ) {
                unavailable.push((
                    n.clone(),
                    format!(
                        "a {} is not a constant; only constants may appear here",
                        k.word()
                    ),
                ));
            }
        }
        for it in &self.file.items {
            let (vars, kind): (&[VarDecl], Kind) = match &it.kind {
                ItemKind::State(v) => (v, Kind::State),
                ItemKind::Input(v, _) => (v, Kind::Input),
                ItemKind::Disturbance(v, _) => (v, Kind::Disturbance),
                _ => continue,
            };
            for v in vars {
                if !self.names.contains_key(&v.name.node) {
                    unavailable.push((
                        v.name.node.clone(),
                        format!(
                            "a {} is not a constant; only constants may appear here",
                            kind.word()
                        ),
                    ));
                }
            }
        }
        unavailable.push((
            "x".into(),
            "the state is not a constant; only constants may appear here".into(),
        ));
        unavailable.push((
            "t".into(),
            "time `t` is only available in `simulate` signals and dynamics".into(),
        ));
        Env {
            consts: &self.consts,
            fns: &self.fns,
            locals: Vec::new(),
            unavailable,
            mode: Mode::Exact,
        }
    }

    /// An environment with the states (zeros) bound, for expressions of x.
    fn state_env(&self, mode: Mode, extra: &[(String, Mat)], allowed_signals: &[Kind]) -> Env<'_> {
        let n: usize = self.states.iter().map(|s| s.len).sum();
        let mut env = self.const_env();
        env.mode = mode;
        env.unavailable.retain(|(name, _)| {
            let k = self.names.get(name).map(|p| p.0);
            !(name == "x"
                || k == Some(Kind::State)
                || k.is_some_and(|k| allowed_signals.contains(&k)))
        });
        for (name, (k, _)) in &self.names {
            if matches!(k, Kind::Input | Kind::Disturbance) && !allowed_signals.contains(k) {
                if let Some(u) = env.unavailable.iter_mut().find(|(n, _)| n == name) {
                    u.1 = format!(
                        "a {} cannot appear here: only states and constants can",
                        k.word()
                    );
                }
            }
        }
        env.locals.push(("x".into(), Mat::zeros(n, 1)));
        for s in &self.states {
            env.locals.push((s.name.clone(), Mat::zeros(s.len, 1)));
        }
        env.locals.extend(extra.iter().cloned());
        env
    }

    /// Whether `e` uses a name whose definition failed (errors already reported).
    fn poisoned(&self, e: &Expr) -> bool {
        self.poisoned_depth(e, 0)
    }

    fn poisoned_depth(&self, e: &Expr, depth: usize) -> bool {
        let mut hit = false;
        let mut called = Vec::new();
        walk_names(e, &mut |n, _, is_call| {
            hit |= self.poisoned.contains(n);
            if is_call {
                called.push(n.to_string());
            }
        });
        // Through user functions too (a function using a failed constant).
        hit || (depth < 16
            && called.iter().any(|f| {
                self.fns
                    .get(f)
                    .is_some_and(|d| self.poisoned_depth(&d.body, depth + 1))
            }))
    }

    /// Whether a missing-declaration error would only repeat a syntax error.
    fn broken(&self, keyword: &str) -> bool {
        self.broken_keywords.contains(keyword)
    }

    fn eval_const(&mut self, e: &Expr) -> Option<Mat> {
        if self.poisoned(e) {
            return None;
        }
        let r = self.const_env().eval(e);
        match r {
            Ok(v) if v.iter().all(|x| x.is_finite()) => Some(v),
            Ok(_) => {
                self.err(
                    Diagnostic::error(e.span, "value is not finite")
                        .with_label("evaluates to NaN or infinity"),
                );
                None
            }
            Err(d) => {
                self.err(d);
                None
            }
        }
    }

    fn scalar(&mut self, e: &Expr, what: &str) -> Option<f64> {
        let v = self.eval_const(e)?;
        if v.nrows() == 1 && v.ncols() == 1 {
            Some(v[(0, 0)])
        } else {
            self.err(
                Diagnostic::error(e.span, format!("{what} must be a scalar")).with_label(format!(
                    "this is {}x{}",
                    v.nrows(),
                    v.ncols()
                )),
            );
            None
        }
    }

    fn positive(&mut self, e: &Expr, what: &str) -> Option<f64> {
        let v = self.scalar(e, what)?;
        if v > 0.0 {
            Some(v)
        } else {
            self.err(
                Diagnostic::error(num_span(e), format!("{what} must be positive"))
                    .with_label(format!("this is {v}")),
            );
            None
        }
    }

    fn vector(&mut self, e: &Expr, len: usize, what: &str) -> Option<Vec<f64>> {
        let v = self.eval_const(e)?;
        if v.len() == len && (v.ncols() == 1 || v.nrows() == 1) {
            Some(v.iter().copied().collect())
        } else {
            self.err(
                Diagnostic::error(
                    e.span,
                    format!(
                        "{what} must have {len} component{}",
                        if len == 1 { "" } else { "s" }
                    ),
                )
                .with_label(format!("this is {}x{}", v.nrows(), v.ncols())),
            );
            None
        }
    }

    fn signals(&mut self, vars: &[VarDecl], kind: Kind, offset0: usize) -> Vec<Signal> {
        let mut out = Vec::new();
        let mut offset = offset0;
        for v in vars {
            let len = match &v.len {
                None => 1,
                Some(n) if n.node.fract() == 0.0 && n.node >= 1.0 && n.node <= 1000.0 => {
                    n.node as usize
                }
                Some(n) => {
                    self.err(
                        Diagnostic::error(
                            n.span,
                            format!(
                                "invalid size `{}` for {} `{}`",
                                n.node,
                                kind.word(),
                                v.name.node
                            ),
                        )
                        .with_label("a size is a whole number from 1 to 1000"),
                    );
                    continue;
                }
            };
            // A duplicate is reported but kept, so dimensions stay as written.
            self.declare(&v.name, kind);
            out.push(Signal {
                name: v.name.node.clone(),
                len,
                is_vector: v.len.is_some(),
                offset,
                span: v.name.span,
            });
            offset += len;
        }
        out
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

    fn run(&mut self) -> Option<Spec> {
        let items = &self.file.items;
        // Version: must come first.
        let mut version_seen = None;
        let mut controller: Option<Spanned<String>> = None;
        for it in items {
            match &it.kind {
                ItemKind::Version(v)
                    if self.singleton(&mut version_seen, it.span, "the language version")
                        && v.node != SUPPORTED_VERSION =>
                {
                    self.err(
                        Diagnostic::error(
                            v.span,
                            format!("unsupported language version {}", v.node),
                        )
                        .with_label("this tsfc reads version 1")
                        .with_help("write `tsf 1;`"),
                    );
                }
                ItemKind::Controller(n) => {
                    let mut seen = controller.as_ref().map(|c| c.span);
                    if self.singleton(&mut seen, it.span, "the controller name") {
                        if !is_c_identifier(&n.node) {
                            self.err(Diagnostic::error(
                                n.span,
                                "controller name is not a valid Rust and C identifier",
                            ));
                        }
                        controller = Some(n.clone());
                    }
                }
                _ => {}
            }
        }
        if version_seen.is_none() && !self.broken("tsf") {
            let at = items
                .first()
                .map_or(Span::new(0, 0), |i| Span::new(i.span.start, i.span.start));
            self.err(
                Diagnostic::error(at, "missing language version")
                    .with_label("the file should start with the version")
                    .with_help("add `tsf 1;` as the first line"),
            );
        }
        if controller.is_none() && !self.broken("controller") {
            self.err(
                Diagnostic::error(Span::new(0, 0), "missing controller name")
                    .with_help("add `controller my_controller;` (it names the generated module)"),
            );
        }
        // Functions first (they may be used by constants), then declarations in order.
        for it in items {
            if let ItemKind::Fn(name, params, body) = &it.kind {
                if self.declare(name, Kind::Fn) {
                    self.fns.insert(
                        name.node.clone(),
                        FnDef {
                            params: params.iter().map(|p| p.node.clone()).collect(),
                            body: body.clone(),
                        },
                    );
                }
            }
        }
        let mut sat_expr = None;
        let mut bound_expr = None;
        for it in items {
            match &it.kind {
                ItemKind::Const(name, e) => {
                    let v = self.eval_const(e);
                    if self.declare(name, Kind::Const) {
                        match v {
                            Some(v) => {
                                self.consts.insert(name.node.clone(), v);
                            }
                            // Later uses are not reported again.
                            None => {
                                self.poisoned.insert(name.node.clone());
                            }
                        }
                    }
                }
                ItemKind::State(vars) => {
                    let off = self.states.iter().map(|s| s.len).sum();
                    let s = self.signals(vars, Kind::State, off);
                    self.states.extend(s);
                }
                ItemKind::Input(vars, sat) => {
                    let off = self.inputs.iter().map(|s| s.len).sum();
                    let s = self.signals(vars, Kind::Input, off);
                    if let Some(e) = sat {
                        sat_expr = Some((
                            s.iter().map(|x| (x.offset, x.len)).collect::<Vec<_>>(),
                            e.clone(),
                        ));
                    }
                    self.inputs.extend(s);
                }
                ItemKind::Disturbance(vars, bound) => {
                    let off = self.disturbances.iter().map(|s| s.len).sum();
                    let s = self.signals(vars, Kind::Disturbance, off);
                    if let Some(e) = bound {
                        bound_expr = Some(e.clone());
                    }
                    self.disturbances.extend(s);
                }
                _ => {}
            }
        }
        self.check_fn_bodies();
        if self.states.is_empty() && !self.broken("state") {
            self.err(
                Diagnostic::error(Span::new(0, 0), "no states declared")
                    .with_help("declare the state, e.g. `state w[3], q[3];`"),
            );
        }
        if self.inputs.is_empty() && !self.broken("input") {
            self.err(
                Diagnostic::error(Span::new(0, 0), "no inputs declared")
                    .with_help("declare the control input, e.g. `input u[3];`"),
            );
        }
        let n: usize = self.states.iter().map(|s| s.len).sum();
        let m: usize = self.inputs.iter().map(|s| s.len).sum();
        let q: usize = self.disturbances.iter().map(|s| s.len).sum();

        let saturation = sat_expr.and_then(|(_, e)| {
            let v = self.eval_const(&e)?;
            let levels: Vec<f64> = if v.len() == 1 {
                vec![v[(0, 0)]; m]
            } else if v.len() == m && (v.ncols() == 1 || v.nrows() == 1) {
                v.iter().copied().collect()
            } else {
                self.err(Diagnostic::error(
                    e.span,
                    format!("saturation needs a scalar or {m} levels (one per input channel)"),
                ));
                return None;
            };
            if levels.iter().any(|l| *l <= 0.0) {
                self.err(Diagnostic::error(
                    e.span,
                    "saturation levels must be positive",
                ));
                return None;
            }
            Some(levels)
        });
        let disturbance_bound = bound_expr.and_then(|e| self.positive(&e, "the disturbance bound"));

        let mut outputs = Vec::new();
        let (mut a, mut b, mut d) = (None, None, None);
        let mut premise_items = Vec::new();
        let mut rule_items = Vec::new();
        let mut objectives = Vec::new();
        let mut relaxation: Option<Spanned<Relaxation>> = None;
        let mut trigger: Option<Spanned<Trigger>> = None;
        let mut trigger_synthesis = None;
        let mut emit = Vec::new();
        let mut emit_seen = None;
        let mut precision = Precision::F64;
        let mut precision_seen = None;
        let mut simulate = None;
        let mut simulate_seen = None;
        for it in items {
            match &it.kind {
                ItemKind::Output(name, e) if self.declare(name, Kind::Output) => {
                    match self.output(name, e, n, m, q) {
                        Some(o) => outputs.push(o),
                        None => {
                            self.poisoned.insert(name.node.clone());
                        }
                    }
                }
                ItemKind::Matrix { name, param, value } => {
                    let slot = match name.node.as_str() {
                        "A" => &mut a,
                        "B" => &mut b,
                        "D" => &mut d,
                        other => {
                            let mut diag = Diagnostic::error(
                                name.span,
                                format!("unknown model matrix `{other}`"),
                            )
                            .with_label("the model matrices are A, B and D");
                            diag = if param.is_some() {
                                diag.with_help("state-dependent matrices are written `A(x) = ...`, `B(x) = ...`, `D(x) = ...`")
                            } else {
                                diag.with_help(format!(
                                    "for a constant write `const {other} = ...;`"
                                ))
                            };
                            self.err(diag);
                            continue;
                        }
                    };
                    if let Some(prev) = slot.as_ref().map(|p: &ModelMatrix| p.span) {
                        let diag = Diagnostic::error(
                            it.span,
                            format!("model matrix `{}` is defined twice", name.node),
                        )
                        .with_secondary(prev, "first definition here");
                        self.diags.push(diag);
                        continue;
                    }
                    if let Some(p) = param {
                        if p.node != "x" {
                            self.diags.push(
                                Diagnostic::error(
                                    p.span,
                                    format!("the parameter of `{}(...)` must be `x`", name.node),
                                )
                                .with_help(format!("write `{}(x) = ...`", name.node)),
                            );
                            continue;
                        }
                    }
                    if param.is_none() {
                        // A constant model matrix can be referred to by later expressions (`D = B;`).
                        match self.eval_const(value) {
                            Some(v) => {
                                if self.declare(name, Kind::Const) {
                                    self.consts.insert(name.node.clone(), v);
                                }
                            }
                            None => {
                                self.poisoned.insert(name.node.clone());
                                continue;
                            }
                        }
                    }
                    *slot = Some(ModelMatrix {
                        expr: value.clone(),
                        state_dependent: param.is_some(),
                        span: it.span,
                    });
                }
                ItemKind::Premise { .. } => premise_items.push(it),
                ItemKind::Rule { .. } => rule_items.push(it),
                ItemKind::Objective { .. } => objectives.push(it),
                ItemKind::Relaxation(name, args) => {
                    let mut seen = relaxation.as_ref().map(|r| r.span);
                    if self.singleton(&mut seen, it.span, "the relaxation") {
                        if let Some(r) = self.relaxation(name, args, it.span) {
                            relaxation = Some(Spanned::new(r, it.span));
                        }
                    }
                }
                ItemKind::Trigger(kind, settings) => {
                    let mut seen = trigger.as_ref().map(|t| t.span);
                    if self.singleton(&mut seen, it.span, "the trigger") {
                        if let Some(t) = self.trigger(kind, settings, n) {
                            if matches!(
                                t,
                                Trigger::Aperiodic {
                                    weight: Weight::Synthesize,
                                    ..
                                }
                            ) {
                                trigger_synthesis = self.trigger_synthesis(settings);
                            }
                            trigger = Some(Spanned::new(t, it.span));
                        }
                    }
                }
                ItemKind::Emit(targets) if self.singleton(&mut emit_seen, it.span, "`emit`") => {
                    for t in targets {
                        match t.node.as_str() {
                            "rust" => emit.push(Emit::Rust),
                            "c" => emit.push(Emit::C),
                            _ => self.err(
                                Diagnostic::error(
                                    t.span,
                                    format!("unknown code target `{}`", t.node),
                                )
                                .with_label("targets are `rust` and `c`"),
                            ),
                        }
                    }
                }
                ItemKind::Precision(p)
                    if self.singleton(&mut precision_seen, it.span, "the precision") =>
                {
                    match p.node.as_str() {
                        "f64" | "double" => precision = Precision::F64,
                        "f32" | "float" => precision = Precision::F32,
                        _ => self.err(
                            Diagnostic::error(p.span, format!("unknown precision `{}`", p.node))
                                .with_label("use `f64` or `f32`"),
                        ),
                    }
                }
                ItemKind::Simulate(stmts)
                    if self.singleton(&mut simulate_seen, it.span, "the `simulate` block") =>
                {
                    simulate = self.simulate(stmts, it.span, n);
                }
                _ => {}
            }
        }
        for (slot, name, rows, cols, what) in [
            (&a, "A", n, n, "n x n"),
            (&b, "B", n, m, "n x m"),
            (&d, "D", n, q, "n x q"),
        ] {
            if let Some(mm) = slot {
                self.check_model_matrix(name, mm, rows, cols, what);
            }
        }
        let rules_give = |mat: &str| {
            !rule_items.is_empty()
                && rule_items.iter().all(|r| matches!(&r.kind, ItemKind::Rule { matrices, .. } if matrices.iter().any(|m| m.name.node == mat)))
        };
        if a.is_none() && !rules_give("A") && !self.broken("A") && !self.poisoned.contains("A") {
            self.err(
                Diagnostic::error(Span::new(0, 0), "no state matrix `A`").with_help(
                    "define `A = ...;` or `A(x) = ...;`, or give `A = ...` in every rule",
                ),
            );
        }
        if b.is_none() && !rules_give("B") && !self.broken("B") && !self.poisoned.contains("B") {
            self.err(
                Diagnostic::error(Span::new(0, 0), "no input matrix `B`").with_help(
                    "define `B = ...;` or `B(x) = ...;`, or give `B = ...` in every rule",
                ),
            );
        }
        if q > 0
            && d.is_none()
            && !rules_give("D")
            && !self.broken("D")
            && !self.poisoned.contains("D")
        {
            let span = self
                .disturbances
                .first()
                .map_or(Span::new(0, 0), |s| s.span);
            self.err(
                Diagnostic::error(
                    span,
                    "a disturbance is declared but there is no disturbance matrix `D`",
                )
                .with_help("define `D = ...;` (n x q)"),
            );
        }

        let rule_count = rule_items.len();
        let premises = self.premises(&premise_items, &rule_items);
        let rules = self.rules(&rule_items, &premises, n, m, q);
        let objectives = objectives
            .into_iter()
            .filter_map(|it| {
                self.objective(it, n, &outputs)
                    .map(|o| Spanned::new(o, it.span))
            })
            .collect::<Vec<_>>();
        let optimized: Vec<Span> = objectives
            .iter()
            .filter(|o| {
                matches!(
                    o.node,
                    Objective::DecayRate(Target::Optimize)
                        | Objective::Hinf {
                            target: Target::Optimize,
                            ..
                        }
                        | Objective::Linf {
                            target: Target::Optimize,
                            ..
                        }
                        | Objective::InputNorm {
                            target: Target::Optimize,
                            ..
                        }
                        | Objective::OutputNorm {
                            target: Target::Optimize,
                            ..
                        }
                )
            })
            .map(|o| o.span)
            .collect();
        if let [first, second, ..] = optimized.as_slice() {
            self.err(
                Diagnostic::error(*second, "more than one objective is optimized")
                    .with_label("second `minimize`/`maximize`")
                    .with_secondary(*first, "first one here")
                    .with_help("optimize one objective and bound the others with `<=` / `>=`"),
            );
        }
        let relaxation = relaxation.unwrap_or(Spanned::new(Relaxation::Basic, Span::new(0, 0)));
        if let Relaxation::Tanaka { s } = relaxation.node {
            if rules.len() == rule_count && (s < 1 || s > rules.len()) {
                self.err(
                    Diagnostic::error(
                        relaxation.span,
                        format!("tanaka(s = {s}) needs 1 <= s <= r = {}", rules.len()),
                    )
                    .with_label("s is the most rules that fire at once"),
                );
            }
        }
        let controller = controller?;
        Some(Spec {
            controller,
            consts: self.consts.clone(),
            fns: self.fns.clone(),
            states: self.states.clone(),
            inputs: self.inputs.clone(),
            saturation,
            disturbances: self.disturbances.clone(),
            disturbance_bound,
            outputs,
            a,
            b,
            d,
            premises,
            rules,
            objectives,
            relaxation,
            trigger,
            trigger_synthesis,
            linf_paper: self.linf_paper,
            emit,
            precision,
            simulate,
        })
    }

    /// The design method of a synthesized trigger weight: `weight = synthesize;`
    /// (none yet: the weight is left to later stages), `weight = synthesize two_step;`
    /// (gains first, then the weight) or `weight = synthesize theorem2(eps1 = .., eps2 = .., eps3 = ..,
    /// xi = .., reading = ..);` (Xu & Huang Theorem 2; every argument optional).
    fn trigger_synthesis(&mut self, settings: &[Setting]) -> Option<TriggerSynthesis> {
        let s = settings.iter().find(|s| s.key.node == "weight")?;
        let mut out = None;
        for m in &s.modifiers {
            if m.name.node == "two_step" {
                self.named(&m.args, &[], "`two_step`")?;
                out = Some(TriggerSynthesis::TwoStep);
                continue;
            }
            if m.name.node != "theorem2" {
                self.err(
                    Diagnostic::error(
                        m.name.span,
                        format!("unknown weight design method `{}`", m.name.node),
                    )
                    .with_help("write `weight = synthesize two_step;` or `weight = synthesize theorem2(eps1 = 1, eps2 = 1, eps3 = 1);`"),
                );
                return None;
            }
            let p = self.named(
                &m.args,
                &["eps1", "eps2", "eps3", "xi", "reading"],
                "`theorem2`",
            )?;
            let reading = p.get("reading").copied().unwrap_or(1.0);
            if ![1.0, 2.0, 3.0].contains(&reading) {
                self.err(Diagnostic::error(
                    m.name.span,
                    "`reading` is 1 (as printed), 2 (block (1,2) from the derivation) or 3 (2 and the sector multiplier by congruence)",
                ));
                return None;
            }
            let eps = |k: &str| p.get(k).copied().unwrap_or(1.0);
            out = Some(TriggerSynthesis::Theorem2 {
                eps: [eps("eps1"), eps("eps2"), eps("eps3")],
                xi: p.get("xi").copied(),
                reading: reading as u8,
            });
        }
        out
    }

    /// Checks that every name in every function body is a parameter, constant or function.
    fn check_fn_bodies(&mut self) {
        let mut found = Vec::new();
        for f in self.file.items.iter() {
            if let ItemKind::Fn(_, params, body) = &f.kind {
                let mut ps: Vec<&str> = params.iter().map(|p| p.node.as_str()).collect();
                let mut seen = Vec::new();
                for p in params {
                    if seen.contains(&p.node.as_str()) {
                        found.push(Diagnostic::error(
                            p.span,
                            format!("parameter `{}` is repeated", p.node),
                        ));
                    }
                    seen.push(p.node.as_str());
                }
                ps.extend(self.consts.keys().map(String::as_str));
                if self.poisoned(body) {
                    continue;
                }
                walk_names(body, &mut |name, span, is_call| {
                    let ok = if is_call {
                        BUILTINS.contains(&name) || self.fns.contains_key(name)
                    } else {
                        ps.contains(&name)
                    };
                    if !ok {
                        let mut d = Diagnostic::error(
                            span,
                            format!("unknown name `{name}` in function body"),
                        )
                        .with_label(if is_call {
                            "not a function"
                        } else {
                            "not a parameter or constant"
                        });
                        if let Some(s) = suggest(name, ps.iter().copied()) {
                            d = d.with_help(format!("did you mean `{s}`?"));
                        } else if !is_call {
                            d = d.with_help("a function sees only its parameters and constants; pass state values as arguments");
                        }
                        found.push(d);
                    }
                });
            }
        }
        self.diags.extend(found);
    }

    fn check_model_matrix(
        &mut self,
        name: &str,
        mm: &ModelMatrix,
        rows: usize,
        cols: usize,
        what: &str,
    ) {
        if self.poisoned(&mm.expr) {
            return;
        }
        let env = if mm.state_dependent {
            self.state_env(Mode::Shapes, &[], &[])
        } else {
            self.state_env(Mode::Exact, &[], &[])
        };
        let r = env.eval(&mm.expr);
        match r {
            Ok(v) if v.nrows() == rows && v.ncols() == cols => {}
            Ok(v) => {
                self.err(
                    Diagnostic::error(
                        mm.expr.span,
                        format!(
                            "`{name}` must be {what} = {rows}x{cols}, but this is {}x{}",
                            v.nrows(),
                            v.ncols()
                        ),
                    )
                    .with_label(format!("{}x{} matrix", v.nrows(), v.ncols()))
                    .with_note(format!(
                        "n = {} states, m = {} inputs, q = {} disturbances",
                        self.states.iter().map(|s| s.len).sum::<usize>(),
                        self.inputs.iter().map(|s| s.len).sum::<usize>(),
                        self.disturbances.iter().map(|s| s.len).sum::<usize>()
                    )),
                );
            }
            Err(d) => {
                let d = if !mm.state_dependent && d.label.contains("cannot appear") {
                    d.with_help(format!(
                        "`{name}` depends on the state: write `{name}(x) = ...`"
                    ))
                } else {
                    d
                };
                self.err(d);
            }
        }
    }

    fn output(&mut self, name: &Ident, e: &Expr, n: usize, m: usize, q: usize) -> Option<Output> {
        // Evaluate with (x, u, w) set to basis vectors: the columns of [C E G].
        let total = n + m + q;
        let eval_at = |this: &Self, v: &[f64]| -> Result<Mat, Diagnostic> {
            let mut extra = Vec::new();
            for s in &this.inputs {
                extra.push((
                    s.name.clone(),
                    Mat::from_column_slice(s.len, 1, &v[n + s.offset..n + s.offset + s.len]),
                ));
            }
            for s in &this.disturbances {
                extra.push((
                    s.name.clone(),
                    Mat::from_column_slice(
                        s.len,
                        1,
                        &v[n + m + s.offset..n + m + s.offset + s.len],
                    ),
                ));
            }
            let mut env = this.state_env(Mode::Exact, &extra, &[Kind::Input, Kind::Disturbance]);
            env.locals[0].1 = Mat::from_column_slice(n, 1, &v[..n]);
            for (i, s) in this.states.iter().enumerate() {
                env.locals[i + 1].1 =
                    Mat::from_column_slice(s.len, 1, &v[s.offset..s.offset + s.len]);
            }
            env.eval(e)
        };
        if self.poisoned(e) {
            return None;
        }
        let zero = vec![0.0; total];
        let y0 = match eval_at(self, &zero) {
            Ok(v) => v,
            Err(d) => {
                self.err(d);
                return None;
            }
        };
        if y0.ncols() != 1 {
            self.err(Diagnostic::error(
                e.span,
                format!(
                    "output `{}` must be a vector, found {}x{}",
                    name.node,
                    y0.nrows(),
                    y0.ncols()
                ),
            ));
            return None;
        }
        let p = y0.nrows();
        let mut cols = Mat::zeros(p, total);
        let mut basis = zero.clone();
        for k in 0..total {
            basis[k] = 1.0;
            let yk = eval_at(self, &basis).ok()?;
            cols.set_column(k, &(yk - &y0).column(0));
            basis[k] = 0.0;
        }
        // Linearity check at a generic point.
        let probe: Vec<f64> = (0..total).map(|k| 0.37 + 0.113 * k as f64).collect();
        let yp = eval_at(self, &probe).ok()?;
        let lin = &y0 + &cols * Mat::from_column_slice(total, 1, &probe);
        let scale = 1.0 + lin.norm();
        if y0.norm() > 1e-12 || (yp - lin).norm() > 1e-9 * scale {
            self.err(
                Diagnostic::error(e.span, format!("output `{}` is not linear in the state, inputs and disturbances", name.node))
                    .with_label("tsfc needs y = C x + E u + G w")
                    .with_help("write the performance output as a linear combination, e.g. `output z = [w; 0.5 * q];`"),
            );
            return None;
        }
        Some(Output {
            name: name.node.clone(),
            c: cols.columns(0, n).into_owned(),
            e: cols.columns(n, m).into_owned(),
            g: cols.columns(n + m, q).into_owned(),
            span: name.span,
        })
    }

    fn premises(&mut self, items: &[&Item], rules: &[&Item]) -> Vec<Premise> {
        let mut out = Vec::new();
        for it in items {
            let ItemKind::Premise {
                names,
                expr,
                range,
                sigma,
                sets,
            } = &it.kind
            else {
                continue;
            };
            // The expression each premise is bound to.
            let bound = match expr {
                Some(e) => e.clone(),
                None => {
                    let Some(first) = names.first() else { continue };
                    if names.len() > 1 {
                        self.err(
                            Diagnostic::error(
                                it.span,
                                "several premise names need a vector expression",
                            )
                            .with_help(format!(
                                "write `premise {} = <vector expression> ...`",
                                names
                                    .iter()
                                    .map(|n| n.node.as_str())
                                    .collect::<Vec<_>>()
                                    .join(", ")
                            )),
                        );
                        continue;
                    }
                    if !self.states.iter().any(|s| s.name == first.node) {
                        let mut d = Diagnostic::error(
                            first.span,
                            format!("premise `{}` is not a state", first.node),
                        )
                        .with_label("a premise without `= expr` must be a state name");
                        if let Some(s) =
                            suggest(&first.node, self.states.iter().map(|s| s.name.as_str()))
                        {
                            d = d.with_help(format!("did you mean `{s}`?"));
                        } else {
                            d = d.with_help(format!(
                                "bind it to an expression of the state: `premise {} = ...`",
                                first.node
                            ));
                        }
                        self.err(d);
                        continue;
                    }
                    Expr {
                        kind: ExprKind::Name(first.node.clone()),
                        span: first.span,
                    }
                }
            };
            if self.poisoned(&bound) {
                continue;
            }
            let r = self.state_env(Mode::Shapes, &[], &[]).eval(&bound);
            let v = match r {
                Ok(v) => v,
                Err(d) => {
                    self.err(d);
                    continue;
                }
            };
            if v.ncols() != 1 {
                self.err(
                    Diagnostic::error(bound.span, "a premise must be a scalar or a vector")
                        .with_label(format!("this is {}x{}", v.nrows(), v.ncols())),
                );
                continue;
            }
            let len = v.nrows();
            if names.len() > 1 && names.len() != len {
                self.err(
                    Diagnostic::error(
                        bound.span,
                        format!(
                            "{} premise names but the expression has {len} components",
                            names.len()
                        ),
                    )
                    .with_label(format!("a {len}-vector")),
                );
                continue;
            }
            let range = match range {
                Some((lo, hi)) => match (
                    self.scalar(lo, "a range bound"),
                    self.scalar(hi, "a range bound"),
                ) {
                    (Some(l), Some(h)) if l < h => Some((l, h)),
                    (Some(l), Some(h)) => {
                        self.err(
                            Diagnostic::error(
                                lo.span.join(hi.span),
                                format!("empty premise range {l} .. {h}"),
                            )
                            .with_help("write `range lo .. hi` with lo < hi"),
                        );
                        None
                    }
                    _ => None,
                },
                None => None,
            };
            let sigma = sigma.as_ref().and_then(|s| self.positive(s, "sigma"));
            let mut checked_sets: Vec<FuzzySet> = Vec::new();
            for s in sets {
                if let Some(prev) = checked_sets.iter().find(|c| c.name == s.name.node) {
                    let d = Diagnostic::error(
                        s.name.span,
                        format!("set `{}` is defined twice", s.name.node),
                    )
                    .with_secondary(prev.span, "first definition here");
                    self.err(d);
                    continue;
                }
                match self.set_shape(s) {
                    Some(shape) => checked_sets.push(FuzzySet {
                        name: s.name.node.clone(),
                        shape,
                        span: s.span,
                    }),
                    None => {
                        for n in names {
                            self.poisoned.insert(format!("{}.{}", n.node, s.name.node));
                        }
                    }
                }
            }
            let dim = if names.len() > 1 { 1 } else { len };
            for (k, name) in names.iter().enumerate() {
                if !self.declare_premise(name) {
                    continue;
                }
                out.push(Premise {
                    name: name.node.clone(),
                    expr: bound.clone(),
                    component: (names.len() > 1).then_some(k),
                    dim,
                    range,
                    sigma,
                    sets: checked_sets.clone(),
                    span: name.span,
                });
            }
        }
        // Vector states used in rules with `about` but not declared as premises: implicit premises.
        for r in rules {
            let ItemKind::Rule { clauses, .. } = &r.kind else {
                continue;
            };
            for c in clauses {
                if matches!(c.set, SetRef::About(_))
                    && !out.iter().any(|p| p.name == c.premise.node)
                {
                    if let Some(s) = self
                        .states
                        .iter()
                        .find(|s| s.name == c.premise.node)
                        .cloned()
                    {
                        out.push(Premise {
                            name: s.name.clone(),
                            expr: Expr {
                                kind: ExprKind::Name(s.name.clone()),
                                span: c.premise.span,
                            },
                            component: None,
                            dim: s.len,
                            range: None,
                            sigma: None,
                            sets: Vec::new(),
                            span: c.premise.span,
                        });
                    }
                }
            }
        }
        out
    }

    /// Premise names share a namespace with states only when they are the same variable.
    fn declare_premise(&mut self, name: &Ident) -> bool {
        match self.names.get(&name.node) {
            Some((Kind::State, _)) => true,
            _ => self.declare(name, Kind::Premise),
        }
    }

    fn set_shape(&mut self, s: &SetDef) -> Option<SetShape> {
        let want = match s.shape.node.as_str() {
            "tri" => 3,
            "trap" => 4,
            "gauss" | "sigmoid" => 2,
            other => {
                let mut d = Diagnostic::error(
                    s.shape.span,
                    format!("unknown membership function `{other}`"),
                )
                .with_label("use tri, trap, gauss or sigmoid");
                d = d.with_suggestion(other, ["tri", "trap", "gauss", "sigmoid"]);
                self.err(d);
                return None;
            }
        };
        if s.args.len() != want {
            self.err(
                Diagnostic::error(
                    s.span,
                    format!(
                        "`{}` takes {want} parameters, {} given",
                        s.shape.node,
                        s.args.len()
                    ),
                )
                .with_help(match s.shape.node.as_str() {
                    "tri" => "tri(a, b, c): feet a and c, peak b",
                    "trap" => "trap(a, b, c, d): feet a and d, plateau b..c",
                    "gauss" => "gauss(center, sigma)",
                    _ => "sigmoid(slope, center)",
                }),
            );
            return None;
        }
        let vals: Option<Vec<f64>> = s
            .args
            .iter()
            .map(|a| self.scalar(&a.value, "a membership parameter"))
            .collect();
        let v = vals?;
        let ordered = v.windows(2).all(|w| w[0] <= w[1]);
        let shape = match s.shape.node.as_str() {
            "tri" if ordered && v[0] < v[2] => SetShape::Tri(v[0], v[1], v[2]),
            "trap" if ordered && v[0] < v[3] => SetShape::Trap(v[0], v[1], v[2], v[3]),
            "gauss" if v[1] > 0.0 => SetShape::Gauss(v[0], v[1]),
            "sigmoid" if v[0] != 0.0 => SetShape::Sigmoid(v[0], v[1]),
            "tri" | "trap" => {
                self.err(
                    Diagnostic::error(
                        s.span,
                        format!("parameters of `{}` must be increasing", s.shape.node),
                    )
                    .with_label(format!("{:?}", v))
                    .with_help("the feet come first and last, e.g. tri(-1, 0, 1), with a < c"),
                );
                return None;
            }
            "gauss" => {
                self.err(
                    Diagnostic::error(s.span, "gauss width sigma must be positive")
                        .with_help("gauss(center, sigma) with sigma > 0"),
                );
                return None;
            }
            _ => {
                self.err(Diagnostic::error(s.span, "sigmoid slope must not be zero"));
                return None;
            }
        };
        Some(shape)
    }

    fn rules(
        &mut self,
        items: &[&Item],
        premises: &[Premise],
        n: usize,
        m: usize,
        q: usize,
    ) -> Vec<RuleSpec> {
        let mut out: Vec<RuleSpec> = Vec::new();
        for it in items {
            let ItemKind::Rule {
                name,
                clauses,
                at,
                matrices,
            } = &it.kind
            else {
                continue;
            };
            if let Some(prev) = out.iter().find(|r| r.name == name.node) {
                let d =
                    Diagnostic::error(name.span, format!("rule `{}` is defined twice", name.node))
                        .with_secondary(prev.span, "first definition here")
                        .with_help("give each rule a unique name");
                self.err(d);
                continue;
            }
            let mut ok = true;
            let mut rc = Vec::new();
            for c in clauses {
                let Some(pi) = premises.iter().position(|p| p.name == c.premise.node) else {
                    ok = false;
                    if self.poisoned.contains(&c.premise.node) {
                        continue;
                    }
                    let mut d = Diagnostic::error(
                        c.premise.span,
                        format!("unknown premise `{}`", c.premise.node),
                    )
                    .with_label("not declared as a premise");
                    if let Some(s) =
                        suggest(&c.premise.node, premises.iter().map(|p| p.name.as_str()))
                    {
                        d = d.with_help(format!("did you mean `{s}`?"));
                    } else {
                        d = d.with_help(format!(
                            "declare it: `premise {} range lo .. hi {{ ... }}`",
                            c.premise.node
                        ));
                    }
                    self.err(d);
                    ok = false;
                    continue;
                };
                let p = &premises[pi];
                if rc.iter().any(|x: &RuleClause| x.premise == pi) {
                    self.err(Diagnostic::error(
                        c.span,
                        format!("premise `{}` appears twice in rule `{}`", p.name, name.node),
                    ));
                    ok = false;
                    continue;
                }
                let set = match &c.set {
                    SetRef::Named(s) => match p.sets.iter().position(|x| x.name == s.node) {
                        Some(i) => ClauseSet::Named(i),
                        None if self.poisoned.contains(&format!("{}.{}", p.name, s.node)) => {
                            ok = false;
                            continue;
                        }
                        None => {
                            let mut d = Diagnostic::error(
                                s.span,
                                format!("premise `{}` has no set `{}`", p.name, s.node),
                            )
                            .with_label("unknown fuzzy set")
                            .with_secondary(p.span, "premise declared here");
                            if let Some(x) =
                                suggest(&s.node, p.sets.iter().map(|x| x.name.as_str()))
                            {
                                d = d.with_help(format!("did you mean `{x}`?"));
                            } else if p.sets.is_empty() {
                                d = d.with_help(
                                    "this premise has no named sets; use `is about <point>`",
                                );
                            } else {
                                d = d.with_help(format!(
                                    "its sets are: {}",
                                    p.sets
                                        .iter()
                                        .map(|x| x.name.as_str())
                                        .collect::<Vec<_>>()
                                        .join(", ")
                                ));
                            }
                            self.err(d);
                            ok = false;
                            continue;
                        }
                    },
                    SetRef::About(e) => match self.vector(
                        e,
                        p.dim,
                        &format!("the `about` point of premise `{}`", p.name),
                    ) {
                        Some(v) => ClauseSet::About(v),
                        None => {
                            ok = false;
                            continue;
                        }
                    },
                };
                rc.push(RuleClause {
                    premise: pi,
                    set,
                    span: c.span,
                });
            }
            let at_point = at.as_ref().and_then(|(args, aspan)| {
                let mut x = vec![0.0; n];
                let mut good = true;
                let mut seen: Vec<&str> = Vec::new();
                for a in args {
                    let Some(s) = self.states.iter().find(|s| s.name == a.name.node).cloned()
                    else {
                        let mut d = Diagnostic::error(
                            a.name.span,
                            format!("`{}` is not a state", a.name.node),
                        )
                        .with_label("`at(...)` sets states");
                        d = d.with_suggestion(
                            &a.name.node,
                            self.states.iter().map(|s| s.name.as_str()),
                        );
                        self.err(d);
                        good = false;
                        continue;
                    };
                    if seen.contains(&a.name.node.as_str()) {
                        self.err(Diagnostic::error(
                            a.name.span,
                            format!("state `{}` is set twice", s.name),
                        ));
                        good = false;
                        continue;
                    }
                    seen.push(&a.name.node);
                    let Some(v) = self.eval_const(&a.value) else {
                        good = false;
                        continue;
                    };
                    if v.len() != s.len || (v.ncols() != 1 && v.nrows() != 1) {
                        let mut d = Diagnostic::error(
                            a.value.span,
                            format!(
                                "rule {} sets {} = {} but {} has {} component{}",
                                name.node,
                                s.name,
                                if v.len() == 1 {
                                    format!("{}", v[(0, 0)])
                                } else {
                                    format!("a {}x{} value", v.nrows(), v.ncols())
                                },
                                s.name,
                                s.len,
                                if s.len == 1 { "" } else { "s" }
                            ),
                        )
                        .with_label(format!(
                            "expected {}",
                            if s.len == 1 {
                                "a scalar".to_string()
                            } else {
                                format!("a {}-vector", s.len)
                            }
                        ));
                        if v.len() == 1 && s.len > 1 {
                            d = d.with_help(format!(
                                "give every component, e.g. `{} = {} * ones({})`",
                                s.name,
                                v[(0, 0)],
                                s.len
                            ));
                        }
                        self.err(d);
                        good = false;
                        continue;
                    }
                    for (k, val) in v.iter().enumerate() {
                        x[s.offset + k] = *val;
                    }
                }
                good.then_some((x, *aspan))
            });
            if at.is_some() && at_point.is_none() {
                ok = false;
            }
            let mut overrides = Vec::new();
            for mat in matrices {
                let (rows, cols) = match mat.name.node.as_str() {
                    "A" => (n, n),
                    "B" => (n, m),
                    "D" => (n, q),
                    other => {
                        self.err(
                            Diagnostic::error(
                                mat.name.span,
                                format!("unknown model matrix `{other}` in rule"),
                            )
                            .with_label("a rule may give A, B or D"),
                        );
                        ok = false;
                        continue;
                    }
                };
                let Some(v) = self.eval_const(&mat.value) else {
                    ok = false;
                    continue;
                };
                if v.nrows() != rows || v.ncols() != cols {
                    self.err(
                        Diagnostic::error(
                            mat.value.span,
                            format!(
                                "`{}` of rule {} must be {rows}x{cols}, but this is {}x{}",
                                mat.name.node,
                                name.node,
                                v.nrows(),
                                v.ncols()
                            ),
                        )
                        .with_label(format!(
                            "{}x{} matrix",
                            v.nrows(),
                            v.ncols()
                        )),
                    );
                    ok = false;
                    continue;
                }
                if overrides
                    .iter()
                    .any(|(n, _, _): &(String, Mat, Span)| *n == mat.name.node)
                {
                    self.err(Diagnostic::error(
                        mat.name.span,
                        format!("`{}` is given twice in rule {}", mat.name.node, name.node),
                    ));
                    ok = false;
                    continue;
                }
                overrides.push((mat.name.node.clone(), v, mat.value.span));
            }
            if !ok {
                continue;
            }
            // Duplicate premise combination.
            let key = |r: &[RuleClause]| {
                let mut k: Vec<String> = r
                    .iter()
                    .map(|c| format!("{}:{:?}", c.premise, c.set))
                    .collect();
                k.sort();
                k
            };
            if let Some(prev) = out
                .iter()
                .find(|r| !rc.is_empty() && key(&r.clauses) == key(&rc))
            {
                let d = Diagnostic::error(name.span, format!("rule `{}` has the same premise as rule `{}`", name.node, prev.name))
                    .with_secondary(prev.span, "same premise here")
                    .with_help("two rules with one premise make the model ambiguous: merge them or change one premise");
                self.err(d);
                continue;
            }
            out.push(RuleSpec {
                name: name.node.clone(),
                clauses: rc,
                at: at_point,
                overrides,
                span: it.span,
            });
        }
        if out.is_empty() && !items.is_empty() {
            return out;
        }
        if items.is_empty() && !self.broken("rule") {
            self.err(
                Diagnostic::error(Span::new(0, 0), "no rules").with_help(
                    "add at least one rule, e.g. `rule R1: z is near => at(theta = 0);`",
                ),
            );
        }
        out
    }

    fn objective(&mut self, it: &Item, n: usize, outputs: &[Output]) -> Option<Objective> {
        let ItemKind::Objective {
            name,
            signals,
            goal,
            for_,
            with,
        } = &it.kind
        else {
            return None;
        };
        let kinds = [
            "stability",
            "decay_rate",
            "hinf",
            "linf",
            "input_norm",
            "output_norm",
            "saturation",
        ];
        let target = |this: &mut Self, word_ok: &str, bound_kind: &str| -> Option<Target> {
            match goal {
                None => {
                    this.err(
                        Diagnostic::error(
                            it.span,
                            format!("objective `{}` needs a goal", name.node),
                        )
                        .with_help(format!("write `{word_ok}` or `{bound_kind} value`")),
                    );
                    None
                }
                Some(Goal::Word(w)) if w.node == word_ok => Some(Target::Optimize),
                Some(Goal::AtMost(e)) if bound_kind == "<=" => {
                    this.positive(e, "the bound").map(Target::Fixed)
                }
                Some(Goal::AtLeast(e)) if bound_kind == ">=" => {
                    this.positive(e, "the bound").map(Target::Fixed)
                }
                Some(g) => {
                    let span = match g {
                        Goal::Word(w) => w.span,
                        Goal::AtMost(e) | Goal::AtLeast(e) => e.span,
                    };
                    this.err(
                        Diagnostic::error(
                            span,
                            format!(
                                "objective `{}` takes `{word_ok}` or `{bound_kind} value`",
                                name.node
                            ),
                        )
                        .with_label("not a valid goal here"),
                    );
                    None
                }
            }
        };
        let disturbance = |this: &mut Self, s: &Ident| -> Option<usize> {
            let found = this.disturbances.iter().position(|d| d.name == s.node);
            if found.is_none() && !this.poisoned.contains(&s.node) {
                let mut d = Diagnostic::error(s.span, format!("`{}` is not a disturbance", s.node))
                    .with_label("expected a declared disturbance");
                d = d.with_suggestion(&s.node, this.disturbances.iter().map(|d| d.name.as_str()));
                this.err(d);
            }
            found
        };
        let output = |this: &mut Self, s: &Ident| -> Option<usize> {
            let found = outputs.iter().position(|o| o.name == s.node);
            if found.is_none() && !this.poisoned.contains(&s.node) {
                let mut d = Diagnostic::error(s.span, format!("`{}` is not an output", s.node))
                    .with_label("expected a declared output");
                if let Some(c) = suggest(&s.node, outputs.iter().map(|o| o.name.as_str())) {
                    d = d.with_help(format!("did you mean `{c}`?"));
                } else {
                    d = d.with_help(format!("declare it: `output {} = ...;`", s.node));
                }
                this.err(d);
            }
            found
        };
        let pair = |this: &mut Self| -> Option<(usize, usize)> {
            match signals.as_slice() {
                [from, to] => {
                    let f = disturbance(this, from);
                    let t = output(this, to);
                    Some((f?, t?))
                }
                _ => {
                    this.err(
                        Diagnostic::error(
                            it.span,
                            format!("`{}` needs `(disturbance -> output)`", name.node),
                        )
                        .with_help(format!("e.g. `objective {}(d -> z) minimize;`", name.node)),
                    );
                    None
                }
            }
        };
        let initial = |this: &mut Self| -> Option<InitialSet> {
            let Some(f) = for_ else {
                this.err(
                    Diagnostic::error(it.span, format!("`{}` needs an initial state", name.node))
                        .with_help("add `for x0 = [...]` or `for x0 in ellipsoid(R)`"),
                );
                return None;
            };
            if f.name.node != "x0" {
                this.err(Diagnostic::error(f.name.span, "expected `x0`"));
                return None;
            }
            if f.is_in {
                match &f.value.kind {
                    ExprKind::Call(c, args) if c.node == "ellipsoid" && args.len() == 1 => {
                        let r = this.eval_const(&args[0].value)?;
                        if r.nrows() != n || r.ncols() != n {
                            this.err(Diagnostic::error(
                                args[0].value.span,
                                format!("ellipsoid matrix must be {n}x{n}"),
                            ));
                            return None;
                        }
                        if r.clone().cholesky().is_none()
                            || (&r - r.transpose()).norm() > 1e-12 * (1.0 + r.norm())
                        {
                            this.err(Diagnostic::error(
                                args[0].value.span,
                                "ellipsoid matrix must be symmetric positive definite",
                            ));
                            return None;
                        }
                        Some(InitialSet::Ellipsoid(r))
                    }
                    _ => {
                        this.err(
                            Diagnostic::error(f.value.span, "expected `ellipsoid(R)`")
                                .with_help("the set {x : x' R x <= 1}"),
                        );
                        None
                    }
                }
            } else {
                this.vector(&f.value, n, "x0").map(InitialSet::Point)
            }
        };
        let param = |this: &mut Self, key: &str| -> Option<f64> {
            let a = with.iter().find(|a| a.name.node == key)?;
            this.positive(&a.value, key)
        };
        let allowed_with: &[&str] = if name.node == "linf" {
            &["xi", "phi", "paper"]
        } else {
            &[]
        };
        for a in with {
            if !allowed_with.contains(&a.name.node.as_str()) {
                self.err(
                    Diagnostic::error(
                        a.name.span,
                        format!(
                            "objective `{}` has no parameter `{}`",
                            name.node, a.name.node
                        ),
                    )
                    .with_label(if allowed_with.is_empty() {
                        "this objective takes no `with` parameters".to_string()
                    } else {
                        format!("parameters: {}", allowed_with.join(", "))
                    }),
                );
                return None;
            }
        }
        let expect_signals = |this: &mut Self, k: usize| -> bool {
            if signals.len() > k {
                this.err(Diagnostic::error(
                    it.span,
                    format!(
                        "objective `{}` takes {} signal{}",
                        name.node,
                        k,
                        if k == 1 { "" } else { "s" }
                    ),
                ));
                false
            } else {
                true
            }
        };
        match name.node.as_str() {
            "stability" => {
                if goal.is_some() || for_.is_some() || !expect_signals(self, 0) {
                    self.err(Diagnostic::error(
                        it.span,
                        "`objective stability;` takes no goal",
                    ));
                    return None;
                }
                Some(Objective::Stability)
            }
            "decay_rate" => {
                if !expect_signals(self, 0) {
                    return None;
                }
                target(self, "maximize", ">=").map(Objective::DecayRate)
            }
            "hinf" => {
                let (from, to) = pair(self)?;
                Some(Objective::Hinf {
                    from,
                    to,
                    target: target(self, "minimize", "<=")?,
                })
            }
            "linf" => {
                let (from, to) = pair(self)?;
                let t = target(self, "minimize", "<=")?;
                self.linf_paper = param(self, "paper");
                Some(Objective::Linf {
                    from,
                    to,
                    target: t,
                    xi: param(self, "xi"),
                    phi: param(self, "phi"),
                })
            }
            "input_norm" => {
                if let Some(s) = signals.first() {
                    if !self.inputs.iter().any(|i| i.name == s.node) {
                        self.err(Diagnostic::error(
                            s.span,
                            format!("`{}` is not an input", s.node),
                        ));
                        return None;
                    }
                }
                let t = target(self, "minimize", "<=")?;
                Some(Objective::InputNorm {
                    target: t,
                    initial: initial(self)?,
                })
            }
            "output_norm" => {
                let Some(s) = signals.first() else {
                    self.err(Diagnostic::error(
                        it.span,
                        "`output_norm` needs an output: `output_norm(z) <= ...`",
                    ));
                    return None;
                };
                let o = output(self, s)?;
                let t = target(self, "minimize", "<=")?;
                Some(Objective::OutputNorm {
                    output: o,
                    target: t,
                    initial: initial(self)?,
                })
            }
            "saturation" => {
                match goal {
                    Some(Goal::Word(w)) if w.node == "region" => {}
                    _ => {
                        self.err(Diagnostic::error(
                            it.span,
                            "write `objective saturation region;`",
                        ));
                        return None;
                    }
                }
                let contain = match for_ {
                    Some(_) => Some(initial(self)?),
                    None => None,
                };
                Some(Objective::SaturationRegion { contain })
            }
            other => {
                self.err(unknown_choice(
                    name.span,
                    "objective",
                    "objectives",
                    other,
                    &kinds,
                ));
                None
            }
        }
    }

    fn named(
        &mut self,
        args: &[NamedArg],
        allowed: &[&str],
        what: &str,
    ) -> Option<HashMap<String, f64>> {
        let mut out = HashMap::new();
        for a in args {
            if !allowed.contains(&a.name.node.as_str()) {
                self.err(
                    Diagnostic::error(
                        a.name.span,
                        format!("{what} has no parameter `{}`", a.name.node),
                    )
                    .with_label(if allowed.is_empty() {
                        "no parameters".to_string()
                    } else {
                        format!("parameters: {}", allowed.join(", "))
                    }),
                );
                return None;
            }
            out.insert(a.name.node.clone(), self.scalar(&a.value, &a.name.node)?);
        }
        Some(out)
    }

    fn relaxation(&mut self, name: &Ident, args: &[NamedArg], span: Span) -> Option<Relaxation> {
        let kinds = ["basic", "tanaka", "tuan", "membership_mismatch"];
        match name.node.as_str() {
            "basic" | "tuan" => {
                self.named(args, &[], &format!("relaxation `{}`", name.node))?;
                Some(if name.node == "basic" {
                    Relaxation::Basic
                } else {
                    Relaxation::Tuan
                })
            }
            "tanaka" => {
                let p = self.named(args, &["s"], "relaxation `tanaka`")?;
                let Some(s) = p.get("s").copied() else {
                    self.err(
                        Diagnostic::error(
                            span,
                            "`tanaka` needs `s`, the most rules that fire at once",
                        )
                        .with_help("write `relaxation tanaka(s = 4);`"),
                    );
                    return None;
                };
                if s.fract() != 0.0 || s < 1.0 {
                    self.err(Diagnostic::error(
                        span,
                        format!("`s` must be a whole number >= 1, found {s}"),
                    ));
                    return None;
                }
                Some(Relaxation::Tanaka { s: s as usize })
            }
            "membership_mismatch" => {
                let p = self.named(args, &["kappa"], "relaxation `membership_mismatch`")?;
                let kappa = p.get("kappa").copied().unwrap_or(0.0);
                if !(0.0..1.0).contains(&kappa) {
                    self.err(Diagnostic::error(
                        span,
                        format!("`kappa` must be in [0, 1), found {kappa}"),
                    ));
                    return None;
                }
                Some(Relaxation::MembershipMismatch { kappa })
            }
            other => {
                self.err(unknown_choice(
                    name.span,
                    "relaxation",
                    "relaxations",
                    other,
                    &kinds,
                ));
                None
            }
        }
    }

    fn range_setting(&mut self, s: &Setting) -> Option<(f64, f64, Option<f64>)> {
        match &s.value {
            Value::Range(lo, hi, step) => {
                let l = self.scalar(lo, "a range bound")?;
                let h = self.scalar(hi, "a range bound")?;
                if l >= h || l.is_nan() || h.is_nan() || l < 0.0 {
                    self.err(Diagnostic::error(
                        s.span,
                        format!("`{}` needs 0 <= lo < hi, found {l} .. {h}", s.key.node),
                    ));
                    return None;
                }
                let st = match step {
                    Some(e) => Some(self.positive(e, "the step")?),
                    None => None,
                };
                Some((l, h, st))
            }
            Value::Expr(e) => {
                self.err(Diagnostic::error(
                    e.span,
                    format!("`{}` needs a range `lo .. hi`", s.key.node),
                ));
                None
            }
        }
    }

    fn setting_scalar(&mut self, s: &Setting) -> Option<f64> {
        match &s.value {
            Value::Expr(e) => self.scalar(e, &format!("`{}`", s.key.node)),
            Value::Range(..) => {
                self.err(Diagnostic::error(
                    s.span,
                    format!("`{}` needs a single value, not a range", s.key.node),
                ));
                None
            }
        }
    }

    fn trigger(&mut self, kind: &Ident, settings: &[Setting], n: usize) -> Option<Trigger> {
        let allowed: &[&str] = match kind.node.as_str() {
            "continuous" => &[],
            "periodic" => &["every"],
            "aperiodic" => &["sampling", "threshold", "weight"],
            "mixed" => &["sampling", "beta", "rho"],
            other => {
                let kinds = ["continuous", "periodic", "aperiodic", "mixed"];
                self.err(unknown_choice(
                    kind.span, "trigger", "triggers", other, &kinds,
                ));
                return None;
            }
        };
        let mut ok = true;
        let mut get: HashMap<&str, &Setting> = HashMap::new();
        for s in settings {
            if !allowed.contains(&s.key.node.as_str()) {
                self.err(
                    Diagnostic::error(
                        s.key.span,
                        format!("trigger `{}` has no setting `{}`", kind.node, s.key.node),
                    )
                    .with_label(if allowed.is_empty() {
                        "no settings".to_string()
                    } else {
                        format!("settings: {}", allowed.join(", "))
                    }),
                );
                ok = false;
            } else if get.insert(s.key.node.as_str(), s).is_some() {
                self.err(Diagnostic::error(
                    s.key.span,
                    format!("setting `{}` is given twice", s.key.node),
                ));
                ok = false;
            }
        }
        let require = |this: &mut Self, key: &str| -> Option<&Setting> {
            let s = get.get(key).copied();
            if s.is_none() && ok {
                this.err(Diagnostic::error(
                    kind.span,
                    format!("trigger `{}` needs `{key} = ...;`", kind.node),
                ));
            }
            s
        };
        let t = match kind.node.as_str() {
            "continuous" => Some(Trigger::Continuous),
            "periodic" => {
                let s = require(self, "every")?;
                let v = self.setting_scalar(s)?;
                if v <= 0.0 {
                    self.err(Diagnostic::error(s.span, "the period must be positive"));
                    return None;
                }
                Some(Trigger::Periodic { every: v })
            }
            "aperiodic" => {
                let s = require(self, "sampling")?;
                let (lo, hi, _) = self.range_setting(s)?;
                if lo <= 0.0 {
                    self.err(Diagnostic::error(s.span, "h_min must be positive"));
                    return None;
                }
                let threshold = match get.get("threshold") {
                    Some(s) => {
                        if s.qualifier.as_ref().is_some_and(|q| q.node != "nu") {
                            self.err(Diagnostic::error(s.span, "write `threshold nu = value;`"));
                            return None;
                        }
                        let nu = self.setting_scalar(s)?;
                        if nu < 0.0 {
                            self.err(Diagnostic::error(
                                s.span,
                                "the threshold nu must be non-negative",
                            ));
                            return None;
                        }
                        let mut adaptive = None;
                        let mut max = None;
                        for m in &s.modifiers {
                            if m.name.node != "adaptive" {
                                self.err(
                                    Diagnostic::error(
                                        m.name.span,
                                        format!("unknown threshold modifier `{}`", m.name.node),
                                    )
                                    .with_help("write `adaptive(mu1 = .., mu2 = .., mu3 = ..)` or `adaptive(mu1 = .., mu2 = .., mu3 = .., max = ..)`"),
                                );
                                return None;
                            }
                            let p =
                                self.named(&m.args, &["mu1", "mu2", "mu3", "max"], "`adaptive`")?;
                            if let Some(&top) = p.get("max") {
                                if top < nu {
                                    self.err(
                                        Diagnostic::error(
                                            m.name.span,
                                            format!("the adaptive ceiling max = {top} is below the threshold nu = {nu}"),
                                        )
                                        .with_help("the law keeps nu(t_k) in [nu, max]: give max >= nu"),
                                    );
                                    return None;
                                }
                                max = Some(top);
                            }
                            match (p.get("mu1"), p.get("mu2"), p.get("mu3")) {
                                (Some(a), Some(b), Some(c)) => adaptive = Some((*a, *b, *c)),
                                _ => {
                                    self.err(Diagnostic::error(
                                        m.name.span,
                                        "`adaptive` needs mu1, mu2 and mu3",
                                    ));
                                    return None;
                                }
                            }
                        }
                        Some(Threshold { nu, adaptive, max })
                    }
                    None => None,
                };
                let weight =
                    match get.get("weight") {
                        None => Weight::Synthesize,
                        Some(s) => match &s.value {
                            Value::Expr(Expr {
                                kind: ExprKind::Name(w),
                                ..
                            }) if w == "synthesize" => Weight::Synthesize,
                            Value::Expr(e) => {
                                let w = self.eval_const(e)?;
                                if w.nrows() != n || w.ncols() != n {
                                    self.err(
                                        Diagnostic::error(
                                            e.span,
                                            format!("the trigger weight must be {n}x{n}"),
                                        )
                                        .with_label(format!("this is {}x{}", w.nrows(), w.ncols())),
                                    );
                                    return None;
                                }
                                Weight::Given(w)
                            }
                            Value::Range(..) => {
                                self.err(Diagnostic::error(
                                    s.span,
                                    "the weight is a matrix or `synthesize`",
                                ));
                                return None;
                            }
                        },
                    };
                Some(Trigger::Aperiodic {
                    sampling: (lo, hi),
                    threshold,
                    weight,
                })
            }
            _ => {
                let s = require(self, "sampling")?;
                let (lo, hi, _) = self.range_setting(s)?;
                let beta = require(self, "beta").and_then(|s| self.setting_scalar(s));
                let rho = require(self, "rho").and_then(|s| self.setting_scalar(s));
                Some(Trigger::Mixed {
                    sampling: (lo, hi),
                    beta: beta?,
                    rho: rho?,
                })
            }
        };
        if ok {
            t
        } else {
            None
        }
    }

    fn simulate(&mut self, stmts: &[SimStmt], span: Span, n: usize) -> Option<Simulation> {
        let mut x0 = None;
        let mut time = None;
        let mut signals = Vec::new();
        let mut seed = 0u64;
        let mut integrator = Integrator::Rk4;
        let mut dynamics = None;
        let mut ok = true;
        let mut seen: Vec<String> = Vec::new();
        for st in stmts {
            match st {
                SimStmt::Setting(s) => {
                    if seen.contains(&s.key.node) {
                        self.err(Diagnostic::error(
                            s.key.span,
                            format!("`{}` is given twice", s.key.node),
                        ));
                        ok = false;
                        continue;
                    }
                    seen.push(s.key.node.clone());
                    match s.key.node.as_str() {
                        "x0" => match &s.value {
                            Value::Expr(e) => x0 = self.vector(e, n, "x0"),
                            Value::Range(..) => {
                                self.err(Diagnostic::error(s.span, "x0 is a vector, not a range"))
                            }
                        },
                        "time" => {
                            if let Some((a, b, st)) = self.range_setting(s) {
                                let h = st.unwrap_or((b - a) / 1000.0);
                                if (b - a) / h > 1e9 {
                                    self.err(
                                        Diagnostic::error(
                                            s.span,
                                            "too many time steps (more than 1e9)",
                                        )
                                        .with_help("increase the step"),
                                    );
                                    ok = false;
                                } else {
                                    time = Some((a, b, h));
                                }
                            } else {
                                ok = false;
                            }
                        }
                        "seed" => match self.setting_scalar(s) {
                            Some(v) if v >= 0.0 && v.fract() == 0.0 && v < 1.8e19 => {
                                seed = v as u64
                            }
                            Some(_) => self.err(Diagnostic::error(
                                s.span,
                                "the seed is a non-negative whole number",
                            )),
                            None => ok = false,
                        },
                        "integrator" => match &s.value {
                            Value::Expr(Expr {
                                kind: ExprKind::Name(w),
                                ..
                            }) if w == "rk4" => integrator = Integrator::Rk4,
                            Value::Expr(Expr {
                                kind: ExprKind::Name(w),
                                ..
                            }) if w == "dopri5" => integrator = Integrator::Dopri5,
                            _ => self.err(
                                Diagnostic::error(s.span, "unknown integrator")
                                    .with_help("use `rk4` or `dopri5`"),
                            ),
                        },
                        other => {
                            let keys = ["x0", "time", "seed", "integrator"];
                            self.err(unknown_choice(
                                s.key.span,
                                "simulate setting",
                                "settings",
                                other,
                                &keys,
                            ));
                            ok = false;
                        }
                    }
                }
                SimStmt::Signal { name, param, value } => {
                    let Some(di) = self.disturbances.iter().position(|d| d.name == name.node)
                    else {
                        self.err(
                            Diagnostic::error(
                                name.span,
                                format!("`{}` is not a disturbance", name.node),
                            )
                            .with_help("signals in `simulate` define disturbances: `d(t) = ...;`"),
                        );
                        ok = false;
                        continue;
                    };
                    if param.node != "t" {
                        self.err(Diagnostic::error(
                            param.span,
                            "the signal parameter must be `t`",
                        ));
                        ok = false;
                        continue;
                    }
                    let len = self.disturbances[di].len;
                    let mut env = self.const_env();
                    env.unavailable.retain(|(n, _)| n != "t");
                    env.locals.push(("t".into(), Mat::zeros(1, 1)));
                    match env.eval(value) {
                        Ok(v) if v.nrows() == len && v.ncols() == 1 => {
                            signals.push((di, value.clone()))
                        }
                        Ok(v) => {
                            self.err(Diagnostic::error(
                                value.span,
                                format!(
                                    "disturbance `{}` has {len} components but this is {}x{}",
                                    name.node,
                                    v.nrows(),
                                    v.ncols()
                                ),
                            ));
                            ok = false;
                        }
                        Err(d) => {
                            self.err(d);
                            ok = false;
                        }
                    }
                }
                SimStmt::Dynamics(body, dspan) => {
                    dynamics = self.dynamics(body, *dspan);
                    if dynamics.is_none() {
                        ok = false;
                    }
                }
            }
        }
        let Some(x0) = x0 else {
            if ok && !seen.iter().any(|k| k == "x0") {
                self.err(
                    Diagnostic::error(span, "`simulate` needs an initial state")
                        .with_help("add `x0 = [...];`"),
                );
            }
            return None;
        };
        let Some(time) = time else {
            if ok && !seen.iter().any(|k| k == "time") {
                self.err(
                    Diagnostic::error(span, "`simulate` needs a time span")
                        .with_help("add `time = 0 .. 10 step 0.01;`"),
                );
            }
            return None;
        };
        ok.then_some(Simulation {
            x0,
            time,
            signals,
            seed,
            integrator,
            dynamics,
            span,
        })
    }

    fn dynamics(&mut self, body: &[Spanned<DynStmt>], span: Span) -> Option<Dynamics> {
        let mut extra: Vec<Signal> = Vec::new();
        let mut consts: Vec<(String, Mat)> = Vec::new();
        let mut ders: Vec<(String, Expr, Span)> = Vec::new();
        let mut ok = true;
        for st in body {
            match &st.node {
                DynStmt::State(vars) => {
                    let mut off = extra.iter().map(|s| s.len).sum();
                    for v in vars {
                        let len = v.len.as_ref().map_or(1.0, |l| l.node);
                        if len.fract() != 0.0 || !(1.0..=1000.0).contains(&len) {
                            self.err(Diagnostic::error(v.name.span, "invalid size"));
                            ok = false;
                            continue;
                        }
                        if self.names.contains_key(&v.name.node)
                            || extra.iter().any(|s| s.name == v.name.node)
                        {
                            self.err(Diagnostic::error(
                                v.name.span,
                                format!("`{}` is already declared", v.name.node),
                            ));
                            ok = false;
                            continue;
                        }
                        extra.push(Signal {
                            name: v.name.node.clone(),
                            len: len as usize,
                            is_vector: v.len.is_some(),
                            offset: off,
                            span: v.name.span,
                        });
                        off += len as usize;
                    }
                }
                DynStmt::Const(name, e) => match self.eval_const(e) {
                    Some(v) => consts.push((name.node.clone(), v)),
                    None => ok = false,
                },
                DynStmt::Derivative(name, e) => {
                    if let Some(prev) = ders.iter().find(|d| d.0 == name.node) {
                        let d =
                            Diagnostic::error(st.span, format!("`{}'` is given twice", name.node))
                                .with_secondary(prev.2, "first here");
                        self.err(d);
                        ok = false;
                        continue;
                    }
                    ders.push((name.node.clone(), e.clone(), st.span));
                }
            }
        }
        // Shape-check every derivative against its state.
        let mut locals: Vec<(String, Mat)> = consts.clone();
        for s in &extra {
            locals.push((s.name.clone(), Mat::zeros(s.len, 1)));
        }
        for s in &self.inputs {
            locals.push((s.name.clone(), Mat::zeros(s.len, 1)));
        }
        for s in &self.disturbances {
            locals.push((s.name.clone(), Mat::zeros(s.len, 1)));
        }
        locals.push(("t".into(), Mat::zeros(1, 1)));
        let all: Vec<Signal> = self
            .states
            .iter()
            .cloned()
            .chain(extra.iter().cloned())
            .collect();
        let mut out = Vec::new();
        for (name, e, dspan) in &ders {
            let Some(sig) = all.iter().find(|s| s.name == *name) else {
                let mut d = Diagnostic::error(*dspan, format!("`{name}` is not a state"))
                    .with_label("a derivative needs a state");
                if let Some(c) = suggest(name, all.iter().map(|s| s.name.as_str())) {
                    d = d.with_help(format!("did you mean `{c}`?"));
                } else {
                    d = d.with_help(format!("declare it in the block: `state {name};`"));
                }
                self.err(d);
                ok = false;
                continue;
            };
            let env = self.state_env(Mode::Shapes, &locals, &[Kind::Input, Kind::Disturbance]);
            match env.eval(e) {
                Ok(v) if v.nrows() == sig.len && v.ncols() == 1 => {
                    out.push((name.clone(), e.clone()))
                }
                Ok(v) => {
                    self.err(Diagnostic::error(
                        e.span,
                        format!(
                            "`{name}'` must have {} component{}, but this is {}x{}",
                            sig.len,
                            if sig.len == 1 { "" } else { "s" },
                            v.nrows(),
                            v.ncols()
                        ),
                    ));
                    ok = false;
                }
                Err(d) => {
                    self.err(d);
                    ok = false;
                }
            }
        }
        for s in &all {
            if !ders.iter().any(|d| d.0 == s.name) {
                self.err(
                    Diagnostic::error(
                        span,
                        format!("`dynamics` gives no derivative for state `{}`", s.name),
                    )
                    .with_help(format!("add `{}' = ...;`", s.name)),
                );
                ok = false;
            }
        }
        // Order derivatives as the states.
        out.sort_by_key(|(n, _)| all.iter().position(|s| s.name == *n));
        ok.then_some(Dynamics {
            extra_states: extra,
            consts,
            derivatives: out,
            span,
        })
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

fn is_c_identifier(s: &str) -> bool {
    let mut ch = s.chars();
    matches!(ch.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
        && ch.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// Calls `f(name, span, is_call)` for every name and call in `e`.
fn walk_names(e: &Expr, f: &mut impl FnMut(&str, Span, bool)) {
    match &e.kind {
        ExprKind::Number(_) => {}
        ExprKind::Name(n) => f(n, e.span, false),
        ExprKind::Matrix(rows) => rows.iter().flatten().for_each(|x| walk_names(x, f)),
        ExprKind::Neg(a) | ExprKind::Transpose(a) => walk_names(a, f),
        ExprKind::Binary(_, a, b) => {
            walk_names(a, f);
            walk_names(b, f);
        }
        ExprKind::Index(a, idx) => {
            walk_names(a, f);
            for i in idx {
                match i {
                    IndexArg::Full => {}
                    IndexArg::One(x) => walk_names(x, f),
                    IndexArg::Range(x, y) => {
                        walk_names(x, f);
                        walk_names(y, f);
                    }
                }
            }
        }
        ExprKind::Call(name, args) => {
            f(&name.node, name.span, true);
            args.iter().for_each(|a| walk_names(&a.value, f));
        }
    }
}
