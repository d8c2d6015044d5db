//! The playground's limits (documented in `docs/playground.md`): the page runs
//! one spec at a time on one thread of a browser tab, so it refuses what the
//! command line would take minutes or gigabytes for, with a message naming
//! the limit and the command to use instead.

/// Largest spec the page checks or compiles, in bytes (`tsfc lsp` takes up
/// to 4 MiB; a spec typed in a browser is a few KiB).
pub const MAX_SPEC_BYTES: usize = 256 << 10;

/// Most states `n` of a model the page certifies.
pub const MAX_STATES: usize = 16;

/// Most rules of a model the page certifies (the LMI count grows with the
/// square of the rules for the pairwise relaxations).
pub const MAX_RULES: usize = 64;

/// Most integration steps of a simulation in the page (the command line
/// takes 10 million).
pub const MAX_SIM_STEPS: u64 = 200_000;

/// The refusal of a spec text over [`MAX_SPEC_BYTES`], if it is.
pub fn spec_size(text: &str) -> Result<(), String> {
    if text.len() > MAX_SPEC_BYTES {
        return Err(format!(
            "the spec is {} KiB; the playground takes at most {} KiB (use `tsfc check`)",
            text.len() >> 10,
            MAX_SPEC_BYTES >> 10
        ));
    }
    Ok(())
}

/// The refusal of a model over [`MAX_STATES`] or [`MAX_RULES`], if it is.
pub fn problem_size(n: usize, rules: usize) -> Result<(), String> {
    if n > MAX_STATES || rules > MAX_RULES {
        return Err(format!(
            "the model has n = {n} states and {rules} rules; the playground certifies at most n = {MAX_STATES} and {MAX_RULES} rules (use `tsfc compile`)"
        ));
    }
    Ok(())
}

/// The refusal of a simulation of `steps` steps over [`MAX_SIM_STEPS`], if it is.
pub fn sim_steps(steps: u64) -> Result<(), String> {
    if steps > MAX_SIM_STEPS {
        return Err(format!(
            "the simulation takes {steps} steps; the playground runs at most {MAX_SIM_STEPS} (shorten the horizon, raise the `time` step, or use `tsfc simulate`)"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #[test]
    fn limits_refuse_past_the_bound_only() {
        assert!(super::spec_size(&"x".repeat(super::MAX_SPEC_BYTES)).is_ok());
        assert!(super::spec_size(&"x".repeat(super::MAX_SPEC_BYTES + 1)).is_err());
        assert!(super::problem_size(16, 64).is_ok());
        assert!(super::problem_size(17, 2).unwrap_err().contains("n = 17"));
        assert!(super::sim_steps(super::MAX_SIM_STEPS + 1).is_err());
    }
}
