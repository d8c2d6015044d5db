//! The review page's figures, drawn with the simulator's charts
//! ([`crate::sim::plot::chart`]: plotters, the embedded font) as SVG text:
//! the membership functions of each premise, the model-consistency profile
//! and the closed-loop plots of the scenario. Each comes with its caption.

use crate::model::{membership, Consistency, TermSpec, TsModel, MISMATCH_TOLERANCE};
use crate::sim::plot::chart::{self, colour, Figure, Mark, Panel, Shape, YAxis, GREY, RED};
use crate::sim::plot::{figures as run_figures, groups};
use crate::sim::{Outcome, SimError};
use tsf_lang::spec::Premise;

/// Points per membership curve (plus the shape's breakpoints in range).
const CURVE_POINTS: usize = 200;

/// A rendered figure: SVG text and caption.
pub struct Svg {
    /// The `<svg>` element (as plotters writes it).
    pub svg: String,
    /// What the figure shows, one sentence or more (plain text).
    pub caption: String,
}

/// The figure as an inline `<svg>` element: the HTML parser gives it the
/// SVG namespace, so the root's `xmlns` (a URL) is left out and the page
/// holds no address at all.
fn inline_svg(fig: &Figure) -> Result<String, SimError> {
    Ok(chart::render_svg(fig)?.replacen(" xmlns=\"http://www.w3.org/2000/svg\"", "", 1))
}

/// `CURVE_POINTS + 1` evenly spaced values over `lo .. hi` and the extra
/// values `breaks` inside it, sorted.
fn abscissae(lo: f64, hi: f64, breaks: &[f64]) -> Vec<f64> {
    let mut xs: Vec<f64> = (0..=CURVE_POINTS)
        .map(|i| lo + (hi - lo) * i as f64 / CURVE_POINTS as f64)
        .chain(breaks.iter().copied().filter(|b| *b > lo && *b < hi))
        .collect();
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    xs
}

/// A panel of membership degrees over `range` (y from 0 to 1).
fn degree_panel(range: (f64, f64), y_label: String, marks: Vec<Mark>) -> Panel {
    let mut all = vec![Mark::plain(
        GREY,
        Shape::Line(vec![(range.0, 0.0), (range.1, 0.0)]),
    )];
    all.extend(marks);
    all.push(Mark::plain(
        GREY,
        Shape::Line(vec![(range.0, 1.0), (range.1, 1.0)]),
    ));
    Panel {
        x: range,
        y_label,
        y: YAxis::Data,
        marks: all,
        notes: Vec::new(),
    }
}

/// The `about` points of the rules on the premise whose first component is `first`.
fn about_points(model: &TsModel, first: usize) -> Vec<(Vec<f64>, f64)> {
    let mut points: Vec<(Vec<f64>, f64)> = Vec::new();
    for t in model.terms.iter().flatten() {
        if let TermSpec::About {
            first: f,
            point,
            sigma,
        } = t
        {
            if *f == first && !points.iter().any(|(p, _)| p == point) {
                points.push((point.clone(), *sigma));
            }
        }
    }
    points
}

