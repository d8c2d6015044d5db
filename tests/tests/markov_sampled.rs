//! The sampled loop with Markov modes (`synth/markov/sampled.rs`): an
//! independent re-check of the functional's derivative bound from the report
//! (random mode, memberships, interval and elapsed time, eigenvalues), a
//! scalar loop whose longest stable sampling interval has a closed form, the
//! refusal of a too-long period with advice that certifies, the textbook
//! two-mode jump system certified as h -> 0, and the simulation of the shipped
//! sampled-data Xue spec under a seeded mode process.

use crate::common;
use crate::markov::{compiled, input_matrix, matrix, three_modes};

use nalgebra::DMatrix;
use serde_json::Value;
use tsfc::driver::prepare;
use tsfc::sim::{simulate_csv, Options};

fn max_eig(m: &DMatrix<f64>) -> f64 {
    let s = (m + m.transpose()) * 0.5;
    s.symmetric_eigenvalues().max()
}

fn min_eig(m: &DMatrix<f64>) -> f64 {
    let s = (m + m.transpose()) * 0.5;
    s.symmetric_eigenvalues().min()
}

/// A tiny deterministic generator (the test's own, not the simulator's).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Random memberships of `r` rules (non-negative, summing to 1).
    fn memberships(&mut self, r: usize) -> Vec<f64> {
        let w: Vec<f64> = (0..r).map(|_| self.next()).collect();
        let s: f64 = w.iter().sum();
        w.iter().map(|v| v / s).collect()
    }
}

/// The plant: A_i per rule, and B_ai of (mode, rule).
type Plant<'p> = (&'p [DMatrix<f64>], &'p dyn Fn(usize, usize) -> DMatrix<f64>);

/// The matrices of a sampled mode loop read from the report alone.
struct Loop {
    h_max: f64,
    pi: DMatrix<f64>,
    y: DMatrix<f64>,
    p: Vec<DMatrix<f64>>,
    l1: Vec<DMatrix<f64>>,
    l2: Vec<DMatrix<f64>>,
    f: Vec<Vec<DMatrix<f64>>>,
}

impl Loop {
    fn of(json: &Value) -> Loop {
        let s = &json["sampled_loop"];
        let modes = s["modes"].as_array().expect("sampled_loop.modes");
        Loop {
            h_max: s["sampling"][1].as_f64().expect("h_max"),
            pi: matrix(&json["transition_rates"]),
            y: matrix(&s["Y"]),
            p: modes.iter().map(|m| matrix(&m["P"])).collect(),
            l1: modes.iter().map(|m| matrix(&m["L1"])).collect(),
            l2: modes.iter().map(|m| matrix(&m["L2"])).collect(),
            f: json["modes"]
                .as_array()
                .expect("modes")
                .iter()
                .map(|m| {
                    m["gains"]
                        .as_array()
                        .expect("gains")
                        .iter()
                        .map(|g| matrix(&g["F"]))
                        .collect()
                })
                .collect(),
        }
    }

