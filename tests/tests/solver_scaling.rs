//! Clarabel's equilibration (Ruiz scaling of the data) makes some feasible
//! event-trigger SDPs stop with a numerical error at the first iteration;
//! tsfc then solves the same SDP once more without it
//! (`compiler/lmi/src/solve/clarabel.rs`, docs/limits.md "solver scaling").
//!
//! Case: Xu & Huang's spacecraft model (the shipped spec's A(x), J, trigger,
//! L-inf and saturation objectives) with its rules moved to a local region
//! (|w_i| <= 0.05 rad/s, |q_i| <= 0.056) and one given gain in every rule,
//! u = -J (2 zeta w_n w + 2 w_n^2 q) with w_n = 0.22 rad/s, zeta = 1. Before the
//! retry tsfc refused it "even with nu = 0"; the first trigger SDP stops at
//! iteration 1. Since issue 37 the trigger SDPs tsfc rescales (sigma > 1) are
//! solved without equilibration from the start (docs/limits.md).

use crate::common;

use tsfc::driver::compile::{compile, Status};
use tsfc::report::SpecInfo;
use tsfc::synth::{Quantity, Settings};

/// The given gain (rows of F, u = F x, x = [w; q]).
const GAIN: &str = "-154, -1.32, -1.76, -33.88, -0.2904, -0.3872; \
                    -1.32, -118.8, -4.4, -0.2904, -26.136, -0.968; \
                    -1.76, -4.4, -83.6, -0.3872, -0.968, -18.392";

/// (w, q) of the seven local rules: the shipped spec's operating points
/// scaled by 0.05 (w) and 0.1 (q).
const POINTS: [(f64, f64); 7] = [
    (0.0, 0.0),
    (0.0, 0.056),
    (0.0, -0.056),
    (0.025, 0.0),
    (-0.025, 0.0),
    (0.05, 0.056),
    (-0.05, -0.056),
];

fn spec() -> String {
    let rules: String = POINTS
        .iter()
        .enumerate()
        .map(|(i, (w, q))| {
            format!(
                "rule R{n}: w is about [{w}, {w}, {w}] and q is about [{q}, {q}, {q}] => \
                 at(w = [{w}, {w}, {w}], q = [{q}, {q}, {q}]), F = [{GAIN}];\n",
                n = i + 1
            )
        })
        .collect();
    format!(
        "tsf 1; controller local_attitude;\n\
         const J = [350, 3, 4; 3, 270, 10; 4, 10, 190];\n\
         state w[3], q[3]; input u[3] saturate 2.0; disturbance tau[3] bound 0.01; output y = x;\n\
         A(x) = [ -inv(J) * skew(w) * J, zeros(3, 3); 0.5 * sqrt(1 - q' * q) * eye(3), -0.5 * skew(w) ];\n\
         B = [inv(J); zeros(3, 3)]; D = B;\n\
         premise w range -0.05 .. 0.05;\npremise q range -0.056 .. 0.056;\n{rules}\
         objective linf(tau -> y) minimize with phi = 0.05;\nobjective saturation region;\n\
         relaxation membership_mismatch(kappa = 0.12);\n\
         trigger aperiodic {{ sampling = 0.001 .. 0.1; \
         threshold nu = 0.2 adaptive(mu1 = 10, mu2 = 1, mu3 = 0.02, max = 0.25); weight = synthesize; }}\n\
         emit rust, c;\n"
    )
}

#[test]
fn a_trigger_sdp_that_fails_scaled_is_certified_unscaled() {
    let src = spec();
    let model = common::model_of("local_attitude.tsf", &src);
    let info = SpecInfo {
        path: "local_attitude.tsf".into(),
        sha256: String::new(),
    };
    let c = compile(&model, info, &Settings::default(), Default::default());
    assert_eq!(c.status, Status::Certified, "{:?}", c.report.diagnosis);
    let retries = c.report.solver.unscaled_retries;
    eprintln!(
        "{} SDPs, {retries} re-solved without equilibration; objectives {:?}",
        c.report.solver.solves, c.report.objectives
    );
    let (design, _) = c.outcome.as_ref().expect("certified");
    let t = design.loop_design.event().expect("a synthesized trigger");
    // Since issue 37 a trigger SDP that tsfc rescales itself (sigma > 1) is
    // solved without equilibration from the start, so it needs no retry;
    // otherwise the first trigger SDP must have gone through the retry.
    let sigma = tsfc::synth::trigger::lyapunov_scale(&t.plan);
    assert!(
        sigma > 1.0 || retries >= 1,
        "no SDP needed the unscaled retry (sigma {sigma})"
    );
    // Measured: event-triggered gamma 0.1362 at nu(t_k) <= 0.25 (continuous
    // analysis 0.0722); a certificate, so it bounds the loop's true gain.
    assert!(t.plan.nu >= 0.25 - 1e-12, "{}", t.plan.nu);
    let gamma = t.gamma;
    assert!(gamma > 0.0 && gamma < 0.1616, "{gamma}");
    // The continuous analysis of the same gain bounds the continuous loop.
    let continuous = design.achieved.get(Quantity::LinfGamma).expect("gamma");
    assert!(
        continuous > 0.0 && continuous < gamma,
        "{continuous} vs {gamma}"
    );

    // Independent necessary condition of the certificate (V' <= -phi V at
    // every vertex loop): max Re eig(A_i + B F) < -phi / 2, from the formula.
    let f = &t.plan.gains[0];
    for &(w, q) in &POINTS {
        let (a, b) = common::spacecraft_local_model(w, q);
        let alpha = common::abscissa(&(&a + &b * f));
        assert!(alpha < -0.025, "({w}, {q}): {alpha}");
    }
}
