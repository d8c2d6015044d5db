//! Expressions: pest pairs to [`Expr`] trees by precedence, each tree measured
//! while it is built so that one deeper than [`MAX_EXPR_DEPTH`] or larger than
//! [`MAX_EXPR_NODES`] is a spec error before anything recurses over it.

use super::{first, next, pratt, Cx, PResult, Rule};
use crate::ast::{Arg, BinOp, Expr, ExprKind, IndexArg, NamedArg};
use crate::diag::Diagnostic;
use crate::limits::{MAX_EXPR_DEPTH, MAX_EXPR_NODES};
use crate::span::Span;
use pest::iterators::Pair;

/// The height and node count of a tree.
#[derive(Debug, Clone, Copy, Default)]
struct Size {
    height: usize,
    nodes: usize,
}

impl Size {
    /// The size of a node over children of sizes `parts`.
    fn over(parts: impl IntoIterator<Item = Size>) -> Size {
        parts.into_iter().fold(Size::LEAF, |acc, p| Size {
            height: acc.height.max(p.height + 1),
            nodes: acc.nodes + p.nodes,
        })
    }

    const LEAF: Size = Size {
        height: 1,
        nodes: 1,
    };
}

/// A tree with its size.
type Built<T> = PResult<(T, Size)>;

/// The error for a tree past a limit, placed on the whole expression by [`Cx::expr`].
fn checked(size: Size) -> PResult<Size> {
    if size.height > MAX_EXPR_DEPTH {
        return Err(Diagnostic::error(
            Span::default(),
            format!("expression nested too deeply: more than {MAX_EXPR_DEPTH} levels"),
        )
        .with_label("this expression")
        .with_note("every operator of a chain like `a + b + c` adds a level")
        .with_help(format!(
            "at most {MAX_EXPR_DEPTH} levels (MAX_EXPR_DEPTH); split it into named constants or functions"
        )));
    }
    if size.nodes > MAX_EXPR_NODES {
        return Err(Diagnostic::error(
            Span::default(),
            format!("expression too large: more than {MAX_EXPR_NODES} terms"),
        )
        .with_label("this expression")
        .with_help(format!(
            "at most {MAX_EXPR_NODES} numbers, names and operators in one expression \
             (MAX_EXPR_NODES); split it into named constants"
        )));
    }
    Ok(size)
}

/// A node of kind `kind` at `span`, of size `size` (within the limits).
fn node(kind: ExprKind, span: Span, size: Size) -> Built<Expr> {
    Ok((Expr { kind, span }, checked(size)?))
}

impl Cx {
    /// An expression (within the size limits).
    pub(super) fn expr(&self, p: Pair<Rule>) -> PResult<Expr> {
        self.built(p).map(|(e, _)| e)
    }

    /// `name = value`.
    pub(super) fn named_arg(&self, p: Pair<Rule>) -> PResult<NamedArg> {
        self.named_arg_built(p).map(|(a, _)| a)
    }

    /// A call argument, positional or named.
    pub(super) fn arg(&self, p: Pair<Rule>) -> PResult<Arg> {
        self.arg_built(p).map(|(a, _)| a)
    }

    fn named_arg_built(&self, p: Pair<Rule>) -> Built<NamedArg> {
        let span = self.span(&p);
        let mut parts = p.into_inner();
        let name = self.ident(next(&mut parts, span)?);
        let (value, size) = self.built(next(&mut parts, span)?)?;
        Ok((NamedArg { name, value }, size))
    }

    fn arg_built(&self, p: Pair<Rule>) -> Built<Arg> {
        if p.as_rule() == Rule::named_arg {
            let (na, size) = self.named_arg_built(p)?;
            let arg = Arg {
                name: Some(na.name),
                value: na.value,
            };
            Ok((arg, size))
        } else {
            let (value, size) = self.built(p)?;
            Ok((Arg { name: None, value }, size))
        }
    }

