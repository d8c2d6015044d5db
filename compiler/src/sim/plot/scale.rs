//! Axis ranges and tick labels that stay readable when a run diverges or goes
//! non-finite: the y-range is taken from the finite values only and clipped
//! to [`CLIP_FACTOR`] times the largest magnitude of the first half of the
//! time span (or to [`ABS_CAP`]), and the figure says so.

/// A panel's y-range is clipped when its values exceed this many times the
/// largest magnitude over the first half of its time span.
pub(crate) const CLIP_FACTOR: f64 = 20.0;

/// No axis extends beyond `+-ABS_CAP`, whatever the reference.
pub(crate) const ABS_CAP: f64 = 1e12;

/// A y-range and whether (and where) it clips the data.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct YRange {
    /// Lower end.
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
    /// `Some((cap, m))`: values were clipped at `+-cap`; `m` is the largest
    /// finite magnitude.
    pub clipped: Option<(f64, f64)>,
}

/// The y-range of the points `(t, y)` shown over the time span `span`, zero
/// always included; non-finite values and points outside `span` are ignored.
pub(crate) fn y_range(points: &[(f64, f64)], span: (f64, f64)) -> YRange {
    let shown = |t: f64| span.0 <= t && t <= span.1;
    let finite = || points.iter().filter(|p| shown(p.0) && p.1.is_finite());
    let (lo, hi) = finite().fold((0.0f64, 0.0f64), |(a, b), p| (a.min(p.1), b.max(p.1)));
    let largest = lo.abs().max(hi.abs());
    let half = span.0 + 0.5 * (span.1 - span.0);
    let early = finite()
        .filter(|p| p.0 <= half)
        .fold(0.0f64, |m, p| m.max(p.1.abs()));
    let cap = if early > 0.0 {
        (CLIP_FACTOR * early).min(ABS_CAP)
    } else {
        ABS_CAP
    };
    let clipped = (largest > cap).then_some((cap, largest));
    let (lo, hi) = if clipped.is_some() {
        (lo.max(-cap), hi.min(cap))
    } else {
        (lo, hi)
    };
    let pad = 0.05 * (hi - lo);
    if pad > 0.0 {
        YRange {
            lo: lo - pad,
            hi: hi + pad,
            clipped,
        }
    } else {
        YRange {
            lo: lo - 1.0,
            hi: hi + 1.0,
            clipped,
        }
    }
}

/// The finite stretches of a series, each point's y clamped to `lo ..= hi`:
/// a NaN or infinite sample ends a stretch instead of breaking the line.
pub(crate) fn stretches(points: &[(f64, f64)], lo: f64, hi: f64) -> Vec<Vec<(f64, f64)>> {
    let mut out: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
    for &(t, y) in points {
        if t.is_finite() && y.is_finite() {
            if let Some(last) = out.last_mut() {
                last.push((t, y.clamp(lo, hi)));
            }
        } else if out.last().is_some_and(|s| !s.is_empty()) {
            out.push(Vec::new());
        }
    }
    out.retain(|s| !s.is_empty());
    out
}

/// A tick label: at most four significant digits, trailing zeros dropped,
/// scientific notation for very large or small magnitudes.
pub(crate) fn tick(v: &f64) -> String {
    // Four significant digits first, so 0.00099999 reads as 0.001.
    let v = format!("{:.3e}", *v).parse::<f64>().unwrap_or(*v);
    let a = v.abs();
    if a < 1e-12 {
        return "0".into();
    }
    if !(1e-4..1e5).contains(&a) {
        let s = format!("{v:.3e}");
        let (m, e) = s.split_once('e').unwrap_or((&s, "0")); // ok: `{:e}` always has an exponent
        return format!("{}e{e}", trim(m));
    }
    let decimals = (3 - a.log10().floor() as i32).clamp(0, 8) as usize;
    trim(&format!("{v:.decimals$}")).to_string()
}

/// A number for a caption or legend: four significant digits.
pub(crate) fn num(v: f64) -> String {
    if v.is_finite() {
        tick(&v)
    } else {
        format!("{v}")
    }
}

fn trim(s: &str) -> &str {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.')
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_short() {
        assert_eq!(tick(&0.30000000000000004), "0.3");
        assert_eq!(tick(&-2.5), "-2.5");
        assert_eq!(tick(&1500.0), "1500");
        assert_eq!(tick(&0.00099999999), "0.001");
        assert_eq!(tick(&1.5e7), "1.5e7");
        assert_eq!(tick(&2e-5), "2e-5");
        assert_eq!(tick(&0.12345678), "0.1235");
        assert_eq!(tick(&1e-15), "0");
    }

    #[test]
    fn a_diverging_series_is_clipped() {
        let pts: Vec<(f64, f64)> = (0..100)
            .map(|k| (k as f64, (0.3 * k as f64).exp()))
            .collect();
        let r = y_range(&pts, (0.0, 99.0));
        assert!(r.clipped.is_some());
        assert!(r.hi < 1e9 && r.hi > 1.0, "{r:?}");
        let calm: Vec<(f64, f64)> = (0..100)
            .map(|k| (k as f64, (-0.1 * k as f64).exp()))
            .collect();
        assert_eq!(y_range(&calm, (0.0, 99.0)).clipped, None);
    }

    #[test]
    fn non_finite_samples_split_the_line() {
        let pts = [
            (0.0, 1.0),
            (1.0, f64::NAN),
            (2.0, 3.0),
            (3.0, f64::INFINITY),
        ];
        let r = y_range(&pts, (0.0, 3.0));
        assert!(r.lo.is_finite() && r.hi.is_finite());
        assert_eq!(stretches(&pts, -10.0, 10.0).len(), 2);
        assert_eq!(stretches(&[(0.0, 50.0)], -1.0, 1.0), vec![vec![(0.0, 1.0)]]);
    }
}
