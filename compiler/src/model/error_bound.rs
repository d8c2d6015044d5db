//! A rigorous bound of the model error on a box of states: for every state
//! x of the box whose premise values lie in their declared ranges,
//! `|A(x) - sum_i h_i(z(x)) A_i|` entrywise (and for B, and D when the spec
//! declares one) is at most the returned bound.
//!
//! Each sub-box is evaluated in affine arithmetic with outward rounding
//! (`tape::affine`; Stolfi and de Figueiredo, 1997): z(x) and the plant's
//! matrices from the spec's expressions lowered to the tape's graph, the
//! memberships and the normalization from their definitions, all on the same
//! noise symbols, so a blend that is affine in a premise (a `rules sector;`
//! model) cancels against A(x) to rounding. The box is refined by
//! branch and bound: the sub-box with the largest bound is bisected along
//! its widest component (relative to the region's width, among the states
//! the expressions read), in rounds that double the number of sub-boxes,
//! until a round improves the bound by less than
//! [`BoundLimits::min_improvement`] or [`BoundLimits::max_boxes`] sub-boxes
//! have been evaluated. The float error at each sub-box's centre is
//! recorded as a lower bound ([`ModelErrorBound::sampled_max`]). When the
//! rules are a full grid over two or more premises, the final sub-boxes are
//! bounded a second time with the blend contracted one premise at a time
//! (`grid`), and the smaller bound is kept per entry.

mod blend;
mod grid;
pub mod premise_range;

use super::consistency::{normalized_weights, StateGraph};
use super::premise::runtime_terms;
use super::TsModel;
use crate::tape::affine;
use blend::{Outcome, Problem};
use nalgebra::DMatrix;
use premise_range::PremiseRange;
use std::cmp::Ordering;
use std::collections::BinaryHeap;
use tsf_lang::spec::{ModelMatrix, Spec};
use tsf_lang::Diagnostic;

/// A state box: per state component, `[lo, hi]` (finite).
pub type StateBox = Vec<(f64, f64)>;

/// Most sub-boxes evaluated by default: 2^10, which keeps the Zhang spec
/// (n = 6, 9 rules, 72 entries) near 0.5 s on one core; finer refinement
/// of a 6-state box improves its bound by a few percent per doubling.
pub const MAX_BOXES: usize = 1024;

/// A refinement round improving the bound by less than this fraction stops it.
pub const MIN_IMPROVEMENT: f64 = 0.01;

/// The work limits of [`bound`].
#[derive(Debug, Clone, PartialEq)]
pub struct BoundLimits {
    /// Most sub-boxes evaluated.
    pub max_boxes: usize,
    /// Relative improvement of a round below which refinement stops.
    pub min_improvement: f64,
}

impl Default for BoundLimits {
    fn default() -> Self {
        BoundLimits {
            max_boxes: MAX_BOXES,
            min_improvement: MIN_IMPROVEMENT,
        }
    }
}

/// Rigorous bounds of the model error on a state box.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelErrorBound {
    /// `|A(x) - A_h(x)|_{kl} <= a_entry[(k, l)]` for every x in the box (n x n).
    pub a_entry: DMatrix<f64>,
    /// The same for B (n x m).
    pub b_entry: DMatrix<f64>,
    /// The same for D, when the spec declares D and has disturbances (n x q).
    pub d_entry: Option<DMatrix<f64>>,
    /// Upper bound of `max_x ||A(x) - A_h(x)||_2` (the largest spectral norm
    /// of a sub-box's entrywise bound, which bounds the error's norm there).
    pub a_norm: f64,
    /// The same for B.
    pub b_norm: f64,
    /// The same for D.
    pub d_norm: Option<f64>,
    /// Sub-boxes evaluated.
    pub boxes: usize,
    /// `true` when refinement stopped improving, `false` when the work limit cut it.
    pub converged: bool,
    /// Largest `||A - A_h||_2`, `||B - B_h||_2` found at the sub-boxes'
    /// centres (float evaluation): a lower bound of the true maximum.
    pub sampled_max: (f64, f64),
    /// Whether every premise value of every state of the box is proved in
    /// its declared range ([`premise_range::check`]); where it is not, the
    /// blend is not defined and the bound covers only the states in range.
    pub premise: PremiseRange,
    /// `true` when a function's argument was clipped to its domain
    /// (`sqrt` of a range reaching below 0): the bound holds where the
    /// plant's expressions are real.
    pub clipped: bool,
}

