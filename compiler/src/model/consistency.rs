//! Model consistency: the T-S model the rules blend, sum_i h_i(z(x)) A_i,
//! compared with the state-dependent A(x) and B(x) it stands for, on a grid
//! of states spanning the rules' operating points. An exact sector model
//! gives 0; a rule whose local model is attached to the wrong sets does not.
//! Above [`MISMATCH_TOLERANCE`] the model stage warns, naming the rules that
//! fire where the mismatch is worst. Only the premise region counts (states
//! whose premise values leave the declared ranges are skipped). A grid state
//! where a premise or A(x), B(x) is not finite is an error (`finite.rs`).

use super::finite;
use super::premise::{premise_values, runtime_terms, PremiseLayout, TermSpec};
use super::LocalModel;
use crate::tape::lower::{Lowerer, Scope, Unsupported};
use crate::tape::{Builder, Id, Registers, Tape};
use nalgebra::DMatrix;
use tsf_lang::eval::Mode;
use tsf_lang::spec::{ModelMatrix, Spec};
use tsf_lang::Diagnostic;
use tsf_runtime::{Rule, Term};

/// Relative mismatch above which the model stage warns (25 %): the worst
/// `||sum_i h_i M_i - M(x)||_F / max_i ||M_i||_F` over the grid, M = A, B.
pub const MISMATCH_TOLERANCE: f64 = 0.25;

/// How the mismatch warning begins (so the driver can recognize it: the
/// plant claim takes its place when one is made).
const MISMATCH_HEADLINE: &str = "the rules blend a model that differs from";

/// Whether `d` is the model stage's mismatch warning.
pub fn is_mismatch_warning(d: &Diagnostic) -> bool {
    !d.is_error() && d.message.starts_with(MISMATCH_HEADLINE)
}

/// Most states evaluated (the grid per varying component shrinks to fit).
pub const MAX_POINTS: usize = 20_000;

/// Points per varying state component, at most.
const MAX_PER_AXIS: usize = 33;

/// Where the blended model and A(x), B(x) differ most.
#[derive(Debug, Clone, PartialEq)]
pub struct Consistency {
    /// States compared (inside the premise region).
    pub points: usize,
    /// Worst relative mismatch (Frobenius norm, relative to the largest local model).
    pub worst: f64,
    /// The matrix it is in (`A` or `B`).
    pub matrix: &'static str,
    /// The state where it is.
    pub at: Vec<f64>,
    /// Rules firing there, with their normalized weights h_i > 1 %.
    pub firing: Vec<(String, f64)>,
    /// The grid: the values of each state component (one value for a
    /// component that does not vary).
    pub axes: Vec<Vec<f64>>,
    /// Per state component k and grid value `axes[k][i]`: the worst relative
    /// mismatch over the compared states with x_k at that value (the maximum
    /// over the other components; 0 where no state was compared).
    pub profile: Vec<Vec<f64>>,
}

impl Consistency {
    /// One sentence of the worst sampled mismatch, e.g. "the rules' blend
    /// differs from A(x) by 32% at x = [-1, 0] (the largest on a grid of 441 states)".
    pub fn sentence(&self) -> String {
        let x = self
            .at
            .iter()
            .map(|v| format!("{v:.4}"))
            .collect::<Vec<_>>()
            .join(", ");
        format!(
            "the rules' blend differs from {}(x) by {:.0}% at x = [{x}] (the largest on a grid of {} states)",
            self.matrix,
            100.0 * self.worst,
            self.points
        )
    }
}

/// Grid bounds: from the smallest to the largest operating-point coordinate,
/// or the box a sector model was fitted on (its rules have no operating point).
pub(super) fn bounds(spec: &Spec, rules: &[LocalModel], n: usize) -> Vec<(f64, f64)> {
    if let Some(s) = &spec.sector {
        return s.sample_box.clone();
    }
    (0..n)
        .map(|k| {
            rules
                .iter()
                .filter_map(|r| r.at.as_ref().and_then(|x| x.get(k).copied()))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                    (lo.min(v), hi.max(v))
                })
        })
        .collect()
}

/// Grid axes over `bounds`, at most [`MAX_POINTS`] points in all.
fn axes(bounds: &[(f64, f64)]) -> Vec<Vec<f64>> {
    let varying = bounds.iter().filter(|(lo, hi)| hi > lo).count().max(1);
    let per_axis =
        ((MAX_POINTS as f64).powf(1.0 / varying as f64).floor() as usize).clamp(2, MAX_PER_AXIS);
    bounds
        .iter()
        .map(|&(lo, hi)| {
            if !(lo.is_finite() && hi.is_finite()) {
                vec![0.0]
            } else if hi > lo {
                (0..per_axis)
                    .map(|i| lo + (hi - lo) * i as f64 / (per_axis - 1) as f64)
                    .collect()
            } else {
                vec![lo]
            }
        })
        .collect()
}

