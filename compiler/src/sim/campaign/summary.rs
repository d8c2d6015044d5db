//! What a campaign keeps: per run a few figures of merit ([`RunRecord`]),
//! over all runs a decimated envelope of the states ([`Envelope`]); a shard's
//! output ([`Partial`]), the merge of shards, and the summary table computed
//! from the merged runs alone (so one run of N and K merged shards give the
//! same summary).

use serde::{Deserialize, Serialize};

/// Format tag of a shard file.
pub const SHARD_FORMAT: &str = "tsfc-monte-carlo-shard/2";

/// The figures of merit of one run (nothing per step).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct RunRecord {
    /// Run index in `0 .. runs`.
    pub index: u64,
    /// The run's seed (its draws and sampling pattern).
    pub seed: u64,
    /// Converged by the declared rule.
    pub converged: bool,
    /// Earliest time from which the declared norm stays within its bound.
    pub settle_time_s: Option<f64>,
    /// Largest |u| per input channel.
    pub max_abs_u: Vec<f64>,
    /// Transmissions to the actuators.
    pub transmissions: u64,
    /// Final norm of the declared signal (`None`: not finite).
    pub final_norm: Option<f64>,
    /// `V = x'Px` ended above its initial value.
    pub diverged: bool,
    /// The state went non-finite (NaN or infinite).
    pub nonfinite: bool,
    /// The run stopped on an error (its message).
    pub error: Option<String>,
}

impl RunRecord {
    /// A failed run: not converged, or an error.
    pub fn failed(&self) -> bool {
        !self.converged || self.error.is_some()
    }

    /// Why the run failed, in a few words.
    pub fn why(&self) -> String {
        if let Some(e) = &self.error {
            return format!("error: {}", e.lines().next().unwrap_or(""));
        }
        let mut why = Vec::new();
        if self.nonfinite {
            why.push("non-finite state".to_string());
        }
        if self.diverged {
            why.push("V(x) grew".to_string());
        }
        why.push(match self.settle_time_s {
            Some(t) => format!("settled only at {t} s"),
            None => match self.final_norm {
                Some(r) => format!("not settled (final norm {r:.3e})"),
                None => "not settled".to_string(),
            },
        });
        why.join(", ")
    }
}

/// Per time bin, the min and max of every state component across runs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Envelope {
    /// Start and end of the time axis.
    pub span: (f64, f64),
    /// Lower envelope `[bin][component]` (`f64::MAX`, above `hi`, where no finite sample fell).
    pub lo: Vec<Vec<f64>>,
    /// Upper envelope `[bin][component]`.
    pub hi: Vec<Vec<f64>>,
}

impl Envelope {
    /// An empty envelope of `bins` bins over `span` for `dim` components.
    pub fn new(span: (f64, f64), bins: usize, dim: usize) -> Self {
        Envelope {
            span,
            lo: vec![vec![f64::MAX; dim]; bins],
            hi: vec![vec![f64::MIN; dim]; bins],
        }
    }

    /// The bin of time `t`.
    pub fn bin(&self, t: f64) -> usize {
        let (t0, t1) = self.span;
        let bins = self.lo.len();
        let k = ((t - t0) / (t1 - t0) * bins as f64).floor();
        if k.is_nan() || k < 0.0 {
            0
        } else {
            (k as usize).min(bins.saturating_sub(1))
        }
    }

    /// Widens bin `k` to include the finite components of `x`.
    pub fn add(&mut self, k: usize, x: &[f64]) {
        if let (Some(lo), Some(hi)) = (self.lo.get_mut(k), self.hi.get_mut(k)) {
            for ((l, h), &v) in lo.iter_mut().zip(hi.iter_mut()).zip(x) {
                if v.is_finite() {
                    *l = l.min(v);
                    *h = h.max(v);
                }
            }
        }
    }

    /// The union with `other` (associative and commutative: the result does
    /// not depend on how runs were grouped).
    pub fn merge(&mut self, other: &Envelope) {
        let bins = self.lo.iter_mut().zip(self.hi.iter_mut());
        for ((lo, hi), (olo, ohi)) in bins.zip(other.lo.iter().zip(&other.hi)) {
            for (l, o) in lo.iter_mut().zip(olo) {
                *l = l.min(*o);
            }
            for (h, o) in hi.iter_mut().zip(ohi) {
                *h = h.max(*o);
            }
        }
    }
}

