//! What the parser knows and the lexer does not: which `+`/`-` are signs and
//! which `(`/`[` open an operand (a parenthesised expression or a matrix
//! literal) rather than follow a name (a call, an index, `w[3]`, `at(..)`).

use crate::parser::{Rule, TsfParser};
use crate::split::split_items;
use pest::Parser as _;
use std::collections::HashSet;

/// Byte offsets of the pieces whose spacing depends on the parse.
#[derive(Debug, Default)]
pub struct Roles {
    /// Unary `+` and `-` (no space after them).
    pub signs: HashSet<usize>,
    /// `(` of a parenthesised expression and `[` of a matrix literal (a space
    /// before them, like before any operand).
    pub operands: HashSet<usize>,
}

/// The roles in `source`, which parses (the caller checked): every item is
/// parsed again and its pairs walked flat (no recursion on the tree).
pub fn roles(source: &str) -> Roles {
    let mut roles = Roles::default();
    let mut ignored = crate::diag::Capped::default();
    for chunk in split_items(source, &mut ignored) {
        let text = &source[chunk.span.start..chunk.span.end];
        let Ok(pairs) = TsfParser::parse(Rule::item, text) else {
            continue;
        };
        for pair in pairs.flatten() {
            let at = chunk.span.start + pair.as_span().start();
            match pair.as_rule() {
                Rule::neg | Rule::pos => {
                    roles.signs.insert(at);
                }
                Rule::matrix | Rule::paren => {
                    roles.operands.insert(at);
                }
                _ => {}
            }
        }
    }
    roles
}
