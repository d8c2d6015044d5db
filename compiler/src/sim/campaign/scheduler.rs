//! `--shard k/K` and `--shard auto[/K]`: the shard of this process, given on
//! the command line or read from the job-array variables of the scheduler
//! that started it (docs/monte_carlo.md, "Campaigns on a cluster"):
//!
//! | scheduler | index (0-based unless said) | size |
//! |---|---|---|
//! | Slurm job array | `SLURM_ARRAY_TASK_ID` (from `SLURM_ARRAY_TASK_MIN`) | `SLURM_ARRAY_TASK_COUNT`, contiguous: `MAX - MIN + 1`, step 1 |
//! | Kubernetes Indexed Job | `JOB_COMPLETION_INDEX` | `auto/K` or `TSFC_SHARD_COUNT` (the Job's `completions`) |
//! | AWS Batch array job | `AWS_BATCH_JOB_ARRAY_INDEX` | `AWS_BATCH_JOB_ARRAY_SIZE`, else `auto/K` or `TSFC_SHARD_COUNT` |
//! | Google Cloud Batch | `BATCH_TASK_INDEX` | `BATCH_TASK_COUNT` |
//!
//! Index i of a size-K array is shard i + 1 of K. A missing, malformed or
//! out-of-range index, a non-contiguous Slurm array, two schedulers at once or
//! a size that disagrees with `auto/K` is refused with the variables named.

use crate::sim::limits::MAX_SHARDS;

/// The environment variable that gives the shard count where the scheduler
/// does not (Kubernetes, AWS Batch without the size variable).
pub const SHARD_COUNT_VAR: &str = "TSFC_SHARD_COUNT";

/// `--shard` as written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShardArg {
    /// `k/K`.
    Fixed(u64, u64),
    /// `auto` or `auto/K`: from the scheduler's environment.
    Auto(Option<u64>),
}

/// A shard count `K`, `1 <= K <= MAX_SHARDS`, from text.
fn count(s: &str, what: &str) -> Result<u64, String> {
    match s.trim().parse::<u64>() {
        Ok(k) if (1..=MAX_SHARDS).contains(&k) => Ok(k),
        Ok(k) => Err(format!(
            "{what} is {k}: a campaign has 1 .. {MAX_SHARDS} shards (docs/limits.md)"
        )),
        Err(_) => Err(format!(
            "{what} `{}` is not a whole number",
            s.escape_debug()
        )),
    }
}

/// Parses `k/K`, `auto` or `auto/K` (`1 <= k <= K <= MAX_SHARDS`).
pub fn parse_shard(s: &str) -> Result<ShardArg, String> {
    let bad = || {
        format!(
            "--shard takes k/K with 1 <= k <= K <= {MAX_SHARDS}, or auto or auto/K (got `{}`)",
            s.escape_debug()
        )
    };
    if s.trim() == "auto" {
        return Ok(ShardArg::Auto(None));
    }
    let (k, kk) = s.split_once('/').ok_or_else(bad)?;
    let kk = count(kk, "the shard count K")
        .map_err(|e| format!("--shard `{}`: {e}", s.escape_debug()))?;
    if k.trim() == "auto" {
        return Ok(ShardArg::Auto(Some(kk)));
    }
    let k: u64 = k.trim().parse().map_err(|_| bad())?;
    if (1..=kk).contains(&k) {
        Ok(ShardArg::Fixed(k, kk))
    } else {
        Err(bad())
    }
}

/// A 0-based index from the variable `var`.
fn index(var: &str, v: &str) -> Result<u64, String> {
    v.trim().parse().map_err(|_| {
        format!(
            "--shard auto: {var}=`{}` is not a whole number",
            v.escape_debug()
        )
    })
}

