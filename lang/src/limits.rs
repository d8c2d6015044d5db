//! The limits of the front end. Each is a spec error past it (with the span
//! of the offending text and a help line naming the limit), never a crash or
//! an unbounded run; `docs/limits.md` lists them with what the user sees.

/// Deepest nesting inside one item: brackets `( [ {`, call parentheses,
/// unary signs and `^` chains each open a level. Checked on the raw text
/// before parsing, because the parser recurses once per level.
pub const MAX_NESTING: usize = 64;

/// Deepest expression tree, and deepest evaluation through function calls.
/// Every operator of a chain `a + b + c + ...` adds a level, so this also
/// bounds the length of a flat chain of operators.
pub const MAX_EXPR_DEPTH: usize = 256;

/// Most nodes (numbers, names, operators, calls, matrix elements) in one expression.
pub const MAX_EXPR_NODES: usize = 100_000;

/// Most work one evaluation may do, in elementary operations: each visited
/// node counts [`NODE_WORK`], each created matrix element or multiply-add one.
/// User functions are expanded at every call, so this bounds functions that
/// call each other many times.
pub const MAX_EVAL_WORK: u64 = 50_000_000;

/// Most evaluation work for checking a whole spec (all its expressions together).
pub const MAX_CHECK_WORK: u64 = 200_000_000;

/// What visiting one expression node counts towards [`MAX_EVAL_WORK`].
pub const NODE_WORK: u64 = 50;

/// Largest exponent of a matrix power `M ^ k`.
pub const MAX_MATRIX_POWER: f64 = 1e6;

/// Most diagnostics reported for one spec; the rest are counted in one line.
pub const MAX_DIAGNOSTICS: usize = 200;

/// Longest piece of source text repeated inside a message (longer ones are
/// shortened around `...`).
pub const MAX_ECHO_CHARS: usize = 40;

/// Longest source line shown under a diagnostic (longer lines are shown
/// around the marked places, with `...` for the rest).
pub const MAX_SHOWN_LINE: usize = 120;

/// Most runs of a Monte Carlo campaign (`runs` of `monte_carlo { }`, and
/// `tsfc simulate --monte-carlo N`).
pub const MAX_MONTE_CARLO_RUNS: u64 = 1_000_000;

/// Most scenarios one `sweep { }` block expands to (all its triggers together).
pub const MAX_SWEEP_SCENARIOS: usize = 256;

/// Largest degree d of `relaxation polya(d = ..)`.
pub const MAX_POLYA_DEGREE: usize = 4;

/// Most coefficient LMIs per objective family under `polya`:
/// (r + d + 1 choose d + 2) for r rules.
pub const MAX_POLYA_LMIS: usize = 5_000;

/// Most rules under `membership_mismatch(kappa = ..)`: its bounded-mismatch
/// LMIs declare 2 r^2 slack matrices per objective family (512 at r = 16).
pub const MAX_MISMATCH_RULES: usize = 16;

/// Most rounds of `weight = synthesize codesign(rounds = ..)`: each round
/// solves two trigger-sized SDPs (a gain step and a trigger step).
pub const MAX_CODESIGN_ROUNDS: u32 = 30;

/// Smallest distance from 0 of each end of a trigger's `region z = lo .. hi`
/// (and the reciprocal the largest): the certificate squares the bounds, so
/// their squares and inverse squares stay normal f64 numbers.
pub const MIN_REGION_BOUND: f64 = 1e-100;

/// Most points of `weight = synthesize transmissions(points = ..)`: each point
/// solves two trigger-sized SDPs and, when the spec has a scenario, one simulation.
pub const MAX_TRANSMISSION_POINTS: u32 = 12;

/// Points of `weight = synthesize transmissions;` without `points`.
pub const DEFAULT_TRANSMISSION_POINTS: u32 = 6;

/// `region z = auto;` starts from the premise's range times this factor (the
/// seed box the gains are designed on), then grows it by factors of 2 up to
/// the range, then bisects [`REGION_AUTO_BISECTIONS`] times in log scale.
pub const REGION_AUTO_SEED: f64 = 1.0 / 64.0;

/// Log-scale bisection steps of `region z = auto;` after the doubling.
pub const REGION_AUTO_BISECTIONS: u32 = 3;

/// Rounds of `weight = synthesize codesign;` without `rounds`.
pub const DEFAULT_CODESIGN_ROUNDS: u32 = 10;

/// (r + d + 1 choose d + 2): the coefficients of Polya's relaxation of degree
/// d for r rules (saturating; `None` past `usize`).
pub fn polya_lmis(r: usize, d: usize) -> Option<usize> {
    let (n, k) = (r + d + 1, d + 2);
    let mut c: usize = 1;
    for i in 0..k.min(n) {
        c = c.checked_mul(n - i)? / (i + 1);
    }
    Some(if k > n { 0 } else { c })
}

/// Most rules under `lyapunov fuzzy(..)`: one relaxed double sum per rule's
/// Lyapunov matrix P_k, so r times the LMIs of the relaxation.
pub const MAX_FUZZY_LYAPUNOV_RULES: usize = 8;

/// Largest bound phi_k of `lyapunov fuzzy(phi = ..)` (1/s): a bound this
/// loose makes the phi-weighted term dominate every condition.
pub const MAX_FUZZY_LYAPUNOV_PHI: f64 = 1e3;