/// Compares the blended model with A(x), B(x); `None` when neither depends
/// on the state (nothing to compare with) or no rule has an operating point
/// (and no sector model built them).
pub(super) fn check(
    spec: &Spec,
    rules: &[LocalModel],
    layout: &PremiseLayout,
    terms: &[Vec<TermSpec>],
    diags: &mut Vec<Diagnostic>,
) -> Option<Consistency> {
    let dependent = |m: &Option<ModelMatrix>| m.as_ref().filter(|m| m.state_dependent).cloned();
    let targets: Vec<(&'static str, ModelMatrix, Vec<&DMatrix<f64>>)> = [
        (
            "A",
            dependent(&spec.a),
            rules.iter().map(|r| &r.a).collect(),
        ),
        (
            "B",
            dependent(&spec.b),
            rules.iter().map(|r| &r.b).collect(),
        ),
    ]
    .into_iter()
    .filter_map(|(name, m, locals)| m.map(|m| (name, m, locals)))
    .collect();
    if targets.is_empty() || (rules.iter().all(|r| r.at.is_none()) && spec.sector.is_none()) {
        return None;
    }
    let ranges = layout.component_ranges();
    let grid = axes(&bounds(spec, rules, spec.n()));
    let mut idx = vec![0usize; grid.len()];
    let mut worst = Consistency {
        points: 0,
        worst: 0.0,
        matrix: "A",
        at: Vec::new(),
        firing: Vec::new(),
        profile: grid.iter().map(|a| vec![0.0; a.len()]).collect(),
        axes: grid.clone(),
    };
    let mut worst_h = Vec::new();
    let exprs: Vec<&ModelMatrix> = targets.iter().map(|(_, m, _)| m).collect();
    let mut compiled = Compiled::new(spec, &exprs);
    // ||M_i||_F of the largest local model, per target.
    let scales: Vec<f64> = targets
        .iter()
        .map(|(_, _, locals)| {
            locals
                .iter()
                .map(|l| l.norm())
                .fold(f64::MIN_POSITIVE, f64::max)
        })
        .collect();
    let terms = runtime_terms(terms);
    let mut x = vec![0.0; grid.len()];
    let mut h = vec![0.0; rules.len()];
    let mut blend = Vec::new();
    let mut not_finite = None;
    loop {
        for ((v, &i), a) in x.iter_mut().zip(&idx).zip(&grid) {
            *v = a[i];
        }
        let fast = compiled.as_mut().is_some_and(|c| c.eval(&x));
        // A state where a premise or matrix is not finite (or the tape
        // faults: a division by 0) is diagnosed by the interpreter.
        let (fired, mut suspicious) = match (fast, &compiled) {
            (true, Some(c)) => (
                normalized_weights(c.premises(), &ranges, &terms, &mut h),
                c.out.iter().any(|v| !v.is_finite()),
            ),
            _ => match premise_values(spec, &x) {
                Ok(z) => (
                    normalized_weights(&z, &ranges, &terms, &mut h),
                    z.iter().any(|v| !v.is_finite()),
                ),
                Err(_) => (false, true),
            },
        };
        if fired {
            worst.points += 1;
            let env = (!fast).then(|| spec.state_env(&x, Mode::Exact));
            for (k, (name, m, locals)) in targets.iter().enumerate() {
                let interpreted;
                let (exact, shape) = match (&compiled, &env) {
                    (Some(c), None) => c.matrix(k),
                    (_, Some(env)) => match env.eval(&m.expr) {
                        Ok(v) => {
                            interpreted = v;
                            (interpreted.as_slice(), interpreted.shape())
                        }
                        Err(_) => {
                            suspicious = true;
                            continue;
                        }
                    },
                    (None, None) => continue,
                };
                // (The compiled outputs were all tested above.)
                suspicious |= env.is_some() && exact.iter().any(|v| !v.is_finite());
                let rel = blend_distance(&h, locals, exact, shape, &mut blend) / scales[k];
                for (row, &i) in worst.profile.iter_mut().zip(&idx) {
                    row[i] = row[i].max(rel);
                }
                if rel > worst.worst {
                    worst.worst = rel;
                    worst.matrix = name;
                    worst.at = x.clone();
                    worst_h = h.clone();
                }
            }
        }
        if suspicious && not_finite.is_none() {
            not_finite = finite::diagnose_at(spec, &x);
        }
        // Odometer over the grid.
        let mut k = 0;
        while k < idx.len() {
            idx[k] += 1;
            if idx[k] < grid[k].len() {
                break;
            }
            idx[k] = 0;
            k += 1;
        }
        if k == idx.len() {
            break;
        }
    }
    worst.firing = rules
        .iter()
        .zip(&worst_h)
        .filter(|(_, h)| **h > 0.01)
        .map(|(r, h)| (r.name.clone(), *h))
        .collect();
    if let Some(d) = not_finite {
        diags.push(d);
        return None;
    }
    if worst.worst > MISMATCH_TOLERANCE {
        diags.push(warning(spec, &worst, &targets));
    }
    Some(worst)
}

