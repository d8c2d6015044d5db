//! The symbol index of a document: every declared name (from the parse) and
//! every identifier of the text resolved to its declaration, for go to
//! definition, find references, hover, completion and the outline.
//!
//! Names in a `.tsf` file are global, except a function's parameters and a
//! state-dependent matrix's `x` (local to their item) and a premise's sets
//! (local to the premise: the set of a rule clause `z is near` is the one of
//! premise `z`).

use std::collections::HashMap;
use tsf_lang::ast::{DynStmt, File, Ident, ItemKind, ModesStmt, SetRef, SimStmt, VarDecl};
use tsf_lang::Span;

/// What a declared name is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// `controller name;`
    Controller,
    /// `const name = ..;` (also inside `dynamics { }`)
    Const,
    /// `fn name(..) = ..;`
    Fn,
    /// A function's parameter or a matrix's state parameter.
    Param,
    /// A state (also the extra states of `dynamics { }`).
    State,
    /// An input.
    Input,
    /// A disturbance.
    Disturbance,
    /// `output name = ..;`
    Output,
    /// `signal name = ..;`
    Signal,
    /// `A(x) = ..;`, `B = ..;`, `D = ..;`
    Matrix,
    /// A premise variable.
    Premise,
    /// A fuzzy set of a premise.
    Set,
    /// `rule name: ..;`
    Rule,
    /// `mode name { .. }`
    Mode,
}

impl Kind {
    /// The word for this kind in hovers and the outline.
    pub fn word(self) -> &'static str {
        match self {
            Kind::Controller => "controller",
            Kind::Const => "constant",
            Kind::Fn => "function",
            Kind::Param => "parameter",
            Kind::State => "state",
            Kind::Input => "input",
            Kind::Disturbance => "disturbance",
            Kind::Output => "output",
            Kind::Signal => "signal",
            Kind::Matrix => "matrix",
            Kind::Premise => "premise",
            Kind::Set => "fuzzy set",
            Kind::Rule => "rule",
            Kind::Mode => "mode",
        }
    }

    /// Whether names of this kind are visible in the whole file.
    fn is_global(self) -> bool {
        !matches!(self, Kind::Param | Kind::Set)
    }
}

/// One declared name.
#[derive(Debug, Clone)]
pub struct Decl {
    /// The name.
    pub name: String,
    /// What it is.
    pub kind: Kind,
    /// The name's span in the declaration.
    pub span: Span,
    /// The whole declaring item (or set definition).
    pub item: Span,
    /// For a parameter: the item it is visible in; for a set: its premise's item.
    pub scope: Option<Span>,
    /// For a set: the names of its premise.
    pub premise: Vec<String>,
}

/// An identifier of the text and the declaration it resolves to.
#[derive(Debug, Clone, Copy)]
pub struct Token {
    /// Where it is.
    pub span: Span,
    /// Index into [`Index::decls`], if it names a declaration.
    pub decl: Option<usize>,
}

/// The declarations and resolved identifiers of one document.
#[derive(Debug, Clone, Default)]
pub struct Index {
    /// Every declaration, in source order.
    pub decls: Vec<Decl>,
    /// Every identifier of the text outside comments, in source order.
    pub tokens: Vec<Token>,
}

impl Index {
    /// The index of `text`, parsed as `file`.
    pub fn build(text: &str, file: &File) -> Self {
        let decls = declarations(file);
        let mut global: HashMap<&str, usize> = HashMap::new();
        let mut at: HashMap<usize, usize> = HashMap::new();
        for (k, d) in decls.iter().enumerate() {
            if d.kind.is_global() {
                global.entry(d.name.as_str()).or_insert(k);
            }
            at.insert(d.span.start, k);
        }
        let clause_sets = clause_sets(file, &decls);
        let mut params: HashMap<&str, Vec<usize>> = HashMap::new();
        for (k, d) in decls.iter().enumerate() {
            if d.kind == Kind::Param {
                params.entry(d.name.as_str()).or_default().push(k);
            }
        }
        let tokens = identifiers(text)
            .into_iter()
            .map(|span| {
                let name = &text[span.start..span.end];
                let decl = at
                    .get(&span.start)
                    .or_else(|| clause_sets.get(&span.start))
                    .copied()
                    .or_else(|| param(&decls, params.get(name)?, span))
                    .or_else(|| global.get(name).copied());
                Token { span, decl }
            })
            .collect();
        Index { decls, tokens }
    }

