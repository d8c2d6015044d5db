//! The pest parser and the conversion of its pairs into the typed AST.
//!
//! Parsing never fails as a whole: every item is parsed on its own, items with
//! syntax errors are reported and left out, the others form the [`File`].

use crate::ast::*;
use crate::diag::{Capped, Diagnostic};
use crate::span::{Span, Spanned};
use crate::split::split_items;

mod expr;
use pest::iterators::Pair;
use pest::pratt_parser::{Assoc, Op, PrattParser};
use pest::Parser as _;
use std::collections::HashSet;
use std::sync::OnceLock;

#[derive(pest_derive::Parser)]
#[grammar = "tsf.pest"]
pub(crate) struct TsfParser;

fn pratt() -> &'static PrattParser<Rule> {
    static P: OnceLock<PrattParser<Rule>> = OnceLock::new();
    P.get_or_init(|| {
        PrattParser::new()
            .op(Op::infix(Rule::add, Assoc::Left) | Op::infix(Rule::sub, Assoc::Left))
            .op(Op::infix(Rule::mul, Assoc::Left)
                | Op::infix(Rule::emul, Assoc::Left)
                | Op::infix(Rule::div, Assoc::Left))
            .op(Op::prefix(Rule::neg) | Op::prefix(Rule::pos))
            .op(Op::infix(Rule::pow, Assoc::Right))
            .op(Op::postfix(Rule::transpose) | Op::postfix(Rule::index))
    })
}

/// Parses a whole file: the items that parsed, the syntax errors (the first
/// [`MAX_DIAGNOSTICS`](crate::limits::MAX_DIAGNOSTICS) of each kind, in source
/// order) and how many more there were.
pub fn parse_file(source: &str) -> (File, Vec<Diagnostic>, usize) {
    let mut split = Capped::default();
    let chunks = split_items(source, &mut split);
    let mut diags = Capped::default();
    let mut file = File::default();
    let mut broken = HashSet::new();
    let mut note_broken = |file: &mut File, b: BrokenItem| {
        // What a broken item declares matters, not how often: keep each once.
        if broken.insert((b.keyword.clone(), b.names.clone())) {
            file.broken.push(b);
        }
    };
    for chunk in chunks {
        let text = &source[chunk.span.start..chunk.span.end];
        if chunk.broken {
            note_broken(&mut file, broken_item(text, chunk.span));
            continue;
        }
        match TsfParser::parse(Rule::item, text) {
            Ok(mut pairs) => {
                let cx = Cx {
                    offset: chunk.span.start,
                };
                if let Some(item) = pairs.next() {
                    match cx.item(item) {
                        Ok(it) => file.items.push(it),
                        Err(d) => {
                            diags.push_with(|| d);
                            note_broken(&mut file, broken_item(text, chunk.span));
                        }
                    }
                }
            }
            Err(e) => {
                diags.push_with(|| syntax_error(&e, chunk.span.start, text));
                note_broken(&mut file, broken_item(text, chunk.span));
            }
        }
    }
    let omitted = split.omitted + diags.omitted;
    let mut all = split.kept;
    all.extend(diags.kept);
    (file, all, omitted)
}

/// What a broken item seems to declare: its first word and the names after it.
fn broken_item(text: &str, span: Span) -> BrokenItem {
    let mut words = Vec::new();
    let mut cur = String::new();
    let mut in_comment = false;
    let mut prev = ' ';
    for ch in text.chars() {
        if in_comment {
            in_comment = ch != '\n' && ch != '\r';
            continue;
        }
        if ch == '/' && prev == '/' {
            cur.clear();
            in_comment = true;
            prev = ' ';
            continue;
        }
        prev = ch;
        if ch.is_ascii_alphanumeric() || ch == '_' {
            cur.push(ch);
        } else {
            if !cur.is_empty() {
                words.push(std::mem::take(&mut cur));
            }
            if matches!(ch, '=' | '{' | ';' | ':') {
                break;
            }
        }
    }
    if !cur.is_empty() {
        words.push(cur);
    }
    let keyword = words.first().cloned().unwrap_or_default();
    let names = match keyword.as_str() {
        "const" | "fn" | "output" | "signal" | "rule" | "controller" => {
            words.get(1).cloned().into_iter().collect()
        }
        "state" | "input" | "disturbance" | "premise" => words
            .iter()
            .skip(1)
            .filter(|w| {
                w.chars().next().is_some_and(|c| !c.is_ascii_digit())
                    && !matches!(w.as_str(), "saturate" | "bound" | "range" | "sigma")
            })
            .cloned()
            .collect(),
        other => vec![other.to_string()],
    };
    BrokenItem {
        keyword,
        names,
        span,
    }
}

