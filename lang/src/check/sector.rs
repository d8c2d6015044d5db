//! `rules sector;`: the rules built from the sector premises (see
//! [`crate::sector`] for the construction and what makes it exact).

use super::{Checker, Dims};
use crate::ast::{Item, ItemKind};
use crate::diag::Diagnostic;
use crate::eval::{Mat, Mode};
use crate::sector::{SectorModel, FIT_TOLERANCE, MAX_SECTOR_PREMISES};
use crate::span::Span;
use crate::spec::{ClauseSet, FuzzySet, ModelMatrix, Premise, RuleClause, RuleSpec, SetShape};

/// What `rules ...;` items asked for.
pub(super) enum Built {
    /// No `rules` item: the rules are the `rule` items.
    NotAsked,
    /// The sector model and its rules.
    Sector(Box<SectorModel>, Vec<RuleSpec>),
    /// Asked, but an error was reported (no "no rules" error on top).
    Failed,
}

/// The model matrices that can depend on the state, by name.
type Matrices<'m> = [(&'static str, Option<&'m ModelMatrix>, usize, usize); 3];

/// One fitted entry: matrix, row, column and the multilinear coefficients.
struct Entry {
    matrix: usize,
    row: usize,
    col: usize,
    coef: Vec<f64>,
}

/// The `i`-th point of the Halton sequence in base `base` (radical inverse):
/// deterministic, evenly spread samples without a random generator.
fn halton(mut i: u64, base: u64) -> f64 {
    let (mut f, mut r) = (1.0, 0.0);
    while i > 0 {
        f /= base as f64;
        r += f * (i % base) as f64;
        i /= base;
    }
    r
}

impl Checker<'_> {
    fn has_errors(&self) -> bool {
        self.diags.iter().any(Diagnostic::is_error)
    }
}

/// The first `n` primes (Halton bases).
fn primes(n: usize) -> Vec<u64> {
    let mut out: Vec<u64> = Vec::with_capacity(n);
    let mut c = 2u64;
    while out.len() < n {
        if out.iter().all(|p| !c.is_multiple_of(*p)) {
            out.push(c);
        }
        c += 1;
    }
    out
}

/// Value of monomial `s` (bit k set: factor t_k) at normalized premises `t`.
fn monomial(s: usize, t: &[f64]) -> f64 {
    t.iter()
        .enumerate()
        .filter(|(k, _)| s & (1 << k) != 0)
        .map(|(_, v)| *v)
        .product()
}