/// The box the consistency check samples: the span of the rules' operating
/// points, or the box a sector model was fitted on; `None` when a component
/// has no finite bounds.
pub fn default_region(model: &TsModel) -> Option<StateBox> {
    let b = super::consistency::bounds(&model.spec, &model.rules, model.n);
    b.iter()
        .all(|(lo, hi)| lo.is_finite() && hi.is_finite() && lo <= hi)
        .then_some(b)
}

/// A sub-box and its bound.
struct Leaf {
    bx: StateBox,
    /// Per target: the entrywise bound (`None`: unbounded).
    mats: Option<Vec<DMatrix<f64>>>,
}

/// Heap key: the score, largest first.
struct Key(f64, usize);

impl PartialEq for Key {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Key {}
impl PartialOrd for Key {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Key {
    fn cmp(&self, other: &Self) -> Ordering {
        self.0.total_cmp(&other.0).then(other.1.cmp(&self.1))
    }
}

/// An upper bound of the spectral norm of a nonnegative matrix: the smaller
/// of its Frobenius norm (rounded up) and its largest singular value widened
/// by 1e-12 (relative; far above the SVD's rounding).
fn spectral_up(m: &DMatrix<f64>) -> f64 {
    let ss = m
        .iter()
        .fold(0.0, |s, v| affine::add_up(s, affine::mul_up(*v, *v)));
    let frob = ss.sqrt() * (1.0 + 4.0 * f64::EPSILON);
    if m.is_empty() {
        return 0.0;
    }
    let sv = m.singular_values().max() * (1.0 + 1e-12) + f64::MIN_POSITIVE;
    if sv.is_finite() {
        frob.min(sv)
    } else {
        frob
    }
}

/// The error bound of `model` (built from `spec`) on `region`.
pub fn bound(
    model: &TsModel,
    spec: &Spec,
    region: &StateBox,
    limits: &BoundLimits,
) -> Result<ModelErrorBound, Diagnostic> {
    let fail = |msg: String| Diagnostic::error(spec.controller.span, msg);
    let n = spec.n();
    if !well_formed(region, n) {
        return Err(fail(format!(
            "the model-error bound needs a box of the {n} states (lo <= hi each)"
        )));
    }
    let (Some(a), Some(b)) = (&spec.a, &spec.b) else {
        return Err(fail(
            "the model-error bound compares the rules with the plant's A(x) and B(x); the spec declares no A or no B".into(),
        ));
    };
    let mut mats: Vec<&ModelMatrix> = vec![a, b];
    let with_d = model.q > 0 && spec.d.is_some();
    if let (true, Some(d)) = (with_d, &spec.d) {
        mats.push(d);
    }
    let graph = StateGraph::lower(spec, &mats).map_err(|e| {
        fail(format!(
            "the model-error bound evaluates the premises and A(x), B(x) on the tape, which cannot express them: {}",
            e.0
        ))
    })?;
    let locals = |k: usize| -> Vec<&DMatrix<f64>> {
        model.rules.iter().map(|r| [&r.a, &r.b, &r.d][k]).collect()
    };
    let targets: Vec<_> = graph
        .shapes
        .iter()
        .enumerate()
        .map(|(k, s)| (*s, locals(k)))
        .collect();
    let scales: Vec<f64> = targets
        .iter()
        .map(|(_, l)| l.iter().map(|m| m.norm()).fold(f64::MIN_POSITIVE, f64::max))
        .collect();
    let ranges = model.premises.component_ranges();
    let deps = affine::depends_on(&graph.builder, &graph.outputs);
    let region: &StateBox = &pinned(region, &deps).map_err(|k| {
        fail(format!(
            "the model-error bound needs finite bounds of state component {k}, which the premises or A(x), B(x) read"
        ))
    })?;
    let premise = premise_range::check(&graph.builder, &graph.outputs[..graph.nz], &ranges, region);
    let sampler = graph
        .builder
        .clone()
        .finish(&graph.outputs)
        .ok_or_else(|| fail("the model-error bound's tape is too large".into()))?;
    let problem = Problem {
        builder: graph.builder,
        outputs: graph.outputs,
        nz: graph.nz,
        targets,
        ranges,
        terms: &model.terms,
        grid: grid::Grid::of(&model.terms),
    };
    let mut sample = Sampler::new(&problem, sampler);
    let score = |mats: &Option<Vec<DMatrix<f64>>>| match mats {
        None => f64::INFINITY,
        Some(m) => m.iter().zip(&scales).map(|(m, s)| m.norm() / s).sum(),
    };
    let mut leaves: Vec<Leaf> = Vec::new();
    let mut heap = BinaryHeap::new();
    let mut boxes = 0;
    let mut clipped = false;
    let mut push = |bx: StateBox, leaves: &mut Vec<Leaf>, heap: &mut BinaryHeap<Key>| {
        boxes += 1;
        sample.at(&bx, &problem);
        let (outcome, clip) = problem.evaluate(&bx, false);
        clipped |= clip;
        let mats = match outcome {
            Outcome::Empty => return,
            Outcome::Unbounded => None,
            Outcome::Bounded(m) => Some(m),
        };
        let s = score(&mats);
        heap.push(Key(s, leaves.len()));
        leaves.push(Leaf { bx, mats });
    };
    push(region.clone(), &mut leaves, &mut heap);
    let relevant = deps.iter().filter(|d| **d).count().max(1);
    let each = premise_range::reads_each(&problem.builder, &problem.outputs[..problem.nz]);
    let split_axis = |leaf: &Leaf| split_axis(&problem, leaf, region, &deps, &each);
    let top = |heap: &BinaryHeap<Key>| heap.peek().map_or(0.0, |k| k.0);
    let mut prev = top(&heap);
    let mut converged = false;
    'rounds: loop {
        if top(&heap) == 0.0 || heap.is_empty() {
            converged = true;
            break;
        }
        let splits = heap.len().max(2 * relevant);
        for _ in 0..splits {
            if leaves.len() + 2 > limits.max_boxes {
                break 'rounds;
            }
            let Some(Key(s, i)) = heap.pop() else { break };
            let Some(k) = split_axis(&leaves[i]) else {
                // The worst sub-box is a point of the states read: done.
                heap.push(Key(s, i));
                converged = true;
                break 'rounds;
            };
            let bx = leaves[i].bx.clone();
            let mid = 0.5 * bx[k].0 + 0.5 * bx[k].1;
            let (mut left, mut right) = (bx.clone(), bx);
            left[k].1 = mid;
            right[k].0 = mid;
            push(left, &mut leaves, &mut heap);
            push(right, &mut leaves, &mut heap);
        }
        let now = top(&heap);
        if now > (1.0 - limits.min_improvement) * prev {
            converged = true;
            break;
        }
        prev = now;
    }
    let contracted = with_contracted_blend(&problem, &leaves, &heap);
    finish(
        &problem,
        contracted.iter().collect(),
        (boxes, clipped, premise),
        converged,
        with_d,
        sample,
        fail,
    )
}

/// The state to split `leaf` along: the widest (relative to `region`) of
/// the states the targets read (`deps`); an unbounded sub-box (where the
/// blend's enclosure breaks down) along the widest state read by the premises
/// whose enclosure leaves its range there, when there are such (`each`: the
/// states each premise reads). `None` when every state read is a point.
fn split_axis(
    problem: &Problem,
    leaf: &Leaf,
    region: &StateBox,
    deps: &[bool],
    each: &[Vec<bool>],
) -> Option<usize> {
    let bx = &leaf.bx;
    let widest = |mask: &[bool]| {
        (0..bx.len())
            .filter(|&k| mask[k] && deps[k] && bx[k].1 > bx[k].0)
            .map(|k| (k, (bx[k].1 - bx[k].0) / (region[k].1 - region[k].0)))
            .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)))
            .map(|(k, _)| k)
    };
    let leaving = leaf.mats.is_none().then(|| {
        premise_range::unproved_reads(
            &problem.builder,
            &problem.outputs[..problem.nz],
            &problem.ranges,
            bx,
            each,
        )
    });
    leaving
        .flatten()
        .and_then(|mask| widest(&mask))
        .or_else(|| widest(deps))
}

