//! A figure as data (title, caption lines, panels of labelled marks) and its
//! rendering to SVG and PNG with the embedded font ([`super::font`]): every
//! panel has ticks, tick labels and a y-axis label, the bottom one the x-axis
//! label, and a legend column on its right naming each labelled mark. Panels
//! whose data were clipped ([`super::scale`]) say so in red.

use super::font::{self, FAMILY};
use super::glyphs::Typeset;
use super::scale::{self, YRange};
use crate::sim::SimError;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// Points `(x, y)` of a series.
pub(crate) type Series = Vec<(f64, f64)>;

/// Figure width in pixels (the height grows with the panel count).
const WIDTH: u32 = 1100;
/// Width of the legend column right of each panel.
const LEGEND_W: u32 = 200;
/// Height of one caption line.
const LINE_H: u32 = 20;
/// Colour of clipping notes and limits.
pub(crate) const RED: RGBColor = RGBColor(214, 39, 40);
/// Colour of the zero line.
pub(crate) const GREY: RGBColor = RGBColor(150, 150, 150);

/// One figure.
pub(crate) struct Figure {
    /// Title (top line, bold).
    pub title: String,
    /// Lines under the title (trigger law, outcome, ...), wrapped to the width.
    pub caption: Vec<String>,
    /// Label of the shared x axis, written under the bottom panel.
    pub x_label: String,
    /// Panels, top to bottom.
    pub panels: Vec<Panel>,
}

/// How a panel's y-axis is scaled.
#[derive(Clone, Copy, PartialEq)]
pub(crate) enum YAxis {
    /// From the data, clipped when they run away ([`scale::y_range`]).
    Data,
    /// `0 .. 1` without tick labels (an event raster).
    Raster,
    /// From 0 to the largest bar, room left for the counts above the bars.
    Counts,
}

/// One panel: marks on a shared x-range.
pub(crate) struct Panel {
    /// x-range.
    pub x: (f64, f64),
    /// y-axis label.
    pub y_label: String,
    /// y scaling.
    pub y: YAxis,
    /// What is drawn, in drawing order.
    pub marks: Vec<Mark>,
    /// Notes written inside the panel, top left.
    pub notes: Vec<String>,
}

/// A drawn element and its legend entry.
pub(crate) struct Mark {
    /// Legend text (`None`: not in the legend).
    pub label: Option<String>,
    /// Colour.
    pub colour: RGBColor,
    /// Geometry.
    pub shape: Shape,
    /// Drawn before the other marks (under them).
    pub beneath: bool,
}

/// The geometry of a [`Mark`].
pub(crate) enum Shape {
    /// A polyline (non-finite points break it).
    Line(Series),
    /// A filled band between two polylines over the same x values.
    Band { upper: Series, lower: Series },
    /// One short vertical tick per x value (a raster).
    Ticks(Vec<f64>),
    /// Dots.
    Dots(Series),
    /// Histogram bars `(from, to, count)`, the count written above each non-empty bar.
    Bars(Vec<(f64, f64, u64)>),
    /// A vertical line across the panel.
    VLine(f64),
}

impl Mark {
    /// A mark without a legend entry.
    pub fn plain(colour: RGBColor, shape: Shape) -> Self {
        Mark {
            label: None,
            colour,
            shape,
            beneath: false,
        }
    }

    /// The mark, drawn under the others (a limit behind the data).
    pub fn beneath(self) -> Self {
        Mark {
            beneath: true,
            ..self
        }
    }

    /// A mark with legend text `label`.
    pub fn labelled(label: impl Into<String>, colour: RGBColor, shape: Shape) -> Self {
        Mark {
            label: Some(label.into()),
            colour,
            shape,
            beneath: false,
        }
    }
}

/// The `i`-th colour of the palette.
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

fn err<E: std::fmt::Debug>(e: E) -> SimError {
    SimError::usage(format!("plot: {e:?}"))
}

/// `text` broken into lines of at most `width` characters at spaces.
fn wrap(text: &str, width: usize) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for word in text.split(' ') {
        match lines.last_mut() {
            Some(l) if l.chars().count() + 1 + word.chars().count() <= width => {
                l.push(' ');
                l.push_str(word);
            }
            _ => lines.push(word.to_string()),
        }
    }
    lines
}

