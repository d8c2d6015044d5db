//! The `sweep { }` block of the scenario (`tsfc simulate --sweep`):
//! triggering laws whose fields written as lists `[a, b, ...]` expand to one
//! scenario per element (a cartesian product over several lists), each
//! expanded law checked by the checker of the `trigger` item; the
//! steady-state `window` and the norm `columns` of the comparison table.

use super::{unknown_choice, Checker, Draft};
use crate::ast::{Expr, ExprKind, Ident, Item, ItemKind, Setting, SweepStmt, Value};
use crate::diag::Diagnostic;
use crate::limits::MAX_SWEEP_SCENARIOS;
use crate::num::Num;
use crate::span::Span;
use crate::spec::{Dynamics, Sweep, SweepColumn, SweepScenario};

/// A `trigger` statement of the block with its list-valued fields.
struct Planned<'s> {
    kind: &'s Ident,
    settings: &'s [Setting],
    span: Span,
    /// Per setting, the elements of its list (None: not a list).
    lists: Vec<Option<&'s [Expr]>>,
}

impl Planned<'_> {
    /// How many scenarios the statement expands to (saturating).
    fn count(&self) -> usize {
        self.lists
            .iter()
            .flatten()
            .fold(1usize, |c, l| c.saturating_mul(l.len()))
    }
}

