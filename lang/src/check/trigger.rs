//! The triggering law: `trigger continuous;`, `periodic { every }`, `jittered { every, jitter }`,
//! `aperiodic { sampling, threshold, weight }`, `mixed { on, beta, rho, monitor | sampling }`,
//! and the design method of a synthesized weight.

use super::{unknown_choice, Checker, Draft};
use crate::ast::{Expr, ExprKind, Ident, Item, Setting, Value};
use crate::diag::Diagnostic;
use crate::limits::{
    DEFAULT_CODESIGN_ROUNDS, DEFAULT_TRANSMISSION_POINTS, MAX_CODESIGN_ROUNDS,
    MAX_TRANSMISSION_POINTS, MIN_REGION_BOUND, REGION_AUTO_SEED,
};
use crate::num::Num;
use crate::span::Spanned;
use crate::spec::{
    Monitor, PeriodicDesign, RegionBound, Threshold, Trigger, TriggerSynthesis, Weight,
};
use std::collections::HashMap;

impl Checker<'_> {
    /// A `trigger` item (given once); a synthesized weight's design method with it.
    pub(super) fn trigger_item(
        &mut self,
        it: &Item,
        kind: &Ident,
        settings: &[Setting],
        n: usize,
        draft: &mut Draft,
    ) {
        let mut seen = draft.trigger.as_ref().map(|t| t.span);
        if !self.singleton(&mut seen, it.span, "the trigger") {
            return;
        }
        let Some(t) = self.trigger(kind, settings, n) else {
            return;
        };
        if matches!(t, Trigger::Mixed { .. }) {
            draft.trigger_on = settings
                .iter()
                .find(|s| s.key.node == "on")
                .and_then(|s| match &s.value {
                    Value::Expr(Expr {
                        kind: ExprKind::Name(name),
                        span,
                    }) => Some(Spanned::new(name.clone(), *span)),
                    _ => None,
                });
        }
        if matches!(
            t,
            Trigger::Aperiodic {
                weight: Weight::Synthesize,
                ..
            }
        ) {
            let errors = self.diags.len();
            draft.trigger_synthesis = self.trigger_synthesis(settings);
            if self.diags.len() == errors {
                let weight = settings.iter().find(|s| s.key.node == "weight");
                draft.weight_span = Some(weight.map_or(kind.span, |s| s.span));
            }
        }
        for s in settings.iter().filter(|s| s.key.node == "region") {
            if let Some(b) = self.region_setting(s, &draft.trigger_region) {
                draft.trigger_region.push(b);
            }
        }
        if matches!(t, Trigger::Periodic { .. }) {
            if let Some(s) = settings.iter().find(|s| s.key.node == "design") {
                draft.periodic_design = self.periodic_design(s);
            }
        }
        draft.trigger_spans = super::compat::TriggerSpans::of(kind.span, settings);
        draft.trigger = Some(Spanned::new(t, it.span));
    }

    /// `region z = lo .. hi;` (lo < 0 < hi; the premise is checked by
    /// [`Checker::trigger_region`] once premises are known), at most once per premise.
    fn region_setting(&mut self, s: &Setting, seen: &[RegionBound]) -> Option<RegionBound> {
        let hint = "write `region z = lo .. hi;` with z a premise variable (or a state the premises read) and lo < 0 < hi: the event-triggered certificate then holds on the states reached from rest, kept inside that box";
        let Some(premise) = &s.qualifier else {
            self.err(
                Diagnostic::error(s.span, "`region` names a premise variable or a state")
                    .with_help(hint),
            );
            return None;
        };
        if seen.iter().any(|b| b.premise == premise.node) {
            self.err(Diagnostic::error(
                s.span,
                format!("`region {}` is given twice", premise.node),
            ));
            return None;
        }
        if let Value::Expr(Expr {
            kind: ExprKind::Name(word),
            ..
        }) = &s.value
        {
            if word == "auto" {
                // The seed box is set once the premise's range is known
                // ([`Checker::trigger_region`]).
                return Some(RegionBound {
                    premise: premise.node.clone(),
                    state: None,
                    range: (-1.0, 1.0),
                    auto: true,
                    span: s.span,
                });
            }
        }
        let Value::Range(lo, hi, None) = &s.value else {
            self.err(
                Diagnostic::error(s.span, "`region` takes a range `lo .. hi` or `auto`")
                    .with_help(hint),
            );
            return None;
        };
        let lo = self.scalar(lo, "a region bound")?;
        let hi = self.scalar(hi, "a region bound")?;
        if !(lo < 0.0 && hi > 0.0) {
            self.err(
                Diagnostic::error(
                    s.span,
                    format!("`region {}` needs lo < 0 < hi, found {} .. {}", premise.node, Num(lo), Num(hi)),
                )
                .with_help("the certified set is an ellipsoid around the equilibrium x = 0, so the box must contain 0 inside"),
            );
            return None;
        }
        if lo.abs().min(hi) < MIN_REGION_BOUND || lo.abs().max(hi) > 1.0 / MIN_REGION_BOUND {
            self.err(
                Diagnostic::error(
                    s.span,
                    format!("`region {}` = {} .. {} is too close to 0 or too wide", premise.node, Num(lo), Num(hi)),
                )
                .with_label(format!(
                    "each end must be between {} and {} from 0 (`MIN_REGION_BOUND`): the certificate squares the bounds",
                    Num(MIN_REGION_BOUND),
                    Num(1.0 / MIN_REGION_BOUND)
                ))
                .with_help("rescale the premise (e.g. in other units) so that the region's ends are ordinary numbers"),
            );
            return None;
        }
        Some(RegionBound {
            premise: premise.node.clone(),
            state: None,
            range: (lo, hi),
            auto: false,
            span: s.span,
        })
    }

    /// The `region` bounds checked against the premises: each names a premise
    /// variable and lies inside its range, or names a state (no premise
    /// variable of that name) whose box the model stage encloses the premises
    /// on (`compiler/src/model/region/states.rs`).
    pub(super) fn trigger_region(
        &mut self,
        bounds: &[RegionBound],
        premises: &[crate::spec::Premise],
    ) -> Vec<RegionBound> {
        let mut out = Vec::new();
        for b in bounds {
            let Some(p) = premises.iter().find(|p| p.name == b.premise) else {
                if let Some(s) = self.states.iter().find(|s| s.name == b.premise) {
                    if b.auto {
                        self.err(
                            Diagnostic::error(
                                b.span,
                                format!("`region {} = auto` needs a premise variable, and `{}` is a state", b.premise, b.premise),
                            )
                            .with_help("write the state's box (`region x = lo .. hi;`), or `auto` on a premise variable with a range"),
                        );
                        continue;
                    }
                    out.push(RegionBound {
                        state: Some((s.offset, s.len)),
                        ..b.clone()
                    });
                    continue;
                }
                let names: Vec<&str> = premises.iter().map(|p| p.name.as_str()).collect();
                let states: Vec<&str> = self.states.iter().map(|s| s.name.as_str()).collect();
                self.err(
                    Diagnostic::error(
                        b.span,
                        format!(
                            "`region {}`: no premise variable or state `{}`",
                            b.premise, b.premise
                        ),
                    )
                    .with_help(format!(
                        "premise variables: {}; states: {}",
                        if names.is_empty() {
                            "none".into()
                        } else {
                            names.join(", ")
                        },
                        states.join(", ")
                    )),
                );
                continue;
            };
            if b.auto {
                let Some((lo, hi)) = p.range.filter(|(lo, hi)| *lo < 0.0 && *hi > 0.0) else {
                    self.err(
                        Diagnostic::error(
                            b.span,
                            format!("`region {} = auto` needs the premise's range lo .. hi with lo < 0 < hi", b.premise),
                        )
                        .with_help("give the premise a range (`premise z range lo .. hi;`) or write the box (`region z = lo .. hi;`)"),
                    );
                    continue;
                };
                out.push(RegionBound {
                    range: (lo * REGION_AUTO_SEED, hi * REGION_AUTO_SEED),
                    ..b.clone()
                });
                continue;
            }
            if let Some((lo, hi)) = p.range {
                if b.range.0 < lo || b.range.1 > hi {
                    self.err(
                        Diagnostic::error(
                            b.span,
                            format!(
                                "`region {}` = {} .. {} leaves the premise range {} .. {}",
                                b.premise,
                                Num(b.range.0),
                                Num(b.range.1),
                                Num(lo),
                                Num(hi)
                            ),
                        )
                        .with_help("the rules' coverage is checked on the premise range only: shrink the region"),
                    );
                    continue;
                }
            }
            out.push(b.clone());
        }
        out
    }

    /// `design = emulation | discrete` of a periodic trigger.
    fn periodic_design(&mut self, s: &Setting) -> Option<Spanned<PeriodicDesign>> {
        let word = match &s.value {
            Value::Expr(Expr {
                kind: ExprKind::Name(w),
                ..
            }) => w.as_str(),
            _ => "",
        };
        match word {
            "emulation" => Some(Spanned::new(PeriodicDesign::Emulation, s.span)),
            "discrete" => Some(Spanned::new(PeriodicDesign::Discrete, s.span)),
            _ => {
                let span = match &s.value {
                    Value::Expr(e) => e.span,
                    Value::Range(..) => s.span,
                };
                self.err(unknown_choice(
                    span,
                    "design",
                    "designs",
                    word,
                    &["emulation", "discrete"],
                ));
                None
            }
        }
    }

    /// The law of `kind` with its settings, each known and given once.
    fn trigger(&mut self, kind: &Ident, settings: &[Setting], n: usize) -> Option<Trigger> {
        let allowed: &[&str] = match kind.node.as_str() {
            "continuous" => &[],
            "periodic" => &["every", "design", "region"],
            "jittered" => &["every", "jitter"],
            "aperiodic" => &["sampling", "threshold", "weight", "region"],
            "mixed" => &["on", "beta", "rho", "monitor", "sampling"],
            other => {
                let kinds = ["continuous", "periodic", "jittered", "aperiodic", "mixed"];
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
            } else if s.key.node == "region" {
                // One per premise: checked by `region_setting`.
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
        let t =
            match kind.node.as_str() {
                "continuous" => Some(Trigger::Continuous),
                "periodic" => {
                    let s = require(self, "every")?;
                    Some(Trigger::Periodic {
                        every: self.period(s)?,
                    })
                }
                "jittered" => {
                    let every = require(self, "every");
                    let jitter = require(self, "jitter");
                    self.jittered(every?, jitter?)
                }
                "aperiodic" => {
                    let s = require(self, "sampling")?;
                    let (lo, hi) = self.sampling(s)?;
                    let threshold = match get.get("threshold") {
                        Some(s) => Some(self.threshold(s)?),
                        None => None,
                    };
                    let weight = match get.get("weight") {
                        None => Weight::Synthesize,
                        Some(s) => self.weight(s, n)?,
                    };
                    Some(Trigger::Aperiodic {
                        sampling: (lo, hi),
                        threshold,
                        weight,
                    })
                }
                _ => {
                    let monitor = self.monitor(kind, &get, ok);
                    let beta = require(self, "beta").and_then(|s| self.mixed_beta(s));
                    let rho = require(self, "rho").and_then(|s| self.mixed_rho(s));
                    if let Some(s) = get.get("on") {
                        if !matches!(
                            &s.value,
                            Value::Expr(Expr {
                                kind: ExprKind::Name(_),
                                ..
                            })
                        ) {
                            self.err(Diagnostic::error(s.span, "`on` names a signal").with_help(
                                "write `on = sigma;` with `signal sigma = ...;` declared",
                            ));
                            return None;
                        }
                    }
                    Some(Trigger::Mixed {
                        monitor: monitor?,
                        beta: beta?,
                        rho: rho?,
                        on: None,
                    })
                }
            };
        if ok {
            t
        } else {
            None
        }
    }

    /// Where a mixed trigger checks its law: `sampling = a .. b;` or
    /// `monitor = step | continuous;` (exactly one).
    fn monitor(
        &mut self,
        kind: &Ident,
        get: &HashMap<&str, &Setting>,
        ok: bool,
    ) -> Option<Monitor> {
        match (get.get("sampling"), get.get("monitor")) {
            (Some(s), None) => self.sampling(s).map(|(lo, hi)| Monitor::Sampling(lo, hi)),
            (None, Some(s)) => match &s.value {
                Value::Expr(Expr {
                    kind: ExprKind::Name(w),
                    ..
                }) if w == "step" => Some(Monitor::Step),
                Value::Expr(Expr {
                    kind: ExprKind::Name(w),
                    ..
                }) if w == "continuous" => Some(Monitor::Continuous),
                _ => {
                    let word = match &s.value {
                        Value::Expr(Expr {
                            kind: ExprKind::Name(w),
                            ..
                        }) => w.clone(),
                        _ => String::new(),
                    };
                    let span = match &s.value {
                        Value::Expr(e) => e.span,
                        Value::Range(..) => s.span,
                    };
                    self.err(unknown_choice(
                        span,
                        "monitor",
                        "monitors",
                        &word,
                        &["step", "continuous"],
                    ));
                    None
                }
            },
            (Some(a), Some(_)) => {
                self.err(
                    Diagnostic::error(a.span, "give `sampling` or `monitor`, not both")
                        .with_help("`sampling = a .. b;` checks at aperiodic instants; `monitor = step;` at every integration step; `monitor = continuous;` continuously"),
                );
                None
            }
            (None, None) => {
                if ok {
                    self.err(
                        Diagnostic::error(kind.span, "trigger `mixed` needs `monitor = continuous;` (or `step`) or `sampling = h_min .. h_max;`"),
                    );
                }
                None
            }
        }
    }

    /// beta >= 0 of a mixed trigger; beta >= 1 is allowed with a warning.
    fn mixed_beta(&mut self, s: &Setting) -> Option<f64> {
        let beta = self.setting_nonnegative(s)?;
        if beta >= 1.0 {
            self.err(
                Diagnostic::warning(s.span, format!("beta = {beta} >= 1: the held signal may differ from the current one by more than its size"))
                    .with_note("no loop with beta >= 1 is certified (the certificate needs beta ||G|| ||G^-1|| < 1 in effect)"),
            );
        }
        Some(beta)
    }

    /// rho >= 0 of a mixed trigger; rho = 0 is allowed with a warning.
    fn mixed_rho(&mut self, s: &Setting) -> Option<f64> {
        let rho = self.setting_nonnegative(s)?;
        if rho == 0.0 {
            self.err(
                Diagnostic::warning(s.span, "rho = 0: Zeno behaviour (infinitely many transmissions in finite time) is not excluded")
                    .with_help("give a small rho > 0 (Amrr et al. use 1e-6 .. 1e-4)"),
            );
        }
        Some(rho)
    }

    /// `jittered { every = h; jitter = j; }` with h > 0 and 0 <= j < h.
    fn jittered(&mut self, every: &Setting, jitter: &Setting) -> Option<Trigger> {
        let h = self.period(every);
        let j = self.setting_nonnegative(jitter);
        let (h, j) = (h?, j?);
        if j >= h {
            self.err(
                Diagnostic::error(jitter.span, format!("the jitter must be shorter than the period, found jitter = {} >= every = {}", Num(j), Num(h)))
                    .with_label("the shortest interval every - jitter would not be positive")
                    .with_secondary(every.span, "the nominal period")
                    .with_help("the sampling intervals lie in [every - jitter, every + jitter]: write 0 <= jitter < every, or use `trigger aperiodic { sampling = h_min .. h_max; }` for intervals in any range"),
            );
            return None;
        }
        Some(Trigger::Jittered {
            every: h,
            jitter: j,
        })
    }

    /// The period `every = h;` with h > 0.
    fn period(&mut self, s: &Setting) -> Option<f64> {
        let v = self.setting_scalar(s)?;
        if v <= 0.0 {
            self.err(Diagnostic::error(s.span, "the period must be positive"));
            return None;
        }
        Some(v)
    }

    /// `sampling = h_min .. h_max;` with h_min > 0.
    fn sampling(&mut self, s: &Setting) -> Option<(f64, f64)> {
        let (lo, hi, _) = self.range_setting(s)?;
        if lo <= 0.0 {
            self.err(Diagnostic::error(s.span, "h_min must be positive"));
            return None;
        }
        Some((lo, hi))
    }

    /// `threshold nu = v [adaptive(mu1 = .., mu2 = .., mu3 = .. [, max = ..])];`
    fn threshold(&mut self, s: &Setting) -> Option<Threshold> {
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
            let p = self.named(&m.args, &["mu1", "mu2", "mu3", "max"], "`adaptive`")?;
            if let Some(&top) = p.get("max") {
                if top < nu {
                    self.err(
                        Diagnostic::error(
                            m.name.span,
                            format!(
                                "the adaptive ceiling max = {top} is below the threshold nu = {nu}"
                            ),
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

    /// `weight = synthesize [method];` or `weight = <n x n matrix>;`
    fn weight(&mut self, s: &Setting, n: usize) -> Option<Weight> {
        Some(match &s.value {
            Value::Expr(Expr {
                kind: ExprKind::Name(w),
                ..
            }) if w == "synthesize" => Weight::Synthesize,
            Value::Expr(e) => {
                let w = self.eval_const(e)?;
                if w.nrows() != n || w.ncols() != n {
                    self.shape_err(
                        Diagnostic::error(e.span, format!("the trigger weight must be {n}x{n}"))
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
        })
    }

    /// The design method of a synthesized trigger weight: `weight = synthesize;`
    /// (none yet: the weight is left to later stages), `weight = synthesize two_step;`
    /// (gains first, then the weight) or `weight = synthesize theorem2(eps1 = .., eps2 = .., eps3 = ..,
    /// xi = .., reading = ..);` (Xu & Huang Theorem 2; every argument optional) or
    /// `weight = synthesize codesign(rounds = ..);` (alternating gain and trigger steps).
    fn trigger_synthesis(&mut self, settings: &[Setting]) -> Option<TriggerSynthesis> {
        let s = settings.iter().find(|s| s.key.node == "weight")?;
        let mut out = None;
        for m in &s.modifiers {
            if m.name.node == "two_step" {
                self.named(&m.args, &[], "`two_step`")?;
                out = Some(TriggerSynthesis::TwoStep);
                continue;
            }
            if m.name.node == "codesign" {
                let p = self.named(&m.args, &["rounds"], "`codesign`")?;
                let rounds = p
                    .get("rounds")
                    .copied()
                    .unwrap_or(f64::from(DEFAULT_CODESIGN_ROUNDS));
                if rounds.fract() != 0.0
                    || !(1.0..=f64::from(MAX_CODESIGN_ROUNDS)).contains(&rounds)
                {
                    let at = m
                        .args
                        .iter()
                        .find(|a| a.name.node == "rounds")
                        .map_or(m.name.span, |a| a.value.span);
                    self.err(
                        Diagnostic::error(at, format!("`rounds` is a whole number in 1 ..= {MAX_CODESIGN_ROUNDS}"))
                            .with_help("each round solves two trigger-sized SDPs (about 20 s each on the Xu & Huang spec)"),
                    );
                    return None;
                }
                out = Some(TriggerSynthesis::Codesign {
                    rounds: rounds as u32,
                });
                continue;
            }
            if m.name.node == "transmissions" {
                let p = self.named(&m.args, &["points", "gamma"], "`transmissions`")?;
                let points = p
                    .get("points")
                    .copied()
                    .unwrap_or(f64::from(DEFAULT_TRANSMISSION_POINTS));
                if points.fract() != 0.0
                    || !(1.0..=f64::from(MAX_TRANSMISSION_POINTS)).contains(&points)
                {
                    let at = m
                        .args
                        .iter()
                        .find(|a| a.name.node == "points")
                        .map_or(m.name.span, |a| a.value.span);
                    self.err(
                        Diagnostic::error(at, format!("`points` is a whole number in 1 ..= {MAX_TRANSMISSION_POINTS}"))
                            .with_help("each point solves two trigger-sized SDPs and simulates the spec's scenario once"),
                    );
                    return None;
                }
                let gamma = p.get("gamma").copied();
                if let Some(g) = gamma.filter(|g| !(g.is_finite() && *g > 0.0)) {
                    self.err(Diagnostic::error(
                        m.name.span,
                        format!("`gamma` is a positive bound on the event-triggered L-inf gain, not {g}"),
                    ));
                    return None;
                }
                out = Some(TriggerSynthesis::Transmissions {
                    points: points as u32,
                    gamma,
                });
                continue;
            }
            if m.name.node != "theorem2" {
                self.err(
                    Diagnostic::error(
                        m.name.span,
                        format!("unknown weight design method `{}`", m.name.node),
                    )
                    .with_help("write `weight = synthesize two_step;`, `weight = synthesize codesign;`, `weight = synthesize transmissions;` or `weight = synthesize theorem2(eps1 = 1, eps2 = 1, eps3 = 1);`"),
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
}

#[cfg(test)]
mod tests {
    use crate::check::testing::*;
    use crate::spec::{Monitor, Threshold, Trigger, TriggerSynthesis, Weight};

    fn trigger(body: &str) -> Trigger {
        let spec = spec_with(&format!("trigger {body}"));
        spec.trigger.expect("a trigger").node // ok: unit test
    }

    #[test]
    fn each_law_with_its_settings() {
        assert_eq!(trigger("continuous;"), Trigger::Continuous);
        assert_eq!(
            trigger("periodic { every = 0.01; }"),
            Trigger::Periodic { every: 0.01 }
        );
        // At sampling instants the law is read, then refused (`compat/trigger.rs`).
        assert_eq!(
            trigger("mixed { monitor = step; beta = 0.1; rho = 0.001; }"),
            Trigger::Mixed {
                monitor: Monitor::Step,
                beta: 0.1,
                rho: 0.001,
                on: None
            }
        );
        let Trigger::Aperiodic {
            sampling, weight, ..
        } = trigger("aperiodic { sampling = 0.001 .. 0.1; weight = 2; }")
        else {
            panic!("not aperiodic"); // ok: unit test
        };
        assert_eq!(sampling, (0.001, 0.1));
        assert!(matches!(weight, Weight::Given(w) if w[(0, 0)] == 2.0));
        // A threshold goes with a synthesized weight (L-inf and the saturation region).
        let spec = valid(&format!(
            "{}disturbance d; D = 1; output z = x1;\n\
             objective linf(d -> z) minimize with phi = 0.1;\nobjective saturation region;\n\
             trigger aperiodic {{ sampling = 0.001 .. 0.1; threshold nu = 0.02 adaptive(mu1 = 10, mu2 = 1, mu3 = 0.02, max = 0.05); }}",
            base_with("input u;", "input u saturate 1;")
        ));
        let Some(Trigger::Aperiodic { threshold, .. }) = spec.trigger.map(|t| t.node) else {
            panic!("not aperiodic"); // ok: unit test
        };
        assert_eq!(
            threshold,
            Some(Threshold {
                nu: 0.02,
                adaptive: Some((10.0, 1.0, 0.02)),
                max: Some(0.05)
            })
        );
    }

    #[test]
    fn settings_are_known_given_once_and_required() {
        let (m, at) = only_error("trigger periodic { period = 1; }");
        assert_eq!(m, "trigger `periodic` has no setting `period`");
        assert_eq!(at, "period");
        let (m, at) = only_error("trigger mixed { beta = -0.1; rho = 1e-6; monitor = step; }");
        assert_eq!(
            (m.as_str(), at.as_str()),
            ("`beta` must not be negative", "-0.1")
        );
        let (m, _) = only_error("trigger mixed { beta = 0.1; rho = -1; monitor = step; }");
        assert_eq!(m, "`rho` must not be negative");
        let (m, at) = only_error("trigger mixed { beta = 0.1; rho = 1; monitor = often; }");
        assert_eq!(
            (m.as_str(), at.as_str()),
            ("unknown monitor `often`", "often")
        );
        let (m, _) = only_error("trigger mixed { beta = 0.1; rho = 1; }");
        assert!(m.starts_with("trigger `mixed` needs `monitor"), "{m}");
        let (m, _) = only_error(
            "trigger mixed { beta = 0.1; rho = 1; monitor = step; sampling = 0.1 .. 1; }",
        );
        assert_eq!(m, "give `sampling` or `monitor`, not both");
        let (m, at) = only_error("trigger periodic;");
        assert_eq!(m, "trigger `periodic` needs `every = ...;`");
        assert_eq!(at, "periodic");
        let (m, _) = only_error("trigger periodic { every = 1; every = 2; }");
        assert_eq!(m, "setting `every` is given twice");
        let (m, at) = only_error("trigger mixed { sampling = 0 .. 0.1; beta = 0.1; rho = 0; }");
        assert_eq!(
            (m.as_str(), at.as_str()),
            ("h_min must be positive", "sampling = 0 .. 0.1;")
        );
        let (m, at) = only_error("trigger aperiodic { sampling = 0 .. 0.1; weight = 1; }");
        assert_eq!(m, "h_min must be positive");
        assert_eq!(at, "sampling = 0 .. 0.1;");
        let (m, at) = only_error("trigger aperiodic { sampling = 0.1 .. 1; weight = [1, 2]; }");
        assert_eq!(m, "the trigger weight must be 1x1");
        assert_eq!(at, "[1, 2]");
    }

    #[test]
    fn a_synthesized_weight_records_its_design_method() {
        let synthesis = |w: &str| {
            let spec = valid(&format!(
                "{}disturbance d; D = 1; output z = x1;\n\
                 objective linf(d -> z) minimize with phi = 0.1;\nobjective saturation region;\n\
                 trigger aperiodic {{ sampling = 0.01 .. 0.1; {w} }}",
                base_with("input u;", "input u saturate 1;")
            ));
            spec.trigger_synthesis
        };
        assert_eq!(synthesis(""), None);
        assert_eq!(
            synthesis("weight = synthesize two_step;"),
            Some(TriggerSynthesis::TwoStep)
        );
        assert_eq!(
            synthesis("weight = synthesize codesign;"),
            Some(TriggerSynthesis::Codesign { rounds: 10 })
        );
        assert_eq!(
            synthesis("weight = synthesize codesign(rounds = 4);"),
            Some(TriggerSynthesis::Codesign { rounds: 4 })
        );
        assert_eq!(
            synthesis("weight = synthesize transmissions;"),
            Some(TriggerSynthesis::Transmissions {
                points: 6,
                gamma: None
            })
        );
        assert_eq!(
            synthesis("weight = synthesize transmissions(points = 12, gamma = 0.16);"),
            Some(TriggerSynthesis::Transmissions {
                points: 12,
                gamma: Some(0.16)
            })
        );
        let rounds = |w: &str| {
            only_error_of(&format!(
                "{}disturbance d; D = 1; output z = x1;\n\
                 objective linf(d -> z) minimize with phi = 0.1;\nobjective saturation region;\n\
                 trigger aperiodic {{ sampling = 0.01 .. 0.1; {w} }}",
                base_with("input u;", "input u saturate 1;")
            ))
        };
        for (w, at) in [
            ("weight = synthesize codesign(rounds = 0);", "0"),
            ("weight = synthesize codesign(rounds = 2.5);", "2.5"),
            ("weight = synthesize codesign(rounds = 31);", "31"),
        ] {
            assert_eq!(
                rounds(w),
                (
                    "`rounds` is a whole number in 1 ..= 30".to_string(),
                    at.to_string()
                )
            );
        }
        assert_eq!(
            synthesis("weight = synthesize theorem2(eps2 = 2, xi = 0.08, reading = 3);"),
            Some(TriggerSynthesis::Theorem2 {
                eps: [1.0, 2.0, 1.0],
                xi: Some(0.08),
                reading: 3
            })
        );
    }
}