fn y_range(p: &Panel) -> YRange {
    let fixed = |lo, hi| YRange {
        lo,
        hi,
        clipped: None,
    };
    match p.y {
        YAxis::Raster => fixed(0.0, 1.0),
        YAxis::Counts => {
            let top = p.marks.iter().flat_map(|m| match &m.shape {
                Shape::Bars(b) => b.iter().map(|q| q.2).max(),
                _ => None,
            });
            fixed(0.0, top.max().unwrap_or(0).max(1) as f64 * 1.15)
        }
        YAxis::Data => {
            let pts: Vec<(f64, f64)> = p
                .marks
                .iter()
                .flat_map(|m| match &m.shape {
                    Shape::Line(s) | Shape::Dots(s) => s.clone(),
                    Shape::Band { upper, lower } => [upper.clone(), lower.clone()].concat(),
                    _ => Vec::new(),
                })
                .collect();
            scale::y_range(&pts, p.x)
        }
    }
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    p: &Panel,
    x_label: Option<&str>,
) -> Result<(), SimError> {
    let (w, _) = area.dim_in_pixel();
    let (plot_area, legend_area) = area.split_horizontally(w.saturating_sub(LEGEND_W));
    let (x0, x1) = if p.x.1 > p.x.0 {
        p.x
    } else {
        (p.x.0, p.x.0 + 1.0)
    };
    let r = y_range(p);
    let mut chart = ChartBuilder::on(&plot_area)
        .margin(8)
        .margin_right(20)
        .x_label_area_size(if x_label.is_some() { 50 } else { 30 })
        .y_label_area_size(90)
        .build_cartesian_2d(x0..x1, r.lo..r.hi)
        .map_err(err)?;
    let blank = |_: &f64| String::new();
    let mut mesh = chart.configure_mesh();
    mesh.x_labels(10)
        .y_labels(if p.y == YAxis::Raster { 0 } else { 6 })
        .x_label_formatter(&scale::tick)
        .y_label_formatter(if p.y == YAxis::Raster {
            &blank
        } else {
            &scale::tick
        })
        .label_style((FAMILY, 14))
        .axis_desc_style((FAMILY, 16))
        .y_desc(p.y_label.as_str())
        .bold_line_style(RGBColor(225, 225, 225))
        .light_line_style(RGBColor(245, 245, 245));
    if let Some(l) = x_label {
        mesh.x_desc(l);
    }
    mesh.draw().map_err(err)?;
    let inside = |s: &Series| scale::stretches(s, r.lo, r.hi);
    let beneath = p.marks.iter().filter(|m| m.beneath);
    for m in beneath.chain(p.marks.iter().filter(|m| !m.beneath)) {
        let c = m.colour;
        match &m.shape {
            Shape::Line(s) => {
                for part in inside(s) {
                    chart
                        .draw_series(LineSeries::new(part, c.stroke_width(2)))
                        .map_err(err)?;
                }
            }
            Shape::Band { upper, lower } => {
                let mut poly: Series = upper.clone();
                poly.extend(lower.iter().rev());
                for part in inside(&poly).into_iter().filter(|q| q.len() > 2) {
                    chart
                        .draw_series([Polygon::new(part, c.mix(0.3).filled())])
                        .map_err(err)?;
                }
            }
            Shape::Ticks(xs) => {
                let ticks = xs
                    .iter()
                    .filter(|x| x.is_finite())
                    .map(|&x| PathElement::new(vec![(x, 0.15), (x, 0.85)], c.stroke_width(1)));
                chart.draw_series(ticks).map_err(err)?;
            }
            Shape::Dots(s) => {
                let dots = inside(s).into_iter().flatten();
                chart
                    .draw_series(dots.map(|q| Circle::new(q, 3, c.filled())))
                    .map_err(err)?;
            }
            Shape::Bars(bars) => {
                let rect = |&(a, b, n): &(f64, f64, u64)| {
                    Rectangle::new([(a, 0.0), (b, n as f64)], c.filled())
                };
                chart.draw_series(bars.iter().map(rect)).map_err(err)?;
                let counts = bars.iter().filter(|q| q.2 > 0).map(|&(a, b, n)| {
                    Text::new(
                        n.to_string(),
                        (0.5 * (a + b), n as f64),
                        (FAMILY, 13)
                            .into_font()
                            .color(&BLACK)
                            .pos(Pos::new(HPos::Center, VPos::Bottom)),
                    )
                });
                chart.draw_series(counts).map_err(err)?;
            }
            Shape::VLine(x) => {
                let line = PathElement::new(vec![(*x, r.lo), (*x, r.hi)], c.stroke_width(2));
                chart.draw_series([line]).map_err(err)?;
            }
        }
    }
    let notes = p
        .notes
        .iter()
        .cloned()
        .chain(r.clipped.iter().map(|&(cap, m)| {
            let (cap, m) = (scale::num(cap), scale::num(m));
            format!("y clipped at +-{cap}: the values reach {m} (runaway)")
        }));
    for (i, n) in notes.enumerate() {
        let style = (FAMILY, 14).into_font().color(&RED);
        let at = EmptyElement::at((x0, r.hi)) + Text::new(n, (8, 6 + 18 * i as i32), style);
        chart.draw_series([at]).map_err(err)?;
    }
    draw_legend(&legend_area, p)
}

fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    p: &Panel,
) -> Result<(), SimError> {
    let entries = p
        .marks
        .iter()
        .filter_map(|m| Some((m.label.as_deref()?, m)));
    for (i, (label, m)) in entries.enumerate() {
        let y = 14 + 22 * i as i32;
        let c = m.colour;
        match m.shape {
            Shape::Band { .. } => area
                .draw(&Rectangle::new(
                    [(4, y - 6), (30, y + 6)],
                    c.mix(0.3).filled(),
                ))
                .map_err(err)?,
            Shape::Bars(_) => area
                .draw(&Rectangle::new([(4, y - 6), (30, y + 6)], c.filled()))
                .map_err(err)?,
            Shape::Dots(_) => area
                .draw(&Circle::new((17, y), 4, c.filled()))
                .map_err(err)?,
            Shape::Ticks(_) => area
                .draw(&PathElement::new(
                    vec![(17, y - 7), (17, y + 7)],
                    c.stroke_width(2),
                ))
                .map_err(err)?,
            _ => area
                .draw(&PathElement::new(vec![(4, y), (30, y)], c.stroke_width(2)))
                .map_err(err)?,
        }
        let style = (FAMILY, 14)
            .into_font()
            .color(&BLACK)
            .pos(Pos::new(HPos::Left, VPos::Center));
        area.draw(&Text::new(label.to_string(), (38, y), style))
            .map_err(err)?;
    }
    Ok(())
}

/// The figure's size: [`WIDTH`] wide, about 230 pixels per panel.
pub(crate) fn size(fig: &Figure) -> (u32, u32) {
    let lines = caption_lines(fig).len() as u32;
    (
        WIDTH,
        (70 + LINE_H * lines + 230 * fig.panels.len() as u32).max(500),
    )
}

fn caption_lines(fig: &Figure) -> Vec<String> {
    fig.caption.iter().flat_map(|c| wrap(c, 125)).collect()
}

fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, fig: &Figure) -> Result<(), SimError> {
    root.fill(&WHITE).map_err(err)?;
    let (_, root_body) = root.split_vertically(8);
    let body = root_body
        .titled(&fig.title, (FAMILY, 22).into_font().style(FontStyle::Bold))
        .map_err(err)?;
    let lines = caption_lines(fig);
    let (head, body) = body.split_vertically(LINE_H * lines.len() as u32 + 6);
    for (i, l) in lines.iter().enumerate() {
        let style = (FAMILY, 15).into_font().color(&RGBColor(60, 60, 60));
        head.draw(&Text::new(l.clone(), (20, LINE_H as i32 * i as i32), style))
            .map_err(err)?;
    }
    let areas = body.split_evenly((fig.panels.len().max(1), 1));
    let last = fig.panels.len().saturating_sub(1);
    for (i, (p, area)) in fig.panels.iter().zip(&areas).enumerate() {
        draw_panel(area, p, (i == last).then_some(fig.x_label.as_str()))?;
    }
    root.present().map_err(err)
}

/// The figure as `(SVG bytes, PNG bytes)`; the same figure gives the same bytes.
pub(crate) fn render(fig: &Figure) -> Result<(Vec<u8>, Vec<u8>), SimError> {
    let s = render_svg(fig)?;
    let size = size(fig);
    let (w, h) = size;
    let mut rgb = vec![0u8; (w * h * 3) as usize];
    {
        let bitmap = BitMapBackend::with_buffer(&mut rgb, size);
        let root = Typeset::new(bitmap, font::faces()?).into_drawing_area();
        draw(&root, fig)?;
    }
    Ok((s.into_bytes(), encode_png(&rgb, size)?))
}

/// The figure as SVG text; the same figure gives the same text.
pub(crate) fn render_svg(fig: &Figure) -> Result<String, SimError> {
    let mut s = String::new();
    #[cfg(not(target_arch = "wasm32"))]
    {
        font::ensure()?;
        let root = SVGBackend::with_string(&mut s, size(fig)).into_drawing_area();
        draw(&root, fig)?;
    }
    #[cfg(target_arch = "wasm32")]
    {
        let svg = SVGBackend::with_string(&mut s, size(fig));
        let root = Typeset::measuring(svg, font::faces()?).into_drawing_area();
        draw(&root, fig)?;
    }
    Ok(s)
}

/// An RGB buffer of `size` as PNG bytes.
fn encode_png(rgb: &[u8], (w, h): (u32, u32)) -> Result<Vec<u8>, SimError> {
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