    /// The bound on the generator of V = x'P_a x + (h - tau) int x''Y x' in
    /// mode `a` as a quadratic form in psi = [x; x(s)], that is
    /// Xi + (h - tau) Phi'Y Phi + tau N Y^{-1} N', with Phi the blended
    /// derivative (plant memberships `hp`, controller memberships `hc`;
    /// plant A_i and B_ai).
    fn bound(
        &self,
        (a_rules, b_of): Plant<'_>,
        a: usize,
        (hp, hc): (&[f64], &[f64]),
        h: f64,
        tau: f64,
    ) -> DMatrix<f64> {
        let n = self.y.nrows();
        let ex = DMatrix::identity(n, 2 * n);
        let es = DMatrix::from_fn(n, 2 * n, |r, c| if c == n + r { 1.0 } else { 0.0 });
        let mut phi = DMatrix::zeros(n, 2 * n);
        for (i, wi) in hp.iter().enumerate() {
            for (j, wj) in hc.iter().enumerate() {
                phi += (&a_rules[i] * &ex + b_of(a, i) * &self.f[a][j] * &es) * (wi * wj);
            }
        }
        let coupling = (0..self.p.len()).fold(DMatrix::zeros(n, n), |s, b| {
            s + &self.p[b] * self.pi[(a, b)]
        });
        let nn = ex.transpose() * &self.l1[a] + es.transpose() * &self.l2[a];
        let he = |m: DMatrix<f64>| &m + m.transpose();
        let xi = he(ex.transpose() * &self.p[a] * &phi)
            + ex.transpose() * coupling * &ex
            + he(&nn * (&ex - &es));
        let yinv = self.y.clone().try_inverse().expect("Y invertible");
        xi + phi.transpose() * &self.y * &phi * (h - tau) + &nn * yinv * nn.transpose() * tau
    }
    /// The largest eigenvalue of [`Loop::bound`] at every vertex (one mode,
    /// one plant and one controller rule, tau in {0, h_max}, h = h_max) and at
    /// `samples` random points (mode, memberships apart, h, tau) from `seed`.
    fn worst(&self, plant: Plant<'_>, rules: usize, seed: u64, samples: usize) -> (f64, f64) {
        let modes = self.p.len();
        let mut worst_vertex = f64::NEG_INFINITY;
        for a in 0..modes {
            for i in 0..rules {
                for j in 0..rules {
                    let (mut hp, mut hc) = (vec![0.0; rules], vec![0.0; rules]);
                    hp[i] = 1.0;
                    hc[j] = 1.0;
                    for tau in [0.0, self.h_max] {
                        let m = self.bound(plant, a, (&hp, &hc), self.h_max, tau);
                        worst_vertex = worst_vertex.max(max_eig(&m));
                    }
                }
            }
        }
        let mut rng = Lcg(seed);
        let mut worst = f64::NEG_INFINITY;
        for _ in 0..samples {
            let a = (rng.next() * modes as f64) as usize % modes;
            let hp = rng.memberships(rules);
            let hc = rng.memberships(rules);
            let h = self.h_max * rng.next().max(1e-6);
            let tau = h * rng.next();
            worst = worst.max(max_eig(&self.bound(plant, a, (&hp, &hc), h, tau)));
        }
        (worst_vertex, worst)
    }
}

fn two_rule_a() -> [DMatrix<f64>; 2] {
    [
        DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -1.0, -0.5]),
        DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -2.0, -0.5]),
    ]
}

/// The three-mode, two-rule plant of `markov.rs` with a stability objective
/// and aperiodic sampling in [0.001, h_max].
fn sampled_three_modes(h_max: f64) -> String {
    three_modes("mode_dependent", "basic").replace(
        "objective decay_rate maximize;",
        &format!(
            "objective decay_rate >= 0.2;\ntrigger aperiodic {{ sampling = 0.001 .. {h_max}; }}"
        ),
    )
}

#[test]
fn the_functional_derivative_bound_holds_from_the_report_at_random_modes_memberships_and_intervals()
{
    let (ok, json) = compiled(&sampled_three_modes(0.05));
    assert!(ok, "{}", json["diagnosis"]);
    let lp = Loop::of(&json);
    assert_eq!(lp.h_max, 0.05);
    assert_eq!(lp.p.len(), 3);
    assert!(min_eig(&lp.y) > 0.0);
    for p in &lp.p {
        assert!(min_eig(p) > 0.0);
    }
    let a_rules = two_rule_a();
    // Every vertex at h_max (r = 1: tau = 0; r = 2: tau = h, the Schur form),
    // then random modes, memberships (plant and controller apart), h and tau.
    let (worst_vertex, worst) = lp.worst((&a_rules, &input_matrix), 2, 17, 2000);
    println!("sampled modes: worst vertex eigenvalue {worst_vertex:.3e}, worst random {worst:.3e}");
    assert!(worst_vertex < 0.0, "{worst_vertex}");
    assert!(worst < 0.0, "{worst}");
    // The certificate names the sampled conditions of every mode.
    let names: Vec<&str> = json["certificate"]["lmis"]
        .as_array()
        .expect("lmis")
        .iter()
        .filter_map(|l| l["name"].as_str())
        .filter(|n| n.contains(" sampled "))
        .collect();
    // 3 modes x 4 pairs x 2 forms x 2 intervals (h_min and h_max).
    assert_eq!(names.len(), 48, "{names:?}");
}