impl Checker<'_> {
    /// Errors reported so far (warnings not counted).
    fn error_count(&self) -> usize {
        self.diags.iter().filter(|d| d.is_error()).count()
    }

    /// The block; `n` controller states, the scenario's `dynamics` and
    /// `time` span are known.
    pub(super) fn sweep(
        &mut self,
        stmts: &[SweepStmt],
        span: Span,
        n: usize,
        dynamics: Option<&Dynamics>,
        time: (f64, f64, f64),
    ) -> Option<Sweep> {
        let mut ok = true;
        let mut planned = Vec::new();
        let mut window = None;
        let mut window_seen = false;
        let mut columns: Option<Vec<SweepColumn>> = None;
        for st in stmts {
            match st {
                SweepStmt::Trigger {
                    kind,
                    settings,
                    span,
                } => match self.sweep_lists(settings) {
                    Some(lists) => planned.push(Planned {
                        kind,
                        settings,
                        span: *span,
                        lists,
                    }),
                    None => ok = false,
                },
                SweepStmt::Columns(cols, cspan) => {
                    if columns.is_some() {
                        self.err(Diagnostic::error(*cspan, "`columns` is given twice"));
                        ok = false;
                        continue;
                    }
                    columns = self.sweep_columns(cols, n, dynamics);
                    ok &= columns.is_some();
                }
                SweepStmt::Setting(s) if s.key.node == "window" => {
                    if window_seen {
                        self.err(Diagnostic::error(s.key.span, "`window` is given twice"));
                        ok = false;
                        continue;
                    }
                    window_seen = true;
                    window = self.sweep_window(s, time);
                    ok &= window.is_some();
                }
                SweepStmt::Setting(s) => {
                    self.err(
                        unknown_choice(s.key.span, "sweep setting", "settings", &s.key.node, &["window"])
                            .with_help("a sweep holds `trigger` laws, `window = start .. end;` and `columns { name = state; }`"),
                    );
                    ok = false;
                }
            }
        }
        let total = planned
            .iter()
            .fold(0usize, |t, p| t.saturating_add(p.count()));
        if total > MAX_SWEEP_SCENARIOS {
            self.err(
                Diagnostic::error(
                    span,
                    format!(
                        "the sweep expands to {total} scenarios, more than {MAX_SWEEP_SCENARIOS}"
                    ),
                )
                .with_help(
                    "shorten the lists or split the sweep over several specs (docs/limits.md)",
                ),
            );
            return None;
        }
        let mut scenarios = Vec::new();
        for p in &planned {
            ok &= self.expand(p, n, &mut scenarios);
        }
        disambiguate(&mut scenarios);
        ok.then(|| Sweep {
            scenarios,
            window,
            columns: columns.unwrap_or_default(),
            span,
        })
    }

    /// Per setting, the elements of a list value `[a, b, ...]` (one row of
    /// numbers); an empty list or a non-numeric element is an error.
    fn sweep_lists<'s>(&mut self, settings: &'s [Setting]) -> Option<Vec<Option<&'s [Expr]>>> {
        let mut ok = true;
        let mut out = Vec::new();
        for s in settings {
            let Value::Expr(Expr {
                kind: ExprKind::Matrix(rows),
                span,
            }) = &s.value
            else {
                out.push(None);
                continue;
            };
            if rows.len() > 1 {
                out.push(None);
                continue;
            }
            let elems: &[Expr] = rows.first().map_or(&[], |r| r.as_slice());
            if elems.is_empty() {
                self.err(
                    Diagnostic::error(*span, format!("the list of `{}` is empty", s.key.node))
                        .with_help(format!(
                            "give at least one value: `{} = [a, b];`",
                            s.key.node
                        )),
                );
                ok = false;
            }
            for e in elems {
                ok &= self.sweep_number(e).is_some();
            }
            out.push(Some(elems));
        }
        ok.then_some(out)
    }

    /// A list element: a constant number.
    fn sweep_number(&mut self, e: &Expr) -> Option<f64> {
        if let ExprKind::Name(w) = &e.kind {
            if !self.consts.contains_key(w) {
                self.err(
                    Diagnostic::error(e.span, "a sweep list holds numbers")
                        .with_label(format!("`{w}` is not a constant"))
                        .with_help("write the values (or constants) to sweep: `[2, 3, 4.5]`; a law such as `synthesize` cannot be swept"),
                );
                return None;
            }
        }
        let v = self.eval_const(e)?;
        if v.nrows() == 1 && v.ncols() == 1 {
            return Some(v[(0, 0)]);
        }
        self.err(
            Diagnostic::error(e.span, "a sweep list holds numbers")
                .with_label(format!("this is {}x{}", v.nrows(), v.ncols()))
                .with_help("a matrix-valued field (a trigger weight) is swept through constants: `weight = U1;` in one law, `weight = U2;` in another"),
        );
        None
    }

    /// Expands one statement into `out`, each law checked by the `trigger`
    /// item's checker; stops at the first law that fails (its errors name the
    /// element).
    fn expand(&mut self, p: &Planned, n: usize, out: &mut Vec<SweepScenario>) -> bool {
        let sizes: Vec<usize> = p.lists.iter().flatten().map(|l| l.len()).collect();
        for k in 0..p.count() {
            // Mixed radix, the first list outermost.
            let mut pick = vec![0usize; sizes.len()];
            let mut rest = k;
            for (slot, &len) in pick.iter_mut().zip(&sizes).rev() {
                *slot = rest % len;
                rest /= len;
            }
            let mut picks = pick.into_iter();
            let mut settings = Vec::with_capacity(p.settings.len());
            let mut subs = Vec::new();
            let mut name = p.kind.node.clone();
            for (s, list) in p.settings.iter().zip(&p.lists) {
                let (Some(list), Some(i)) = (list, list.and_then(|_| picks.next())) else {
                    settings.push(s.clone());
                    continue;
                };
                let e = &list[i];
                if let Value::Expr(whole) = &s.value {
                    subs.push((whole.span, e.span));
                }
                let v = self.sweep_number(e).unwrap_or(f64::NAN);
                name.push_str(&format!(" {} = {}", s.key.node, Num(v)));
                settings.push(Setting {
                    value: Value::Expr(e.clone()),
                    ..s.clone()
                });
            }
            let item = Item {
                kind: ItemKind::Trigger(p.kind.clone(), settings.clone()),
                span: p.span,
            };
            let mut draft = Draft::default();
            let errors = self.error_count();
            self.trigger_item(&item, p.kind, &settings, n, &mut draft);
            // Warnings (beta >= 1, rho = 0) keep the scenario; errors drop it.
            let Some(t) = draft.trigger.filter(|_| self.error_count() == errors) else {
                return false;
            };
            self.sweep_on.push(draft.trigger_on.take());
            out.push(SweepScenario {
                name,
                trigger: t.node,
                trigger_synthesis: draft.trigger_synthesis,
                source: (p.span, subs),
            });
        }
        true
    }

    /// `columns { name = group; }`: `x`, a state or an extra state of `dynamics`.
    fn sweep_columns(
        &mut self,
        cols: &[(Ident, Ident)],
        n: usize,
        dynamics: Option<&Dynamics>,
    ) -> Option<Vec<SweepColumn>> {
        let mut ok = true;
        let mut out: Vec<SweepColumn> = Vec::new();
        let extra = dynamics.map_or(&[][..], |d| d.extra_states.as_slice());
        for (name, group) in cols {
            if out.iter().any(|c| c.name == name.node) {
                self.err(Diagnostic::error(
                    name.span,
                    format!("column `{}` is given twice", name.node),
                ));
                ok = false;
                continue;
            }
            let at = if group.node == "x" {
                Some((0, n))
            } else if let Some(s) = self.states.iter().find(|s| s.name == group.node) {
                Some((s.offset, s.len))
            } else {
                extra
                    .iter()
                    .find(|s| s.name == group.node)
                    .map(|s| (n + s.offset, s.len))
            };
            let Some(at) = at else {
                let mut names = vec!["x"];
                names.extend(self.states.iter().map(|s| s.name.as_str()));
                names.extend(extra.iter().map(|s| s.name.as_str()));
                self.err(
                    unknown_choice(group.span, "state group", "state groups", &group.node, &names)
                        .with_help("a column is the largest norm of `x`, a state or an extra state of `dynamics` over the window"),
                );
                ok = false;
                continue;
            };
            out.push(SweepColumn {
                name: name.node.clone(),
                group: group.node.clone(),
                at,
            });
        }
        ok.then_some(out)
    }

    /// `window = start .. end;` inside the scenario's time span.
    fn sweep_window(&mut self, s: &Setting, time: (f64, f64, f64)) -> Option<(f64, f64)> {
        let (a, b, step) = self.range_setting(s)?;
        if step.is_some() {
            self.err(
                Diagnostic::error(s.span, "the window has no step").with_help(
                    "the norms are taken at every sampling instant: write `window = start .. end;`",
                ),
            );
            return None;
        }
        let (t0, t1, _) = time;
        if a < t0 || b > t1 {
            self.err(
                Diagnostic::error(
                    s.span,
                    format!(
                        "the window {} .. {} s is outside the time span",
                        Num(a),
                        Num(b)
                    ),
                )
                .with_label(format!("the scenario runs {} .. {} s", Num(t0), Num(t1)))
                .with_help("give a window inside `time`"),
            );
            return None;
        }
        Some((a, b))
    }
}

