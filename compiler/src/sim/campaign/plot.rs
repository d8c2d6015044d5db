//! Plots of a campaign, as SVG and PNG with the simulator's figure layer
//! ([`crate::sim::plot::chart`]: embedded font, titles, ticks, axis labels,
//! legends, clipping of runaway values):
//! - `envelope`: one panel per state signal (vector states share a panel, one
//!   colour per component), time on the horizontal axis; a light band from the
//!   lowest to the highest value of the component across all runs in each of
//!   [`super::ENVELOPE_BINS`] time bins (legend `w[0] min..max`), the nominal
//!   run (no perturbation) as a line of the same colour (`w[0] nominal`);
//! - `settle`: histogram of the settle times of the runs that settled (30
//!   bins from the smallest to the largest, the count above each bar), a red
//!   line at the declared convergence time, labelled;
//! - `transmissions`: histogram of the transmission counts per run (30 bins).

use super::summary::Partial;
use crate::sim::plot::chart::{self, colour, Figure, Mark, Panel, Series, Shape, YAxis, GREY, RED};
use crate::sim::plot::groups;
use crate::sim::plot::scale::num;
use crate::sim::SimError;

/// Histogram bins.
const BINS: usize = 30;

fn title(p: &Partial, what: &str) -> String {
    format!(
        "{}: {what} ({} runs, seed {})",
        p.name,
        p.runs.len(),
        p.seed
    )
}

fn envelope(p: &Partial) -> Figure {
    let env = &p.envelope;
    let (t0, t1) = env.span;
    let bins = env.lo.len();
    let mid = |k: usize| t0 + (t1 - t0) * (k as f64 + 0.5) / bins.max(1) as f64;
    let panels = groups(&p.state_names)
        .into_iter()
        .map(|(base, idx)| {
            let mut marks = vec![Mark::plain(GREY, Shape::Line(vec![(t0, 0.0), (t1, 0.0)]))];
            for (c, &i) in idx.iter().enumerate() {
                let name = &p.state_names[i];
                let band: Vec<usize> = (0..bins)
                    .filter(|&k| env.lo[k][i] <= env.hi[k][i])
                    .collect();
                let edge = |v: &Vec<Vec<f64>>| -> Series {
                    band.iter().map(|&k| (mid(k), v[k][i])).collect()
                };
                marks.push(Mark::labelled(
                    format!("{name} min..max"),
                    colour(c),
                    Shape::Band {
                        upper: edge(&env.hi),
                        lower: edge(&env.lo),
                    },
                ));
            }
            for (c, &i) in idx.iter().enumerate() {
                let line = (0..bins)
                    .map(|k| {
                        (
                            mid(k),
                            p.nominal
                                .get(k)
                                .and_then(|r| *r.get(i)?)
                                .unwrap_or(f64::NAN),
                        )
                    })
                    .collect();
                let label = format!("{} nominal", p.state_names[i]);
                marks.push(Mark::labelled(label, colour(c), Shape::Line(line)));
            }
            Panel {
                x: (t0, t1),
                y_label: base,
                y: YAxis::Data,
                marks,
                notes: Vec::new(),
            }
        })
        .collect();
    let failed = p.runs.iter().filter(|r| r.failed()).count();
    Figure {
        title: title(p, "state envelope"),
        caption: vec![
            format!(
                "band: lowest to highest value over all runs in each of {bins} time bins; line: the nominal run (no perturbation)"
            ),
            format!("{failed} of {} runs failed (not converged or an error)", p.runs.len()),
        ],
        x_label: "time [s]".into(),
        panels,
    }
}