/// The live sub-boxes of the refinement (which follows the flat bound),
/// bounded with the grid's contracted blend too when the rules are a full
/// grid: the smaller bound is kept per entry (both enclose the same value).
fn with_contracted_blend(problem: &Problem, leaves: &[Leaf], heap: &BinaryHeap<Key>) -> Vec<Leaf> {
    heap.iter()
        .map(|k| {
            let l = &leaves[k.1];
            let mats = match (&l.mats, problem.grid.is_some()) {
                (Some(flat), true) => match problem.evaluate(&l.bx, true).0 {
                    Outcome::Bounded(g) => Some(
                        flat.iter()
                            .zip(&g)
                            .map(|(f, g)| f.zip_map(g, f64::min))
                            .collect(),
                    ),
                    _ => Some(flat.clone()),
                },
                (m, _) => m.clone(),
            };
            Leaf {
                bx: l.bx.clone(),
                mats,
            }
        })
        .collect()
}

/// `n` intervals, each lo <= hi (no NaN; infinite ends allowed).
fn well_formed(region: &StateBox, n: usize) -> bool {
    region.len() == n
        && region
            .iter()
            .all(|(lo, hi)| lo.partial_cmp(hi).is_some_and(|o| o.is_le()))
}

/// `region` with every state no premise and no entry reads pinned at 0 (its
/// value does not matter, so it may be unbounded); `Err(k)`: state k is read
/// but unbounded.
fn pinned(region: &StateBox, deps: &[bool]) -> Result<StateBox, usize> {
    region
        .iter()
        .zip(deps)
        .enumerate()
        .map(|(k, (&(lo, hi), &read))| match read {
            false => Ok((0.0, 0.0)),
            true if lo.is_finite() && hi.is_finite() => Ok((lo, hi)),
            true => Err(k),
        })
        .collect()
}

