//! The short human summary `tsfc compile` prints.

use crate::driver::compile::{Compiled, Status};
use crate::model::TsModel;
use std::fmt::Write;
use std::path::Path;

/// A few lines: what is certified of the plant first, then verdict, achieved
/// objectives, certificate, solver, where the report is.
pub fn summary(model: &TsModel, c: &Compiled, report_path: &Path) -> String {
    let mut s = String::new();
    let r = &c.report;
    match (&r.plant.claim, &r.plant.note) {
        (Some(claim), _) => {
            let _ = writeln!(s, "plant: {claim}");
        }
        (None, Some(note)) => {
            let _ = writeln!(s, "plant: {note}");
        }
        (None, None) => {}
    }
    if let Some(t) = &r.plant.truth_plant {
        let _ = writeln!(s, "plant: {t}");
    }
    let verdict = match c.status {
        Status::Certified => "certified",
        Status::Infeasible => "infeasible",
        Status::Refused => "refused",
    };
    let _ = writeln!(
        s,
        "{verdict}: controller `{}` (n = {}, m = {}, {} rules, relaxation {})",
        r.controller, r.n, r.m, r.rules, r.relaxation
    );
    let mode = if r.mode == "analysis" {
        "analysis: the rules give their gains F; tsfc certifies the objectives for them"
    } else {
        "synthesis: tsfc designs the gains"
    };
    let _ = writeln!(s, "  mode                 {mode}");
    for (k, v) in r.objectives.entries() {
        let _ = writeln!(s, "  {k:<20} {v}");
    }
    // A refused analysis lists its verdicts under the diagnosis.
    if r.diagnosis.is_none() {
        for v in &r.verdicts {
            let value = match (v.quantity, v.value) {
                (Some(q), Some(x)) => format!(", {q} = {x:.6}"),
                _ => String::new(),
            };
            let word = if v.certified {
                "certified"
            } else {
                "not certified"
            };
            let _ = writeln!(s, "  verdict              {}: {word}{value}", v.objective);
        }
    }
    if let Some(line) = r.sampled_loop.as_ref().map(sampled_line) {
        let _ = writeln!(s, "  sampled loop         {line}");
    }
    if let Some(cert) = &r.certificate {
        let strict = cert.lmis.iter().filter(|l| l.strict).count();
        let _ = writeln!(
            s,
            "  certificate          {} conditions ({strict} strict), min margin {:.3e}, worst `{}`",
            cert.lmis.len(),
            cert.min_margin,
            cert.worst
        );
    }
    if let Some(sp) = &r.stored_precision {
        let _ = writeln!(
            s,
            "  stored precision     {}: {}, worst margin {:.3e} at `{}`; membership rounding needs {:.3e} of {:.3e}",
            sp.precision,
            if sp.certified { "certified" } else { "NOT certified" },
            sp.worst_margin,
            sp.worst_lmi,
            sp.membership_rounding_bound.required_margin,
            sp.membership_rounding_bound.available_margin
        );
    }
    for red in &r.reductions {
        let _ = writeln!(s, "  reduction            {red}");
    }
    for n in &r.notes {
        let _ = writeln!(s, "  note                 {n}");
    }
    let scenario = r
        .region_of_attraction
        .as_ref()
        .zip(model.spec.simulate.as_ref());
    if let Some(w) = scenario.and_then(|(roa, sim)| outside_level(roa.scenario_x0_level?, &sim.x0))
    {
        let _ = writeln!(s, "  warning              {w}");
    }
    if let Some(d) = &r.diagnosis {
        let _ = writeln!(s, "  {}", d.message);
        for a in &d.achievable {
            let _ = writeln!(s, "    {a}");
        }
    }
    let retried = match r.solver.unscaled_retries {
        0 => String::new(),
        k => format!(" ({k} re-solved without equilibration)"),
    };
    let _ = writeln!(
        s,
        "  solver               clarabel, {} SDP(s){retried}, status {}, {} iterations; solve {:.3} s of {:.3} s total",
        r.solver.solves, r.solver.status, r.solver.iterations, r.timings_s.solve, r.timings_s.total
    );
    let _ = writeln!(s, "  report               {}", report_path.display());
    let _ = model;
    s
}

/// What the sampled loop (the loop the generated code runs) certifies, in
/// one line: its sampling, its own decay rate or stability only (the
/// `objectives` lines above are the continuous loop's), its H-inf gain.
fn sampled_line(l: &crate::report::SampledReport) -> String {
    let [lo, hi] = l.sampling;
    let when = if lo == hi {
        format!("every {hi} s")
    } else {
        format!("intervals in [{lo}, {hi}] s")
    };
    let rate = match (l.decay_rate > 0.0, l.modes.is_some()) {
        (true, _) => format!("decay rate {} certified", l.decay_rate),
        (false, false) => {
            "asymptotic stability only (a decay rate above is the continuous loop's)".to_string()
        }
        (false, true) => {
            "mean-square stability only (a decay rate above is the continuous loop's)".to_string()
        }
    };
    let hinf = l
        .hinf_gamma
        .map_or(String::new(), |g| format!(", H-inf gain {g:.6}"));
    format!("{when}: {rate}{hinf}")
}

/// The warning when the initial state `x0` of a scenario lies outside the
/// certified region of attraction {x : x'Ux <= 1} (None inside it).
pub fn outside_region(u: &nalgebra::DMatrix<f64>, x0: &[f64]) -> Option<String> {
    if u.nrows() != x0.len() || u.ncols() != x0.len() {
        return None;
    }
    let x = nalgebra::DVector::from_column_slice(x0);
    outside_level((x.transpose() * u * &x)[(0, 0)], x0)
}

/// [`outside_region`] from the level x0'Ux0.
fn outside_level(level: f64, x0: &[f64]) -> Option<String> {
    let shown = x0
        .iter()
        .map(|v| format!("{v}"))
        .collect::<Vec<_>>()
        .join(", ");
    (level > 1.0 || level.is_nan()).then(|| {
        format!(
            "the scenario starts outside the certified region of attraction: x0 = [{shown}] is at level x0'Ux0 = {level:.4e} > 1 (U = P/c of the certificate); the certificate covers this direction up to x0 scaled by {:.4e}, so nothing is certified about this run",
            1.0 / level.sqrt()
        )
    })
}
