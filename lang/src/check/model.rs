//! The model: the performance outputs (linear in x, u, w) and the matrices
//! A, B, D (constant, state-dependent, or given in every rule).

use super::{Checker, Dims, Draft, Kind};
use crate::ast::{Expr, Ident, Item, ItemKind};
use crate::diag::Diagnostic;
use crate::eval::{Mat, Mode};
use crate::span::Span;
use crate::spec::{ModelMatrix, Output};

impl Checker<'_> {
    /// `output name = expr;`: declared, then reduced to [C E G].
    pub(super) fn output_item(&mut self, name: &Ident, e: &Expr, dims: Dims, draft: &mut Draft) {
        if !self.declare(name, Kind::Output) {
            return;
        }
        match self.output(name, e, dims) {
            Some(o) => draft.outputs.push(o),
            None => {
                self.poison(name.node.clone());
            }
        }
    }

    /// `A = ...;` or `A(x) = ...;` (and B, D): one definition each.
    pub(super) fn matrix_item(
        &mut self,
        it: &Item,
        name: &Ident,
        param: Option<&Ident>,
        value: &Expr,
        draft: &mut Draft,
    ) {
        let slot = match name.node.as_str() {
            "A" => &mut draft.a,
            "B" => &mut draft.b,
            "D" => &mut draft.d,
            other => {
                let mut diag =
                    Diagnostic::error(name.span, format!("unknown model matrix `{other}`"))
                        .with_label("the model matrices are A, B and D");
                diag = if param.is_some() {
                    diag.with_help("state-dependent matrices are written `A(x) = ...`, `B(x) = ...`, `D(x) = ...`")
                } else {
                    diag.with_help(format!("for a constant write `const {other} = ...;`"))
                };
                self.err(diag);
                return;
            }
        };
        if let Some(prev) = slot.as_ref().map(|p: &ModelMatrix| p.span) {
            let diag = Diagnostic::error(
                it.span,
                format!("model matrix `{}` is defined twice", name.node),
            )
            .with_secondary(prev, "first definition here");
            self.diags.push(diag);
            return;
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
                return;
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
                    self.poison(name.node.clone());
                    return;
                }
            }
        }
        *slot = Some(ModelMatrix {
            expr: value.clone(),
            state_dependent: param.is_some(),
            span: it.span,
        });
    }

    /// The shapes of A, B, D, and that each is defined (or given in every rule).
    pub(super) fn check_model(&mut self, draft: &Draft, dims: Dims) {
        let Dims { n, m, q } = dims;
        for (slot, name, rows, cols, what) in [
            (&draft.a, "A", n, n, "n x n"),
            (&draft.b, "B", n, m, "n x m"),
            (&draft.d, "D", n, q, "n x q"),
        ] {
            if let Some(mm) = slot {
                self.check_model_matrix(name, mm, rows, cols, what);
            }
        }
        let rules_give = |mat: &str| {
            !draft.rule_items.is_empty()
                && draft.rule_items.iter().all(|r| matches!(&r.kind, ItemKind::Rule { matrices, .. } if matrices.iter().any(|m| m.name.node == mat)))
        };
        if draft.a.is_none()
            && !rules_give("A")
            && !self.broken("A")
            && !self.poisoned.contains("A")
        {
            self.err(
                Diagnostic::error(Span::new(0, 0), "no state matrix `A`").with_help(
                    "define `A = ...;` or `A(x) = ...;`, or give `A = ...` in every rule",
                ),
            );
        }
        if draft.b.is_none()
            && !rules_give("B")
            && !self.broken("B")
            && !self.poisoned.contains("B")
        {
            self.err(
                Diagnostic::error(Span::new(0, 0), "no input matrix `B`").with_help(
                    "define `B = ...;` or `B(x) = ...;`, or give `B = ...` in every rule",
                ),
            );
        }
        if q > 0
            && draft.d.is_none()
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
        let r = self.evaluate(&env, &mm.expr);
        match r {
            Ok(v) if v.nrows() == rows && v.ncols() == cols => {}
            Ok(v) => {
                self.shape_err(
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

    /// The output's [C E G], found by evaluating at basis vectors; None unless linear.
    pub(super) fn output(&mut self, name: &Ident, e: &Expr, dims: Dims) -> Option<Output> {
        let Dims { n, m, q } = dims;
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
            this.evaluate(&env, e)
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
}

#[cfg(test)]
mod tests {
    use crate::check::testing::*;

    #[test]
    fn outputs_are_split_into_c_e_g() {
        let spec = spec_with("disturbance d; D = 0.5;\noutput z = [x1; 2 * u; 3 * d];");
        let z = &spec.outputs[0];
        assert_eq!(z.c.as_slice(), &[1.0, 0.0, 0.0]);
        assert_eq!(z.e.as_slice(), &[0.0, 2.0, 0.0]);
        assert_eq!(z.g.as_slice(), &[0.0, 0.0, 3.0]);
    }

    #[test]
    fn a_nonlinear_output_is_rejected() {
        let (m, at) = only_error("output z = x1 * x1;");
        assert_eq!(
            m,
            "output `z` is not linear in the state, inputs and disturbances"
        );
        assert_eq!(at, "x1 * x1");
    }

    #[test]
    fn model_matrices_have_the_model_shapes() {
        let (m, at) = only_error_of(&base_with("A = -1;", "A = [1, 2];"));
        assert_eq!(m, "`A` must be n x n = 1x1, but this is 1x2");
        assert_eq!(at, "[1, 2]");
        let (m, _) = only_error("A = -3;");
        assert_eq!(m, "model matrix `A` is defined twice");
        let (m, at) = only_error("C = 1;");
        assert_eq!(m, "unknown model matrix `C`");
        assert_eq!(at, "C");
    }

    #[test]
    fn state_dependent_matrices_and_missing_ones() {
        let spec = valid(&base_with("A = -1;", "A(x) = -1 - x1 * x1;"));
        assert!(spec.a.is_some_and(|a| a.state_dependent));
        let (m, at) = only_error_of(&base_with("A = -1;", "A = -x1;"));
        assert!(m.contains("x1"), "{m}");
        assert_eq!(at, "x1");
        let (m, at) = only_error("disturbance d;");
        assert_eq!(
            m,
            "a disturbance is declared but there is no disturbance matrix `D`"
        );
        assert_eq!(at, "d");
    }
}
