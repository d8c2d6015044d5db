//! What a shard file must prove before `--merge` trusts it: its identity (the
//! format, the tsfc version, the spec's SHA-256 and a hash of the design it
//! ran) and the shape and range of every field. Shard files come from other
//! machines and may be damaged or forged: nothing in them is used as a path,
//! a size or an index before it is checked here.

use super::summary::{Partial, RunRecord, SHARD_FORMAT};
use super::ENVELOPE_BINS;
use crate::sim::limits::MAX_SHARDS;
use crate::sim::Prepared;
use sha2::{Digest, Sha256};
use tsf_lang::limits::MAX_MONTE_CARLO_RUNS;

/// Longest controller name a campaign writes files for (bytes): the longest
/// output name adds 20 bytes, file systems allow 255.
pub const MAX_NAME_BYTES: usize = 200;
/// Longest state, input or signal name in a shard file (bytes).
const MAX_LABEL_BYTES: usize = 256;
/// Most state or input names in a shard file.
const MAX_COMPONENTS: usize = 1024;
/// Longest error message of one run (bytes).
const MAX_ERROR_BYTES: usize = 64 << 10;

/// The hash of a design as the simulator runs it: the gains (every mode's),
/// the saturation levels, the trigger weight and the Lyapunov matrix P that
/// judges divergence, as the bits of their f64 values in a fixed order. The
/// same for a design compiled here and one reused from its report (the report
/// stores every value in round-trip form).
pub fn design_sha256(prepared: &Prepared) -> String {
    let t = &prepared.tables;
    let mut h = Sha256::new();
    let mut put = |tag: &str, values: &mut dyn Iterator<Item = f64>| {
        h.update(tag.as_bytes());
        let mut count = 0u64;
        for v in values {
            h.update(v.to_bits().to_le_bytes());
            count += 1;
        }
        h.update(count.to_le_bytes());
    };
    put("gains", &mut t.gains.iter().flatten().flatten().copied());
    let modes = t
        .modes
        .iter()
        .flat_map(|m| m.gains.iter().flatten().flatten());
    put("mode gains", &mut modes.flatten().copied());
    put("u_max", &mut t.u_max.iter().copied());
    let weight = prepared.trigger_weight.iter().flat_map(|w| w.iter());
    put("trigger weight", &mut weight.copied());
    put("P", &mut prepared.p.iter().copied());
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

/// Whether `name` can be a file-name prefix: a controller identifier
/// (`[A-Za-z_][A-Za-z0-9_]*`, what the language accepts) of at most
/// [`MAX_NAME_BYTES`]: no separator, no `..`, no control character.
pub fn plain_name(name: &str) -> bool {
    let mut ch = name.chars();
    name.len() <= MAX_NAME_BYTES
        && matches!(ch.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
        && ch.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// Whether `s` is printable text of at most `max` bytes (newlines and tabs
/// only where `lines`).
fn text(s: &str, max: usize, lines: bool) -> bool {
    s.len() <= max
        && s.chars()
            .all(|c| !c.is_control() || (lines && matches!(c, '\n' | '\t')))
}

/// Whether `s` is 64 lowercase hexadecimal digits.
fn sha(s: &str) -> bool {
    s.len() == 64 && s.bytes().all(|b| matches!(b, b'0'..=b'9' | b'a'..=b'f'))
}

/// How many run indices `i < runs` satisfy `i mod K == k - 1`.
pub fn shard_size(runs: u64, (k, kk): (u64, u64)) -> u64 {
    if k == 0 || kk == 0 || k > runs {
        0
    } else {
        (runs - k) / kk + 1
    }
}

/// Checks every field of a shard (or whole-campaign) file; the first problem
/// found, in words.
pub fn validate(p: &Partial) -> Result<(), String> {
    if p.format != SHARD_FORMAT {
        return Err(format!(
            "it has format `{}`, this tsfc reads `{SHARD_FORMAT}` (written by tsfc {})",
            p.format.escape_debug(),
            p.tsfc_version.escape_debug()
        ));
    }
    if !plain_name(&p.name) {
        return Err(format!(
            "its controller name `{}` is not a plain file name (an identifier of at most {MAX_NAME_BYTES} bytes: letters, digits, `_`)",
            p.name.escape_debug()
        ));
    }
    if !text(&p.tsfc_version, 64, false) || p.tsfc_version.is_empty() {
        return Err("its tsfc version is not a version".into());
    }
    if !sha(&p.spec_sha256) || !sha(&p.design_sha256) {
        return Err("its spec or design hash is not 64 hexadecimal digits".into());
    }
    if !(1..=MAX_MONTE_CARLO_RUNS).contains(&p.runs_total) {
        return Err(format!(
            "its campaign has {} runs: 1 .. {MAX_MONTE_CARLO_RUNS}",
            p.runs_total
        ));
    }
    let (k, kk) = p.shard;
    if !(1 <= k && k <= kk && kk <= MAX_SHARDS) {
        return Err(format!(
            "its shard {k}/{kk} is not 1 <= k <= K <= {MAX_SHARDS}"
        ));
    }
    let (t0, t1) = p.time_s;
    if !(t0.is_finite() && t1.is_finite() && t0 < t1) {
        return Err(format!(
            "its time span {t0} .. {t1} is not a finite interval"
        ));
    }
    let (signal, tol, by) = &p.converged_rule;
    let rule_ok = text(signal, MAX_LABEL_BYTES, false)
        && tol.is_finite()
        && *tol >= 0.0
        && by.is_finite()
        && *by <= t1;
    if !rule_ok {
        return Err(
            "its convergence rule is not a signal, a finite bound and a time of the span".into(),
        );
    }
    let names_ok = |names: &[String]| {
        names.len() <= MAX_COMPONENTS
            && names
                .iter()
                .all(|s| !s.is_empty() && text(s, MAX_LABEL_BYTES, false))
    };
    if p.state_names.is_empty() || !names_ok(&p.state_names) || !names_ok(&p.input_names) {
        return Err("its state or input names are not short printable names".into());
    }
    envelope(p)?;
    let want = shard_size(p.runs_total, p.shard);
    if p.runs.len() as u64 != want {
        return Err(format!(
            "shard {k}/{kk} of {} runs holds {} runs, not {want}",
            p.runs_total,
            p.runs.len()
        ));
    }
    for (pos, r) in p.runs.iter().enumerate() {
        let i = k - 1 + pos as u64 * kk;
        run(p, r, i).map_err(|e| format!("run {}: {e}", r.index))?;
    }
    Ok(())
}

/// The envelope and nominal run: [`ENVELOPE_BINS`] bins of one value per
/// state, over the campaign's span.
fn envelope(p: &Partial) -> Result<(), String> {
    let dim = p.state_names.len();
    let env = &p.envelope;
    if env.span != p.time_s {
        return Err("its envelope spans another time interval than the campaign".into());
    }
    let shaped =
        |rows: &[Vec<f64>]| rows.len() == ENVELOPE_BINS && rows.iter().all(|r| r.len() == dim);
    if !shaped(&env.lo) || !shaped(&env.hi) {
        return Err(format!(
            "its envelope is not {ENVELOPE_BINS} bins of {dim} values (one per state name)"
        ));
    }
    for (lo, hi) in env.lo.iter().zip(&env.hi) {
        for (l, h) in lo.iter().zip(hi) {
            let empty = *l == f64::MAX && *h == f64::MIN;
            if !(empty || (l.is_finite() && h.is_finite() && l <= h)) {
                return Err(
                    "its envelope has a bin whose lower edge is above its upper one".into(),
                );
            }
        }
    }
    let nominal_ok = p.nominal.len() == ENVELOPE_BINS
        && p.nominal
            .iter()
            .all(|r| r.len() == dim && r.iter().flatten().all(|v| v.is_finite()));
    if !nominal_ok {
        return Err(format!(
            "its nominal run is not {ENVELOPE_BINS} bins of {dim} finite values"
        ));
    }
    Ok(())
}

/// One run record: its index is the `pos`-th of the shard (`i`), its seed the
/// campaign's for that index, its numbers finite and its verdict consistent.
fn run(p: &Partial, r: &RunRecord, i: u64) -> Result<(), String> {
    let (t0, t1) = p.time_s;
    if r.index != i {
        return Err(format!("expected run {i} at this place of the shard"));
    }
    if r.seed != super::draw::run_seed(p.seed, i) {
        return Err("its seed is not the campaign's seed for this run".into());
    }
    if r.max_abs_u.len() != p.input_names.len()
        || r.max_abs_u.iter().any(|u| !(u.is_finite() && *u >= 0.0))
    {
        return Err("its largest |u| is not one finite value per input".into());
    }
    if r.settle_time_s
        .is_some_and(|t| !(t.is_finite() && t0 <= t && t <= t1))
    {
        return Err("its settle time is outside the span".into());
    }
    if r.final_norm.is_some_and(|v| !(v.is_finite() && v >= 0.0)) {
        return Err("its final norm is not a finite norm".into());
    }
    if r.error
        .as_deref()
        .is_some_and(|e| !text(e, MAX_ERROR_BYTES, true))
    {
        return Err(format!(
            "its error message is not printable text of at most {MAX_ERROR_BYTES} bytes"
        ));
    }
    let by = p.converged_rule.2;
    if r.converged && (r.error.is_some() || r.nonfinite || r.settle_time_s.is_none_or(|t| t > by)) {
        return Err("it is marked converged but did not settle in time".into());
    }
    Ok(())
}

/// The fields two shards of one campaign must share, named for the message.
pub fn differences(a: &Partial, b: &Partial) -> Vec<&'static str> {
    let checks: [(&'static str, bool); 12] = [
        ("tsfc version", a.tsfc_version == b.tsfc_version),
        ("spec sha256", a.spec_sha256 == b.spec_sha256),
        ("design hash", a.design_sha256 == b.design_sha256),
        ("controller name", a.name == b.name),
        ("runs", a.runs_total == b.runs_total),
        ("seed", a.seed == b.seed),
        ("shard count", a.shard.1 == b.shard.1),
        ("time span", a.time_s == b.time_s),
        ("convergence rule", a.converged_rule == b.converged_rule),
        ("state names", a.state_names == b.state_names),
        ("input names", a.input_names == b.input_names),
        ("nominal run", a.nominal == b.nominal),
    ];
    checks
        .into_iter()
        .filter(|(_, same)| !same)
        .map(|(what, _)| what)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_names_are_identifiers() {
        for ok in ["mc", "_x1", "Ctrl_2"] {
            assert!(plain_name(ok), "{ok}");
        }
        for bad in [
            "", "../evil", "a/b", "a\\b", "..", ".x", "x\u{1b}", "1x", "é", "a b",
        ] {
            assert!(!plain_name(bad), "{bad:?}");
        }
        assert!(!plain_name(&"a".repeat(MAX_NAME_BYTES + 1)));
    }

    #[test]
    fn shard_sizes_count_the_indices() {
        for (runs, kk) in [(24, 3), (10, 4), (3, 5), (1, 1), (7, 7)] {
            let total: u64 = (1..=kk).map(|k| shard_size(runs, (k, kk))).sum();
            assert_eq!(total, runs);
            for k in 1..=kk {
                let n = (0..runs).filter(|i| i % kk == k - 1).count() as u64;
                assert_eq!(shard_size(runs, (k, kk)), n);
            }
        }
    }
}
