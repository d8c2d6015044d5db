//! The premise-range check of a region: every premise value z(x) of every
//! state x of the box lies in its declared range (where the rules' blend,
//! hence the model-error bound, is defined), proved with the affine
//! enclosures of z over sub-boxes (outward rounding), not sampled.
//!
//! A sub-box whose enclosure of some z leaves the range is bisected along its
//! widest component (relative to the region's width, among the states read
//! by the premises not yet proved inside on it), breadth first, until every enclosure lies inside the
//! range ([`PremiseRange::Inside`]), the float value of z at a sub-box's
//! centre lies outside it ([`PremiseRange::Leaves`], a witness state), or
//! [`MAX_PREMISE_BOXES`] sub-boxes have been evaluated
//! ([`PremiseRange::Unproven`]). An enclosure may exceed a range end by
//! [`RANGE_SLACK`] times max(1, |end|): a premise whose maximum is its range
//! end (sinc(theta) = 1 at theta = 0) cannot be enclosed below that end by
//! outward-rounded arithmetic.

use crate::tape::affine::{self, Affine, Form, Noise};
use crate::tape::{Builder, Id};
use std::collections::VecDeque;

/// Most sub-boxes the check evaluates before it gives up (unproven).
pub const MAX_PREMISE_BOXES: usize = 4096;

/// Relative slack of a range end (the rounding of an enclosure that reaches it).
pub const RANGE_SLACK: f64 = 1e-12;

/// The verdict of the premise-range check.
#[derive(Debug, Clone, PartialEq)]
pub enum PremiseRange {
    /// Every premise value of every state of the box is in its range.
    Inside {
        /// Sub-boxes evaluated.
        boxes: usize,
    },
    /// The state `x` has premise value `z` (number `premise`) outside its range.
    Leaves {
        /// Index of the premise value (in the premise layout).
        premise: usize,
        /// The state.
        x: Vec<f64>,
        /// Its premise value.
        z: f64,
    },
    /// The work limit was hit before every sub-box was proved inside.
    Unproven {
        /// A sub-box still unproved.
        bx: Vec<(f64, f64)>,
    },
}

impl PremiseRange {
    /// Whether every premise value is proved inside its range.
    pub fn is_inside(&self) -> bool {
        matches!(self, PremiseRange::Inside { .. })
    }
}

/// `v` inside `[lo, hi]` up to the slack of the range's ends.
fn within(v: (f64, f64), (lo, hi): (f64, f64)) -> bool {
    let slack = |e: f64| RANGE_SLACK * e.abs().max(1.0);
    v.0 >= lo - slack(lo) && v.1 <= hi + slack(hi)
}

/// Enclosures of the premise values `z` over the box `bx`.
fn enclose(builder: &Builder, z: &[Id], bx: &[(f64, f64)]) -> Vec<Form> {
    let mut noise = Noise::new(bx.len() as u32);
    noise.tight_ranges = true;
    let inputs: Vec<Form> = bx
        .iter()
        .enumerate()
        .map(|(k, &(lo, hi))| Affine::input(lo, hi, k as u32))
        .collect();
    affine::enclose(builder, z, &inputs, &mut noise)
}

/// Intervals of the premise values `z` over the one box `bx` (affine
/// arithmetic, outward rounding, no subdivision); `None` where unbounded.
pub fn on_box(builder: &Builder, z: &[Id], bx: &[(f64, f64)]) -> Vec<Option<(f64, f64)>> {
    enclose(builder, z, bx)
        .into_iter()
        .map(|f| f.ok().map(|f| f.range()))
        .collect()
}

/// Checks that every premise value `z` (outputs of `builder`, declared
/// `ranges`) stays in range over `region` (states no premise reads are
/// never split).
pub fn check(
    builder: &Builder,
    z: &[Id],
    ranges: &[(f64, f64)],
    region: &[(f64, f64)],
) -> PremiseRange {
    let each = reads_each(builder, z);
    let mut queue = VecDeque::from([region.to_vec()]);
    let mut boxes = 0;
    while let Some(bx) = queue.pop_front() {
        boxes += 1;
        let Some(reads) = unproved_reads(builder, z, ranges, &bx, &each) else {
            continue;
        };
        let x: Vec<f64> = bx.iter().map(|(lo, hi)| 0.5 * lo + 0.5 * hi).collect();
        let point: Vec<(f64, f64)> = x.iter().map(|v| (*v, *v)).collect();
        for (k, (f, r)) in enclose(builder, z, &point).iter().zip(ranges).enumerate() {
            if let Ok(f) = f {
                let v = f.center();
                if !within((v, v), *r) {
                    return PremiseRange::Leaves {
                        premise: k,
                        x,
                        z: v,
                    };
                }
            }
        }
        if boxes + queue.len() + 2 > MAX_PREMISE_BOXES {
            return PremiseRange::Unproven { bx };
        }
        let Some((left, right)) = bisect(&bx, region, &reads) else {
            // A point of the states read whose enclosure still leaves: no proof.
            return PremiseRange::Unproven { bx };
        };
        queue.push_back(left);
        queue.push_back(right);
    }
    PremiseRange::Inside { boxes }
}