    /// The identifier at byte `offset` (also just after its last character).
    pub fn token_at(&self, offset: usize) -> Option<&Token> {
        let k = self.tokens.partition_point(|t| t.span.end < offset);
        self.tokens
            .get(k)
            .filter(|t| t.span.start <= offset && offset <= t.span.end)
    }

    /// The declaration the identifier at `offset` names.
    pub fn decl_at(&self, offset: usize) -> Option<(usize, &Decl)> {
        let k = self.token_at(offset)?.decl?;
        Some((k, &self.decls[k]))
    }

    /// Every identifier naming declaration `k` (its declaration included).
    pub fn references(&self, k: usize) -> impl Iterator<Item = Span> + '_ {
        self.tokens
            .iter()
            .filter(move |t| t.decl == Some(k))
            .map(|t| t.span)
    }
}

/// The declarations of a parsed file, in source order.
fn declarations(file: &File) -> Vec<Decl> {
    let mut out = Decls::default();
    for it in &file.items {
        let span = it.span;
        match &it.kind {
            ItemKind::Controller(n) => out.add(n, Kind::Controller, span),
            ItemKind::Const(n, _) => out.add(n, Kind::Const, span),
            ItemKind::Fn(n, params, _) => {
                out.add(n, Kind::Fn, span);
                for p in params {
                    out.local(p, Kind::Param, span, span, &[]);
                }
            }
            ItemKind::State(v) => out.vars(v, Kind::State, span),
            ItemKind::Input(v, _) => out.vars(v, Kind::Input, span),
            ItemKind::Disturbance(v, _) => out.vars(v, Kind::Disturbance, span),
            ItemKind::Output(n, _) => out.add(n, Kind::Output, span),
            ItemKind::Signal(n, _) => out.add(n, Kind::Signal, span),
            ItemKind::Matrix { name, param, .. } => {
                out.add(name, Kind::Matrix, span);
                if let Some(p) = param {
                    out.local(p, Kind::Param, span, span, &[]);
                }
            }
            ItemKind::Premise { names, sets, .. } => {
                for n in names {
                    out.add(n, Kind::Premise, span);
                }
                for s in sets {
                    out.local(&s.name, Kind::Set, s.span, span, names);
                }
            }
            ItemKind::Rule { name, .. } => out.add(name, Kind::Rule, span),
            ItemKind::Simulate(stmts) => {
                for st in stmts {
                    let SimStmt::Dynamics(body, _) = st else {
                        continue;
                    };
                    for d in body {
                        match &d.node {
                            DynStmt::State(v) => out.vars(v, Kind::State, d.span),
                            DynStmt::Const(n, _) => out.add(n, Kind::Const, d.span),
                            DynStmt::Derivative(..) => {}
                        }
                    }
                }
            }
            ItemKind::Modes(stmts) => {
                for st in stmts {
                    if let ModesStmt::Mode { name, span, .. } = st {
                        out.add(name, Kind::Mode, *span);
                    }
                }
            }
            _ => {}
        }
    }
    out.0
}

/// Declarations being collected.
#[derive(Default)]
struct Decls(Vec<Decl>);

impl Decls {
    /// A name visible in the whole file, declared by `item`.
    fn add(&mut self, name: &Ident, kind: Kind, item: Span) {
        self.push(name, kind, item, None, &[]);
    }

    /// A name visible in `scope` (a set: of the premise `premise`).
    fn local(&mut self, name: &Ident, kind: Kind, item: Span, scope: Span, premise: &[Ident]) {
        self.push(name, kind, item, Some(scope), premise);
    }

    fn push(
        &mut self,
        name: &Ident,
        kind: Kind,
        item: Span,
        scope: Option<Span>,
        premise: &[Ident],
    ) {
        self.0.push(Decl {
            name: name.node.clone(),
            kind,
            span: name.span,
            item,
            scope,
            premise: premise.iter().map(|p| p.node.clone()).collect(),
        });
    }

    /// The names of a signal declaration.
    fn vars(&mut self, vars: &[VarDecl], kind: Kind, item: Span) {
        for v in vars {
            self.add(&v.name, kind, item);
        }
    }
}

/// The parameter among `candidates` (in source order; their items do not
/// overlap) whose item contains `span`: the first of the last item starting
/// before it, found by bisection.
fn param(decls: &[Decl], candidates: &[usize], span: Span) -> Option<usize> {
    let scope = |k: usize| decls[k].scope.unwrap_or_default();
    let n = candidates.partition_point(|&k| scope(k).start <= span.start);
    let last = scope(*candidates.get(n.checked_sub(1)?)?);
    if span.end > last.end {
        return None;
    }
    let first = candidates[..n].partition_point(|&k| scope(k).start < last.start);
    Some(candidates[first])
}

