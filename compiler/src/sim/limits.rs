//! The simulator's limits (documented in `docs/limits.md`): how many steps
//! one run may take, how long the adaptive integrator may keep shrinking its
//! step, and how many points a plot keeps. Every entry point (the spec's
//! `time` setting, a horizon, trigger or initial-state override, the library's
//! [`super::Options`]) goes through [`step_count`].

/// Most steps of one run: `(t1 - t0) / min(h, h_min)` with `h` the scenario's
/// step and `h_min` the shortest sampling interval of the trigger.
pub const MAX_STEPS: u64 = 10_000_000;

/// Most trial steps (accepted and rejected) of the adaptive integrator over a
/// whole run; a system that needs more is too stiff for it.
pub const MAX_ADAPTIVE_STEPS: u64 = 10 * MAX_STEPS;

/// Largest magnitude of a state component the simulator integrates. The
/// trigger gates and the metrics square norms, and f64 squares overflow past
/// about 1.3e154: beyond this a run would compare infinities (a mixed trigger
/// then fires at every instant and the run crawls), so the initial state is
/// refused and a run that grows past it stops as failed.
pub const MAX_STATE_MAGNITUDE: f64 = 1e150;

/// Most steps of a Monte Carlo campaign over all its runs (each run is also
/// bounded by [`MAX_STEPS`]): `runs * steps per run`, about a day of one core.
pub const MAX_CAMPAIGN_STEPS: u64 = 100_000_000_000;

/// Most shards of a Monte Carlo campaign (`--shard k/K`: K at most this):
/// the largest job arrays of the schedulers it runs on (Kubernetes Indexed
/// Jobs and Google Cloud Batch take 100,000 tasks; Slurm and AWS Batch fewer).
pub const MAX_SHARDS: u64 = 100_000;

/// Largest shard file `--merge` reads (bytes): a shard of 10^6 runs with a
/// long error message per run fits.
pub const MAX_SHARD_FILE_BYTES: u64 = 2 << 30;

/// Most worker threads `--jobs` takes (a campaign or sweep needs no more).
pub const MAX_JOBS: usize = 1024;

/// `--jobs N`: a whole number of threads in 1 ..= [`MAX_JOBS`].
pub fn parse_jobs(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(n) if (1..=MAX_JOBS).contains(&n) => Ok(n),
        _ => Err(format!(
            "--jobs takes a whole number of threads in 1 ..= {MAX_JOBS} (got `{}`)",
            s.escape_debug()
        )),
    }
}

/// Most points per plotted series (samples, transmission instants, gaps).
pub const MAX_PLOT_POINTS: usize = 4000;

/// Progress lines on a non-terminal stderr: at most one per this many seconds.
pub const PROGRESS_LOG_PERIOD_S: f64 = 10.0;

/// The number of steps of the span `t0 .. t1` at step `h` when samples may be
/// as close as `shortest_interval` (pass `h` for grid sampling): the
/// simulator's one step count. Refuses a span or step that is not positive
/// and finite, and more than [`MAX_STEPS`] steps; the message says which.
pub fn step_count(t0: f64, t1: f64, h: f64, shortest_interval: f64) -> Result<u64, String> {
    use tsf_lang::num::Num;
    let (t0n, t1n) = (Num(t0), Num(t1));
    if !(t0.is_finite() && t1.is_finite() && t1 > t0) {
        return Err(format!(
            "the time span {t0n} .. {t1n} is empty or not finite"
        ));
    }
    if !(h.is_finite() && h > 0.0) {
        return Err(format!("the step {} s is not a positive number", Num(h)));
    }
    if !(shortest_interval.is_finite() && shortest_interval > 0.0) {
        return Err(format!(
            "the shortest sampling interval {} s is not a positive number",
            Num(shortest_interval)
        ));
    }
    // The slack keeps a span of exactly k steps from counting k + 1.
    let steps = ((t1 - t0) / h.min(shortest_interval) - 1e-9).ceil();
    if steps.is_finite() && steps <= MAX_STEPS as f64 {
        // ok: 1 <= steps <= MAX_STEPS, exact in u64.
        Ok(steps.max(1.0) as u64)
    } else {
        Err(format!(
            "{t0n} .. {t1n} s at step {} s is {steps:.3e} steps; the simulator takes at most {MAX_STEPS:.0e}",
            Num(h.min(shortest_interval)),
            MAX_STEPS = MAX_STEPS as f64
        ))
    }
}

