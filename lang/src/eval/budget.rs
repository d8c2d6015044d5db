//! The work an evaluation may do: every visited node and every matrix
//! element created or multiplied is paid from a [`Budget`], so a spec whose
//! functions expand exponentially, or whose matrices are huge, is a spec
//! error after a bounded time instead of a run that never ends.

use crate::diag::Diagnostic;
use crate::limits::{MAX_CHECK_WORK, MAX_EVAL_WORK};
use crate::span::Span;
use std::cell::Cell;

/// What a budget is for (it names the limit in the error).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Scope {
    /// One evaluation: [`MAX_EVAL_WORK`].
    Evaluation,
    /// All evaluations of one check: [`MAX_CHECK_WORK`].
    Check,
}

/// Work units left to spend.
#[derive(Debug)]
pub struct Budget {
    left: Cell<u64>,
    scope: Scope,
}

impl Default for Budget {
    fn default() -> Self {
        Budget::evaluation()
    }
}

impl Budget {
    /// The budget of one evaluation: [`MAX_EVAL_WORK`].
    pub fn evaluation() -> Self {
        Budget {
            left: Cell::new(MAX_EVAL_WORK),
            scope: Scope::Evaluation,
        }
    }

    /// The budget of checking one spec: [`MAX_CHECK_WORK`] for all its evaluations.
    pub(crate) fn check() -> Self {
        Budget {
            left: Cell::new(MAX_CHECK_WORK),
            scope: Scope::Check,
        }
    }

    /// A budget for one evaluation paid from this one: [`MAX_EVAL_WORK`], or
    /// what is left here if that is less. Give back what it did not use with
    /// [`Budget::settle`].
    pub(crate) fn part(&self) -> Self {
        let left = self.left.get();
        if left >= MAX_EVAL_WORK {
            Budget::evaluation()
        } else {
            Budget {
                left: Cell::new(left),
                scope: self.scope,
            }
        }
    }

    /// Charges this budget with what `part` (made by [`Budget::part`]) spent.
    pub(crate) fn settle(&self, part: &Budget) {
        let limit = self.left.get().min(MAX_EVAL_WORK);
        let spent = limit.saturating_sub(part.left.get());
        self.left.set(self.left.get().saturating_sub(spent));
    }

    /// Whether nothing is left.
    pub fn is_spent(&self) -> bool {
        self.left.get() == 0
    }

    /// Pays `work` units for the expression at `span`.
    pub(crate) fn pay(&self, work: u64, span: Span) -> Result<(), Diagnostic> {
        let left = self.left.get();
        if work <= left {
            self.left.set(left - work);
            return Ok(());
        }
        self.left.set(0);
        Err(self.spent_error(span))
    }

    /// The error for running out at `span`.
    pub(crate) fn spent_error(&self, span: Span) -> Diagnostic {
        match self.scope {
            Scope::Evaluation => Diagnostic::error(
                span,
                format!("evaluation takes too much work: more than {MAX_EVAL_WORK} operations"),
            )
            .with_label("evaluating this runs out of work")
            .with_note(
                "a function is expanded at every call, so functions calling each other \
                 several times multiply the work; large matrices count every element",
            )
            .with_help(format!(
                "at most {MAX_EVAL_WORK} operations per evaluation (MAX_EVAL_WORK): \
                 compute the value once in a `const`, or use smaller matrices"
            )),
            Scope::Check => Diagnostic::error(
                span,
                format!(
                    "checking the spec takes too much work: more than {MAX_CHECK_WORK} operations"
                ),
            )
            .with_label("the evaluations of the spec run out of work here")
            .with_help(format!(
                "at most {MAX_CHECK_WORK} operations for all expressions of a spec \
                 (MAX_CHECK_WORK): compute shared values once in a `const`"
            )),
        }
    }
}