/// The set named by each rule clause `z is set`, by the start of the set's name.
fn clause_sets(file: &File, decls: &[Decl]) -> HashMap<usize, usize> {
    let mut sets: HashMap<(&str, &str), usize> = HashMap::new();
    for (k, d) in decls.iter().enumerate() {
        if d.kind == Kind::Set {
            for p in &d.premise {
                sets.entry((p.as_str(), d.name.as_str())).or_insert(k);
            }
        }
    }
    let mut out = HashMap::new();
    for it in &file.items {
        let ItemKind::Rule { clauses, .. } = &it.kind else {
            continue;
        };
        for c in clauses {
            if let SetRef::Named(set) = &c.set {
                if let Some(&k) = sets.get(&(c.premise.node.as_str(), set.node.as_str())) {
                    out.insert(set.span.start, k);
                }
            }
        }
    }
    out
}

/// The spans of the identifiers of `text`, outside comments and numbers.
pub fn identifiers(text: &str) -> Vec<Span> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    let is_ident = |c: u8| c.is_ascii_alphanumeric() || c == b'_';
    let digits = |mut i: usize| {
        while i < b.len() && b[i].is_ascii_digit() {
            i += 1;
        }
        i
    };
    while i < b.len() {
        let c = b[i];
        if c == b'/' && b.get(i + 1) == Some(&b'/') {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if c == b'/' && b.get(i + 1) == Some(&b'*') {
            i = text[i + 2..].find("*/").map_or(b.len(), |k| i + 2 + k + 2);
        } else if c.is_ascii_digit() || c == b'.' && b.get(i + 1).is_some_and(u8::is_ascii_digit) {
            i = digits(i);
            if b.get(i) == Some(&b'.') && b.get(i + 1).is_some_and(u8::is_ascii_digit) {
                i = digits(i + 1);
            }
            if matches!(b.get(i), Some(b'e' | b'E')) {
                let s = if matches!(b.get(i + 1), Some(b'+' | b'-')) {
                    i + 2
                } else {
                    i + 1
                };
                if b.get(s).is_some_and(u8::is_ascii_digit) {
                    i = digits(s);
                }
            }
        } else if c.is_ascii_alphabetic() || c == b'_' {
            let start = i;
            while i < b.len() && is_ident(b[i]) {
                i += 1;
            }
            out.push(Span::new(start, i));
        } else {
            i += 1;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolves_parameters_and_sets_in_their_scope() {
        let text = "const a = 1;\nfn f(a, b) = a + b;\nfn g(a) = a * 2;\nconst c = a;\n\
                    premise p = x[0] { lo = tri(0, 0, 1); }\npremise q = x[1] { lo = tri(0, 0, 1); }\n\
                    rule R: q is lo and p is lo => at(x = [0, 0]);\n";
        let (file, _, _) = tsf_lang::check_source_parsed(text);
        let idx = Index::build(text, &file);
        let decl_of = |needle: &str, k: usize| {
            let at = text.match_indices(needle).nth(k).expect(needle).0;
            let d = &idx.decls[idx.token_at(at).and_then(|t| t.decl).expect("resolved")];
            (d.kind, d.span.start)
        };
        let pos = |needle: &str| text.find(needle).unwrap();
        // `a` in f's body is f's parameter, in g's body g's, in `const c` the constant.
        assert_eq!(decl_of("a + b", 0), (Kind::Param, pos("a, b")));
        assert_eq!(decl_of("a * 2", 0), (Kind::Param, pos("a) = a *")));
        assert_eq!(decl_of("a;", 0), (Kind::Const, pos("a = 1")));
        // `q is lo` is q's set, `p is lo` p's.
        let q_lo = text.match_indices("lo = tri").nth(1).unwrap().0;
        assert_eq!(decl_of("lo and", 0), (Kind::Set, q_lo));
        assert_eq!(decl_of("lo =>", 0), (Kind::Set, pos("lo = tri")));
        assert_eq!(
            idx.references(idx.decls.iter().position(|d| d.span.start == q_lo).unwrap())
                .count(),
            2
        );
    }

    #[test]
    fn lexes_identifiers_not_comments_or_numbers() {
        let text = "a1 = 1e-5 + .5e3 * b; // c d\n/* e */ f 0..n";
        let names: Vec<&str> = identifiers(text)
            .into_iter()
            .map(|s| &text[s.start..s.end])
            .collect();
        assert_eq!(names, ["a1", "b", "f", "n"]);
    }
}
