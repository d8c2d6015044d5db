//! Plots of a campaign, as SVG and PNG with the simulator's plotting helpers
//! (no text, like every plot of `tsfc simulate`; the figures are described here):
//! - `envelope`: one panel per state signal (vector states share a panel, one
//!   colour per component), time on the horizontal axis; a light band from the
//!   lowest to the highest value of the component across all runs in each of
//!   [`super::ENVELOPE_BINS`] time bins, the nominal run (no perturbation) as
//!   a line of the same colour, a grey line at zero;
//! - `settle`: histogram of the settle times of the runs that settled (30
//!   bins from the smallest to the largest), a red line at the declared
//!   convergence time when it falls inside that range;
//! - `transmissions`: histogram of the transmission counts per run (30 bins).

use super::summary::Partial;
use crate::sim::plot::{colour, encode_png, SIZE};
use crate::sim::SimError;
use plotters::coord::Shift;
use plotters::prelude::*;

/// Histogram bins.
const BINS: usize = 30;

enum Figure<'a> {
    Envelope(&'a Partial),
    Histogram { values: Vec<f64>, mark: Option<f64> },
}

fn err<E: std::fmt::Debug>(e: E) -> SimError {
    SimError::usage(format!("plot: {e:?}"))
}

/// Component indices grouped by signal name (`w[0]`, `w[1]` -> `w`).
fn groups(names: &[String]) -> Vec<Vec<usize>> {
    let mut groups: Vec<(String, Vec<usize>)> = Vec::new();
    for (i, name) in names.iter().enumerate() {
        let base = name.split('[').next().unwrap_or(name).to_string();
        match groups.iter_mut().find(|g| g.0 == base) {
            Some(g) => g.1.push(i),
            None => groups.push((base, vec![i])),
        }
    }
    groups.into_iter().map(|g| g.1).collect()
}

fn light(c: RGBColor) -> RGBColor {
    let f = |v: u8| (255 - (255 - v as u16) * 2 / 5) as u8;
    RGBColor(f(c.0), f(c.1), f(c.2))
}

fn draw_envelope<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    p: &Partial,
) -> Result<(), SimError> {
    let env = &p.envelope;
    let (t0, t1) = env.span;
    let bins = env.lo.len();
    let mid = |k: usize| t0 + (t1 - t0) * (k as f64 + 0.5) / bins as f64;
    let gs = groups(&p.state_names);
    let areas = root.split_evenly((gs.len().max(1), 1));
    for (idx, area) in gs.iter().zip(&areas) {
        let vals = idx.iter().flat_map(|&i| {
            env.lo
                .iter()
                .zip(&env.hi)
                .filter(move |(l, h)| l[i] <= h[i])
                .flat_map(move |(l, h)| [l[i], h[i]])
        });
        let (lo, hi) = vals
            .chain([0.0])
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            });
        let pad = if hi > lo { 0.05 * (hi - lo) } else { 1.0 };
        let (lo, hi) = (lo - pad, hi + pad);
        let mut chart = ChartBuilder::on(area)
            .margin(12)
            .build_cartesian_2d(t0..t1, lo..hi)
            .map_err(err)?;
        let plot = chart.plotting_area();
        plot.draw(&Rectangle::new([(t0, lo), (t1, hi)], BLACK.stroke_width(1)))
            .map_err(err)?;
        plot.draw(&PathElement::new(
            vec![(t0, 0.0), (t1, 0.0)],
            RGBColor(170, 170, 170),
        ))
        .map_err(err)?;
        for (c, &i) in idx.iter().enumerate() {
            let band: Vec<usize> = (0..bins)
                .filter(|&k| env.lo[k][i] <= env.hi[k][i])
                .collect();
            let mut poly: Vec<(f64, f64)> = band.iter().map(|&k| (mid(k), env.hi[k][i])).collect();
            poly.extend(band.iter().rev().map(|&k| (mid(k), env.lo[k][i])));
            if poly.len() > 2 {
                plot.draw(&Polygon::new(poly, light(colour(c)).mix(0.6).filled()))
                    .map_err(err)?;
            }
        }
        for (c, &i) in idx.iter().enumerate() {
            let line = (0..bins).filter_map(|k| Some((mid(k), (*p.nominal.get(k)?.get(i)?)?)));
            chart
                .draw_series(LineSeries::new(line, colour(c).stroke_width(2)))
                .map_err(err)?;
        }
    }
    Ok(())
}

