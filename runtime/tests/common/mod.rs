//! Shared fixture: a 4-state, 2-input, 2-premise, 4-rule controller mixing
//! every kind of premise term, with holes (far from the centres no rule fires).
#![allow(dead_code)]

use tsf_runtime::{Controller, FactoredController, Membership, Rule, Term};

pub const N: usize = 4;
pub const M: usize = 2;
pub const P: usize = 2;
pub const R: usize = 4;

pub static ABOUT_POINT: [f64; 2] = [0.5, -0.5];

pub static R0: [Term<'static, f64>; 2] = [
    Term::Is {
        var: 0,
        set: Membership::tri(-1.0, -1.0, 0.0),
    },
    Term::Is {
        var: 1,
        set: Membership::trap(-2.0, -1.0, 1.0, 2.0),
    },
];
pub static R1: [Term<'static, f64>; 2] = [
    Term::Is {
        var: 0,
        set: Membership::tri(-1.0, 0.0, 1.0),
    },
    Term::Is {
        var: 1,
        set: Membership::gauss(0.0, 0.5),
    },
];
pub static R2: [Term<'static, f64>; 2] = [
    Term::Is {
        var: 0,
        set: Membership::tri(0.0, 1.0, 1.0),
    },
    Term::Is {
        var: 1,
        set: Membership::sigmoid(4.0, 0.0),
    },
];
pub static R3: [Term<'static, f64>; 1] = [Term::About {
    first: 0,
    point: &ABOUT_POINT,
    sigma: 0.3,
}];

pub const CENTRES: [[f64; P]; R] = [[-1.0, 0.0], [0.0, 0.0], [1.0, 1.0], [0.5, -0.5]];
pub const MAP: [[f64; N]; P] = [[1.0, 0.0, 0.5, 0.0], [0.0, 1.0, 0.0, -0.25]];

/// The fixture with the given gains and saturation levels.
pub fn controller(
    gains: [[[f64; N]; M]; R],
    u_max: [f64; M],
) -> Controller<'static, f64, N, M, P, R> {
    Controller {
        premise_map: MAP,
        rules: [
            Rule::new(&R0),
            Rule::new(&R1),
            Rule::new(&R2),
            Rule::new(&R3),
        ],
        centres: CENTRES,
        gains,
        u_max,
    }
}

/// The fixture as a [`FactoredController`] (its rules share no term: the
/// seven terms in rule order).
pub fn factored(
    gains: [[[f64; N]; M]; R],
    u_max: [f64; M],
) -> FactoredController<'static, f64, N, M, P, R, 7> {
    FactoredController {
        premise_map: MAP,
        terms: [R0[0], R0[1], R1[0], R1[1], R2[0], R2[1], R3[0]],
        rules: [&[0, 1], &[2, 3], &[4, 5], &[6]],
        centres: CENTRES,
        gains,
        u_max,
    }
}

/// Reference membership semantics written independently with `std`.
pub mod reference {
    pub fn trap(z: f64, a: f64, b: f64, c: f64, d: f64) -> f64 {
        if z.is_nan() || z < a || z > d {
            0.0
        } else if z >= b && z <= c {
            1.0
        } else if z < b {
            (z - a) / (b - a)
        } else {
            (d - z) / (d - c)
        }
    }
    pub fn gauss(z: f64, c: f64, s: f64) -> f64 {
        (-0.5 * ((z - c) / s).powi(2)).exp()
    }
    pub fn sigmoid(z: f64, k: f64, c: f64) -> f64 {
        1.0 / (1.0 + (-k * (z - c)).exp())
    }

    /// Weights of the fixture's four rules.
    pub fn weights(z: [f64; 2]) -> [f64; 4] {
        let d2 = (z[0] - 0.5).powi(2) + (z[1] + 0.5).powi(2);
        [
            trap(z[0], -1.0, -1.0, -1.0, 0.0) * trap(z[1], -2.0, -1.0, 1.0, 2.0),
            trap(z[0], -1.0, 0.0, 0.0, 1.0) * gauss(z[1], 0.0, 0.5),
            trap(z[0], 0.0, 1.0, 1.0, 1.0) * sigmoid(z[1], 4.0, 0.0),
            (-0.5 * d2 / 0.09).exp(),
        ]
    }

    /// Strengths, with the nearest-centre fallback; `true` if some rule fired.
    pub fn strengths(z: [f64; 2]) -> ([f64; 4], bool) {
        let w = weights(z);
        let s: f64 = w.iter().sum();
        if s > 0.0 {
            (w.map(|wi| wi / s), true)
        } else {
            let mut h = [0.0; 4];
            let dist = |c: [f64; 2]| (z[0] - c[0]).powi(2) + (z[1] - c[1]).powi(2);
            let best = (0..4)
                .min_by(|&i, &j| dist(super::CENTRES[i]).total_cmp(&dist(super::CENTRES[j])))
                .unwrap();
            h[best] = 1.0;
            (h, false)
        }
    }
}