impl Checker<'_> {
    /// `rules sector;` (at most once, no `rule` items beside it): the sector
    /// premises get their `max`/`min` sets and the 2^p rules are built.
    pub(super) fn sector_rules(
        &mut self,
        items: &[&Item],
        rule_items: &[&Item],
        premises: &mut [Premise],
        matrices: Matrices<'_>,
        dims: Dims,
    ) -> Built {
        let Some(first) = items.first() else {
            return Built::NotAsked;
        };
        let mut ok = true;
        for it in items {
            let ItemKind::Rules(kind) = &it.kind else {
                continue;
            };
            if kind.node != "sector" {
                self.err(
                    Diagnostic::error(
                        kind.span,
                        format!("unknown rule construction `{}`", kind.node),
                    )
                    .with_label("the compiler builds `sector` rules")
                    .with_help(
                        "write `rules sector;`, or write the rules with `rule R1: ... => ...;`",
                    ),
                );
                ok = false;
            }
        }
        for it in items.iter().skip(1) {
            self.err(
                Diagnostic::error(it.span, "`rules` is given twice")
                    .with_secondary(first.span, "first given here"),
            );
            ok = false;
        }
        for it in rule_items {
            self.err(
                Diagnostic::error(it.span, "a `rule` beside `rules sector;`")
                    .with_secondary(
                        first.span,
                        "the compiler builds every rule from the sector premises",
                    )
                    .with_help("remove this rule, or remove `rules sector;` and write every rule"),
            );
            ok = false;
        }
        let sector = self.sector_premises(premises, first.span);
        match (ok, sector) {
            // A matrix of the wrong shape was reported by `check_model`.
            (true, Some(idx)) if self.sector_shapes(&matrices) => {
                self.sector_model(first.span, idx, premises, matrices, dims)
            }
            _ => Built::Failed,
        }
    }

    /// Whether every state-dependent matrix has its declared shape (the
    /// fit indexes its entries by that shape).
    fn sector_shapes(&self, matrices: &Matrices<'_>) -> bool {
        let env = self.state_env(Mode::Shapes, &[], &[]);
        matrices.iter().all(|(_, mm, rows, cols)| {
            mm.filter(|m| m.state_dependent).is_none_or(|mm| {
                self.evaluate(&env, &mm.expr)
                    .is_ok_and(|v| (v.nrows(), v.ncols()) == (*rows, *cols))
            })
        })
    }

    /// The sector premises (scalar, with a range, no sets), checked.
    fn sector_premises(&mut self, premises: &[Premise], at: Span) -> Option<Vec<usize>> {
        let mut idx = Vec::new();
        let mut ok = true;
        for (k, p) in premises.iter().enumerate() {
            if !p.sets.is_empty() {
                self.err(
                    Diagnostic::error(
                        p.span,
                        format!("premise `{}` declares sets beside `rules sector;`", p.name),
                    )
                    .with_secondary(at, "the sector sets `max` and `min` are built here")
                    .with_help(format!(
                        "write `premise {} ... range lo .. hi;` without sets",
                        p.name
                    )),
                );
                ok = false;
            } else if p.dim != 1 {
                self.err(
                    Diagnostic::error(p.span, format!("premise `{}` is a vector: a sector premise is a scalar", p.name))
                        .with_help("bind one scalar premise per component: `premise a, b, c = v range lo .. hi;`"),
                );
                ok = false;
            } else {
                match p.range {
                    Some((lo, hi)) if hi > lo => idx.push(k),
                    Some(_) => {
                        self.err(
                            Diagnostic::error(
                                p.span,
                                format!("premise `{}` has an empty range", p.name),
                            )
                            .with_help("a sector premise needs `range lo .. hi` with lo < hi"),
                        );
                        ok = false;
                    }
                    None => {
                        self.err(
                            Diagnostic::error(p.span, format!("sector premise `{}` has no range", p.name))
                                .with_label("the sector is [lo, hi]: the bounds of this premise over the operating region")
                                .with_help(format!("write `premise {} ... range lo .. hi;`", p.name)),
                        );
                        ok = false;
                    }
                }
            }
        }
        // No premise at all after premise items were declared: they failed
        // and were reported already.
        if ok && idx.is_empty() && !(premises.is_empty() && self.has_errors()) {
            self.err(
                Diagnostic::error(at, "`rules sector;` has no sector premise")
                    .with_help("declare each bounded nonlinear term as a premise with a range, e.g. `premise z = x1 range -25 .. 25;`"),
            );
            return None;
        }
        if idx.is_empty() {
            return None;
        }
        if idx.len() > MAX_SECTOR_PREMISES {
            self.err(
                Diagnostic::error(
                    at,
                    format!(
                        "{} sector premises: at most {MAX_SECTOR_PREMISES} ({} rules)",
                        idx.len(),
                        1usize << MAX_SECTOR_PREMISES
                    ),
                )
                .with_help("write fewer premises, or write the rules with `rule`"),
            );
            return None;
        }
        ok.then_some(idx)
    }

    /// The sampling box: a state that is itself a sector premise spans its range.
    fn sample_box(&self, premises: &[Premise], idx: &[usize], n: usize) -> Vec<(f64, f64)> {
        let mut b = vec![(-1.0, 1.0); n];
        for &k in idx {
            let p = &premises[k];
            let crate::ast::ExprKind::Name(name) = &p.expr.kind else {
                continue;
            };
            if let (Some(s), Some(r)) = (self.states.iter().find(|s| &s.name == name), p.range) {
                if s.len == 1 {
                    b[s.offset] = r;
                }
            }
        }
        b
    }

    /// Values of the sector premises and of the state-dependent matrices at `x`
    /// (`None` if anything is not finite or fails to evaluate).
    fn sector_sample(
        &self,
        x: &[f64],
        premises: &[Premise],
        idx: &[usize],
        matrices: &Matrices<'_>,
    ) -> Option<(Vec<f64>, Vec<f64>)> {
        let mut env = self.state_env(Mode::Exact, &[], &[]);
        env.locals
            .push(("x".into(), Mat::from_column_slice(x.len(), 1, x)));
        for s in &self.states {
            let v = &x[s.offset..s.offset + s.len];
            env.locals
                .push((s.name.clone(), Mat::from_column_slice(v.len(), 1, v)));
        }
        let mut z = Vec::with_capacity(idx.len());
        for &k in idx {
            let p = &premises[k];
            let v = self.evaluate(&env, &p.expr).ok()?;
            z.push(*v.get(p.component.unwrap_or(0))?);
        }
        let mut y = Vec::new();
        for (_, mm, rows, cols) in matrices {
            if let Some(mm) = mm.filter(|m| m.state_dependent) {
                let v = self.evaluate(&env, &mm.expr).ok()?;
                if (v.nrows(), v.ncols()) != (*rows, *cols) {
                    return None;
                }
                y.extend(v.iter().copied());
            }
        }
        (z.iter().chain(&y).all(|v| v.is_finite())).then_some((z, y))
    }

    fn sector_model(
        &mut self,
        span: Span,
        idx: Vec<usize>,
        premises: &mut [Premise],
        matrices: Matrices<'_>,
        dims: Dims,
    ) -> Built {
        let p = idx.len();
        let monomials = 1usize << p;
        let wanted = (16 * monomials).clamp(64, 1024);
        let sample_box = self.sample_box(premises, &idx, dims.n);
        let bases = primes(dims.n.max(1));
        let ranges: Vec<(f64, f64)> = idx
            .iter()
            .map(|&k| premises[k].range.unwrap_or((-1.0, 1.0)))
            .collect();
        let (mut rows, mut ys, mut xs, mut ts) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for i in 1..=wanted as u64 {
            let x: Vec<f64> = sample_box
                .iter()
                .zip(&bases)
                .map(|(&(lo, hi), &b)| lo + (hi - lo) * halton(i, b))
                .collect();
            if let Some((z, y)) = self.sector_sample(&x, premises, &idx, &matrices) {
                let t: Vec<f64> = z
                    .iter()
                    .zip(&ranges)
                    .map(|(v, (lo, hi))| (2.0 * v - lo - hi) / (hi - lo))
                    .collect();
                rows.push((0..monomials).map(|s| monomial(s, &t)).collect::<Vec<_>>());
                ts.push(t);
                ys.push(y);
                xs.push(x);
            }
            if self.budget.is_spent() {
                return Built::Failed;
            }
        }
        if rows.len() < 4 * monomials {
            self.err(
                Diagnostic::error(
                    span,
                    "the model is not finite on enough sampled states to build the sector rules",
                )
                .with_label(format!(
                    "{} of {wanted} states give finite premises and A, B, D",
                    rows.len()
                ))
                .with_help("the model must be defined (finite) around the operating region"),
            );
            return Built::Failed;
        }
        let phi = Mat::from_fn(rows.len(), monomials, |r, c| rows[r][c]);
        let svd = phi.clone().svd(true, true);
        if !independent(&svd.singular_values) {
            let names: Vec<&str> = idx.iter().map(|&k| premises[k].name.as_str()).collect();
            // The premises whose removal leaves independent products.
            let removable: Vec<String> = (0..p)
                .filter(|&drop| {
                    let keep: Vec<usize> = (0..p).filter(|&q| q != drop).collect();
                    let sub = Mat::from_fn(ts.len(), 1 << keep.len(), |r, c| {
                        let t: Vec<f64> = keep.iter().map(|&q| ts[r][q]).collect();
                        monomial(c, &t)
                    });
                    independent(&sub.svd(false, false).singular_values)
                })
                .map(|k| format!("`{}`", names[k]))
                .collect();
            let help = if removable.is_empty() {
                "a premise that is a function of the others adds no information: remove it"
                    .to_string()
            } else {
                format!(
                    "{} is a function of the other premises: remove that premise (any one of them); the entries that used it are then fitted through the others and their products (each entry must be affine in each remaining premise, so a product such as s * c needs no premise of its own)",
                    removable.join(" or ")
                )
            };
            self.err(
                Diagnostic::error(
                    span,
                    "the sector premises are not independent on the sampled states",
                )
                .with_label(format!(
                    "the products of ({}) are linearly dependent",
                    names.join(", ")
                ))
                .with_help(help),
            );
            return Built::Failed;
        }
        let entries = match self.fit_entries(&svd, &phi, &ys, &xs, &matrices) {
            Ok(e) => e,
            Err(d) => {
                self.err(*d);
                return Built::Failed;
            }
        };
        let residual = entries.1;
        let rules = self.vertex_rules(span, &idx, premises, &matrices, &entries.0);
        Built::Sector(
            Box::new(SectorModel {
                premises: idx,
                sample_box,
                samples: rows.len(),
                residual,
                span,
            }),
            rules,
        )
    }

    /// The multilinear coefficients of every state-dependent entry, and the worst
    /// relative residual; an entry above [`FIT_TOLERANCE`] is an error.
    fn fit_entries(
        &self,
        svd: &nalgebra::SVD<f64, nalgebra::Dyn, nalgebra::Dyn>,
        phi: &Mat,
        ys: &[Vec<f64>],
        xs: &[Vec<f64>],
        matrices: &Matrices<'_>,
    ) -> Result<(Vec<Entry>, f64), Box<Diagnostic>> {
        let mut out = Vec::new();
        let mut worst = 0.0f64;
        let mut col = 0;
        for (mi, (name, mm, rows, cols)) in matrices.iter().enumerate() {
            let Some(mm) = mm.filter(|m| m.state_dependent) else {
                continue;
            };
            // Column-major, as the evaluator's matrices iterate.
            for c in 0..*cols {
                for r in 0..*rows {
                    let y = Mat::from_fn(ys.len(), 1, |k, _| ys[k][col]);
                    col += 1;
                    let coef = svd.solve(&y, 0.0).map_err(|e| {
                        Box::new(Diagnostic::error(
                            mm.span,
                            format!("internal error: sector fit: {e}"),
                        ))
                    })?;
                    let fit = phi * &coef;
                    let scale = 1.0 + y.amax();
                    let (k, err) = (0..ys.len())
                        .map(|k| (k, (fit[k] - y[k]).abs() / scale))
                        .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
                    if err.is_nan() || err > FIT_TOLERANCE {
                        let x = xs[k]
                            .iter()
                            .map(|v| format!("{v:.4}"))
                            .collect::<Vec<_>>()
                            .join(", ");
                        return Err(Box::new(
                            Diagnostic::error(
                                mm.expr.span,
                                format!("entry `{name}(x)[{r}, {c}]` (0-based, as the language indexes) is not affine in each sector premise"),
                            )
                            .with_label(format!("relative residual {err:.2e} (tolerance {FIT_TOLERANCE:.0e}) at x = [{x}]"))
                            .with_help("it has a nonlinear term no premise names: declare that term as a premise with its range, e.g. `premise z = <term> range lo .. hi;`"),
                        ));
                    }
                    worst = worst.max(err);
                    out.push(Entry {
                        matrix: mi,
                        row: r,
                        col: c,
                        coef: coef.iter().copied().collect(),
                    });
                }
            }
        }
        Ok((out, worst))
    }

    /// The 2^p rules: bit k of the vertex index (premise k, first premise most
    /// significant) picks `min` when set, `max` when clear.
    fn vertex_rules(
        &mut self,
        span: Span,
        idx: &[usize],
        premises: &mut [Premise],
        matrices: &Matrices<'_>,
        entries: &[Entry],
    ) -> Vec<RuleSpec> {
        let p = idx.len();
        for &k in idx {
            let pr = &mut premises[k];
            let (lo, hi) = pr.range.unwrap_or((-1.0, 1.0));
            pr.sets = vec![
                FuzzySet {
                    name: "max".into(),
                    shape: SetShape::Tri(lo, hi, hi),
                    span: pr.span,
                },
                FuzzySet {
                    name: "min".into(),
                    shape: SetShape::Tri(lo, lo, hi),
                    span: pr.span,
                },
            ];
        }
        (0..1usize << p)
            .map(|v| {
                let is_min = |k: usize| v & (1 << (p - 1 - k)) != 0;
                // Normalized vertex: t_k = +1 at max, -1 at min (monomial bit k = premise k).
                let t: Vec<f64> = (0..p).map(|k| if is_min(k) { -1.0 } else { 1.0 }).collect();
                let name = (0..p)
                    .map(|k| {
                        format!(
                            "{}_{}",
                            premises[idx[k]].name,
                            if is_min(k) { "min" } else { "max" }
                        )
                    })
                    .collect::<Vec<_>>()
                    .join("_");
                let clauses = (0..p)
                    .map(|k| RuleClause {
                        premise: idx[k],
                        set: ClauseSet::Named(usize::from(is_min(k))),
                        span,
                    })
                    .collect();
                let overrides = matrices
                    .iter()
                    .enumerate()
                    .filter(|(_, (_, mm, _, _))| mm.is_some_and(|m| m.state_dependent))
                    .map(|(mi, (name, _, rows, cols))| {
                        let mut m = Mat::zeros(*rows, *cols);
                        for e in entries.iter().filter(|e| e.matrix == mi) {
                            m[(e.row, e.col)] = e
                                .coef
                                .iter()
                                .enumerate()
                                .map(|(s, c)| c * monomial(s, &t))
                                .sum();
                        }
                        (name.to_string(), m, span)
                    })
                    .collect();
                RuleSpec {
                    name,
                    clauses,
                    at: None,
                    overrides,
                    gain: None,
                    span,
                }
            })
            .collect()
    }
}

/// Whether singular values show full column rank (smallest above 1e-9 of the
/// largest, none NaN).
fn independent(singular: &nalgebra::DVector<f64>) -> bool {
    let (smax, smin) = singular
        .iter()
        .fold((0.0f64, f64::INFINITY), |(a, b), &s| (a.max(s), b.min(s)));
    !(smin.is_nan() || smax.is_nan() || smin <= 1e-9 * smax)
}