/// x' = a x + u with two identical modes and one (fault-blind) gain,
/// co-designed with the sampled loop: the
/// loop is x(s_{l+1}) = g(h) x(s_l), g(h) = e^{a h} + (e^{a h} - 1) f / a,
/// stable for every interval sequence in (0, H] iff |g| < 1 on (0, H]:
/// H = ln((f - a) / (f + a)) / a for f < -a.
fn scalar(every: f64) -> String {
    format!(
        "tsf 1; controller scal; state x1; input u; A = 1; B = 1;\n\
         premise x1 range -1 .. 1 {{ all = trap(-2, -1, 1, 2); }}\n\
         rule R: x1 is all => A = 1;\n\
         objective decay_rate >= 0.5;\n\
         modes {{ mode one {{ }} mode two {{ }} rates = [-1, 1; 2, -2]; design = mode_independent; }}\n\
         trigger periodic {{ every = {every}; }}\n"
    )
}

/// The advised value `every = <v>` in a refusal's advice.
fn advised_period(json: &Value) -> f64 {
    let advice = json["diagnosis"]["achievable"][0]
        .as_str()
        .expect("advice")
        .to_string();
    assert!(
        advice.contains("the longest certified sampling interval is about")
            || advice.contains("the co-design is solved and certified at h_max"),
        "{advice}"
    );
    let at = advice.find("every = ").expect("a period to write") + "every = ".len();
    advice[at..]
        .split(';')
        .next()
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or_else(|| panic!("{advice}"))
}

#[test]
fn a_too_long_period_is_refused_with_advice_that_certifies_below_the_closed_form() {
    // Fault-blind: the gain is co-designed with the sampled loop, so the
    // refusal is the co-design's, and its advice halves the period.
    let (ok, refused) = compiled(&scalar(5.0));
    assert!(!ok);
    assert!(
        refused["diagnosis"]["message"]
            .as_str()
            .is_some_and(|m| m.contains("no fault-blind gains were found for the sampled loop")),
        "{}",
        refused["diagnosis"]
    );
    let advice = advised_period(&refused);
    let (ok, json) = compiled(&scalar(advice));
    assert!(ok, "advised {advice}: {}", json["diagnosis"]);
    let a = 1.0;
    let f = json["modes"][0]["gains"][0]["F"][0][0].as_f64().expect("F");
    assert!(f < -a, "{f}");
    let exact = ((f - a) / (f + a)).ln() / a;
    let g = |h: f64| (a * h).exp() + ((a * h).exp() - 1.0) * f / a;
    println!("scalar: f = {f:.4}, exact H = {exact:.4}, advised {advice}");
    // Sound: the advised period is inside the exact stability interval.
    assert!(advice < exact, "{advice} >= {exact}");
    assert!(g(advice).abs() < 1.0);
    // And not vacuous: the functional reaches a good part of the exact bound.
    assert!(advice > 0.3 * exact, "{advice} vs {exact}");
}