/// Per premise value, the states it reads.
pub fn reads_each(builder: &Builder, z: &[Id]) -> Vec<Vec<bool>> {
    z.iter()
        .map(|id| affine::depends_on(builder, std::slice::from_ref(id)))
        .collect()
}

/// The states read by the premise values whose enclosure over `bx` is not
/// proved inside its range (`each`: [`reads_each`]); `None` when every one
/// is proved. Splitting only these states leaves the proved premises proved
/// (a sub-box's states are the box's) and spends no sub-box on a state only
/// proved premises read.
pub fn unproved_reads(
    builder: &Builder,
    z: &[Id],
    ranges: &[(f64, f64)],
    bx: &[(f64, f64)],
    each: &[Vec<bool>],
) -> Option<Vec<bool>> {
    let mut reads: Option<Vec<bool>> = None;
    for ((f, r), dep) in enclose(builder, z, bx).iter().zip(ranges).zip(each) {
        if !f.as_ref().is_ok_and(|f| within(f.range(), *r)) {
            let acc = reads.get_or_insert_with(|| vec![false; bx.len()]);
            acc.iter_mut().zip(dep).for_each(|(a, d)| *a |= *d);
        }
    }
    reads
}

/// A sub-box: per state, `[lo, hi]`.
type SubBox = Vec<(f64, f64)>;

/// The halves of the sub-box `bx` of `region`, split at the midpoint of its
/// widest component relative to the region's width, among the states
/// `reads` marks (ties: the first); `None` when each of those is a point.
fn bisect(bx: &[(f64, f64)], region: &[(f64, f64)], reads: &[bool]) -> Option<(SubBox, SubBox)> {
    let (k, _) = (0..bx.len())
        .filter(|&k| reads[k] && bx[k].1 > bx[k].0)
        .map(|k| (k, (bx[k].1 - bx[k].0) / (region[k].1 - region[k].0)))
        .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)))?;
    let mid = 0.5 * bx[k].0 + 0.5 * bx[k].1;
    let (mut left, mut right) = (bx.to_vec(), bx.to_vec());
    left[k].1 = mid;
    right[k].0 = mid;
    Some((left, right))
}

/// An enclosure of each premise value over a box: the hull of its affine
/// enclosures over a cover of the box by sub-boxes.
#[derive(Debug, Clone, PartialEq)]
pub struct Hull {
    /// Per premise value: `[lo, hi]` holding z(x) for every state x of the
    /// box, or `None` when some sub-box's enclosure is unbounded.
    pub ranges: Vec<Option<(f64, f64)>>,
    /// Sub-boxes of the cover.
    pub boxes: usize,
}

/// The hull of the enclosures of the premise values `z` (outputs of
/// `builder`) over `region`, which every sub-box is bisected ([`bisect`],
/// whole rounds, so the cover is uniform in the states read) until another
/// round would pass [`MAX_PREMISE_BOXES`] sub-boxes or none splits. Sound:
/// the sub-boxes cover the region, and each enclosure holds z on its sub-box.
pub fn hull(builder: &Builder, z: &[Id], region: &[(f64, f64)]) -> Hull {
    let reads = affine::depends_on(builder, z);
    let mut cover = vec![region.to_vec()];
    while 2 * cover.len() <= MAX_PREMISE_BOXES {
        let split: Vec<_> = cover
            .iter()
            .filter_map(|bx| bisect(bx, region, &reads))
            .collect();
        if split.len() < cover.len() {
            break;
        }
        cover = split.into_iter().flat_map(|(l, r)| [l, r]).collect();
    }
    let mut ranges: Vec<Option<(f64, f64)>> =
        vec![Some((f64::INFINITY, f64::NEG_INFINITY)); z.len()];
    for bx in &cover {
        for (r, f) in ranges.iter_mut().zip(enclose(builder, z, bx)) {
            *r = match (*r, f) {
                (Some((lo, hi)), Ok(f)) => {
                    let (a, b) = f.range();
                    Some((lo.min(a), hi.max(b)))
                }
                _ => None,
            };
        }
    }
    Hull {
        ranges,
        boxes: cover.len(),
    }
}