/// The output of one shard (or of a whole campaign, shard 1 of 1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Partial {
    /// [`SHARD_FORMAT`].
    pub format: String,
    /// The tsfc version that ran the shard.
    pub tsfc_version: String,
    /// SHA-256 of the spec the shard ran.
    pub spec_sha256: String,
    /// Hash of the design the shard ran ([`super::shard::design_sha256`]).
    pub design_sha256: String,
    /// Controller name (a plain file name: [`super::shard::plain_name`]).
    pub name: String,
    /// Campaign size N (all shards).
    pub runs_total: u64,
    /// Campaign seed.
    pub seed: u64,
    /// `(k, K)`: this shard ran the indices `i` with `i mod K == k - 1`.
    pub shard: (u64, u64),
    /// Simulated span (s).
    pub time_s: (f64, f64),
    /// The declared convergence rule: signal name, bound, time.
    pub converged_rule: (String, f64, f64),
    /// State component names (envelope columns).
    pub state_names: Vec<String>,
    /// Input names.
    pub input_names: Vec<String>,
    /// The shard's runs, by index.
    pub runs: Vec<RunRecord>,
    /// The shard's state envelope.
    pub envelope: Envelope,
    /// The nominal run (no perturbation) per bin: its last sample in the bin
    /// (the previous bin's where none fell; `None`: not finite).
    pub nominal: Vec<Vec<Option<f64>>>,
}

/// Merges the shards `parts` of one campaign (every shard exactly once),
/// each already checked by [`super::shard::validate`]: they must agree on
/// their identity and campaign ([`super::shard::differences`]).
pub fn merge(mut parts: Vec<Partial>) -> Result<Partial, String> {
    parts.sort_by_key(|p| p.shard.0);
    let Some(first) = parts.first() else {
        return Err("no shard files to merge".into());
    };
    let total = first.shard.1;
    for p in &parts[1..] {
        let differ = super::shard::differences(first, p);
        if !differ.is_empty() {
            return Err(format!(
                "shard {}/{} and shard {}/{} belong to different campaigns: their {} differ",
                first.shard.0,
                first.shard.1,
                p.shard.0,
                p.shard.1,
                differ.join(", ")
            ));
        }
    }
    let ks: Vec<u64> = parts.iter().map(|p| p.shard.0).collect();
    if ks.len() as u64 != total || ks.iter().zip(1..).any(|(&k, want)| k != want) {
        let mut shown: Vec<String> = ks.iter().take(20).map(u64::to_string).collect();
        if ks.len() > 20 {
            shown.push(format!("... ({} in all)", ks.len()));
        }
        return Err(format!(
            "the shards present are [{}]; a campaign of {total} shards needs each of 1..={total} once",
            shown.join(", ")
        ));
    }
    let mut merged = first.clone();
    merged.shard = (1, 1);
    for p in &parts[1..] {
        merged.runs.extend(p.runs.iter().cloned());
        merged.envelope.merge(&p.envelope);
    }
    merged.runs.sort_by_key(|r| r.index);
    if merged.runs.len() as u64 != merged.runs_total
        || merged
            .runs
            .iter()
            .enumerate()
            .any(|(i, r)| r.index != i as u64)
    {
        return Err(format!(
            "the shards hold {} runs, not the runs 0..{} once each",
            merged.runs.len(),
            merged.runs_total
        ));
    }
    Ok(merged)
}

/// Minimum, median, 95th percentile and maximum (nearest rank) of `v`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Spread {
    /// Smallest.
    pub min: f64,
    /// Median.
    pub median: f64,
    /// 95th percentile.
    pub p95: f64,
    /// Largest.
    pub max: f64,
}

fn spread(mut v: Vec<f64>) -> Option<Spread> {
    v.retain(|x| x.is_finite());
    v.sort_by(f64::total_cmp);
    let rank = |q: f64| v[(((q * v.len() as f64).ceil() as usize).max(1) - 1).min(v.len() - 1)];
    (!v.is_empty()).then(|| Spread {
        min: v[0],
        median: rank(0.5),
        p95: rank(0.95),
        max: v[v.len() - 1],
    })
}

