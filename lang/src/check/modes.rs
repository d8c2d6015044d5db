//! The `modes { ... }` block: named modes of a continuous-time Markov chain
//! (per-mode actuator effectiveness or input matrix, optional actuator bias),
//! the transition-rate matrix (a generator: square, one row per mode,
//! off-diagonals >= 0, rows summing to 0) and the design option
//! (`mode_dependent`, `mode_independent`); what the compiler does not
//! support together with modes is refused in `compat/modes.rs`.

use super::{unknown_choice, Checker, Dims, Draft};
use crate::ast::{Expr, ExprKind, Item, ItemKind, ModesStmt, Setting, Value};
use crate::diag::Diagnostic;
use crate::eval::Mat;
use crate::modes::{Actuator, Mode, ModeDesign, Modes};
use crate::num::Num;
use crate::span::{Span, Spanned};
use crate::spec::{Relaxation, RuleSpec, SpannedObjective};
use std::collections::HashMap;

/// Rows of the rate matrix must sum to 0 within this, relative to the sum of
/// the magnitudes of the row's entries.
pub const ROW_SUM_TOLERANCE: f64 = 1e-9;

/// Smallest positive transition rate: the mode conditions divide by each
/// rate (the X-form's -X_b / pi_ab block); a smaller one is 0 in effect.
pub const MIN_POSITIVE_RATE: f64 = 1e-12;

/// Most modes a `modes` block may declare (docs/limits.md).
pub const MAX_MODES: usize = 32;

/// The checked items the modes block must be consistent with.
pub(super) struct Around<'s> {
    pub objectives: &'s [SpannedObjective],
    pub relaxation: &'s Spanned<Relaxation>,
    pub rules: &'s [RuleSpec],
    pub saturated: bool,
}

impl<'a> Checker<'a> {
    /// The `modes` block of the file, if any (given once), checked.
    pub(super) fn modes_block(
        &mut self,
        items: &'a [Item],
        draft: &Draft,
        dims: Dims,
        around: Around<'_>,
    ) -> Option<Modes> {
        let mut seen = None;
        let mut block = None;
        for it in items {
            if let ItemKind::Modes(stmts) = &it.kind {
                if self.singleton(&mut seen, it.span, "the `modes` block") {
                    block = Some((it.span, stmts));
                }
            }
        }
        let (span, stmts) = block?;
        let modes = self.modes(span, stmts, dims)?;
        self.modes_supported(&modes, draft, &around)
            .then_some(modes)
    }

    fn modes(&mut self, span: Span, stmts: &[ModesStmt], dims: Dims) -> Option<Modes> {
        let mut modes = Vec::new();
        let mut names: HashMap<&str, Span> = HashMap::new();
        let mut settings: HashMap<&str, &Setting> = HashMap::new();
        let mut ok = true;
        for s in stmts {
            match s {
                ModesStmt::Mode {
                    name,
                    settings,
                    span,
                } => {
                    if let Some(first) = names.insert(name.node.as_str(), name.span) {
                        self.err(
                            Diagnostic::error(
                                name.span,
                                format!("mode `{}` is defined twice", name.node),
                            )
                            .with_secondary(first, "first defined here"),
                        );
                        ok = false;
                        continue;
                    }
                    match self.mode(&name.node, settings, *span, dims) {
                        Some(m) => modes.push(m),
                        None => ok = false,
                    }
                }
                ModesStmt::Setting(s) => {
                    ok &= self.block_setting(s, &mut settings);
                }
            }
        }
        if names.is_empty() {
            self.err(
                Diagnostic::error(span, "`modes` defines no mode")
                    .with_help("define each mode: `mode normal { }`"),
            );
            return None;
        }
        let design = match settings.get("design") {
            None => ModeDesign::Dependent,
            Some(s) => self.mode_design(s)?,
        };
        let Some(rates) = settings.get("rates") else {
            self.err(
                Diagnostic::error(span, "`modes` needs `rates = [...];`")
                    .with_note("the transition-rate matrix: one row and one column per mode"),
            );
            return None;
        };
        // Rows index the modes as written, a duplicate included.
        let count = stmts
            .iter()
            .filter(|s| matches!(s, ModesStmt::Mode { .. }))
            .count();
        if count > MAX_MODES {
            self.err(
                Diagnostic::error(span, format!("{count} modes: at most {MAX_MODES}"))
                    .with_note("generated code takes the mode as an 8-bit index, and every mode adds an n x n Lyapunov matrix and coupling blocks to the SDP"),
            );
            return None;
        }
        let rates = self.rates(rates, count)?;
        ok.then_some(Modes {
            modes,
            rates,
            design,
            span,
        })
    }

