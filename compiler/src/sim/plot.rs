//! Plots of a run, as SVG and PNG (plotters, SVG and bitmap backends only;
//! PNG encoded with the `png` crate so files can be written atomically).
//!
//! Plots carry no text: plotters would need a font backend (system fonts or
//! an embedded font) to lay out labels, and the build must rely on nothing but
//! crates.io. The figures are therefore described here and in the metrics:
//! - `states`: one panel per state signal (vector states share a panel, one
//!   colour per component, in component order), time on the horizontal axis,
//!   a grey line at zero;
//! - `inputs`: one panel per input channel (blue), the saturation levels
//!   `+-u_bar` in red when the channel is limited;
//! - `events`: top, one stem per transmission instant; bottom, the
//!   inter-event time (time since the previous transmission) at each
//!   transmission, with the axis from 0 to the largest gap.
//!
//! Every series is the outcome's thinned trace: at most
//! [`super::limits::MAX_PLOT_POINTS`] points, every `stride`-th one and the last.

use super::scenario::Outcome;
use super::SimError;
use plotters::coord::Shift;
use plotters::prelude::*;

/// Figure size in pixels.
pub(crate) const SIZE: (u32, u32) = (1000, 700);

#[derive(Clone, Copy)]
enum Figure {
    States,
    Inputs,
    Events,
}

type Series = Vec<(f64, f64)>;

/// One panel: line series (with colours) on a y-range.
struct Panel {
    lines: Vec<(Series, RGBColor)>,
    stems: Vec<f64>,
    dots: Series,
}

/// The `i`-th colour of the plots' palette.
pub(crate) fn colour(i: usize) -> RGBColor {
    const C: [RGBColor; 6] = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(23, 190, 207),
    ];
    C[i % C.len()]
}

const LIMIT: RGBColor = RGBColor(214, 39, 40);

fn panels(fig: Figure, o: &Outcome) -> Vec<Panel> {
    let tr = &o.trace;
    let (t0, t1) = o.metrics.time_s;
    let column = |get: &dyn Fn(usize) -> f64| -> Series {
        (0..tr.t.len()).map(|k| (tr.t[k], get(k))).collect()
    };
    match fig {
        Figure::States => {
            // Group components by signal name (`w[0]`, `w[1]` -> `w`).
            let mut groups: Vec<(String, Vec<usize>)> = Vec::new();
            for (i, name) in tr.state_names.iter().enumerate() {
                let base = name.split('[').next().unwrap_or(name).to_string();
                match groups.iter_mut().find(|g| g.0 == base) {
                    Some(g) => g.1.push(i),
                    None => groups.push((base, vec![i])),
                }
            }
            groups
                .into_iter()
                .map(|(_, idx)| Panel {
                    lines: idx
                        .iter()
                        .enumerate()
                        .map(|(c, &i)| (column(&|k| tr.x[k][i]), colour(c)))
                        .collect(),
                    stems: Vec::new(),
                    dots: Vec::new(),
                })
                .collect()
        }
        Figure::Inputs => (0..tr.input_names.len())
            .map(|s| {
                let mut lines = vec![(column(&|k| tr.u[k][s]), colour(0))];
                if let Some(&ub) = o.u_max.get(s).filter(|v| v.is_finite()) {
                    lines.push((vec![(t0, ub), (t1, ub)], LIMIT));
                    lines.push((vec![(t0, -ub), (t1, -ub)], LIMIT));
                }
                Panel {
                    lines,
                    stems: Vec::new(),
                    dots: Vec::new(),
                }
            })
            .collect(),
        Figure::Events => vec![
            Panel {
                lines: Vec::new(),
                stems: tr.events.clone(),
                dots: Vec::new(),
            },
            Panel {
                lines: Vec::new(),
                stems: Vec::new(),
                dots: tr.gaps.clone(),
            },
        ],
    }
}

fn y_range(p: &Panel) -> (f64, f64) {
    if !p.stems.is_empty() {
        return (0.0, 1.1);
    }
    let ys = p
        .lines
        .iter()
        .flat_map(|(s, _)| s.iter().map(|q| q.1))
        .chain(p.dots.iter().map(|q| q.1))
        .chain([0.0])
        .filter(|v| v.is_finite());
    let (lo, hi) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    let pad = 0.05 * (hi - lo);
    if pad > 0.0 {
        (lo - pad, hi + pad)
    } else {
        (lo - 1.0, hi + 1.0)
    }
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    fig: Figure,
    o: &Outcome,
) -> Result<(), SimError> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| SimError::usage(format!("plot: {e}"));
    root.fill(&WHITE).map_err(err)?;
    let (t0, t1) = o.metrics.time_s;
    let ps = panels(fig, o);
    let areas = root.split_evenly((ps.len().max(1), 1));
    let grey = RGBColor(170, 170, 170);
    for (p, area) in ps.iter().zip(&areas) {
        let (lo, hi) = y_range(p);
        let mut chart = ChartBuilder::on(area)
            .margin(12)
            .build_cartesian_2d(t0..t1, lo..hi)
            .map_err(err)?;
        let plot = chart.plotting_area();
        plot.draw(&Rectangle::new([(t0, lo), (t1, hi)], BLACK.stroke_width(1)))
            .map_err(err)?;
        plot.draw(&PathElement::new(vec![(t0, 0.0), (t1, 0.0)], grey))
            .map_err(err)?;
        for (s, c) in &p.lines {
            chart
                .draw_series(LineSeries::new(s.iter().copied(), c.stroke_width(2)))
                .map_err(err)?;
        }
        chart
            .draw_series(
                p.stems
                    .iter()
                    .map(|&t| PathElement::new(vec![(t, 0.0), (t, 1.0)], colour(0))),
            )
            .map_err(err)?;
        chart
            .draw_series(
                p.dots
                    .iter()
                    .map(|&q| Circle::new(q, 2, colour(1).filled())),
            )
            .map_err(err)?;
    }
    root.present().map_err(err)
}

fn svg(fig: Figure, o: &Outcome) -> Result<Vec<u8>, SimError> {
    let mut s = String::new();
    {
        let root = SVGBackend::with_string(&mut s, SIZE).into_drawing_area();
        draw(&root, fig, o)?;
    }
    Ok(s.into_bytes())
}

fn png(fig: Figure, o: &Outcome) -> Result<Vec<u8>, SimError> {
    let (w, h) = SIZE;
    let mut rgb = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
        draw(&root, fig, o)?;
    }
    encode_png(&rgb, SIZE)
}

/// An RGB buffer of `size` as PNG bytes.
pub(crate) fn encode_png(rgb: &[u8], (w, h): (u32, u32)) -> Result<Vec<u8>, SimError> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut wr = enc
            .write_header()
            .map_err(|e| SimError::usage(format!("png: {e}")))?;
        wr.write_image_data(rgb)
            .map_err(|e| SimError::usage(format!("png: {e}")))?;
    }
    Ok(out)
}

/// The plot files of a run: `(file name, bytes)`.
pub fn plots(o: &Outcome) -> Result<Vec<(String, Vec<u8>)>, SimError> {
    let mut files = Vec::new();
    for (fig, tag) in [
        (Figure::States, "states"),
        (Figure::Inputs, "inputs"),
        (Figure::Events, "events"),
    ] {
        files.push((format!("{}.{tag}.svg", o.name), svg(fig, o)?));
        files.push((format!("{}.{tag}.png", o.name), png(fig, o)?));
    }
    Ok(files)
}