/// A readable name for a grammar rule in "expected ..." messages.
fn rule_name(r: &Rule) -> Option<&'static str> {
    Some(match r {
        Rule::ident | Rule::goal_word => "a name",
        Rule::number => "a number",
        Rule::expr | Rule::value | Rule::range_value | Rule::index_arg | Rule::slice => {
            "an expression"
        }
        Rule::add | Rule::sub | Rule::mul | Rule::emul | Rule::div | Rule::pow => "an operator",
        Rule::transpose | Rule::index => return None,
        Rule::neg | Rule::pos => return None,
        Rule::matrix => "a matrix `[...]`",
        Rule::call => "a function call",
        Rule::paren => "`(`",
        Rule::set_block | Rule::setting_block => "`{`",
        Rule::set_def => "a set definition `name = tri(...);`",
        Rule::setting => "a setting `name = value;`",
        Rule::clause => "a clause `premise is set`",
        Rule::kw_and => "`and`",
        Rule::kw_is => "`is`",
        Rule::kw_about => "`about`",
        Rule::kw_at | Rule::at_point => "`at(...)`",
        Rule::kw_for | Rule::obj_for => "`for`",
        Rule::kw_in => "`in`",
        Rule::kw_with | Rule::obj_with => "`with`",
        Rule::kw_range | Rule::premise_range => "`range`",
        Rule::kw_sigma | Rule::premise_sigma => "`sigma`",
        Rule::kw_step => "`step`",
        Rule::measure_noise | Rule::kw_noise => "`noise <= bound`",
        Rule::named_arg => "`name = value`",
        Rule::consequent => "a consequent (`at(...)` or `A = ...`)",
        Rule::antecedent => "a premise",
        Rule::signals => "`(signal)`",
        Rule::goal | Rule::goal_le | Rule::goal_ge => {
            "a goal (`<= value`, `>= value`, `minimize`, `maximize`)"
        }
        Rule::saturate => "`saturate`",
        Rule::bound => "`bound`",
        Rule::var_decl | Rule::var_list => "a declaration `name` or `name[size]`",
        Rule::derivative => "a derivative `name' = ...;`",
        Rule::dynamics_block => "`dynamics { ... }`",
        Rule::signal_def => "a signal `name(t) = ...;`",
        Rule::sim_stmt => "a simulate statement",
        Rule::monte_carlo_block => "`monte_carlo { ... }`",
        Rule::mc_stmt => "a monte_carlo statement",
        Rule::sweep_block => "`sweep { ... }`",
        Rule::sweep_stmt => "a sweep statement (`trigger`, `columns` or `window`)",
        Rule::sweep_columns => "`columns { ... }`",
        Rule::sweep_column => "a column `name = state;`",
        Rule::mc_vary => "`name scale|offset|in uniform(lo, hi);`",
        Rule::mc_converged => "`converged |x| <= tol by t;`",
        Rule::mc_how | Rule::kw_scale | Rule::kw_offset => "`scale`, `offset` or `in`",
        Rule::kw_by => "`by`",
        Rule::modifier => "a modifier",
        Rule::emit_target => "a target `rust`, `c` or `c(style = ..)`",
        Rule::mode_def | Rule::kw_mode => "a mode `mode name { ... }`",
        Rule::EOI => "end of item",
        Rule::item => "an item (`const`, `state`, `rule`, ...)",
        _ => return None,
    })
}

