//! `Controller::step`, `FactoredController::step` and the triggers allocate nothing: a counting global
//! allocator records every allocation made on the test's own thread.

mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use tsf_runtime::{AdaptiveTrigger, MixedTrigger, PeriodicTrigger, RelativeTrigger};

thread_local! {
    static ALLOCS: Cell<usize> = const { Cell::new(0) };
}

struct Counting;

// SAFETY: forwards to the system allocator; only adds a thread-local counter
// (const-initialised, so touching it never allocates).
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = ALLOCS.try_with(|c| c.set(c.get() + 1));
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let _ = ALLOCS.try_with(|c| c.set(c.get() + 1));
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocs() -> usize {
    ALLOCS.with(Cell::get)
}

#[test]
fn step_and_triggers_do_not_allocate() {
    // Sanity: the counter does see allocations.
    let before = allocs();
    let v = std::hint::black_box(vec![1u8; 16]);
    assert!(allocs() > before);
    drop(v);

    let mut g = [[[0.0; common::N]; common::M]; common::R];
    g[1][0][0] = -1.5;
    g[3][1][2] = 2.0;
    let c = common::controller(g, [1.0, 1.0]);
    let f = common::factored(g, [1.0, 1.0]);
    let mut periodic = PeriodicTrigger::new(3);
    let mut relative = RelativeTrigger::new([[1.0; 4]; 4], 0.1);
    let mut adaptive = AdaptiveTrigger::new([[1.0; 4]; 4], 0.2, 10.0, 1.0, 0.02);
    let mut mixed = MixedTrigger::new(0.5, 0.01);

    let before = allocs();
    let mut acc = 0.0;
    for k in 0..10_000 {
        let t = k as f64 * 1e-3;
        let x = [
            t.sin(),
            (3.0 * t).cos(),
            20.0 * t - 5.0,
            f64::from(k % 7) - 3.0,
        ];
        let x = if k % 1000 == 999 { [f64::NAN; 4] } else { x };
        let s = std::hint::black_box(&c).step(std::hint::black_box(&x));
        acc += s.u[0] + s.u[1];
        let s = c.step_with_premises(&x, &[40.0, 40.0]);
        acc += s.u[0];
        let s = std::hint::black_box(&f).step(std::hint::black_box(&x));
        acc += s.u[0] + s.u[1];
        acc += f64::from(u8::from(periodic.decide()));
        acc += f64::from(u8::from(relative.decide(&x)));
        acc += f64::from(u8::from(adaptive.decide(&x)));
        acc += f64::from(u8::from(mixed.decide(&x)));
    }
    let after = allocs();
    assert!(std::hint::black_box(acc).is_finite());
    assert_eq!(after - before, 0, "step/decide allocated");
}
