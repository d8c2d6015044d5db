//! The observer tests' shared pieces: the runtime observer of a two-state,
//! one-input, one-output, two-rule design, and one RK4 step of a plant.

use tsf_runtime::{FactoredController, Observer, Term};
use tsfc::tables::Tables;

/// The runtime observer of a design with n = 2, m = 1, one output, two rules.
pub type Runtime<'a> = Observer<'a, f64, 2, 1, 1, 1, 2, 2>;

/// The runtime's observer on the generated tables (premises supplied by the
/// caller: `step_with_premises`).
pub fn runtime_observer<'a>(t: &'a Tables, terms: &'a [Term<'a, f64>]) -> Runtime<'a> {
    let o = t.observer.as_ref().expect("observer tables");
    let rules: Vec<&[usize]> = t.factored.rules.iter().map(Vec::as_slice).collect();
    let m2 = |r: &[Vec<f64>]| [[r[0][0], r[0][1]], [r[1][0], r[1][1]]];
    let col = |r: &[Vec<f64>]| [[r[0][0]], [r[1][0]]];
    Observer {
        controller: FactoredController {
            premise_map: [[0.0, 0.0]],
            terms: [terms[0], terms[1]],
            rules: [rules[0], rules[1]],
            centres: [[t.centres[0][0]], [t.centres[1][0]]],
            gains: [
                [[t.gains[0][0][0], t.gains[0][0][1]]],
                [[t.gains[1][0][0], t.gains[1][0][1]]],
            ],
            u_max: [t.u_max[0]],
        },
        output_map: o.output_map.as_ref().map(|s| col(s)),
        phi: [m2(&o.phi[0]), m2(&o.phi[1])],
        gu: [col(&o.gu[0]), col(&o.gu[1])],
        gy: [col(&o.gy[0]), col(&o.gy[1])],
    }
}

/// One classical RK4 step of length `h` of x' = f(x) (two states).
pub fn rk4_step(x: &mut [f64; 2], h: f64, f: impl Fn([f64; 2]) -> [f64; 2]) {
    let k1 = f(*x);
    let k2 = f([x[0] + h / 2.0 * k1[0], x[1] + h / 2.0 * k1[1]]);
    let k3 = f([x[0] + h / 2.0 * k2[0], x[1] + h / 2.0 * k2[1]]);
    let k4 = f([x[0] + h * k3[0], x[1] + h * k3[1]]);
    for i in 0..2 {
        x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
}