fn syntax_error(e: &pest::error::Error<Rule>, offset: usize, text: &str) -> Diagnostic {
    use pest::error::{ErrorVariant, InputLocation};
    let (start, end) = match e.location {
        InputLocation::Pos(p) => (p, p),
        InputLocation::Span((s, e)) => (s, e),
    };
    // Point at the offending token (or the end of the item).
    let token_end = text[start.min(text.len())..]
        .char_indices()
        .find(|(_, c)| c.is_whitespace() || matches!(c, ';' | ',' | ')' | ']' | '}'))
        .map_or(text.len(), |(i, c)| {
            start + if i == 0 { c.len_utf8() } else { i }
        });
    let end = end.max(token_end).min(text.len());
    let span = Span::new(start, end).shifted(offset);
    let found = text[start.min(text.len())..end]
        .chars()
        .take(24)
        .collect::<String>();
    let found = if found.trim().is_empty() {
        "end of item".to_string()
    } else {
        format!("`{}`", found.trim())
    };
    let mut expected: Vec<&str> = match &e.variant {
        ErrorVariant::ParsingError { positives, .. } => {
            positives.iter().filter_map(rule_name).collect()
        }
        ErrorVariant::CustomError { .. } => Vec::new(),
    };
    expected.sort_unstable();
    expected.dedup();
    let msg = if expected.is_empty() {
        format!("syntax error: unexpected {found}")
    } else {
        format!(
            "syntax error: expected {}, found {found}",
            join_or(&expected)
        )
    };
    let mut d = Diagnostic::error(span, msg).with_label("unexpected here");
    if text.trim_end().ends_with(';') || text.trim_end().ends_with('}') {
        if expected.contains(&"an operator") && found != "end of item" {
            d = d.with_help("a `;` may be missing at the end of the previous statement");
        }
    } else {
        d = d.with_help("every item ends with `;` (or with a `{ ... }` block)");
    }
    d
}

fn join_or(items: &[&str]) -> String {
    match items {
        [] => String::new(),
        [one] => (*one).to_string(),
        [rest @ .., last] => format!("{} or {last}", rest.join(", ")),
    }
}

/// Conversion context: the byte offset of the item in the file.
struct Cx {
    offset: usize,
}

type PResult<T> = Result<T, Diagnostic>;

impl Cx {
    fn span(&self, p: &Pair<Rule>) -> Span {
        let s = p.as_span();
        Span::new(s.start(), s.end()).shifted(self.offset)
    }

    fn ident(&self, p: Pair<Rule>) -> Ident {
        Spanned::new(p.as_str().to_string(), self.span(&p))
    }

