//! The two networked roles of the Xu & Huang event-triggered loop, as
//! generated into the flight crate: the sensor-side trigger against
//! `tsf_runtime`'s trigger used directly, and the sensor and controller
//! closing the loop around the spacecraft.

use flight_example::event_triggered::sensor::{
    Sensor, H_MAX, H_MIN, MU1, MU2, MU3, N, NU_MAX, NU_MIN, WEIGHT,
};
use flight_example::event_triggered::{Controller, M};
use std::hint::black_box;
use tsf_runtime::AdaptiveTrigger;

/// SplitMix64.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next() >> 11) as f64 / (1u64 << 53) as f64)
    }
}

#[test]
fn sensor_tables_are_consistent() {
    // Read through black_box: the checks are about the generated values.
    let (h_min, h_max, nu_min, nu_max) = black_box((H_MIN, H_MAX, NU_MIN, NU_MAX));
    assert_eq!((N, Sensor::N), (6, 6));
    assert!(0.0 < h_min && h_min < h_max, "[{h_min}, {h_max}]");
    assert!(
        0.0 <= nu_min && nu_min <= nu_max && nu_max < 1.0,
        "[{nu_min}, {nu_max}]"
    );
    assert!(black_box([MU1, MU2, MU3]).iter().all(|&m| m >= 0.0));
    let u = black_box(WEIGHT);
    for (i, row) in u.iter().enumerate() {
        assert!(row[i] > 0.0, "U[{i}][{i}] = {}", row[i]);
        for (j, v) in row.iter().enumerate() {
            assert_eq!(*v, u[j][i], "U is symmetric");
        }
    }
    let s = Sensor::new();
    assert_eq!((s.nu(), s.last()), (NU_MIN, None));
    assert_eq!(Sensor::default(), s);
}

/// 2000 random sequences (scales 1e-3..3, relative steps 0.3 %..100 %):
/// `Sensor::sample` is `Some(x)` exactly when the runtime's adaptive trigger
/// (built here from the generated constants, `with_max(NU_MAX)`) transmits,
/// with the same nu bit for bit and the same last state; nu stays within the
/// certified range and reaches both ends.
#[test]
fn sensor_is_the_runtime_adaptive_trigger() {
    let mut rng = Rng(0x5e11);
    let (mut sent, mut held, mut at_max, mut at_min_after_drop) = (0, 0, 0, 0);
    for k in 0..2000 {
        let mut sensor = Sensor::new();
        let mut reference = AdaptiveTrigger::new(WEIGHT, NU_MIN, MU1, MU2, MU3).with_max(NU_MAX);
        let scale = 10f64.powf(rng.uniform(-3.0, 0.5));
        let step = 10f64.powf(rng.uniform(-2.5, 0.0)) * scale;
        let decay = if k % 3 == 0 {
            0.0
        } else {
            rng.uniform(0.0, 0.2)
        };
        let mut x: [f64; N] = core::array::from_fn(|_| rng.uniform(-scale, scale));
        for i in 0..40 {
            if k % 97 == 5 && i == 20 {
                x[0] = f64::NAN; // a faulty sample transmits and resets nu to NU_MIN
            }
            let before = sensor.nu();
            let got = sensor.sample(&x);
            let want = reference.decide(&x);
            assert_eq!(got.is_some(), want, "sequence {k} sample {i}: decision");
            if let Some(tx) = got {
                assert_eq!(
                    tx.map(f64::to_bits),
                    x.map(f64::to_bits),
                    "transmits x itself"
                );
                sent += 1;
            } else {
                held += 1;
            }
            assert_eq!(sensor.nu().to_bits(), reference.nu().to_bits(), "nu");
            assert_eq!(
                sensor.last().map(|l| l.map(f64::to_bits)),
                reference.last().map(|l| l.map(f64::to_bits)),
                "last transmitted state"
            );
            let nu = sensor.nu();
            assert!((NU_MIN..=NU_MAX).contains(&nu), "nu = {nu}");
            at_max += usize::from(nu == NU_MAX);
            at_min_after_drop += usize::from(nu == NU_MIN && before > NU_MIN);
            for c in x.iter_mut() {
                *c = if c.is_nan() {
                    0.0
                } else {
                    *c * (1.0 - decay) + rng.uniform(-step, step)
                };
            }
        }
    }
    println!("sent {sent}, held {held}, at NU_MAX {at_max}, back to NU_MIN {at_min_after_drop}");
    assert!(sent > 1000 && held > 1000 && at_max > 100 && at_min_after_drop > 10);
}