/// The result from the final sub-boxes.
#[allow(clippy::too_many_arguments)]
fn finish(
    problem: &Problem,
    live: Vec<&Leaf>,
    (boxes, clipped, premise): (usize, bool, PremiseRange),
    converged: bool,
    with_d: bool,
    sample: Sampler,
    fail: impl Fn(String) -> Diagnostic,
) -> Result<ModelErrorBound, Diagnostic> {
    if live.is_empty() {
        return Err(fail(
            "no state of the box has its premise values inside their declared ranges: the rules' blend is not defined there".into(),
        ));
    }
    if let Some(l) = live.iter().find(|l| l.mats.is_none()) {
        let bx =
            l.bx.iter()
                .map(|(lo, hi)| format!("[{lo:.4}, {hi:.4}]"))
                .collect::<Vec<_>>()
                .join(", ");
        return Err(fail(format!(
            "the model error is not bounded on the box: on the sub-box {bx} an expression divides by a range containing 0 (or leaves its domain), after {boxes} sub-boxes"
        ))
        .with_help("shrink the box away from the singularity"));
    }
    let count = problem.targets.len();
    let mut entry: Vec<DMatrix<f64>> = problem
        .targets
        .iter()
        .map(|((r, c), _)| DMatrix::zeros(*r, *c))
        .collect();
    let mut norm = vec![0.0f64; count];
    for l in &live {
        for (k, m) in l.mats.iter().flatten().enumerate() {
            entry[k] = entry[k].zip_map(m, f64::max);
            norm[k] = norm[k].max(spectral_up(m));
        }
    }
    let d_entry = with_d.then(|| entry[2].clone());
    Ok(ModelErrorBound {
        a_entry: entry[0].clone(),
        b_entry: entry[1].clone(),
        d_entry,
        a_norm: norm[0],
        b_norm: norm[1],
        d_norm: with_d.then(|| norm[2]),
        boxes,
        converged,
        sampled_max: (sample.max[0], sample.max[1]),
        premise,
        clipped,
    })
}

/// The float model error at sub-box centres (a lower bound of the maximum).
struct Sampler<'a> {
    tape: crate::tape::Tape,
    /// The rules' terms in the runtime's form.
    rules: Vec<Vec<tsf_runtime::Term<'a, f64>>>,
    regs: Box<crate::tape::Registers>,
    out: Vec<f64>,
    h: Vec<f64>,
    /// Largest spectral norm per target.
    max: Vec<f64>,
}

impl<'a> Sampler<'a> {
    fn new(problem: &Problem<'a>, tape: crate::tape::Tape) -> Self {
        Sampler {
            rules: runtime_terms(problem.terms),
            regs: tape.registers(),
            out: vec![0.0; problem.outputs.len()],
            h: vec![0.0; problem.terms.len()],
            max: vec![0.0; problem.targets.len()],
            tape,
        }
    }

    /// Records the error at the centre of `bx` (`problem` gives the rules).
    fn at(&mut self, bx: &[(f64, f64)], problem: &Problem) {
        let x: Vec<f64> = bx.iter().map(|(lo, hi)| 0.5 * lo + 0.5 * hi).collect();
        self.tape.write(&mut self.regs, 0, &x);
        if self.tape.run(&mut self.regs).is_err() {
            return;
        }
        self.tape.read(&self.regs, &mut self.out);
        let z = &self.out[..problem.nz];
        if !normalized_weights(z, &problem.ranges, &self.rules, &mut self.h) {
            return;
        }
        let mut at = problem.nz;
        for (k, ((rows, cols), locals)) in problem.targets.iter().enumerate() {
            let exact = DMatrix::from_column_slice(*rows, *cols, &self.out[at..at + rows * cols]);
            let mut blend = DMatrix::zeros(*rows, *cols);
            for (hi, l) in self.h.iter().zip(locals) {
                if l.shape() == (*rows, *cols) {
                    blend += *l * *hi;
                }
            }
            let e = (blend - exact).singular_values().max();
            if e.is_finite() {
                self.max[k] = self.max[k].max(e);
            }
            at += rows * cols;
        }
    }
}
