//! `Controller::step` of each generated controller (criterion).
//! Run: `cargo bench -p flight-example --bench step`.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use flight_example::{attitude, event_triggered, pendulum};

fn bench(c: &mut Criterion) {
    let mut zhang = attitude::Controller::new();
    let xz = [0.08, -0.05, 0.1, 0.12, 0.06, -0.08];
    c.bench_function("zhang_multiobjective step (R=9, n=6, m=3)", |b| {
        b.iter(|| zhang.step(black_box(&xz)))
    });
    let mut xu = event_triggered::Controller::new();
    let xx = [0.01, -0.02, 0.01, -0.3802, 0.2124, 0.5013];
    c.bench_function("xu_event_triggered step (R=7, about sets)", |b| {
        b.iter(|| xu.step(black_box(&xx)))
    });
    let mut pend = pendulum::Controller::new();
    let xp = [1.0, 0.0];
    c.bench_function("inverted_pendulum step (R=2, sinc premise)", |b| {
        b.iter(|| pend.step(black_box(&xp)))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