/// Spacecraft attitude (Xu & Huang (2)-(3), J from the spec): `w' = J^-1
/// (-w x Jw + u)`, `q' = 1/2 (sqrt(1 - q'q) I + q^x) w`.
fn plant(x: &[f64; N], u: &[f64; M]) -> [f64; N] {
    const J: [[f64; 3]; 3] = [[350.0, 3.0, 4.0], [3.0, 270.0, 10.0], [4.0, 10.0, 190.0]];
    let (w, q) = ([x[0], x[1], x[2]], [x[3], x[4], x[5]]);
    let jw: [f64; 3] = core::array::from_fn(|i| (0..3).map(|j| J[i][j] * w[j]).sum());
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let wjw = cross(w, jw);
    let rhs: [f64; 3] = core::array::from_fn(|i| -wjw[i] + u[i]);
    // J^-1 rhs by Cramer's rule.
    let det3 = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det3(J);
    let wdot: [f64; 3] = core::array::from_fn(|c| {
        let mut m = J;
        for (r, row) in m.iter_mut().enumerate() {
            row[c] = rhs[r];
        }
        det3(m) / d
    });
    let q0 = (1.0 - q.iter().map(|v| v * v).sum::<f64>()).max(0.0).sqrt();
    let qw = cross(q, w);
    [
        wdot[0],
        wdot[1],
        wdot[2],
        0.5 * (q0 * w[0] + qw[0]),
        0.5 * (q0 * w[1] + qw[1]),
        0.5 * (q0 * w[2] + qw[2]),
    ]
}

fn norm(x: &[f64; N]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

/// The networked loop: at every sampling instant the sensor decides; on a
/// transmission the controller steps on the transmitted state x(t_k) and its
/// command is held until the next one. The attitude converges while most
/// samples are not transmitted.
#[test]
fn sensor_and_controller_close_the_loop() {
    let h = 0.01; // sampling interval, within [H_MIN, H_MAX]
    assert!((H_MIN..=H_MAX).contains(&h));
    let substeps = 10;
    let mut sensor = Sensor::new();
    let mut controller = Controller::new();
    let mut x = [0.02, -0.01, 0.015, 0.1, -0.08, 0.06];
    let x0 = norm(&x);
    let mut u = [0.0; M];
    let (mut samples, mut sent) = (0usize, 0usize);
    let mut nu_seen = (f64::INFINITY, 0.0f64);
    for _ in 0..(120.0 / h) as usize {
        samples += 1;
        if let Some(xk) = sensor.sample(&x) {
            sent += 1;
            u = controller.step(&xk);
            assert!(!controller.fault());
            assert_eq!(sensor.last(), Some(&xk));
        }
        assert!(u.iter().all(|v| v.abs() <= 2.0), "|u| <= 2 N m: {u:?}");
        nu_seen = (nu_seen.0.min(sensor.nu()), nu_seen.1.max(sensor.nu()));
        // RK4 with the command held over the sampling interval.
        let dt = h / f64::from(substeps);
        for _ in 0..substeps {
            let add = |a: &[f64; N], k: &[f64; N], s: f64| -> [f64; N] {
                core::array::from_fn(|i| a[i] + s * k[i])
            };
            let k1 = plant(&x, &u);
            let k2 = plant(&add(&x, &k1, dt / 2.0), &u);
            let k3 = plant(&add(&x, &k2, dt / 2.0), &u);
            let k4 = plant(&add(&x, &k3, dt), &u);
            x = core::array::from_fn(|i| {
                x[i] + dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
            });
        }
    }
    let x_end = norm(&x);
    println!(
        "|x(0)| = {x0:.3e}, |x(120 s)| = {x_end:.3e}; {sent} of {samples} samples sent; \
         nu in [{:.4}, {:.4}]",
        nu_seen.0, nu_seen.1
    );
    assert!(
        x_end < 0.05 * x0,
        "the loop converges: |x| {x0:e} -> {x_end:e}"
    );
    assert!(
        sent < samples / 2,
        "events save bandwidth: {sent} of {samples}"
    );
    assert!(NU_MIN <= nu_seen.0 && nu_seen.1 <= NU_MAX);
}