/// Numbers equal names (` (2)`, ` (3)`, ...) so every row is named once.
fn disambiguate(scenarios: &mut [SweepScenario]) {
    for k in 1..scenarios.len() {
        let base = scenarios[k].name.clone();
        let same = scenarios[..k]
            .iter()
            .filter(|s| s.name == base || s.name.starts_with(&format!("{base} (")))
            .count();
        if same > 0 {
            scenarios[k].name = format!("{base} ({})", same + 1);
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::check::testing::*;
    use crate::spec::{Monitor, Trigger};

    const SIM: &str = "simulate { x0 = 0.5; time = 0 .. 10 step 0.01;\n";

    #[test]
    fn lists_expand_to_a_product_in_source_order() {
        let spec = spec_with(&format!(
            "{SIM} sweep {{ trigger periodic {{ every = [0.1, 0.2]; }}\n trigger mixed {{ sampling = 0.01 .. 0.1; beta = [0.5, 1]; rho = [1e-6, 1e-5, 1e-4]; }}\n window = 5 .. 10; columns {{ s = x1; all = x; }} }} }}"
        ));
        let sw = spec.simulate.and_then(|s| s.sweep).expect("a sweep"); // ok: unit test (cfg(test))
        assert_eq!(sw.window, Some((5.0, 10.0)));
        assert_eq!(sw.columns.len(), 2);
        assert_eq!((sw.columns[0].at, sw.columns[1].at), ((0, 1), (0, 1)));
        // The sampling range is not a list: 2 + 2 * 3 scenarios.
        assert_eq!(sw.scenarios.len(), 8);
        assert_eq!(sw.scenarios[0].trigger, Trigger::Periodic { every: 0.1 });
        assert_eq!(sw.scenarios[0].name, "periodic every = 0.1");
        assert_eq!(sw.scenarios[3].name, "mixed beta = 0.5 rho = 1e-5");
        assert_eq!(
            sw.scenarios[7].trigger,
            Trigger::Mixed {
                monitor: Monitor::Sampling(0.01, 0.1),
                beta: 1.0,
                rho: 1e-4,
                on: None,
            }
        );
        assert_eq!(sw.scenarios[7].source.1.len(), 2);
    }

    #[test]
    fn a_mixed_law_monitors_the_named_signal_wherever_it_is_declared() {
        // The signal is declared after the simulate block: resolved once all are checked.
        let spec = spec_with(&format!(
            "{SIM} sweep {{ trigger mixed {{ on = s; beta = 0.5; rho = [1e-6, 1e-5]; monitor = step; }} }} }}\nsignal s = [2 * x1];"
        ));
        let sw = spec.simulate.and_then(|s| s.sweep).expect("a sweep"); // ok: unit test (cfg(test))
        assert_eq!(sw.scenarios.len(), 2);
        for sc in &sw.scenarios {
            let Trigger::Mixed { on, monitor, .. } = &sc.trigger else {
                panic!("{:?}", sc.trigger); // ok: unit test (cfg(test))
            };
            assert_eq!(*monitor, Monitor::Step);
            assert_eq!(on.as_ref().map(|s| s.name.as_str()), Some("s"));
        }
        let (m, at) = only_error(&format!(
            "{SIM} sweep {{ trigger mixed {{ on = q; beta = 0.5; rho = [1e-6]; monitor = step; }} }} }}\nsignal s = [2 * x1];"
        ));
        assert_eq!((m.as_str(), at.as_str()), ("unknown signal `q`", "q"));
    }

    #[test]
    fn each_law_goes_through_the_trigger_checker() {
        let (m, at) = only_error(&format!(
            "{SIM} sweep {{ trigger periodic {{ every = [2, -1]; }} }} }}"
        ));
        assert_eq!(
            (m.as_str(), at.as_str()),
            ("the period must be positive", "every = [2, -1];")
        );
        let (m, at) = only_error(&format!(
            "{SIM} sweep {{ trigger periodic {{ period = [2]; }} }} }}"
        ));
        assert_eq!(
            (m.as_str(), at.as_str()),
            ("trigger `periodic` has no setting `period`", "period")
        );
    }

    #[test]
    fn lists_windows_and_columns_are_checked() {
        let one = |body: &str| only_error(&format!("{SIM} sweep {{ {body} }} }}"));
        assert_eq!(
            one("trigger periodic { every = []; }"),
            ("the list of `every` is empty".into(), "[]".into())
        );
        assert_eq!(
            one("trigger periodic { every = [1, synthesize]; }"),
            ("a sweep list holds numbers".into(), "synthesize".into())
        );
        assert_eq!(
            one("window = 5 .. 20;"),
            (
                "the window 5 .. 20 s is outside the time span".into(),
                "window = 5 .. 20;".into()
            )
        );
        assert_eq!(
            one("columns { v = y; }"),
            ("unknown state group `y`".into(), "y".into())
        );
        assert_eq!(
            one("span = 1;"),
            ("unknown sweep setting `span`".into(), "span".into())
        );
    }

    #[test]
    fn the_expansion_is_capped() {
        let list = (1..=17)
            .map(|k| k.to_string())
            .collect::<Vec<_>>()
            .join(", ");
        let (m, _) = only_error(&format!(
            "{SIM} sweep {{ trigger mixed {{ sampling = 0.01 .. 0.1; beta = [{list}]; rho = [{list}]; }} }} }}"
        ));
        assert_eq!(m, "the sweep expands to 289 scenarios, more than 256");
    }
}