/// The textbook two-mode jump system of `markov.rs` (b = 1 or 0, rates
/// [-p, p; q, -q], mean-square stabilizable iff 2 a < q): as the sampling
/// interval shrinks the sampled certificate recovers the continuous
/// mode-dependent design.
#[test]
fn the_textbook_jump_system_is_certified_sampled_as_h_goes_to_zero() {
    let (p, q) = (1.0, 2.0);
    let text = |a: f64, every: f64| {
        format!(
            "tsf 1; controller jump; state x1; input u; A = {a}; B = 1;\n\
             premise x1 range -1 .. 1 {{ all = trap(-2, -1, 1, 2); }}\n\
             rule R: x1 is all => A = {a};\n\
             modes {{ mode actuated {{ }} mode failed {{ effectiveness = 0; }}\n\
             rates = [-{p}, {p}; {q}, -{q}]; }}\n\
             trigger periodic {{ every = {every}; }}\n"
        )
    };
    // Below the boundary 2 a < q the continuous design exists, and its gains
    // are certified for a short enough period (the failed mode alone is
    // unstable: only the coupling through the chain stabilizes it).
    for a in [0.5, 0.9] {
        let (ok, json) = compiled(&text(a, 1e-3));
        assert!(ok, "a = {a}: {}", json["diagnosis"]);
        let lp = Loop::of(&json);
        let a_rules = [DMatrix::from_element(1, 1, a)];
        let b_of = |mode: usize, _| DMatrix::from_element(1, 1, if mode == 0 { 1.0 } else { 0.0 });
        for mode in 0..2 {
            for tau in [0.0, lp.h_max] {
                let m = lp.bound((&a_rules, &b_of), mode, (&[1.0], &[1.0]), lp.h_max, tau);
                assert!(max_eig(&m) < 0.0, "a = {a}, mode {mode}");
            }
        }
    }
    // Above it nothing is certified, sampled or not.
    let (ok, json) = compiled(&text(1.05, 1e-3));
    assert!(!ok);
    assert!(
        json["diagnosis"]["message"]
            .as_str()
            .is_some_and(|m| m.contains("mode conditions are infeasible")),
        "{}",
        json["diagnosis"]
    );
    // A long period is refused; its advice certifies.
    let (ok, refused) = compiled(&text(0.5, 10.0));
    assert!(!ok);
    let advice = advised_period(&refused);
    let (ok, json) = compiled(&text(0.5, advice));
    assert!(ok, "advised {advice}: {}", json["diagnosis"]);
}

const XUE_SAMPLED: &str = "xue2024_markov_sampled.tsf";

#[test]
fn xue2024_sampled_compiles_certified_and_converges_with_jumps_between_samples() {
    let m = common::shipped(XUE_SAMPLED);
    assert_eq!((m.n, m.m, m.r()), (6, 3, 3));
    let p = prepare(&common::spec_path(XUE_SAMPLED)).expect("certified");
    assert_eq!(p.tables.header.sampling, Some((0.01, 0.08)));
    let mut csv = Vec::new();
    let o = simulate_csv(&p, &Options::default(), &mut csv).expect("runs");
    let mm = o.metrics.modes.as_ref().expect("modes");
    println!(
        "xue sampled: converged {} settle {:?} max|u| {:?} final {:.3e}; {} jumps, {} transmissions of {} samples",
        o.metrics.converged,
        o.metrics.settle_time_s,
        o.metrics.max_abs_u,
        o.metrics.final_state_norm,
        mm.transitions,
        o.metrics.transmissions,
        o.metrics.samples
    );
    assert!(
        o.metrics.converged && !o.metrics.failed,
        "{:?}",
        o.metrics.failures()
    );
    assert!(mm.transitions > 50);
    // Rows: one per sample and one per jump; a jump is not a sample, and the
    // command changes there (re-blended from the held sample).
    assert_eq!(o.metrics.samples, o.metrics.transmissions + mm.transitions);
    let csv = String::from_utf8(csv).expect("utf-8");
    let rows: Vec<Vec<f64>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().expect("number")).collect())
        .collect();
    let (sent, mode, u0) = (rows[0].len() - 2, rows[0].len() - 1, 15);
    let mut times = Vec::new();
    let mut rebl = 0;
    for w in rows.windows(2) {
        if w[1][sent] == 1.0 {
            times.push(w[1][0]);
        }
        if w[1][mode] != w[0][mode] {
            assert_eq!(w[1][sent], 0.0, "a jump at t = {} is not a sample", w[1][0]);
            rebl += usize::from(w[1][u0] != w[0][u0]);
        }
    }
    // Sampling intervals within [h_min, h_max] (the last one ends the run).
    for d in times.windows(2).take(times.len().saturating_sub(2)) {
        let gap = d[1] - d[0];
        assert!((0.01 - 1e-9..=0.08 + 1e-9).contains(&gap), "interval {gap}");
    }
    assert!(rebl > mm.transitions as usize / 2, "{rebl} re-blends");
}