/// The shard `(k, K)` of `arg`; `env` reads a variable (`std::env::var`
/// in the command line, a map in tests).
pub fn resolve(arg: ShardArg, env: &dyn Fn(&str) -> Option<String>) -> Result<(u64, u64), String> {
    let given = match arg {
        ShardArg::Fixed(k, kk) => return Ok((k, kk)),
        ShardArg::Auto(given) => given,
    };
    let set: Vec<&str> = [
        "SLURM_ARRAY_TASK_ID",
        "JOB_COMPLETION_INDEX",
        "AWS_BATCH_JOB_ARRAY_INDEX",
        "BATCH_TASK_INDEX",
    ]
    .into_iter()
    .filter(|v| env(v).is_some())
    .collect();
    let var = match set.as_slice() {
        [one] => *one,
        [] => return Err("--shard auto: no job-array index in the environment (SLURM_ARRAY_TASK_ID, JOB_COMPLETION_INDEX, AWS_BATCH_JOB_ARRAY_INDEX or BATCH_TASK_INDEX); outside a job array write --shard k/K".into()),
        many => return Err(format!(
            "--shard auto: the environment names several job-array indices ({}); write --shard k/K",
            many.join(", ")
        )),
    };
    let raw = env(var).unwrap_or_default();
    let i = index(var, &raw)?;
    let own_count = |v: &str| env(v).map(|s| count(&s, v)).transpose();
    let (i, from_env): (u64, Option<(u64, String)>) = if var == "SLURM_ARRAY_TASK_ID" {
        slurm(i, env)?
    } else {
        let size_var = match var {
            "AWS_BATCH_JOB_ARRAY_INDEX" => Some("AWS_BATCH_JOB_ARRAY_SIZE"),
            "BATCH_TASK_INDEX" => Some("BATCH_TASK_COUNT"),
            _ => None,
        };
        let size = match size_var {
            Some(v) => own_count(v)?.map(|k| (k, v.to_string())),
            None => None,
        };
        (i, size)
    };
    let explicit = match given {
        Some(k) => Some((k, "auto/K".to_string())),
        None => own_count(SHARD_COUNT_VAR)?.map(|k| (k, SHARD_COUNT_VAR.to_string())),
    };
    let (kk, source) = match (from_env, explicit) {
        (Some((a, va)), Some((b, vb))) if a != b => {
            return Err(format!(
                "--shard auto: {va} says {a} shards but {vb} says {b}"
            ))
        }
        (Some(k), _) | (None, Some(k)) => k,
        (None, None) => {
            return Err(format!(
                "--shard auto: {var} gives the index but nothing gives the number of shards: write --shard auto/K or set {SHARD_COUNT_VAR}=K (the array's size)"
            ))
        }
    };
    if i >= kk {
        return Err(format!(
            "--shard auto: {var}={raw} is out of range for {kk} shards ({source}): indices are 0 .. {}",
            kk - 1
        ));
    }
    Ok((i + 1, kk))
}