    /// A setting of the block (`rates`, `design`), known and given once.
    fn block_setting<'s>(
        &mut self,
        s: &'s Setting,
        seen: &mut HashMap<&'s str, &'s Setting>,
    ) -> bool {
        const KEYS: [&str; 2] = ["rates", "design"];
        let key = s.key.node.as_str();
        if !KEYS.contains(&key) {
            self.err(unknown_choice(
                s.key.span,
                "setting of `modes`",
                "settings",
                key,
                &KEYS,
            ));
            return false;
        }
        if seen.insert(key, s).is_some() {
            self.err(Diagnostic::error(
                s.key.span,
                format!("setting `{key}` is given twice"),
            ));
            return false;
        }
        true
    }

    /// One `mode name { effectiveness | B, bias }`.
    fn mode(&mut self, name: &str, settings: &[Setting], span: Span, dims: Dims) -> Option<Mode> {
        const KEYS: [&str; 3] = ["effectiveness", "B", "bias"];
        let mut get: HashMap<&str, &Setting> = HashMap::new();
        for s in settings {
            let key = s.key.node.as_str();
            if !KEYS.contains(&key) {
                self.err(unknown_choice(
                    s.key.span,
                    "setting of a mode",
                    "settings",
                    key,
                    &KEYS,
                ));
                return None;
            }
            if get.insert(key, s).is_some() {
                self.err(Diagnostic::error(
                    s.key.span,
                    format!("setting `{key}` is given twice"),
                ));
                return None;
            }
        }
        let actuator = match (get.get("effectiveness"), get.get("B")) {
            (Some(f), Some(b)) => {
                self.err(
                    Diagnostic::error(b.span, "a mode gives `effectiveness` or `B`, not both")
                        .with_secondary(f.span, "effectiveness here")
                        .with_help("B = B_i * diag(effectiveness) for every rule i; or give B"),
                );
                return None;
            }
            (Some(f), None) => {
                let e = self.single_expr(f)?;
                let v = self.vector(e, dims.m, "the effectiveness")?;
                if let Some(k) = v.iter().position(|x| *x < 0.0) {
                    self.err(
                        Diagnostic::error(e.span, "an actuator effectiveness must not be negative")
                            .with_label(format!("component {k} is {}", Num(v[k]))),
                    );
                    return None;
                }
                Actuator::Effectiveness(v)
            }
            (None, Some(b)) => {
                let e = self.single_expr(b)?;
                let v = self.eval_const(e)?;
                if (v.nrows(), v.ncols()) != (dims.n, dims.m) {
                    self.shape_err(
                        Diagnostic::error(
                            e.span,
                            format!("a mode's `B` must be {}x{}", dims.n, dims.m),
                        )
                        .with_label(format!(
                            "this is {}x{}",
                            v.nrows(),
                            v.ncols()
                        )),
                    );
                    return None;
                }
                Actuator::Given(v)
            }
            (None, None) => Actuator::Effectiveness(vec![1.0; dims.m]),
        };
        let bias = match get.get("bias") {
            Some(s) => {
                let e = self.single_expr(s)?;
                Some(self.vector(e, dims.m, "the bias")?)
            }
            None => None,
        };
        Some(Mode {
            name: name.to_string(),
            actuator,
            bias,
            span,
        })
    }

    /// The expression of a setting that takes one value (not a range).
    fn single_expr<'s>(&mut self, s: &'s Setting) -> Option<&'s Expr> {
        match &s.value {
            Value::Expr(e) => Some(e),
            Value::Range(..) => {
                self.err(Diagnostic::error(
                    s.span,
                    format!("`{}` needs a single value, not a range", s.key.node),
                ));
                None
            }
        }
    }

    /// `design = mode_dependent | mode_independent`.
    fn mode_design(&mut self, s: &Setting) -> Option<ModeDesign> {
        let e = self.single_expr(s)?;
        let choices = [ModeDesign::Dependent, ModeDesign::Independent];
        let words = choices.map(ModeDesign::keyword);
        let word = match &e.kind {
            ExprKind::Name(w) => w.as_str(),
            _ => "",
        };
        match choices.into_iter().find(|c| c.keyword() == word) {
            Some(c) => Some(c),
            None => {
                self.err(unknown_choice(
                    e.span,
                    "mode design",
                    "designs",
                    if word.is_empty() { "?" } else { word },
                    &words,
                ));
                None
            }
        }
    }

    /// The transition-rate matrix: `count` x `count`, off-diagonals >= 0,
    /// rows summing to 0 (within [`ROW_SUM_TOLERANCE`]).
    fn rates(&mut self, s: &Setting, count: usize) -> Option<Mat> {
        let e = self.single_expr(s)?;
        let pi = self.eval_const(e)?;
        if pi.nrows() != pi.ncols() || pi.nrows() != count {
            let what = if pi.nrows() == pi.ncols() {
                "the wrong size"
            } else {
                "not square"
            };
            self.err(
                Diagnostic::error(
                    e.span,
                    format!("the transition-rate matrix is {what}: it must be {count}x{count}"),
                )
                .with_label(format!("this is {}x{}", pi.nrows(), pi.ncols()))
                .with_note(format!(
                    "one row and one column per mode ({count} mode{})",
                    if count == 1 { "" } else { "s" }
                )),
            );
            return None;
        }
        let literal = Literal::of(e, count);
        let mut ok = true;
        for a in 0..count {
            for b in (0..count).filter(|b| *b != a) {
                let v = pi[(a, b)];
                let refusal = if v < 0.0 {
                    Some((
                        "a transition rate between two modes must not be negative".to_string(),
                        "off-diagonal entries are rates (>= 0); the diagonal is minus the row's other entries",
                    ))
                } else if v > 0.0 && v < MIN_POSITIVE_RATE {
                    Some((
                        format!("a transition rate below {} is not supported", Num(MIN_POSITIVE_RATE)),
                        "write 0 for a transition that does not happen (the mode conditions divide by every positive rate)",
                    ))
                } else {
                    None
                };
                if let Some((message, help)) = refusal {
                    let label = format!("rate from mode {} to mode {} is {}", a + 1, b + 1, Num(v));
                    let d = Diagnostic::error(literal.entry(a, b), message).with_label(label);
                    self.err(if v < 0.0 {
                        d.with_note(help)
                    } else {
                        d.with_help(help)
                    });
                    ok = false;
                }
            }
        }
        if !ok {
            return None;
        }
        for a in 0..count {
            let row = pi.row(a);
            let sum: f64 = row.iter().sum();
            let scale: f64 = row.iter().map(|v| v.abs()).sum();
            if sum.abs() > ROW_SUM_TOLERANCE * scale {
                let diagonal = pi[(a, a)] - sum;
                self.err(
                    Diagnostic::error(
                        literal.row(a),
                        format!(
                            "row {} of the transition-rate matrix does not sum to 0",
                            a + 1
                        ),
                    )
                    .with_label(format!("sums to {}", Num(sum)))
                    .with_help(format!(
                        "the diagonal entry that makes it sum to 0 is {}",
                        Num(diagonal)
                    )),
                );
                ok = false;
            }
        }
        ok.then_some(pi)
    }
}