/// A histogram of `values` (30 bins from the smallest to the largest; for
/// whole numbers at most 30 bins of a whole width), the x-range widened to
/// show `mark`.
fn histogram(values: &[f64], mark: Option<Mark>) -> (Panel, String) {
    let finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    let (mut lo, mut hi) = finite
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    if finite.is_empty() {
        (lo, hi) = (0.0, 1.0);
    }
    // Counts (integers): bins of a whole number of values centred on them, so
    // no bin holds one value where its neighbours hold two.
    let integral = !finite.is_empty() && finite.iter().all(|v| v.fract() == 0.0);
    if integral || hi <= lo {
        (lo, hi) = (lo - 0.5, hi + 0.5);
    }
    let (w, bins) = if integral {
        let w = ((hi - lo) / BINS as f64).ceil();
        (w, ((hi - lo) / w).ceil() as usize)
    } else {
        ((hi - lo) / BINS as f64, BINS)
    };
    let mut counts = vec![0u64; bins];
    for &v in &finite {
        let k = (((v - lo) / w).floor().max(0.0) as usize).min(bins - 1);
        counts[k] += 1;
    }
    let bars = (0..bins)
        .map(|k| (lo + k as f64 * w, lo + (k + 1) as f64 * w, counts[k]))
        .collect();
    let mut x = (lo - w, hi + w);
    let mut marks = vec![Mark::labelled("runs per bin", colour(0), Shape::Bars(bars))];
    let mut notes = Vec::new();
    if finite.is_empty() {
        notes.push("no run to count".to_string());
    }
    // The marker widens the axis at most to twice the values' range, so the
    // bars stay readable; farther out, a note says where it is.
    if let Some(m) = mark {
        match m.shape {
            Shape::VLine(t) if t > x.1 + (hi - lo) => notes.push(format!(
                "{}: right of the axis",
                m.label.unwrap_or_default()
            )),
            Shape::VLine(t) if t < x.0 - (hi - lo) => {
                notes.push(format!("{}: left of the axis", m.label.unwrap_or_default()))
            }
            Shape::VLine(t) => {
                x = (x.0.min(t - w), x.1.max(t + w));
                marks.push(m);
            }
            _ => marks.push(m),
        }
    }
    let stats = format!(
        "{} values, from {} to {}; bin width {}",
        finite.len(),
        num(lo),
        num(hi),
        num(w)
    );
    let panel = Panel {
        x,
        y_label: "runs".into(),
        y: YAxis::Counts,
        marks,
        notes,
    };
    (panel, stats)
}

fn settle(p: &Partial) -> Figure {
    let values: Vec<f64> = p.runs.iter().filter_map(|r| r.settle_time_s).collect();
    let (signal, bound, t) = &p.converged_rule;
    let mark = Mark::labelled(
        format!("convergence time {} s", num(*t)),
        RED,
        Shape::VLine(*t),
    );
    let (panel, stats) = histogram(&values, Some(mark));
    Figure {
        title: title(p, "settle times"),
        caption: vec![
            format!(
                "settle time: earliest t from which ||{signal}|| <= {} holds to the end; the rule asks for it by t = {} s",
                num(*bound),
                num(*t)
            ),
            format!("{} of {} runs settled; {stats}", values.len(), p.runs.len()),
        ],
        x_label: "settle time [s]".into(),
        panels: vec![panel],
    }
}

fn transmissions(p: &Partial) -> Figure {
    let values: Vec<f64> = p.runs.iter().map(|r| r.transmissions as f64).collect();
    let (panel, stats) = histogram(&values, None);
    Figure {
        title: title(p, "transmissions per run"),
        caption: vec![format!(
            "transmissions to the actuators over {} .. {} s; {stats}",
            num(p.time_s.0),
            num(p.time_s.1)
        )],
        x_label: "transmissions per run".into(),
        panels: vec![panel],
    }
}

/// The plot files of a campaign: `(file name, bytes)`.
pub fn plots(p: &Partial) -> Result<Vec<(String, Vec<u8>)>, SimError> {
    let mut files = Vec::new();
    for (tag, fig) in [
        ("envelope", envelope(p)),
        ("settle", settle(p)),
        ("transmissions", transmissions(p)),
    ] {
        let (svg, png) = chart::render(&fig)?;
        files.push((format!("{}.mc.{tag}.svg", p.name), svg));
        files.push((format!("{}.mc.{tag}.png", p.name), png));
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bars(values: &[f64]) -> Vec<(f64, f64, u64)> {
        let (panel, _) = histogram(values, None);
        match &panel.marks[0].shape {
            Shape::Bars(b) => b.clone(),
            _ => panic!("bars expected"), // ok: test helper, the first mark is the bars
        }
    }

    /// Counts from 180 to 238 (59 whole values) with two runs each: bins of
    /// width 2 centred on whole numbers, every bin holding 4 runs but the last
    /// (one value); with a width of 59/30 some bins held one value.
    #[test]
    fn whole_numbers_get_whole_bins() {
        let values: Vec<f64> = (180..=238).flat_map(|v| [v as f64; 2]).collect();
        let b = bars(&values);
        assert_eq!(b.len(), 30);
        for (k, &(lo, hi, count)) in b.iter().enumerate() {
            assert_eq!(hi - lo, 2.0);
            assert_eq!(lo, 179.5 + 2.0 * k as f64);
            assert_eq!(count, if k == 29 { 2 } else { 4 }, "bin {k}");
        }
        assert_eq!(b.iter().map(|x| x.2).sum::<u64>(), values.len() as u64);
        // One value: one bin around it.
        assert_eq!(bars(&[7.0, 7.0]), vec![(6.5, 7.5, 2)]);
        // Fractional values keep 30 bins over their range.
        assert_eq!(bars(&[0.5, 1.25, 3.0]).len(), BINS);
    }
}