/// The premise values z(x) and the state-dependent matrices of the check,
/// compiled once into a tape (the interpreter's values to rounding); a state
/// where the tape faults (a division by 0) goes to the interpreter, and so
/// does every state when an expression has no tape form.
struct Compiled {
    tape: Tape,
    regs: Box<Registers>,
    /// Number of premise values (the first outputs).
    nz: usize,
    /// Shapes of the matrices that follow, column-major.
    shapes: Vec<(usize, usize)>,
    out: Vec<f64>,
}

impl Compiled {
    fn new(spec: &Spec, mats: &[&ModelMatrix]) -> Option<Self> {
        let g = StateGraph::lower(spec, mats).ok()?;
        let tape = g.builder.finish(&g.outputs)?;
        Some(Compiled {
            regs: tape.registers(),
            out: vec![0.0; g.outputs.len()],
            tape,
            nz: g.nz,
            shapes: g.shapes,
        })
    }

    /// Evaluates z(x) and the matrices at `x`; `false` where the tape faults.
    fn eval(&mut self, x: &[f64]) -> bool {
        self.tape.write(&mut self.regs, 0, x);
        if self.tape.run(&mut self.regs).is_err() {
            return false;
        }
        self.tape.read(&self.regs, &mut self.out);
        true
    }

    /// z of the last [`Compiled::eval`].
    fn premises(&self) -> &[f64] {
        &self.out[..self.nz]
    }

    /// Matrix `k` of the last [`Compiled::eval`], column-major, and its shape.
    fn matrix(&self, k: usize) -> (&[f64], (usize, usize)) {
        let at = self.nz + self.shapes[..k].iter().map(|(r, c)| r * c).sum::<usize>();
        let (r, c) = self.shapes[k];
        (&self.out[at..at + r * c], (r, c))
    }
}

/// The premise values z(x) and matrices of state expressions as one graph
/// over the state (the interpreter's bindings, `Spec::state_env`): shared by
/// the consistency grid and the model-error bound.
pub(super) struct StateGraph {
    /// The graph.
    pub builder: Builder,
    /// Its outputs: z, then each matrix column-major.
    pub outputs: Vec<Id>,
    /// Number of premise values (the first outputs).
    pub nz: usize,
    /// Shapes of the matrices that follow.
    pub shapes: Vec<(usize, usize)>,
}

impl StateGraph {
    /// Lowers the premises and `mats`, or why they have no tape form.
    pub fn lower(spec: &Spec, mats: &[&ModelMatrix]) -> Result<StateGraph, Unsupported> {
        let n = spec.n();
        let mut lw = Lowerer::new(Builder::new(n), &spec.consts, &spec.fns);
        let mut scope = vec![("x".to_string(), lw.inputs(0, n))];
        scope.extend(lw.bind(&spec.states, 0));
        let scope: &Scope = &scope;
        let mut outputs = Vec::new();
        for p in &spec.premises {
            let v = lw.expr(&p.expr, scope)?;
            match p.component {
                Some(k) => outputs.push(
                    *v.data
                        .get(k)
                        .ok_or_else(|| Unsupported("premise component".into()))?,
                ),
                None => outputs.extend(v.data),
            }
        }
        let nz = outputs.len();
        let mut shapes = Vec::with_capacity(mats.len());
        for m in mats {
            let v = lw.expr(&m.expr, scope)?;
            shapes.push((v.rows, v.cols));
            outputs.extend(v.data);
        }
        Ok(StateGraph {
            builder: lw.b,
            outputs,
            nz,
            shapes,
        })
    }
}

/// ||sum_i h_i M_i - exact||_F (column-major `exact` of `shape`; local
/// models of another shape are left out), accumulated in `blend` (reused).
fn blend_distance(
    h: &[f64],
    locals: &[&DMatrix<f64>],
    exact: &[f64],
    shape: (usize, usize),
    blend: &mut Vec<f64>,
) -> f64 {
    blend.clear();
    blend.resize(exact.len(), 0.0);
    // A rule of weight 0 adds 0 * v: at most a -0 becomes +0, whose
    // squared difference is the same, so it is left out.
    for (hi, l) in h
        .iter()
        .zip(locals)
        .filter(|(hi, l)| **hi != 0.0 && l.shape() == shape)
    {
        for (b, v) in blend.iter_mut().zip(l.as_slice()) {
            *b += hi * v;
        }
    }
    blend
        .iter()
        .zip(exact)
        .map(|(b, v)| (b - v) * (b - v))
        .sum::<f64>()
        .sqrt()
}