    fn number(&self, p: &Pair<Rule>) -> PResult<f64> {
        match p.as_str().parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(Diagnostic::error(
                self.span(p),
                format!("number `{}` is out of range", p.as_str()),
            )
            .with_label("not a finite double-precision number")
            .with_help("the largest magnitude is about 1.8e308")),
        }
    }

    /// `x = lo .. hi` or `x[k] = lo .. hi` of `plant region`.
    fn plant_bound(&self, b: Pair<Rule>, span: Span) -> PResult<PlantBound> {
        let mut parts = b.into_inner().peekable();
        let name = self.ident(next(&mut parts, span)?);
        let index = match parts.next_if(|p| p.as_rule() == Rule::plant_index) {
            Some(i) => {
                let num = next(&mut i.into_inner(), span)?;
                Some(Spanned::new(self.number(&num)?, self.span(&num)))
            }
            None => None,
        };
        let lo = self.expr(next(&mut parts, span)?)?;
        let hi = self.expr(next(&mut parts, span)?)?;
        Ok(PlantBound {
            name,
            index,
            lo,
            hi,
        })
    }

    fn item(&self, item: Pair<Rule>) -> PResult<Item> {
        let span = self.span(&item);
        let inner = item.into_inner().next();
        let Some(p) = inner else {
            return Err(Diagnostic::error(span, "empty item"));
        };
        let rule = p.as_rule();
        let mut it = p.into_inner();
        let kind = match rule {
            Rule::version => {
                let n = next(&mut it, span)?;
                ItemKind::Version(Spanned::new(self.number(&n)?, self.span(&n)))
            }
            Rule::controller => ItemKind::Controller(self.ident(next(&mut it, span)?)),
            Rule::const_def => {
                let name = self.ident(next(&mut it, span)?);
                ItemKind::Const(name, self.expr(next(&mut it, span)?)?)
            }
            Rule::fn_def => {
                let name = self.ident(next(&mut it, span)?);
                let mut params = Vec::new();
                let mut body = None;
                for p in it {
                    match p.as_rule() {
                        Rule::params => params = p.into_inner().map(|i| self.ident(i)).collect(),
                        _ => body = Some(self.expr(p)?),
                    }
                }
                let body =
                    body.ok_or_else(|| Diagnostic::error(span, "function without a body"))?;
                ItemKind::Fn(name, params, body)
            }
            Rule::state_decl => ItemKind::State(self.var_list(next(&mut it, span)?)?),
            Rule::input_decl | Rule::disturbance_decl => {
                let vars = self.var_list(next(&mut it, span)?)?;
                let extra = match it.next() {
                    Some(p) => {
                        let energy = p.as_rule() == Rule::energy;
                        Some((energy, self.expr(first(p, span)?)?))
                    }
                    None => None,
                };
                if rule == Rule::input_decl {
                    ItemKind::Input(vars, extra.map(|(_, e)| e))
                } else {
                    ItemKind::Disturbance(
                        vars,
                        extra.map(|(energy, e)| {
                            if energy {
                                crate::ast::DisturbanceLimit::Energy(e)
                            } else {
                                crate::ast::DisturbanceLimit::Bound(e)
                            }
                        }),
                    )
                }
            }
            Rule::output_decl => {
                let name = self.ident(next(&mut it, span)?);
                ItemKind::Output(name, self.expr(next(&mut it, span)?)?)
            }
            Rule::signal_decl => {
                let name = self.ident(next(&mut it, span)?);
                ItemKind::Signal(name, self.expr(next(&mut it, span)?)?)
            }
            Rule::matrix_def => {
                let name = self.ident(next(&mut it, span)?);
                let p2 = next(&mut it, span)?;
                if p2.as_rule() == Rule::ident {
                    let param = Some(self.ident(p2));
                    ItemKind::Matrix {
                        name,
                        param,
                        value: self.expr(next(&mut it, span)?)?,
                    }
                } else {
                    ItemKind::Matrix {
                        name,
                        param: None,
                        value: self.expr(p2)?,
                    }
                }
            }
            Rule::premise_decl => self.premise(it, span)?,
            Rule::rules_decl => ItemKind::Rules(self.ident(next(&mut it, span)?)),
            Rule::rule_decl => self.rule(it, span)?,
            Rule::objective_decl => self.objective(it, span)?,
            Rule::relaxation_decl => {
                let name = self.ident(next(&mut it, span)?);
                ItemKind::Relaxation(name, it.map(|p| self.named_arg(p)).collect::<PResult<_>>()?)
            }
            Rule::plant_decl => ItemKind::PlantRegion(
                it.map(|b| self.plant_bound(b, span))
                    .collect::<PResult<_>>()?,
            ),
            Rule::measure_decl => {
                let name = self.ident(next(&mut it, span)?);
                let value = self.expr(next(&mut it, span)?)?;
                let noise = match it.next() {
                    Some(n) => {
                        let mut parts = n.into_inner().filter(|q| q.as_rule() != Rule::kw_noise);
                        Some(self.expr(next(&mut parts, span)?)?)
                    }
                    None => None,
                };
                ItemKind::Measure { name, value, noise }
            }
            Rule::control_decl => {
                let name = self.ident(next(&mut it, span)?);
                ItemKind::Control(name, it.map(|p| self.named_arg(p)).collect::<PResult<_>>()?)
            }
            Rule::lyapunov_decl => {
                let name = self.ident(next(&mut it, span)?);
                ItemKind::Lyapunov(name, it.map(|p| self.named_arg(p)).collect::<PResult<_>>()?)
            }
            Rule::trigger_decl => {
                let (name, settings) = self.trigger_decl(it, span)?;
                ItemKind::Trigger(name, settings)
            }
            Rule::emit_decl => ItemKind::Emit(
                it.map(|target| {
                    let mut parts = target.into_inner();
                    let name = self.ident(next(&mut parts, span)?);
                    let args = parts.map(|a| self.named_arg(a)).collect::<PResult<_>>()?;
                    Ok(EmitTarget { name, args })
                })
                .collect::<PResult<_>>()?,
            ),
            Rule::precision_decl => ItemKind::Precision(self.ident(next(&mut it, span)?)),
            Rule::simulate_decl => {
                ItemKind::Simulate(it.map(|p| self.sim_stmt(p)).collect::<PResult<_>>()?)
            }
            Rule::modes_decl => {
                ItemKind::Modes(it.map(|p| self.modes_stmt(p)).collect::<PResult<_>>()?)
            }
            Rule::adaptive_decl => {
                ItemKind::Adaptive(it.map(|p| self.adaptive_stmt(p)).collect::<PResult<_>>()?)
            }
            _ => return Err(Diagnostic::error(span, "unsupported item")),
        };
        Ok(Item { kind, span })
    }

    fn var_list(&self, p: Pair<Rule>) -> PResult<Vec<VarDecl>> {
        p.into_inner()
            .map(|v| {
                let vspan = self.span(&v);
                let mut parts = v.into_inner();
                let name = self.ident(next(&mut parts, vspan)?);
                let len = match parts.next() {
                    Some(n) => Some(Spanned::new(self.number(&n)?, self.span(&n))),
                    None => None,
                };
                Ok(VarDecl { name, len })
            })
            .collect()
    }

    fn premise(&self, it: pest::iterators::Pairs<Rule>, span: Span) -> PResult<ItemKind> {
        let mut names = Vec::new();
        let mut expr = None;
        let mut range = None;
        let mut sigma = None;
        let mut sets = Vec::new();
        for p in it {
            match p.as_rule() {
                Rule::ident_list => names = p.into_inner().map(|i| self.ident(i)).collect(),
                Rule::expr => expr = Some(self.expr(p)?),
                Rule::premise_range => {
                    let mut r = p.into_inner().filter(|q| q.as_rule() == Rule::expr);
                    let lo = self.expr(next(&mut r, span)?)?;
                    let hi = self.expr(next(&mut r, span)?)?;
                    range = Some((lo, hi));
                }
                Rule::premise_sigma => {
                    let mut r = p.into_inner().filter(|q| q.as_rule() == Rule::expr);
                    sigma = Some(self.expr(next(&mut r, span)?)?);
                }
                Rule::set_block => {
                    for s in p.into_inner() {
                        let sspan = self.span(&s);
                        let mut parts = s.into_inner();
                        let name = self.ident(next(&mut parts, sspan)?);
                        let call = next(&mut parts, sspan)?;
                        let mut c = call.into_inner();
                        let shape = self.ident(next(&mut c, sspan)?);
                        let args = c.map(|a| self.arg(a)).collect::<PResult<_>>()?;
                        sets.push(SetDef {
                            name,
                            shape,
                            args,
                            span: sspan,
                        });
                    }
                }
                _ => {}
            }
        }
        Ok(ItemKind::Premise {
            names,
            expr,
            range,
            sigma,
            sets,
        })
    }

    fn rule(&self, mut it: pest::iterators::Pairs<Rule>, span: Span) -> PResult<ItemKind> {
        let name = self.ident(next(&mut it, span)?);
        let ante = next(&mut it, span)?;
        let mut clauses = Vec::new();
        for c in ante.into_inner().filter(|c| c.as_rule() == Rule::clause) {
            let cspan = self.span(&c);
            let mut parts = c.into_inner().filter(|q| q.as_rule() != Rule::kw_is);
            let premise = self.ident(next(&mut parts, cspan)?);
            let set = next(&mut parts, cspan)?;
            let set = if set.as_rule() == Rule::about_set {
                let mut e = set.into_inner().filter(|q| q.as_rule() == Rule::expr);
                SetRef::About(self.expr(next(&mut e, cspan)?)?)
            } else {
                SetRef::Named(self.ident(set))
            };
            clauses.push(Clause {
                premise,
                set,
                span: cspan,
            });
        }
        let cons = next(&mut it, span)?;
        let mut at = None;
        let mut matrices = Vec::new();
        for p in cons.into_inner() {
            match p.as_rule() {
                Rule::at_point => {
                    let aspan = self.span(&p);
                    let args = p
                        .into_inner()
                        .filter(|q| q.as_rule() == Rule::named_arg)
                        .map(|q| self.named_arg(q))
                        .collect::<PResult<_>>()?;
                    at = Some((args, aspan));
                }
                _ => matrices.push(self.named_arg(p)?),
            }
        }
        Ok(ItemKind::Rule {
            name,
            clauses,
            at,
            matrices,
        })
    }

    fn objective(&self, mut it: pest::iterators::Pairs<Rule>, span: Span) -> PResult<ItemKind> {
        let name = self.ident(next(&mut it, span)?);
        let mut signals = Vec::new();
        let mut goal = None;
        let mut for_ = None;
        let mut with = Vec::new();
        for p in it {
            match p.as_rule() {
                Rule::signals => signals = p.into_inner().map(|i| self.ident(i)).collect(),
                Rule::goal => {
                    let g = first(p, span)?;
                    goal = Some(match g.as_rule() {
                        Rule::goal_le => Goal::AtMost(self.expr(first(g, span)?)?),
                        Rule::goal_ge => Goal::AtLeast(self.expr(first(g, span)?)?),
                        _ => Goal::Word(self.ident(first(g, span)?)),
                    });
                }
                Rule::obj_for => {
                    let mut parts = p.into_inner().filter(|q| q.as_rule() != Rule::kw_for);
                    let name = self.ident(next(&mut parts, span)?);
                    let mut is_in = false;
                    let mut value = None;
                    for q in parts {
                        match q.as_rule() {
                            Rule::kw_in => is_in = true,
                            _ => value = Some(self.expr(q)?),
                        }
                    }
                    let value =
                        value.ok_or_else(|| Diagnostic::error(span, "`for` without a value"))?;
                    for_ = Some(ObjectiveFor { name, is_in, value });
                }
                Rule::obj_with => {
                    with = p
                        .into_inner()
                        .filter(|q| q.as_rule() == Rule::named_arg)
                        .map(|q| self.named_arg(q))
                        .collect::<PResult<_>>()?;
                }
                _ => {}
            }
        }
        Ok(ItemKind::Objective {
            name,
            signals,
            goal,
            for_,
            with,
        })
    }

    fn setting(&self, p: Pair<Rule>) -> PResult<Setting> {
        let span = self.span(&p);
        let mut key = None;
        let mut qualifier = None;
        let mut value = None;
        let mut modifiers = Vec::new();
        for q in p.into_inner() {
            match q.as_rule() {
                Rule::ident if key.is_none() => key = Some(self.ident(q)),
                Rule::ident => qualifier = Some(self.ident(q)),
                Rule::value => value = Some(self.value(q, span)?),
                Rule::modifier => {
                    let mut m = q.into_inner();
                    let name = self.ident(next(&mut m, span)?);
                    let args = m.map(|a| self.named_arg(a)).collect::<PResult<_>>()?;
                    modifiers.push(Modifier { name, args });
                }
                _ => {}
            }
        }
        let key = key.ok_or_else(|| Diagnostic::error(span, "setting without a name"))?;
        let value = value.ok_or_else(|| Diagnostic::error(span, "setting without a value"))?;
        Ok(Setting {
            key,
            qualifier,
            value,
            modifiers,
            span,
        })
    }

    fn value(&self, p: Pair<Rule>, span: Span) -> PResult<Value> {
        let v = first(p, span)?;
        if v.as_rule() == Rule::range_value {
            let mut parts = v.into_inner().filter(|q| q.as_rule() == Rule::expr);
            let lo = self.expr(next(&mut parts, span)?)?;
            let hi = self.expr(next(&mut parts, span)?)?;
            let step = match parts.next() {
                Some(s) => Some(self.expr(s)?),
                None => None,
            };
            Ok(Value::Range(lo, hi, step))
        } else {
            Ok(Value::Expr(self.expr(v)?))
        }
    }

    fn modes_stmt(&self, p: Pair<Rule>) -> PResult<ModesStmt> {
        let span = self.span(&p);
        if p.as_rule() == Rule::setting {
            return Ok(ModesStmt::Setting(Box::new(self.setting(p)?)));
        }
        let mut it = p.into_inner().filter(|q| q.as_rule() != Rule::kw_mode);
        let name = self.ident(next(&mut it, span)?);
        let settings = match it.next() {
            Some(block) => block
                .into_inner()
                .map(|s| self.setting(s))
                .collect::<PResult<_>>()?,
            None => Vec::new(),
        };
        Ok(ModesStmt::Mode {
            name,
            settings,
            span,
        })
    }

    fn adaptive_stmt(&self, p: Pair<Rule>) -> PResult<AdaptiveStmt> {
        let span = self.span(&p);
        let s = first(p, span)?;
        let rule = s.as_rule();
        if rule == Rule::setting {
            return Ok(AdaptiveStmt::Setting(Box::new(self.setting(s)?)));
        }
        let mut parts = s.into_inner();
        match rule {
            Rule::signal_def => {
                let name = self.ident(next(&mut parts, span)?);
                let param = self.ident(next(&mut parts, span)?);
                let value = self.expr(next(&mut parts, span)?)?;
                Ok(AdaptiveStmt::Signal {
                    name,
                    param,
                    value,
                    span,
                })
            }
            Rule::mc_converged => {
                let mut parts = parts
                    .filter(|q| q.as_rule() != Rule::kw_converged && q.as_rule() != Rule::kw_by);
                let signal = self.ident(next(&mut parts, span)?);
                let tol = self.expr(next(&mut parts, span)?)?;
                let by = self.expr(next(&mut parts, span)?)?;
                Ok(AdaptiveStmt::Converged {
                    signal,
                    tol,
                    by,
                    span,
                })
            }
            _ => {
                let robust = next(&mut parts, span)?.as_rule() == Rule::kw_robust;
                let name = self.ident(next(&mut parts, span)?);
                let (mut rate, mut lo, mut hi, mut init, mut layer) =
                    (None, None, None, None, None);
                let mut last = Rule::kw_rate;
                for q in parts {
                    match q.as_rule() {
                        Rule::expr => {
                            let e = Some(self.expr(q)?);
                            match last {
                                Rule::kw_rate => rate = e,
                                Rule::kw_bounds if lo.is_none() => lo = e,
                                Rule::kw_bounds => hi = e,
                                Rule::kw_init => init = e,
                                _ => layer = e,
                            }
                        }
                        r => last = r,
                    }
                }
                let missing = || Diagnostic::error(span, "incomplete estimate");
                Ok(AdaptiveStmt::Estimate {
                    robust,
                    name,
                    rate: rate.ok_or_else(missing)?,
                    lo: lo.ok_or_else(missing)?,
                    hi: hi.ok_or_else(missing)?,
                    init,
                    layer,
                    span,
                })
            }
        }
    }

    fn sim_stmt(&self, p: Pair<Rule>) -> PResult<SimStmt> {
        let span = self.span(&p);
        let s = first(p, span)?;
        match s.as_rule() {
            Rule::setting => Ok(SimStmt::Setting(self.setting(s)?)),
            Rule::signal_def => {
                let mut parts = s.into_inner();
                let name = self.ident(next(&mut parts, span)?);
                let param = self.ident(next(&mut parts, span)?);
                let value = self.expr(next(&mut parts, span)?)?;
                Ok(SimStmt::Signal { name, param, value })
            }
            Rule::monte_carlo_block => {
                let mspan = self.span(&s);
                let stmts = s
                    .into_inner()
                    .map(|p| self.mc_stmt(p))
                    .collect::<PResult<_>>()?;
                Ok(SimStmt::MonteCarlo(stmts, mspan))
            }
            Rule::sweep_block => {
                let sspan = self.span(&s);
                let stmts = s
                    .into_inner()
                    .map(|p| self.sweep_stmt(p))
                    .collect::<PResult<_>>()?;
                Ok(SimStmt::Sweep(stmts, sspan))
            }
            _ => {
                let dspan = self.span(&s);
                let mut stmts = Vec::new();
                for d in s.into_inner() {
                    let ds = self.span(&d);
                    let rule = d.as_rule();
                    let mut parts = d.into_inner();
                    let stmt = match rule {
                        Rule::state_decl => DynStmt::State(self.var_list(next(&mut parts, ds)?)?),
                        Rule::const_def => {
                            let n = self.ident(next(&mut parts, ds)?);
                            DynStmt::Const(n, self.expr(next(&mut parts, ds)?)?)
                        }
                        _ => {
                            let n = self.ident(next(&mut parts, ds)?);
                            DynStmt::Derivative(n, self.expr(next(&mut parts, ds)?)?)
                        }
                    };
                    stmts.push(Spanned::new(stmt, ds));
                }
                Ok(SimStmt::Dynamics(stmts, dspan))
            }
        }
    }
}

