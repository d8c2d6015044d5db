//! Plots of a run, as SVG and PNG (plotters with its SVG and bitmap backends
//! and the `ab_glyph` text backend; the font, DejaVu Sans, is compiled in:
//! [`font`]). PNG is encoded with the `png` crate so files can be written
//! atomically. Every figure has a title (controller, spec file stem, what it
//! shows), caption lines (trigger law, truth plant, outcome: converged and
//! when, or why the run failed), axes with ticks, tick labels and labels
//! (`time [s]`, the spec's signal names) and a legend per panel:
//! - `states`: one panel per state signal (vector states share a panel, one
//!   colour per component, `w[0]`, `w[1]`, ... in the legend), a grey line at
//!   zero, a red line where the state went NaN or infinite;
//! - `inputs`: one panel per input channel, the saturation levels
//!   `+u_bar`/`-u_bar` in red when the channel is limited;
//! - `events`: top, a raster with one tick per transmission; bottom, the
//!   inter-event time (time since the previous transmission) at each
//!   transmission; the trigger law in the caption;
//! - `modes` (specs with `modes`): the Markov mode r(t) as a staircase, the
//!   time share of each mode in the caption.
//!
//! A run that diverges or goes non-finite still gives readable figures: the
//! y-range comes from the finite values and is clipped when they run away
//! ([`scale`]), with a red note in the panel. Rendering is deterministic: the
//! same outcome gives byte-identical files.
//!
//! Every series is the outcome's thinned trace: at most
//! [`super::limits::MAX_PLOT_POINTS`] points, every `stride`-th one and the last.

pub(crate) mod chart;
pub(crate) mod font;
pub(crate) mod glyphs;
pub(crate) mod scale;

use super::scenario::Outcome;
use super::SimError;
use chart::{colour, Figure, Mark, Panel, Series, Shape, YAxis, GREY, RED};
use scale::num;

/// Component indices grouped by signal name (`w[0]`, `w[1]` -> `w`), in order.
pub(crate) fn groups(names: &[String]) -> Vec<(String, Vec<usize>)> {
    let mut groups: Vec<(String, Vec<usize>)> = Vec::new();
    for (i, name) in names.iter().enumerate() {
        let base = name.split('[').next().unwrap_or(name).to_string();
        match groups.iter_mut().find(|g| g.0 == base) {
            Some(g) => g.1.push(i),
            None => groups.push((base, vec![i])),
        }
    }
    groups
}

fn title(o: &Outcome, what: &str) -> String {
    if o.spec.is_empty() {
        format!("{}: {what}", o.name)
    } else {
        format!("{} ({}.tsf): {what}", o.name, o.spec)
    }
}

/// The caption lines every figure of the run shares.
fn caption(o: &Outcome) -> Vec<String> {
    let m = &o.metrics;
    let outcome = if m.failed {
        format!("RUN FAILED: {}", m.failures().join("; "))
    } else {
        let settled = m.settle_time_s.map_or("did not settle".into(), |t| {
            format!("settled at t = {} s", num(t))
        });
        let verdict = if m.converged {
            "converged"
        } else {
            "did not converge"
        };
        format!(
            "{verdict} ({settled}; final ||x|| = {}, tolerance {})",
            num(m.final_state_norm),
            num(m.convergence_tolerance)
        )
    };
    let mut lines = vec![
        format!("trigger: {}", m.trigger),
        format!("plant: {}; {}", m.plant, m.integrator),
        outcome,
    ];
    if span(o) != m.time_s {
        lines.push(format!(
            "time axis cut at {} s of the run's {} .. {} s: the state is not finite after t = {} s",
            num(span(o).1),
            num(m.time_s.0),
            num(m.time_s.1),
            num(m.nonfinite_at_s.unwrap_or(f64::NAN))
        ));
    }
    lines
}

/// The time axis: the whole run, or up to shortly after the state went
/// non-finite (nothing is left to see after that instant).
fn span(o: &Outcome) -> (f64, f64) {
    let (t0, t1) = o.metrics.time_s;
    match o.metrics.nonfinite_at_s {
        Some(t) if t > t0 && t < t1 => (t0, t1.min(t0 + 1.25 * (t - t0))),
        _ => (t0, t1),
    }
}

fn zero(span: (f64, f64)) -> Mark {
    Mark::plain(GREY, Shape::Line(vec![(span.0, 0.0), (span.1, 0.0)]))
}

fn panel(o: &Outcome, y_label: &str, marks: Vec<Mark>) -> Panel {
    let span = span(o);
    let mut all = vec![zero(span)];
    all.extend(marks);
    if let Some(t) = o.metrics.nonfinite_at_s {
        all.push(Mark::labelled(
            format!("non-finite at {} s", num(t)),
            RED,
            Shape::VLine(t),
        ));
    }
    Panel {
        x: span,
        y_label: y_label.to_string(),
        y: YAxis::Data,
        marks: all,
        notes: Vec::new(),
    }
}

fn column(o: &Outcome, get: impl Fn(usize) -> f64) -> Series {
    (0..o.trace.t.len())
        .map(|k| (o.trace.t[k], get(k)))
        .collect()
}

fn states(o: &Outcome) -> Figure {
    let tr = &o.trace;
    let panels = groups(&tr.state_names)
        .into_iter()
        .map(|(base, idx)| {
            let lines = idx.iter().enumerate().map(|(c, &i)| {
                let s = column(o, |k| tr.x[k].get(i).copied().unwrap_or(f64::NAN));
                Mark::labelled(&tr.state_names[i], colour(c), Shape::Line(s))
            });
            panel(o, &base, lines.collect())
        })
        .collect();
    Figure {
        title: title(o, "state trajectories"),
        caption: caption(o),
        x_label: "time [s]".into(),
        panels,
    }
}