/// Normalized rule weights at premise values `z` into `h` (`terms`: each
/// rule's, from [`runtime_terms`]): `true` if the values lie in the declared
/// ranges and some rule fires.
pub(super) fn normalized_weights(
    z: &[f64],
    ranges: &[(f64, f64)],
    terms: &[Vec<Term<'_, f64>>],
    h: &mut [f64],
) -> bool {
    let inside = z.len() == ranges.len()
        && z.iter()
            .zip(ranges)
            .all(|(v, (lo, hi))| *v >= *lo && *v <= *hi);
    if !inside {
        return false;
    }
    let mut total = 0.0;
    for (w, t) in h.iter_mut().zip(terms) {
        *w = Rule::new(t).weight(z);
        total += *w;
    }
    if !(total > 0.0 && total.is_finite()) {
        return false;
    }
    for w in h.iter_mut() {
        *w /= total;
    }
    true
}

fn warning(
    spec: &Spec,
    c: &Consistency,
    targets: &[(&'static str, ModelMatrix, Vec<&DMatrix<f64>>)],
) -> Diagnostic {
    let span = targets
        .iter()
        .find(|(n, _, _)| *n == c.matrix)
        .map_or(spec.controller.span, |(_, m, _)| m.span);
    let x =
        c.at.iter()
            .map(|v| format!("{v:.4}"))
            .collect::<Vec<_>>()
            .join(", ");
    let firing = c
        .firing
        .iter()
        .map(|(r, h)| format!("{r} (h = {h:.2})"))
        .collect::<Vec<_>>()
        .join(", ");
    let mut d = Diagnostic::warning(
        span,
        format!(
            "{MISMATCH_HEADLINE} {}(x) by {:.0}% at x = [{x}]; the certificate covers the blended model, not {}(x)",
            c.matrix,
            100.0 * c.worst,
            c.matrix
        ),
    )
    .with_label(format!("{}(x) defined here", c.matrix))
    .with_help(format!(
        "rules firing there: {firing}; check that each rule's sets match its operating point (where a rule fires alone its local model should equal {}(x)); tolerance {:.0}%",
        c.matrix,
        100.0 * MISMATCH_TOLERANCE
    ));
    for (r, _) in &c.firing {
        if let Some(rule) = spec.rules.iter().find(|s| s.name == *r) {
            d = d.with_secondary(rule.span, format!("rule {r} fires here"));
        }
    }
    d
}

#[cfg(test)]
mod tests {
    use super::{premise_values, Compiled};
    use tsf_lang::eval::Mode;

    const XU: &str = include_str!("../../../specs/xu2020_event_triggered.tsf");

    /// The compiled z(x), A(x), B(x) equal the interpreter's to rounding at
    /// random states of the Xu & Huang region (sqrt, skew, inv(J) products).
    #[test]
    fn compiled_grid_values_equal_the_interpreters() {
        let spec = tsf_lang::check_source(XU)
            .0
            .expect("the shipped spec checks"); // ok: unit test
        let a = spec.a.clone().expect("A(x)"); // ok: unit test
        let mut c = Compiled::new(&spec, &[&a]).expect("a tape"); // ok: unit test
        let mut rng = crate::util::rng::SplitMix64::new(17);
        for _ in 0..200 {
            let x: Vec<f64> = (0..6)
                .map(|k| {
                    let r = if k < 3 { 1.0 } else { 0.56 };
                    rng.uniform(-r, r)
                })
                .collect();
            assert!(c.eval(&x), "no division by 0");
            let z0 = premise_values(&spec, &x).expect("premises"); // ok: unit test
            let a0 = spec.state_env(&x, Mode::Exact).eval(&a.expr).expect("A(x)"); // ok: unit test
            assert_eq!(c.premises().len(), z0.len());
            for (p, q) in c.premises().iter().zip(&z0) {
                assert!((p - q).abs() <= 1e-15 * q.abs().max(1.0), "{p} vs {q}");
            }
            let (m, shape) = c.matrix(0);
            assert_eq!(shape, a0.shape());
            let d = (nalgebra::DMatrix::from_column_slice(6, 6, m) - &a0).amax();
            assert!(d <= 1e-13 * a0.amax().max(1.0), "A differs by {d}");
        }
    }
}