/// A failed run in the summary.
#[derive(Debug, Clone, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Failure {
    /// Run index.
    pub index: u64,
    /// Run seed.
    pub seed: u64,
    /// Why.
    pub why: String,
}

/// Most failures listed by name in the summary (all are counted).
pub const MAX_LISTED_FAILURES: usize = 100;

/// The campaign's summary.
#[derive(Debug, Clone, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Summary {
    /// Controller name.
    pub name: String,
    /// Runs.
    pub runs: u64,
    /// Campaign seed.
    pub seed: u64,
    /// The rule: `|signal| <= bound by time`.
    pub converged_rule: String,
    /// Runs that converged.
    pub converged: u64,
    /// `converged / runs`.
    pub fraction_converged: f64,
    /// Settle times of the runs that settled (s).
    pub settle_time_s: Option<Spread>,
    /// Largest |u| per channel over all runs.
    pub worst_abs_u: Vec<f64>,
    /// Transmissions per run.
    pub transmissions: Option<Spread>,
    /// Final norms.
    pub final_norm: Option<Spread>,
    /// Runs with a non-finite state.
    pub nonfinite: u64,
    /// Runs whose `V = x'Px` grew.
    pub diverged: u64,
    /// Runs stopped by an error.
    pub errors: u64,
    /// Failed runs (at most [`MAX_LISTED_FAILURES`]), by index.
    pub failures: Vec<Failure>,
    /// Failed runs in all.
    pub failed: u64,
}

/// The summary of a merged (or whole) campaign.
pub fn summarize(p: &Partial) -> Summary {
    let runs = p.runs.len() as u64;
    let converged = p.runs.iter().filter(|r| r.converged).count() as u64;
    let m = p.input_names.len();
    let mut worst = vec![0.0f64; m];
    for r in &p.runs {
        for (w, u) in worst.iter_mut().zip(&r.max_abs_u) {
            *w = w.max(*u);
        }
    }
    let failed: Vec<&RunRecord> = p.runs.iter().filter(|r| r.failed()).collect();
    let (sig, tol, by) = &p.converged_rule;
    Summary {
        name: p.name.clone(),
        runs,
        seed: p.seed,
        converged_rule: format!("|{sig}| <= {tol:e} from {by} s on"),
        converged,
        fraction_converged: if runs == 0 {
            0.0
        } else {
            converged as f64 / runs as f64
        },
        settle_time_s: spread(p.runs.iter().filter_map(|r| r.settle_time_s).collect()),
        worst_abs_u: worst,
        transmissions: spread(p.runs.iter().map(|r| r.transmissions as f64).collect()),
        final_norm: spread(p.runs.iter().filter_map(|r| r.final_norm).collect()),
        nonfinite: p.runs.iter().filter(|r| r.nonfinite).count() as u64,
        diverged: p.runs.iter().filter(|r| r.diverged).count() as u64,
        errors: p.runs.iter().filter(|r| r.error.is_some()).count() as u64,
        failures: failed
            .iter()
            .take(MAX_LISTED_FAILURES)
            .map(|r| Failure {
                index: r.index,
                seed: r.seed,
                why: r.why(),
            })
            .collect(),
        failed: failed.len() as u64,
    }
}

fn fmt_spread(s: &Option<Spread>, unit: &str) -> [String; 4] {
    match s {
        Some(s) => [s.min, s.median, s.p95, s.max].map(|v| match unit {
            "" => format!("{v}"),
            " s" => format!("{v:.3} s"),
            _ => format!("{v:.3e}"),
        }),
        None => std::array::from_fn(|_| "-".to_string()),
    }
}

