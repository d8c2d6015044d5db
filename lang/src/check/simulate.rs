//! The `simulate` scenario: initial state, time span, seed, integrator,
//! disturbance signals of `t`, the truth `dynamics` (see [`super::dynamics`]),
//! the `monte_carlo` uncertainty and the `sweep` scenarios (see [`super::sweep`]).

use super::{unknown_choice, Checker, Draft};
use crate::ast::{Expr, ExprKind, Ident, Item, McStmt, Setting, SimStmt, SweepStmt, Value};
use crate::diag::Diagnostic;
use crate::eval::Mat;
use crate::modes::Modes;
use crate::span::{Span, Spanned};
use crate::spec::{Dynamics, Integrator, Simulation};

/// Settings of `simulate`.
const SIM_KEYS: [&str; 7] = [
    "x0",
    "xhat0",
    "time",
    "seed",
    "integrator",
    "mode0",
    "mode_seed",
];

/// What the statements of a `simulate` block set so far.
struct Scenario<'a> {
    x0: Option<Vec<f64>>,
    xhat0: Option<Spanned<Vec<f64>>>,
    time: Option<(f64, f64, f64)>,
    signals: Vec<(usize, Expr)>,
    seed: u64,
    mode0: Option<Spanned<String>>,
    mode_seed: Option<u64>,
    integrator: Integrator,
    dynamics: Option<Dynamics>,
    /// The `monte_carlo` block (checked once the rest of the scenario is known).
    monte_carlo: Option<(&'a [McStmt], Span)>,
    /// The `sweep` block (checked once the rest of the scenario is known).
    sweep: Option<(&'a [SweepStmt], Span)>,
    /// False once a statement failed (missing settings are then not reported).
    ok: bool,
    /// Setting keys given so far.
    seen: Vec<String>,
}

impl Checker<'_> {
    /// The `simulate` item (given once).
    pub(super) fn simulate_item(
        &mut self,
        it: &Item,
        stmts: &[SimStmt],
        n: usize,
        draft: &mut Draft,
    ) {
        if self.singleton(&mut draft.simulate_seen, it.span, "the `simulate` block") {
            draft.simulate = self.simulate(stmts, it.span, n);
        }
    }

    /// The scenario; it needs `x0` and `time`.
    fn simulate(&mut self, stmts: &[SimStmt], span: Span, n: usize) -> Option<Simulation> {
        let mut sc = Scenario {
            x0: None,
            xhat0: None,
            time: None,
            signals: Vec::new(),
            seed: 0,
            mode0: None,
            mode_seed: None,
            integrator: Integrator::Rk4,
            dynamics: None,
            monte_carlo: None,
            sweep: None,
            ok: true,
            seen: Vec::new(),
        };
        for st in stmts {
            match st {
                SimStmt::Setting(s) => self.sim_setting(s, n, &mut sc),
                SimStmt::Signal { name, param, value } => match self.sim_signal(name, param, value)
                {
                    Some(signal) => sc.signals.push(signal),
                    None => sc.ok = false,
                },
                SimStmt::MonteCarlo(body, mspan) => {
                    if sc.monte_carlo.is_some() {
                        self.err(Diagnostic::error(*mspan, "`monte_carlo` is given twice"));
                        sc.ok = false;
                    }
                    sc.monte_carlo = Some((body, *mspan));
                }
                SimStmt::Sweep(body, sspan) => {
                    if sc.sweep.is_some() {
                        self.err(Diagnostic::error(*sspan, "`sweep` is given twice"));
                        sc.ok = false;
                    }
                    sc.sweep = Some((body, *sspan));
                }
                SimStmt::Dynamics(body, dspan) => {
                    sc.dynamics = self.dynamics(body, *dspan);
                    if sc.dynamics.is_none() {
                        sc.ok = false;
                    }
                }
            }
        }
        let Some(x0) = sc.x0 else {
            if sc.ok && !sc.seen.iter().any(|k| k == "x0") {
                self.err(
                    Diagnostic::error(span, "`simulate` needs an initial state")
                        .with_help("add `x0 = [...];`"),
                );
            }
            return None;
        };
        let Some(time) = sc.time else {
            if sc.ok && !sc.seen.iter().any(|k| k == "time") {
                self.err(
                    Diagnostic::error(span, "`simulate` needs a time span")
                        .with_help("add `time = 0 .. 10 step 0.01;`"),
                );
            }
            return None;
        };
        let monte_carlo = match sc.monte_carlo {
            Some((body, mspan)) => {
                let mc = self.monte_carlo(body, mspan, n, sc.dynamics.as_ref(), time, &sc.signals);
                if mc.is_none() {
                    sc.ok = false;
                }
                mc
            }
            None => None,
        };
        let sweep = match sc.sweep {
            Some((body, sspan)) => {
                let sw = self.sweep(body, sspan, n, sc.dynamics.as_ref(), time);
                sc.ok &= sw.is_some();
                sw
            }
            None => None,
        };
        sc.ok.then_some(Simulation {
            monte_carlo,
            sweep,
            x0,
            xhat0: sc.xhat0,
            time,
            signals: sc.signals,
            seed: sc.seed,
            mode0: sc.mode0,
            mode_seed: sc.mode_seed,
            integrator: sc.integrator,
            dynamics: sc.dynamics,
            span,
        })
    }

    /// One setting: `x0`, `xhat0`, `time`, `seed`, `integrator`, `mode0` or
    /// `mode_seed`, each given once.
    fn sim_setting(&mut self, s: &Setting, n: usize, sc: &mut Scenario<'_>) {
        if sc.seen.contains(&s.key.node) {
            self.err(Diagnostic::error(
                s.key.span,
                format!("`{}` is given twice", s.key.node),
            ));
            sc.ok = false;
            return;
        }
        sc.seen.push(s.key.node.clone());
        match s.key.node.as_str() {
            "x0" => match &s.value {
                Value::Expr(e) => sc.x0 = self.vector(e, n, "x0"),
                Value::Range(..) => {
                    self.err(Diagnostic::error(s.span, "x0 is a vector, not a range"))
                }
            },
            "xhat0" => match &s.value {
                Value::Expr(e) => match self.vector(e, n, "xhat0") {
                    Some(v) => {
                        sc.xhat0 = Some(Spanned {
                            node: v,
                            span: s.span,
                        })
                    }
                    None => sc.ok = false,
                },
                Value::Range(..) => {
                    self.err(Diagnostic::error(s.span, "xhat0 is a vector, not a range"));
                    sc.ok = false;
                }
            },
            "time" => {
                if let Some((a, b, st)) = self.range_setting(s) {
                    let h = st.unwrap_or((b - a) / 1000.0);
                    if (b - a) / h > 1e9 {
                        self.err(
                            Diagnostic::error(s.span, "too many time steps (more than 1e9)")
                                .with_help("increase the step"),
                        );
                        sc.ok = false;
                    } else {
                        sc.time = Some((a, b, h));
                    }
                } else {
                    sc.ok = false;
                }
            }
            "seed" | "mode_seed" => match self.setting_scalar(s) {
                Some(v) if v >= 0.0 && v.fract() == 0.0 && v < 1.8e19 => {
                    if s.key.node == "seed" {
                        sc.seed = v as u64;
                    } else {
                        sc.mode_seed = Some(v as u64);
                    }
                }
                Some(_) => self.err(Diagnostic::error(
                    s.span,
                    format!("`{}` is a non-negative whole number", s.key.node),
                )),
                None => sc.ok = false,
            },
            "mode0" => match &s.value {
                Value::Expr(
                    e @ Expr {
                        kind: ExprKind::Name(w),
                        ..
                    },
                ) => {
                    sc.mode0 = Some(Spanned {
                        node: w.clone(),
                        span: e.span,
                    })
                }
                _ => {
                    self.err(
                        Diagnostic::error(s.span, "`mode0` names a mode")
                            .with_help("e.g. `mode0 = normal;` with `mode normal { }` in `modes`"),
                    );
                    sc.ok = false;
                }
            },
            "integrator" => match &s.value {
                Value::Expr(Expr {
                    kind: ExprKind::Name(w),
                    ..
                }) if w == "rk4" => sc.integrator = Integrator::Rk4,
                Value::Expr(Expr {
                    kind: ExprKind::Name(w),
                    ..
                }) if w == "dopri5" => sc.integrator = Integrator::Dopri5,
                _ => self.err(
                    Diagnostic::error(s.span, "unknown integrator")
                        .with_help("use `rk4` or `dopri5`"),
                ),
            },
            other => {
                self.err(unknown_choice(
                    s.key.span,
                    "simulate setting",
                    "settings",
                    other,
                    &SIM_KEYS,
                ));
                sc.ok = false;
            }
        }
    }

    /// `xhat0` (the observer's initial estimate) against the controller
    /// kind: only an observer-based controller has an estimate.
    pub(super) fn simulate_estimate(&mut self, spec: &crate::spec::Spec) {
        let Some(at) = spec.simulate.as_ref().and_then(|s| s.xhat0.as_ref()) else {
            return;
        };
        let kind = spec.control.kind;
        if kind != crate::spec::ControlKind::ObserverBased {
            self.err(
                Diagnostic::error(
                    at.span,
                    format!(
                        "`xhat0` is the initial estimate of an observer, but this controller is `control {}`",
                        kind.keyword()
                    ),
                )
                .with_label("no estimate to start")
                .with_help("remove `xhat0`, or declare `control observer_based;` (with `measure y = ..;`)"),
            );
        }
    }

    /// The mode settings of `simulate` against the `modes` block: `mode0`
    /// names one of its modes, and neither setting is given without modes.
    pub(super) fn simulate_modes(&mut self, modes: Option<&Modes>, sim: Option<&Simulation>) {
        let Some(sim) = sim else { return };
        match modes {
            None => {
                if let Some(m0) = &sim.mode0 {
                    self.err(
                        Diagnostic::error(m0.span, "`mode0` needs a `modes` block")
                            .with_help("declare the modes: `modes { mode normal { } ... }`"),
                    );
                }
            }
            Some(modes) => {
                if let Some(m0) = &sim.mode0 {
                    let names: Vec<&str> = modes.modes.iter().map(|m| m.name.as_str()).collect();
                    if !names.contains(&m0.node.as_str()) {
                        self.err(unknown_choice(m0.span, "mode", "modes", &m0.node, &names));
                    }
                }
            }
        }
    }

    /// `d(t) = expr;`: a disturbance of the right length as a function of time.
    fn sim_signal(&mut self, name: &Ident, param: &Ident, value: &Expr) -> Option<(usize, Expr)> {
        let Some(di) = self.disturbances.iter().position(|d| d.name == name.node) else {
            self.err(
                Diagnostic::error(name.span, format!("`{}` is not a disturbance", name.node))
                    .with_help("signals in `simulate` define disturbances: `d(t) = ...;`"),
            );
            return None;
        };
        if param.node != "t" {
            self.err(Diagnostic::error(
                param.span,
                "the signal parameter must be `t`",
            ));
            return None;
        }
        let len = self.disturbances[di].len;
        let mut env = self.const_env();
        env.unavailable.retain(|(n, _)| n != "t");
        env.locals.push(("t".into(), Mat::zeros(1, 1)));
        match self.evaluate(&env, value) {
            Ok(v) if v.nrows() == len && v.ncols() == 1 => Some((di, value.clone())),
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
                None
            }
            Err(d) => {
                self.err(d);
                None
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::check::testing::*;
    use crate::spec::Integrator;

    #[test]
    fn a_scenario_with_its_settings_and_signals() {
        let spec = spec_with(
            "disturbance d; D = 1;\nsimulate { x0 = 0.5; time = 0 .. 2 step 0.1; seed = 3; integrator = dopri5; d(t) = sin(t); }",
        );
        let s = spec.simulate.expect("a scenario"); // ok: unit test
        assert_eq!(s.x0, vec![0.5]);
        assert_eq!(s.time, (0.0, 2.0, 0.1));
        assert_eq!((s.seed, s.integrator), (3, Integrator::Dopri5));
        assert_eq!(s.signals.len(), 1);
    }

    #[test]
    fn required_and_unknown_settings() {
        let (m, at) = only_error("simulate { time = 0 .. 1; }");
        assert_eq!(m, "`simulate` needs an initial state");
        assert_eq!(at, "simulate { time = 0 .. 1; }");
        let (m, at) = only_error("simulate { x0 = 0; time = 0 .. 1; steps = 3; }");
        assert_eq!(m, "unknown simulate setting `steps`");
        assert_eq!(at, "steps");
        let (m, _) = only_error("simulate { x0 = 0; x0 = 1; time = 0 .. 1; }");
        assert_eq!(m, "`x0` is given twice");
    }

    /// An observer-based spec (x1 measured) with the scenario `sim`.
    fn observer_spec(sim: &str) -> String {
        format!(
            "tsf 1; controller c; state x1, x2; input u;\n\
             A = [0, 1; 1, 0]; B = [0; 1];\n\
             premise x1 range -1 .. 1 {{ n = tri(-1, -1, 1); p = tri(-1, 1, 1); }}\n\
             rule R1: x1 is n => at(x1 = -1);\nrule R2: x1 is p => at(x1 = 1);\n\
             objective decay_rate >= 0.5;\nmeasure y = x1;\ncontrol observer_based;\n{sim}\n"
        )
    }

    #[test]
    fn xhat0_is_an_estimate_of_n_components_for_observers_only() {
        let spec = valid(&observer_spec(
            "simulate { x0 = [0.5, 0]; xhat0 = [0, 0.8]; time = 0 .. 1; }",
        ));
        let s = spec.simulate.expect("a scenario"); // ok: unit test
        assert_eq!(s.xhat0.map(|x| x.node), Some(vec![0.0, 0.8]));
        let (m, at) = only_error_of(&observer_spec(
            "simulate { x0 = [0.5, 0]; xhat0 = [0, 0.8, 1]; time = 0 .. 1; }",
        ));
        assert_eq!(m, "xhat0 must have 2 components");
        assert_eq!(at, "[0, 0.8, 1]");
        let (m, _) = only_error_of(&observer_spec(
            "simulate { x0 = [0.5, 0]; xhat0 = 0 .. 1; time = 0 .. 1; }",
        ));
        assert_eq!(m, "xhat0 is a vector, not a range");
        let (m, at) = only_error("simulate { x0 = 0.5; xhat0 = 0.1; time = 0 .. 1; }");
        assert_eq!(
            m,
            "`xhat0` is the initial estimate of an observer, but this controller is `control state_feedback`"
        );
        assert_eq!(at, "xhat0 = 0.1;");
    }

    #[test]
    fn mode_settings_name_a_mode_of_the_block() {
        let modes =
            "modes { mode ok { } mode weak { effectiveness = 0.5; } rates = [-1, 1; 2, -2]; }\n";
        let spec = spec_with(&format!(
            "{modes}simulate {{ x0 = 0; time = 0 .. 1; mode0 = weak; mode_seed = 7; }}"
        ));
        let s = spec.simulate.expect("a scenario"); // ok: unit test
        assert_eq!(s.mode0.map(|m| m.node), Some("weak".to_string()));
        assert_eq!(s.mode_seed, Some(7));
        let (m, at) = only_error(&format!(
            "{modes}simulate {{ x0 = 0; time = 0 .. 1; mode0 = wek; }}"
        ));
        assert_eq!(m, "unknown mode `wek`");
        assert_eq!(at, "wek");
        let (m, at) = only_error("simulate { x0 = 0; time = 0 .. 1; mode0 = ok; }");
        assert_eq!(m, "`mode0` needs a `modes` block");
        assert_eq!(at, "ok");
        let (m, _) = only_error(&format!(
            "{modes}simulate {{ x0 = 0; time = 0 .. 1; mode_seed = -1; }}"
        ));
        assert_eq!(m, "`mode_seed` is a non-negative whole number");
    }

    #[test]
    fn signals_define_disturbances_of_time() {
        let (m, at) = only_error("simulate { x0 = 0; time = 0 .. 1; e(t) = t; }");
        assert_eq!(m, "`e` is not a disturbance");
        assert_eq!(at, "e");
        let (m, at) =
            only_error("disturbance d; D = 1;\nsimulate { x0 = 0; time = 0 .. 1; d(t) = [t; t]; }");
        assert_eq!(m, "disturbance `d` has 1 components but this is 2x1");
        assert_eq!(at, "[t; t]");
    }
}