/// A Slurm array task's 0-based place and its array's size: the array must
/// be contiguous (`--array=a-b`, step 1).
fn slurm(
    id: u64,
    env: &dyn Fn(&str) -> Option<String>,
) -> Result<(u64, Option<(u64, String)>), String> {
    let get = |v: &str| -> Result<Option<u64>, String> { env(v).map(|s| index(v, &s)).transpose() };
    let (min, max) = match (get("SLURM_ARRAY_TASK_MIN")?, get("SLURM_ARRAY_TASK_MAX")?) {
        (Some(a), Some(b)) if a <= b => (a, b),
        _ => return Err("--shard auto: SLURM_ARRAY_TASK_ID is set without SLURM_ARRAY_TASK_MIN <= SLURM_ARRAY_TASK_MAX".into()),
    };
    if !(min..=max).contains(&id) {
        return Err(format!(
            "--shard auto: SLURM_ARRAY_TASK_ID={id} is outside SLURM_ARRAY_TASK_MIN .. MAX = {min} .. {max}"
        ));
    }
    let span = max - min + 1;
    let step = get("SLURM_ARRAY_TASK_STEP")?.unwrap_or(1);
    let tasks = get("SLURM_ARRAY_TASK_COUNT")?.unwrap_or(span);
    if step != 1 || tasks != span {
        return Err(format!(
            "--shard auto: the Slurm array is not contiguous ({tasks} tasks from {min} to {max}, step {step}): submit --array={min}-{max} (or 0-{}), or write --shard k/K",
            tasks.saturating_sub(1)
        ));
    }
    if span > MAX_SHARDS {
        return Err(format!(
            "--shard auto: the Slurm array has {span} tasks: a campaign has 1 .. {MAX_SHARDS} shards (docs/limits.md)"
        ));
    }
    Ok((id - min, Some((span, "SLURM_ARRAY_TASK_COUNT".into()))))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with<'a>(vars: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |k| {
            vars.iter()
                .find(|(n, _)| *n == k)
                .map(|(_, v)| v.to_string())
        }
    }

    #[test]
    fn parse_refuses_absurd_counts() {
        assert_eq!(parse_shard("2/3"), Ok(ShardArg::Fixed(2, 3)));
        assert_eq!(parse_shard("auto"), Ok(ShardArg::Auto(None)));
        assert_eq!(parse_shard("auto/8"), Ok(ShardArg::Auto(Some(8))));
        for bad in [
            "1/18446744073709551615",
            "1/4000000000",
            "0/3",
            "4/3",
            "1/0",
            "x",
            "auto/0",
        ] {
            assert!(parse_shard(bad).is_err(), "{bad}");
        }
        assert!(parse_shard("1/100000").is_ok());
    }

    #[test]
    fn each_scheduler_maps_to_k_of_kk() {
        let slurm = [
            ("SLURM_ARRAY_TASK_ID", "5"),
            ("SLURM_ARRAY_TASK_MIN", "4"),
            ("SLURM_ARRAY_TASK_MAX", "7"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ];
        assert_eq!(resolve(ShardArg::Auto(None), &with(&slurm)), Ok((2, 4)));
        let k8s = [("JOB_COMPLETION_INDEX", "0")];
        assert_eq!(resolve(ShardArg::Auto(Some(3)), &with(&k8s)), Ok((1, 3)));
        let k8s_env = [("JOB_COMPLETION_INDEX", "2"), ("TSFC_SHARD_COUNT", "3")];
        assert_eq!(resolve(ShardArg::Auto(None), &with(&k8s_env)), Ok((3, 3)));
        let aws = [
            ("AWS_BATCH_JOB_ARRAY_INDEX", "9"),
            ("AWS_BATCH_JOB_ARRAY_SIZE", "10"),
        ];
        assert_eq!(resolve(ShardArg::Auto(None), &with(&aws)), Ok((10, 10)));
        let gcp = [("BATCH_TASK_INDEX", "1"), ("BATCH_TASK_COUNT", "2")];
        assert_eq!(resolve(ShardArg::Auto(None), &with(&gcp)), Ok((2, 2)));
    }

    /// The variables of one task.
    type Vars = &'static [(&'static str, &'static str)];

    #[test]
    fn missing_out_of_range_and_gapped_indices_are_refused() {
        let cases: [(Vars, Option<u64>, &str); 8] = [
            (&[], None, "no job-array index"),
            (
                &[("JOB_COMPLETION_INDEX", "0")],
                None,
                "nothing gives the number",
            ),
            (&[("JOB_COMPLETION_INDEX", "3")], Some(3), "out of range"),
            (
                &[("JOB_COMPLETION_INDEX", "-1")],
                Some(3),
                "not a whole number",
            ),
            (
                &[("BATCH_TASK_INDEX", "0"), ("BATCH_TASK_COUNT", "2")],
                Some(3),
                "says 2 shards",
            ),
            (
                &[
                    ("SLURM_ARRAY_TASK_ID", "2"),
                    ("SLURM_ARRAY_TASK_MIN", "0"),
                    ("SLURM_ARRAY_TASK_MAX", "4"),
                    ("SLURM_ARRAY_TASK_COUNT", "3"),
                ],
                None,
                "not contiguous",
            ),
            (
                &[
                    ("SLURM_ARRAY_TASK_ID", "9"),
                    ("SLURM_ARRAY_TASK_MIN", "0"),
                    ("SLURM_ARRAY_TASK_MAX", "4"),
                ],
                None,
                "outside",
            ),
            (
                &[("JOB_COMPLETION_INDEX", "0"), ("BATCH_TASK_INDEX", "0")],
                Some(2),
                "several",
            ),
        ];
        for (vars, k, want) in cases {
            let e = resolve(ShardArg::Auto(k), &with(vars)).expect_err(want); // ok: unit test
            assert!(e.contains(want), "{e}");
        }
    }
}