fn inputs(o: &Outcome) -> Figure {
    let (t0, t1) = span(o);
    let tr = &o.trace;
    let panels = tr
        .input_names
        .iter()
        .enumerate()
        .map(|(s, name)| {
            let u = column(o, |k| tr.u[k].get(s).copied().unwrap_or(f64::NAN));
            let mut marks = vec![Mark::labelled(name, colour(0), Shape::Line(u))];
            if let Some(&ub) = o.u_max.get(s).filter(|v| v.is_finite()) {
                for (sign, v) in [("+", ub), ("-", -ub)] {
                    let line = Shape::Line(vec![(t0, v), (t1, v)]);
                    let label = format!("{sign}u_bar = {}", num(v));
                    marks.push(Mark::labelled(label, RED, line).beneath());
                }
            }
            panel(o, name, marks)
        })
        .collect();
    let mut caption = caption(o);
    caption.push(format!(
        "held command (saturated); {} of {} samples clipped by the runtime",
        o.metrics.saturated_samples, o.metrics.samples
    ));
    Figure {
        title: title(o, "control inputs"),
        caption,
        x_label: "time [s]".into(),
        panels,
    }
}

fn events(o: &Outcome) -> Figure {
    let m = &o.metrics;
    let tr = &o.trace;
    let gap = |v: Option<f64>| v.map_or("-".into(), num);
    let mut caption = caption(o);
    caption.push(format!(
        "{} transmissions of {} samples; inter-event time mean {} s, min {} s, max {} s{}",
        m.transmissions,
        m.samples,
        gap(m.mean_inter_event_s),
        gap(m.min_inter_event_s),
        gap(m.max_inter_event_s),
        if (tr.events.len() as u64) < m.transmissions {
            format!(" (plotted: {} of them, thinned)", tr.events.len())
        } else {
            String::new()
        }
    ));
    let raster = Panel {
        x: span(o),
        y_label: "transmissions".into(),
        y: YAxis::Raster,
        marks: vec![Mark::labelled(
            "transmission",
            colour(0),
            Shape::Ticks(tr.events.clone()),
        )],
        notes: Vec::new(),
    };
    let gaps = panel(
        o,
        "inter-event time [s]",
        vec![Mark::labelled(
            "since the previous one",
            colour(1),
            Shape::Dots(tr.gaps.clone()),
        )],
    );
    Figure {
        title: title(o, "transmission instants and inter-event times"),
        caption,
        x_label: "time [s]".into(),
        panels: vec![raster, gaps],
    }
}

/// The Markov mode r(t) as a staircase (mode index on the y axis, the
/// names in the legend), for a spec with `modes`.
fn modes(o: &Outcome) -> Option<Figure> {
    let tr = &o.trace;
    let mm = o.metrics.modes.as_ref()?;
    let (_, t1) = span(o);
    let mut stairs = Vec::with_capacity(2 * tr.modes.len() + 1);
    for (k, &(t, a)) in tr.modes.iter().enumerate() {
        let y = a as f64;
        if let Some(&(_, prev)) = k.checked_sub(1).and_then(|j| tr.modes.get(j)) {
            stairs.push((t, prev as f64));
        }
        stairs.push((t, y));
    }
    if let Some(&(_, a)) = tr.modes.last() {
        stairs.push((t1, a as f64));
    }
    let legend: Vec<String> = tr
        .mode_names
        .iter()
        .enumerate()
        .map(|(a, name)| format!("{a} = {name}"))
        .collect();
    let mut caption = caption(o);
    caption.push(format!(
        "{} gains; mode process seed {}, {} jumps; time share {}",
        mm.design,
        mm.seed,
        mm.transitions,
        mm.modes
            .iter()
            .map(|m| format!("{} {:.1}%", m.name, 100.0 * m.fraction))
            .collect::<Vec<_>>()
            .join(", ")
    ));
    let panel = panel(
        o,
        "mode",
        vec![Mark::labelled(
            legend.join(", "),
            colour(0),
            Shape::Line(stairs),
        )],
    );
    Some(Figure {
        title: title(o, "Markov mode r(t)"),
        caption,
        x_label: "time [s]".into(),
        panels: vec![panel],
    })
}

/// The figures of a run and their tags (`states`, `inputs`, `events`, `modes`).
pub(crate) fn figures(o: &Outcome) -> Vec<(Figure, &'static str)> {
    let mut figures = vec![
        (states(o), "states"),
        (inputs(o), "inputs"),
        (events(o), "events"),
    ];
    if let Some(f) = modes(o) {
        figures.push((f, "modes"));
    }
    figures
}

/// The plots of a run as SVG only: `(file name, SVG text)` (the playground's).
pub fn svgs(o: &Outcome) -> Result<Vec<(String, String)>, SimError> {
    figures(o)
        .into_iter()
        .map(|(fig, tag)| Ok((format!("{}.{tag}.svg", o.name), chart::render_svg(&fig)?)))
        .collect()
}

/// The plot files of a run: `(file name, bytes)`.
pub fn plots(o: &Outcome) -> Result<Vec<(String, Vec<u8>)>, SimError> {
    let mut files = Vec::new();
    for (fig, tag) in figures(o) {
        let (svg, png) = chart::render(&fig)?;
        files.push((format!("{}.{tag}.svg", o.name), svg));
        files.push((format!("{}.{tag}.png", o.name), png));
    }
    Ok(files)
}