    fn built(&self, p: Pair<Rule>) -> Built<Expr> {
        let span = self.span(&p);
        pratt()
            .map_primary(|q| self.primary(q))
            .map_prefix(|op, rhs| {
                let (rhs, size) = rhs?;
                let s = self.span(&op).join(rhs.span);
                match op.as_rule() {
                    Rule::neg => node(ExprKind::Neg(Box::new(rhs)), s, Size::over([size])),
                    _ => Ok((rhs, size)),
                }
            })
            .map_postfix(|lhs, op| {
                let (lhs, size) = lhs?;
                let s = lhs.span.join(self.span(&op));
                if op.as_rule() == Rule::transpose {
                    return node(ExprKind::Transpose(Box::new(lhs)), s, Size::over([size]));
                }
                let mut args = Vec::new();
                let mut sizes = vec![size];
                for a in op.into_inner() {
                    let (arg, size) = self.index_arg(a, s)?;
                    args.push(arg);
                    sizes.push(size);
                }
                node(ExprKind::Index(Box::new(lhs), args), s, Size::over(sizes))
            })
            .map_infix(|lhs, op, rhs| {
                let ((lhs, a), (rhs, b)) = (lhs?, rhs?);
                let bop = match op.as_rule() {
                    Rule::add => BinOp::Add,
                    Rule::sub => BinOp::Sub,
                    Rule::mul => BinOp::Mul,
                    Rule::emul => BinOp::EMul,
                    Rule::div => BinOp::Div,
                    _ => BinOp::Pow,
                };
                let s = lhs.span.join(rhs.span);
                let kind = ExprKind::Binary(bop, Box::new(lhs), Box::new(rhs));
                node(kind, s, Size::over([a, b]))
            })
            .parse(p.into_inner())
            .map_err(|d: Diagnostic| {
                if d.span == Span::default() {
                    Diagnostic { span, ..d }
                } else {
                    d
                }
            })
    }

    /// One index of `e[...]`, with the size of its expressions.
    fn index_arg(&self, p: Pair<Rule>, span: Span) -> Built<IndexArg> {
        let mut parts = p.into_inner();
        let a = next(&mut parts, span)?;
        if a.as_rule() == Rule::full_range {
            return Ok((IndexArg::Full, Size::default()));
        }
        let (lo, l) = self.built(a)?;
        let Some(slice) = parts.next() else {
            return Ok((IndexArg::One(lo), l));
        };
        let (hi, h) = self.built(first(slice, span)?)?;
        let size = Size {
            height: l.height.max(h.height),
            nodes: l.nodes + h.nodes,
        };
        Ok((IndexArg::Range(lo, hi), size))
    }

    fn primary(&self, p: Pair<Rule>) -> Built<Expr> {
        let span = self.span(&p);
        let (kind, size) = match p.as_rule() {
            Rule::number => (ExprKind::Number(self.number(&p)?), Size::LEAF),
            Rule::ident => (ExprKind::Name(p.as_str().to_string()), Size::LEAF),
            Rule::paren => return self.built(first(p, span)?),
            Rule::call => {
                let mut parts = p.into_inner();
                let name = self.ident(next(&mut parts, span)?);
                let mut args = Vec::new();
                let mut sizes = Vec::new();
                for a in parts {
                    let (arg, size) = self.arg_built(a)?;
                    args.push(arg);
                    sizes.push(size);
                }
                (ExprKind::Call(name, args), Size::over(sizes))
            }
            _ => {
                let mut rows = Vec::new();
                let mut sizes = Vec::new();
                for row in p.into_inner() {
                    let mut elements = Vec::new();
                    for e in row.into_inner() {
                        let (e, size) = self.built(e)?;
                        elements.push(e);
                        sizes.push(size);
                    }
                    rows.push(elements);
                }
                (ExprKind::Matrix(rows), Size::over(sizes))
            }
        };
        Ok((Expr { kind, span }, checked(size)?))
    }
}