impl Summary {
    /// The summary table in Markdown.
    pub fn markdown(&self) -> String {
        let mut s = format!(
            "# Monte Carlo: `{}`\n\n{} runs, seed {}; converged means {}.\n\n| metric | value |\n|---|---|\n",
            self.name, self.runs, self.seed, self.converged_rule
        );
        for (k, v) in self.rows() {
            s.push_str(&format!("| {k} | {v} |\n"));
        }
        if self.failed > 0 {
            s.push_str(&format!(
                "\n## Failed runs ({}{})\n\n| run | seed | why |\n|---|---|---|\n",
                self.failed,
                if self.failed as usize > self.failures.len() {
                    format!(", first {}", self.failures.len())
                } else {
                    String::new()
                }
            ));
            for f in &self.failures {
                s.push_str(&format!("| {} | {} | {} |\n", f.index, f.seed, f.why));
            }
        }
        s
    }

    /// The summary as CSV rows `metric,value`.
    pub fn csv(&self) -> String {
        let mut s = String::from("metric,value\n");
        for (k, v) in self.rows() {
            s.push_str(&format!("{k},\"{v}\"\n"));
        }
        s
    }

    fn rows(&self) -> Vec<(String, String)> {
        let mut rows = vec![
            ("runs".into(), self.runs.to_string()),
            (
                "fraction converged".into(),
                format!(
                    "{:.4} ({} of {})",
                    self.fraction_converged, self.converged, self.runs
                ),
            ),
        ];
        let labels = ["min", "median", "p95", "max"];
        for (name, spread, unit) in [
            ("settle time", &self.settle_time_s, " s"),
            ("transmissions", &self.transmissions, ""),
            ("final norm", &self.final_norm, "e"),
        ] {
            for (l, v) in labels.iter().zip(fmt_spread(spread, unit)) {
                rows.push((format!("{name} {l}"), v));
            }
        }
        rows.push((
            "worst abs(u) per channel".into(),
            self.worst_abs_u
                .iter()
                .map(|u| format!("{u:.4}"))
                .collect::<Vec<_>>()
                .join(" "),
        ));
        rows.push(("non-finite runs".into(), self.nonfinite.to_string()));
        rows.push(("runs with V(x) growing".into(), self.diverged.to_string()));
        rows.push(("runs stopped by an error".into(), self.errors.to_string()));
        rows.push(("failed runs".into(), self.failed.to_string()));
        rows
    }
}

/// The per-run table as CSV.
pub fn runs_csv(p: &Partial) -> String {
    let mut s = String::from(
        "run,seed,converged,settle_time_s,transmissions,final_norm,diverged,nonfinite",
    );
    for u in &p.input_names {
        s.push_str(&format!(",max_abs_{u}"));
    }
    s.push_str(",error\n");
    for r in &p.runs {
        s.push_str(&format!(
            "{},{},{},{},{},{},{},{}",
            r.index,
            r.seed,
            r.converged,
            r.settle_time_s.map_or(String::new(), |t| t.to_string()),
            r.transmissions,
            r.final_norm.map_or(String::new(), |v| format!("{v:e}")),
            r.diverged,
            r.nonfinite
        ));
        for u in &r.max_abs_u {
            s.push_str(&format!(",{u:e}"));
        }
        s.push_str(&format!(
            ",\"{}\"\n",
            r.error
                .as_deref()
                .unwrap_or("")
                .replace('"', "'")
                .replace('\n', " ")
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_uses_nearest_ranks() {
        let s = spread((1..=100).map(f64::from).collect()).expect("values"); // ok: unit test
        assert_eq!((s.min, s.median, s.p95, s.max), (1.0, 50.0, 95.0, 100.0));
        assert!(spread(vec![f64::NAN]).is_none());
    }

    #[test]
    fn envelopes_merge_in_any_grouping() {
        let mut a = Envelope::new((0.0, 1.0), 4, 1);
        let mut b = a.clone();
        a.add(a.bin(0.1), &[1.0]);
        b.add(b.bin(0.1), &[-2.0]);
        b.add(b.bin(1.0), &[f64::NAN]);
        let mut ab = a.clone();
        ab.merge(&b);
        let mut ba = b.clone();
        ba.merge(&a);
        assert_eq!(ab, ba);
        assert_eq!((ab.lo[0][0], ab.hi[0][0]), (-2.0, 1.0));
        assert_eq!(ab.hi[3][0], f64::MIN);
    }
}