/// A series thinned to at most `cap` points as it streams by: every
/// `stride`-th item is kept (the stride doubles whenever the kept items reach
/// the cap), and [`Thinned::finish_with`] adds the last item. The result is
/// deterministic and uniform in the item index.
#[derive(Debug, Clone)]
pub struct Thinned<T> {
    items: Vec<T>,
    cap: usize,
    stride: u64,
    seen: u64,
    last_kept: bool,
}

impl<T> Thinned<T> {
    /// An empty series keeping at most `cap` (at least 2) points.
    pub fn new(cap: usize) -> Self {
        Thinned {
            items: Vec::new(),
            cap: cap.max(2),
            stride: 1,
            seen: 0,
            last_kept: false,
        }
    }

    /// Offers the next item; `make` runs only if the item is kept.
    pub fn push_with(&mut self, make: impl FnOnce() -> T) {
        let keep = self.seen.is_multiple_of(self.stride);
        self.seen += 1;
        self.last_kept = keep;
        if !keep {
            return;
        }
        self.items.push(make());
        // Keep one slot for the last item.
        if self.items.len() + 1 >= self.cap {
            self.last_kept = self.items.len() % 2 == 1;
            let mut i = 0;
            self.items.retain(|_| {
                i += 1;
                i % 2 == 1
            });
            self.stride *= 2;
        }
    }

    /// Offers the next item.
    pub fn push(&mut self, item: T) {
        self.push_with(|| item);
    }

    /// The kept items, with the last offered one (built by `make`) appended
    /// if it was not kept.
    pub fn finish_with(mut self, make: impl FnOnce() -> T) -> Vec<T> {
        if self.seen > 0 && !self.last_kept {
            self.items.push(make());
        }
        self.items
    }

    /// Items offered so far.
    pub fn seen(&self) -> u64 {
        self.seen
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn step_count_refuses_past_the_limit_and_bad_spans() {
        assert_eq!(step_count(0.0, 5.0, 0.001, 0.001), Ok(5000));
        assert_eq!(step_count(0.0, 5.0, 0.001, 0.01), Ok(5000));
        assert_eq!(step_count(0.0, 5.0, 0.01, 0.001), Ok(5000));
        let end = 0.5 * MAX_STEPS as f64;
        assert_eq!(step_count(0.0, end, 0.5, 0.5), Ok(MAX_STEPS));
        let over = step_count(0.0, end + 1.0, 0.5, 0.5).expect_err("just over");
        assert!(over.contains("at most 1e7"), "{over}");
        for (t0, t1, h, hmin) in [
            (0.0, 0.0, 0.1, 0.1),
            (0.0, -1.0, 0.1, 0.1),
            (0.0, f64::NAN, 0.1, 0.1),
            (0.0, f64::INFINITY, 0.1, 0.1),
            (0.0, 1.0, 0.0, 0.1),
            (0.0, 1.0, f64::NAN, 0.1),
            (0.0, 1.0, 0.1, 0.0),
            (0.0, 1.0, 0.1, -0.5),
            (0.0, 1e12, 0.01, 0.01),
            (0.0, 1.0, 1e-300, 1.0),
        ] {
            assert!(step_count(t0, t1, h, hmin).is_err(), "{t0} {t1} {h} {hmin}");
        }
    }

    #[test]
    fn thinning_is_bounded_uniform_and_keeps_both_ends() {
        for len in [0u64, 1, 2, 7, 9, 10, 11, 1000, 12_345] {
            let mut s = Thinned::new(10);
            for k in 0..len {
                s.push(k);
            }
            let v = s.finish_with(|| len - 1);
            assert!(v.len() <= 10, "{len}: {v:?}");
            if len == 0 {
                assert!(v.is_empty());
                continue;
            }
            assert_eq!(v[0], 0);
            assert_eq!(v.last(), Some(&(len - 1)), "{len}: {v:?}");
            // Uniform stride apart from the appended last item.
            let body = &v[..v.len() - 1];
            let gaps: Vec<u64> = body.windows(2).map(|w| w[1] - w[0]).collect();
            assert!(gaps.windows(2).all(|g| g[0] == g[1]), "{len}: {v:?}");
            if len < 9 {
                assert_eq!(v.len() as u64, len, "short series are kept whole");
            }
        }
    }
}