/// B_ai of the Xue plant: rule i's B with mode a's effectiveness (the bias
/// mode adds a constant input only).
fn xue_input(b: &DMatrix<f64>, mode: usize) -> DMatrix<f64> {
    let eff = [[1.0, 1.0, 1.0], [0.7, 0.8, 0.6], [1.0, 1.0, 1.0]][mode];
    b * DMatrix::from_diagonal(&nalgebra::DVector::from_row_slice(&eff))
}

#[test]
fn xue2024_fault_blind_sampled_is_co_designed_certified_rechecked_and_converges() {
    let text = std::fs::read_to_string(common::spec_path(XUE_SAMPLED))
        .expect("shipped spec")
        .replace("design = mode_dependent;", "design = mode_independent;");
    assert!(text.contains("design = mode_independent;"));
    let name = "xue_fault_blind_sampled.tsf".to_string();
    let source = tsfc::driver::frontend::Source {
        name: name.clone(),
        text,
        bytes: Vec::new(),
    };
    let run = tsfc::pipeline::Front::from_source(source, name)
        .compile(&tsfc::synth::Settings::default())
        .expect("compiles");
    let json = crate::common::schema::report_json(&run.compiled.report);
    assert_eq!(json["status"], "certified", "{}", json["diagnosis"]);
    let lp = Loop::of(&json);
    assert_eq!(lp.h_max, 0.08);
    // One gain set for every mode.
    for a in 1..3 {
        for j in 0..3 {
            assert_eq!(lp.f[a][j], lp.f[0][j], "mode {a} rule {j}");
        }
    }
    let largest = lp.f[0].iter().map(|f| f.norm()).fold(0.0, f64::max);
    // Independent re-check of the generator bound from the report: A_i and B_i
    // from the model, the modes' effectiveness written here.
    let a_rules: Vec<DMatrix<f64>> = run.model.rules.iter().map(|r| r.a.clone()).collect();
    let b_rules: Vec<DMatrix<f64>> = run.model.rules.iter().map(|r| r.b.clone()).collect();
    let b_of = |a: usize, i: usize| xue_input(&b_rules[i], a);
    let (worst_vertex, worst) = lp.worst((&a_rules, &b_of), 3, 29, 500);
    assert!(worst_vertex < 0.0, "{worst_vertex}");
    assert!(worst < 0.0, "{worst}");
    // The continuous certificate (common P, decay 0.05) holds for these gains
    // too: every condition of the certificate is met.
    assert_eq!(json["certificate"]["ok"], true);
    // The closed loop converges under the seeded mode process, sampled.
    let p = tsfc::driver::prepare_run(&run).expect("certified");
    let o = simulate_csv(&p, &Options::default(), &mut Vec::new()).expect("runs");
    let mm = o.metrics.modes.as_ref().expect("modes");
    println!(
        "xue fault-blind sampled: largest ||F_j|| {largest:.0}; vertex {worst_vertex:.3e}, random {worst:.3e}; converged {} settle {:?} max|u| {:?} final {:.3e}; {} jumps",
        o.metrics.converged,
        o.metrics.settle_time_s,
        o.metrics.max_abs_u,
        o.metrics.final_state_norm,
        mm.transitions
    );
    assert!(
        o.metrics.converged && !o.metrics.failed,
        "{:?}",
        o.metrics.failures()
    );
    assert!(mm.transitions > 50);
    assert!(o.metrics.final_state_norm < 1e-2);
}