/// Spans of the entries of a literal rate matrix (the whole expression when
/// it is not a literal of the right shape).
struct Literal<'e> {
    whole: Span,
    rows: Option<&'e [Vec<Expr>]>,
}

impl<'e> Literal<'e> {
    fn of(e: &'e Expr, count: usize) -> Self {
        let rows = match &e.kind {
            ExprKind::Matrix(rows)
                if rows.len() == count && rows.iter().all(|r| r.len() == count) =>
            {
                Some(rows.as_slice())
            }
            _ => None,
        };
        Literal {
            whole: e.span,
            rows,
        }
    }

    fn entry(&self, a: usize, b: usize) -> Span {
        self.rows.map_or(self.whole, |r| r[a][b].span)
    }

    fn row(&self, a: usize) -> Span {
        match self.rows.and_then(|r| Some((r[a].first()?, r[a].last()?))) {
            Some((first, last)) => Span::new(first.span.start, last.span.end),
            None => self.whole,
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::check::testing::*;
    use crate::modes::{Actuator, ModeDesign};

    const TWO: &str = "modes { mode ok { } mode weak { effectiveness = 0.5; bias = 0.1; } rates = [-1, 1; 2, -2]; }";

    #[test]
    fn a_valid_block_is_checked() {
        let spec = spec_with(TWO);
        let m = spec.modes.expect("modes"); // ok: unit test
        assert_eq!(m.len(), 2);
        assert_eq!(m.design, ModeDesign::Dependent);
        assert_eq!(m.modes[1].actuator, Actuator::Effectiveness(vec![0.5]));
        assert_eq!(m.modes[1].bias, Some(vec![0.1]));
        assert_eq!(m.rates[(1, 0)], 2.0);
    }

    #[test]
    fn at_most_max_modes() {
        let k = super::MAX_MODES + 1;
        let modes: String = (0..k).map(|a| format!("mode m{a} {{ }} ")).collect();
        let rows = vec![vec!["0"; k].join(", "); k];
        let (m, _) = only_error(&format!(
            "modes {{ {modes} rates = [{}]; }}",
            rows.join("; ")
        ));
        assert_eq!(m, format!("{k} modes: at most {}", super::MAX_MODES));
    }

    #[test]
    fn the_design_option_is_read() {
        let src = TWO.replace("rates", "design = mode_independent; rates");
        let m = spec_with(&src).modes.expect("modes"); // ok: unit test
        assert_eq!(m.design, ModeDesign::Independent);
        let (msg, at) = only_error(&TWO.replace("rates", "design = mode_blind; rates"));
        assert_eq!(msg, "unknown mode design `mode_blind`");
        assert_eq!(at, "mode_blind");
    }

    #[test]
    fn rows_must_sum_to_zero_with_the_corrected_diagonal_as_help() {
        let e = errors(&format!("{BASE}{}", TWO.replace("2, -2", "2, -3")));
        assert_eq!(e.len(), 1, "{e:#?}");
        assert_eq!(
            e[0].0.message,
            "row 2 of the transition-rate matrix does not sum to 0"
        );
        assert_eq!(e[0].1, "2, -3");
        assert!(
            e[0].0.help.iter().any(|h| h.contains("is -2")),
            "{:?}",
            e[0].0.help
        );
        // Within the relative tolerance: accepted.
        spec_with(&TWO.replace("2, -2", "2, -2.0000000000001"));
    }

    #[test]
    fn negative_rates_wrong_sizes_and_unknown_settings() {
        let (m, at) = only_error(&TWO.replace("-1, 1; 2, -2", "1, -1; 2, -2"));
        assert_eq!(
            m,
            "a transition rate between two modes must not be negative"
        );
        assert_eq!(at, "-1");
        let (m, at) = only_error(&TWO.replace("[-1, 1; 2, -2]", "[-1, 1]"));
        assert_eq!(
            m,
            "the transition-rate matrix is not square: it must be 2x2"
        );
        assert_eq!(at, "[-1, 1]");
        let (m, _) = only_error(&TWO.replace("[-1, 1; 2, -2]", "[0]"));
        assert_eq!(
            m,
            "the transition-rate matrix is the wrong size: it must be 2x2"
        );
        let (m, at) = only_error(&TWO.replace("bias", "bais"));
        assert_eq!(m, "unknown setting of a mode `bais`");
        assert_eq!(at, "bais");
        let (m, _) = only_error(&TWO.replace("mode weak", "mode ok"));
        assert_eq!(m, "mode `ok` is defined twice");
        let (m, _) = only_error(&TWO.replace("rates = [-1, 1; 2, -2];", ""));
        assert_eq!(m, "`modes` needs `rates = [...];`");
    }

    #[test]
    fn a_sampled_loop_is_accepted_and_event_triggers_are_refused_with_help() {
        // Periodic and threshold-free aperiodic: the sampled mode loop (no
        // trigger weight is asked for).
        spec_with(&format!("{TWO}\ntrigger periodic {{ every = 0.01; }}"));
        let s = spec_with(&format!(
            "{TWO}\ntrigger aperiodic {{ sampling = 0.001 .. 0.05; }}\nobjective decay_rate >= 0.1;"
        ));
        assert!(s.modes.is_some() && s.trigger.is_some());
        let e = errors(&format!(
            "{BASE}{TWO}\ntrigger aperiodic {{ sampling = 0.001 .. 0.05; threshold nu = 0.1; weight = 1; }}"
        ));
        let d = e
            .iter()
            .find(|(d, _)| d.message.starts_with("an event-triggered loop"))
            .unwrap_or_else(|| panic!("{e:#?}")); // ok: unit test
        assert!(d.1.starts_with("trigger aperiodic"), "{}", d.1);
        assert!(d
            .0
            .help
            .iter()
            .any(|h| h.contains("a sampled loop is supported")));
        let (m, _) = only_error(&format!(
            "{TWO}\ntrigger periodic {{ every = 0.1; design = discrete; }}"
        ));
        assert_eq!(
            m,
            "the discrete-time design (`design = discrete`) is not supported with `modes`"
        );
        let (m, at) = only_error(&format!(
            "{TWO}\noutput z = x1;\ndisturbance d;\nD = 1;\nobjective hinf(d -> z) minimize;\ntrigger periodic {{ every = 0.1; }}"
        ));
        assert_eq!(m, "objective `hinf` with a sampled loop is not supported with `modes`: the sampled-loop certificate covers mean-square stability");
        assert!(at.starts_with("objective hinf"), "{at}");
    }

    #[test]
    fn unsupported_combinations_point_at_the_item() {
        let (m, at) = only_error(&format!("{TWO}\nobjective input_norm(u) <= 1 for x0 = 1;"));
        assert_eq!(m, "objective `input_norm` is not supported with `modes`");
        assert!(at.starts_with("objective input_norm"));
        // Code is generated for both designs.
        spec_with(&format!("{TWO}\nemit rust, c;"));
        let ok = TWO.replace("rates", "design = mode_independent; rates");
        spec_with(&format!("{ok}\nemit rust;"));
    }
}