impl Cx {
    /// The kind and settings of a `trigger` declaration (item or sweep statement).
    fn trigger_decl<'i>(
        &self,
        mut it: impl Iterator<Item = Pair<'i, Rule>>,
        span: Span,
    ) -> PResult<(Ident, Vec<Setting>)> {
        let name = self.ident(next(&mut it, span)?);
        let settings = match it.next() {
            Some(block) => block
                .into_inner()
                .map(|s| self.setting(s))
                .collect::<PResult<_>>()?,
            None => Vec::new(),
        };
        Ok((name, settings))
    }

    fn sweep_stmt(&self, p: Pair<Rule>) -> PResult<SweepStmt> {
        let span = self.span(&p);
        let s = first(p, span)?;
        let sspan = self.span(&s);
        match s.as_rule() {
            Rule::trigger_decl => {
                let (kind, settings) = self.trigger_decl(s.into_inner(), sspan)?;
                Ok(SweepStmt::Trigger {
                    kind,
                    settings,
                    span: sspan,
                })
            }
            Rule::sweep_columns => {
                let mut columns = Vec::new();
                for c in s.into_inner() {
                    let cspan = self.span(&c);
                    let mut parts = c.into_inner();
                    let name = self.ident(next(&mut parts, cspan)?);
                    let group = self.ident(next(&mut parts, cspan)?);
                    columns.push((name, group));
                }
                Ok(SweepStmt::Columns(columns, sspan))
            }
            _ => Ok(SweepStmt::Setting(Box::new(self.setting(s)?))),
        }
    }

    fn mc_stmt(&self, p: Pair<Rule>) -> PResult<McStmt> {
        let span = self.span(&p);
        let s = first(p, span)?;
        let rule = s.as_rule();
        if rule == Rule::setting {
            return Ok(McStmt::Setting(self.setting(s)?));
        }
        let mut parts = s.into_inner();
        if rule == Rule::mc_vary {
            let name = self.ident(next(&mut parts, span)?);
            let how_pair = next(&mut parts, span)?;
            let how_span = self.span(&how_pair);
            let how = match how_pair.as_str() {
                "scale" => Vary::Scale,
                "offset" => Vary::Offset,
                _ => Vary::In,
            };
            let dist = self.expr(next(&mut parts, span)?)?;
            return Ok(McStmt::Vary {
                name,
                how: Spanned::new(how, how_span),
                dist,
                span,
            });
        }
        let mut parts =
            parts.filter(|q| q.as_rule() != Rule::kw_converged && q.as_rule() != Rule::kw_by);
        let signal = self.ident(next(&mut parts, span)?);
        let tol = self.expr(next(&mut parts, span)?)?;
        let by = self.expr(next(&mut parts, span)?)?;
        Ok(McStmt::Converged {
            signal,
            tol,
            by,
            span,
        })
    }
}

fn next<'a>(it: &mut impl Iterator<Item = Pair<'a, Rule>>, span: Span) -> PResult<Pair<'a, Rule>> {
    it.next()
        .ok_or_else(|| Diagnostic::error(span, "internal parser error: incomplete item"))
}

fn first(p: Pair<Rule>, span: Span) -> PResult<Pair<Rule>> {
    p.into_inner()
        .next()
        .ok_or_else(|| Diagnostic::error(span, "internal parser error: empty node"))
}
