//! Runs `Controller::step` of the Zhang & Zeng controller 1000 times, for
//! instruction counting: `valgrind --tool=callgrind --toggle-collect='*attitude*Controller*step*'
//! target/release/examples/step_count` (see README, "Generated code").

use flight_example::attitude::Controller;
use std::hint::black_box;

fn main() {
    let mut c = Controller::new();
    let mut x = [0.08, -0.05, 0.1, 0.12, 0.06, -0.08];
    let mut acc = 0.0;
    for k in 0..1000 {
        x[0] = 0.08 + 1e-5 * f64::from(k % 7);
        let u = c.step(black_box(&x));
        acc += u[0];
    }
    println!("{acc}");
}