/// The membership figure of premise `k` of the model: its named sets over
/// its range (one curve each), or, for `about` sets, the section of each
/// radial set along each component through its point.
pub fn membership_figure(model: &TsModel, k: usize) -> Result<Svg, SimError> {
    let slot = &model.premises.slots[k];
    let premise: Option<&Premise> = model.spec.premises.get(k);
    let range = slot.range;
    let mut panels = Vec::new();
    let mut caption = format!(
        "Membership functions of premise `{}` over its range {} .. {}",
        slot.name, range.0, range.1
    );
    let sets = premise.map_or(&[][..], |p| p.sets.as_slice());
    if !sets.is_empty() {
        let marks = sets
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let m = membership(s.shape);
                let line = abscissae(range.0, range.1, &s.shape.breakpoints())
                    .into_iter()
                    .map(|z| (z, m.degree(z)))
                    .collect();
                Mark::labelled(&s.name, colour(i), Shape::Line(line))
            })
            .collect();
        panels.push(degree_panel(
            range,
            format!("degree of {}", slot.name),
            marks,
        ));
        caption.push_str(&format!(
            ": one curve per named set ({}).",
            sets.iter()
                .map(|s| s.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    let points = about_points(model, slot.first);
    if !points.is_empty() {
        for c in 0..slot.dim {
            let name = model.premises.component_name(slot.first + c);
            let marks = points
                .iter()
                .enumerate()
                .map(|(i, (p, sigma))| {
                    let line = abscissae(range.0, range.1, &[p[c]])
                        .into_iter()
                        .map(|z| (z, (-0.5 * ((z - p[c]) / sigma).powi(2)).exp()))
                        .collect();
                    let shown: Vec<String> = p.iter().map(|v| format!("{v}")).collect();
                    let label = format!("about [{}]", shown.join(", "));
                    Mark::labelled(label, colour(i), Shape::Line(line))
                })
                .collect();
            panels.push(degree_panel(range, format!("degree along {name}"), marks));
        }
        caption.push_str(&format!(
            ": the radial `about` sets exp(-0.5 ||z - p||^2 / sigma^2) (sigma = {}), cut along each component of z through the set's point p (the other components at p), one curve per point.",
            points[0].1
        ));
    }
    if panels.is_empty() {
        caption.push_str(": no set of this premise is used by a rule.");
        return Ok(Svg {
            svg: String::new(),
            caption,
        });
    }
    let fig = Figure {
        title: format!("{}: premise {}", model.spec.controller.node, slot.name),
        caption: Vec::new(),
        x_label: slot.name.clone(),
        panels,
    };
    Ok(Svg {
        svg: inline_svg(&fig)?,
        caption,
    })
}

/// The model-consistency profile: for each state signal, one panel with one
/// curve per component: the worst relative mismatch of the blended model
/// against A(x), B(x) over the grid states with that component at each value.
pub fn consistency_figure(model: &TsModel, c: &Consistency) -> Result<Option<Svg>, SimError> {
    let names = tsf_lang::spec::Signal::names_of(&model.spec.states);
    let mut panels = Vec::new();
    for (base, idx) in groups(&names) {
        let varying: Vec<usize> = idx
            .into_iter()
            .filter(|&k| c.axes.get(k).is_some_and(|a| a.len() > 1))
            .collect();
        let Some(lo) = varying.iter().map(|&k| c.axes[k][0]).reduce(f64::min) else {
            continue;
        };
        let hi = varying
            .iter()
            .filter_map(|&k| c.axes[k].last().copied())
            .fold(lo, f64::max);
        let mut marks = vec![Mark::labelled(
            format!("tolerance {:.0}%", 100.0 * MISMATCH_TOLERANCE),
            RED,
            Shape::Line(vec![(lo, MISMATCH_TOLERANCE), (hi, MISMATCH_TOLERANCE)]),
        )
        .beneath()];
        for (i, &k) in varying.iter().enumerate() {
            let line = c.axes[k].iter().copied().zip(c.profile[k].iter().copied());
            marks.push(Mark::labelled(
                &names[k],
                colour(i),
                Shape::Line(line.collect()),
            ));
        }
        panels.push(Panel {
            x: (lo, hi),
            y_label: format!("mismatch along {base}"),
            y: YAxis::Data,
            marks,
            notes: Vec::new(),
        });
    }
    if panels.is_empty() {
        return Ok(None);
    }
    let fig = Figure {
        title: format!("{}: model consistency", model.spec.controller.node),
        caption: Vec::new(),
        x_label: "state component value".into(),
        panels,
    };
    Ok(Some(Svg {
        svg: inline_svg(&fig)?,
        caption: format!(
            "Model-consistency map of the model stage: on a grid of {} states inside the premise region, the relative mismatch ||sum_i h_i M_i - M(x)||_F / max_i ||M_i||_F of the blended model against M = A(x), B(x); each curve gives, for one state component and each of its grid values, the worst mismatch over the other components. Worst {:.1}% in {} at x = [{}]; tolerance {:.0}% (red).",
            c.points,
            100.0 * c.worst,
            c.matrix,
            c.at.iter().map(|v| format!("{v}")).collect::<Vec<_>>().join(", "),
            100.0 * MISMATCH_TOLERANCE
        ),
    }))
}

/// Most points of a series in the page's closed-loop plots (the simulator's
/// plot files keep up to [`crate::sim::limits::MAX_PLOT_POINTS`]): the page's
/// size stays bounded whatever the horizon.
pub const MAX_REVIEW_PLOT_POINTS: usize = 1000;

/// Every `stride`-th element and the last, at most about `max` of them.
fn thin<T: Clone>(v: &[T], max: usize) -> Vec<T> {
    if v.len() <= max {
        return v.to_vec();
    }
    let stride = v.len().div_ceil(max - 1);
    let mut kept: Vec<T> = v.iter().step_by(stride).cloned().collect();
    if !(v.len() - 1).is_multiple_of(stride) {
        kept.extend(v.last().cloned());
    }
    kept
}

/// The run with its trace thinned to [`MAX_REVIEW_PLOT_POINTS`] per series.
fn thinned(o: &Outcome) -> Outcome {
    let mut o = o.clone();
    let m = MAX_REVIEW_PLOT_POINTS;
    let tr = &mut o.trace;
    tr.t = thin(&tr.t, m);
    tr.x = thin(&tr.x, m);
    tr.u = thin(&tr.u, m);
    tr.sent = thin(&tr.sent, m);
    tr.events = thin(&tr.events, m);
    tr.gaps = thin(&tr.gaps, m);
    tr.modes = thin(&tr.modes, m);
    o
}

/// The closed-loop plots of a run (states, inputs, events, modes), as the
/// simulator draws them from the run's trace thinned to
/// [`MAX_REVIEW_PLOT_POINTS`]; the caption is the figure's own caption lines.
pub fn run_figures_svg(o: &Outcome) -> Result<Vec<Svg>, SimError> {
    run_figures(&thinned(o))
        .into_iter()
        .map(|(fig, _)| {
            Ok(Svg {
                svg: inline_svg(&fig)?,
                caption: format!("{}. {}.", fig.title, fig.caption.join("; ")),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::thin;

    /// Thinning keeps the first and the last element, at most `max` in all,
    /// and leaves a short series alone.
    #[test]
    fn thin_keeps_the_ends_and_bounds_the_count() {
        let v: Vec<usize> = (0..10_001).collect();
        for max in [2, 3, 1000, 9_999] {
            let t = thin(&v, max);
            assert!(t.len() <= max, "{} > {max}", t.len());
            assert_eq!((t[0], t[t.len() - 1]), (0, 10_000));
        }
        assert_eq!(thin(&v[..5], 1000), v[..5].to_vec());
    }
}