fn draw_histogram<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    values: &[f64],
    mark: Option<f64>,
) -> Result<(), SimError> {
    let (mut lo, mut hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    if !(lo.is_finite() && hi.is_finite()) {
        (lo, hi) = (0.0, 1.0);
    }
    if hi <= lo {
        (lo, hi) = (lo - 0.5, hi + 0.5);
    }
    let w = (hi - lo) / BINS as f64;
    let mut counts = [0u64; BINS];
    for &v in values {
        let k = (((v - lo) / w).floor().max(0.0) as usize).min(BINS - 1);
        counts[k] += 1;
    }
    let top = counts.iter().copied().max().unwrap_or(0).max(1) as f64 * 1.05;
    let mut chart = ChartBuilder::on(root)
        .margin(20)
        .build_cartesian_2d(lo..hi, 0.0..top)
        .map_err(err)?;
    let plot = chart.plotting_area();
    plot.draw(&Rectangle::new(
        [(lo, 0.0), (hi, top)],
        BLACK.stroke_width(1),
    ))
    .map_err(err)?;
    chart
        .draw_series(counts.iter().enumerate().map(|(k, &c)| {
            let x = lo + k as f64 * w;
            Rectangle::new([(x, 0.0), (x + w, c as f64)], colour(0).filled())
        }))
        .map_err(err)?;
    if let Some(m) = mark.filter(|m| (lo..=hi).contains(m)) {
        chart
            .plotting_area()
            .draw(&PathElement::new(
                vec![(m, 0.0), (m, top)],
                RGBColor(214, 39, 40).stroke_width(2),
            ))
            .map_err(err)?;
    }
    Ok(())
}

fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, fig: &Figure) -> Result<(), SimError> {
    root.fill(&WHITE).map_err(err)?;
    match fig {
        Figure::Envelope(p) => draw_envelope(root, p)?,
        Figure::Histogram { values, mark } => draw_histogram(root, values, *mark)?,
    }
    root.present().map_err(err)
}

fn render(fig: &Figure) -> Result<(Vec<u8>, Vec<u8>), SimError> {
    let mut s = String::new();
    {
        let root = SVGBackend::with_string(&mut s, SIZE).into_drawing_area();
        draw(&root, fig)?;
    }
    let (w, h) = SIZE;
    let mut rgb = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
        draw(&root, fig)?;
    }
    Ok((s.into_bytes(), encode_png(&rgb, SIZE)?))
}

/// The plot files of a campaign: `(file name, bytes)`.
pub fn plots(p: &Partial) -> Result<Vec<(String, Vec<u8>)>, SimError> {
    let settle: Vec<f64> = p.runs.iter().filter_map(|r| r.settle_time_s).collect();
    let tx: Vec<f64> = p.runs.iter().map(|r| r.transmissions as f64).collect();
    let figs = [
        ("envelope", Figure::Envelope(p)),
        (
            "settle",
            Figure::Histogram {
                values: settle,
                mark: Some(p.converged_rule.2),
            },
        ),
        (
            "transmissions",
            Figure::Histogram {
                values: tx,
                mark: None,
            },
        ),
    ];
    let mut files = Vec::new();
    for (tag, fig) in &figs {
        let (svg, png) = render(fig)?;
        files.push((format!("{}.mc.{tag}.svg", p.name), svg));
        files.push((format!("{}.mc.{tag}.png", p.name), png));
    }
    Ok(files)
}
