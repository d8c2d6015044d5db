//! The C runtime's float elementary functions (`tsf_expf`, `tsf_sqrtf`,
//! `tsf_atanf`, `tsf_sinf`, `tsf_cosf`, `tsf_sincf`, `tsf_exprelf`) are the
//! Rust runtime's binary32 `math::<f>f`, bit for bit, on every branch: edges,
//! special values, and ~1.4 million seeded arguments over the f32 range.

use crate::c_codegen::{build, c_compiler, run_driver, work_dir, write_runtime, Rng};
use std::fmt::Write as _;
use tsf_runtime::math;

const DRIVER: &str = r#"#include "tsf_runtime.h"
#include <stdio.h>
#include <string.h>

static unsigned bits(float v) {
    unsigned b;
    memcpy(&b, &v, sizeof b);
    return b;
}

int main(void) {
    unsigned b;
    while (scanf("%x", &b) == 1) {
        float v;
        memcpy(&v, &b, sizeof v);
        printf("%08x %08x %08x %08x %08x %08x %08x\n", bits(tsf_expf(v)), bits(tsf_sqrtf(v)),
               bits(tsf_atanf(v)), bits(tsf_sinf(v)), bits(tsf_cosf(v)), bits(tsf_sincf(v)),
               bits(tsf_exprelf(v)));
    }
    return 0;
}
"#;

/// The seven functions of the runtime at `v`, as bit patterns (NaN as one pattern).
fn rust_bits(v: f32) -> [u32; 7] {
    let fs: [fn(f32) -> f32; 7] = [
        math::expf,
        math::sqrtf,
        math::atanf,
        math::sinf,
        math::cosf,
        math::sincf,
        math::exprelf,
    ];
    fs.map(|f| canonical(f(v).to_bits()))
}

/// Every NaN as the one quiet NaN (C and Rust may differ in NaN payloads).
fn canonical(b: u32) -> u32 {
    if f32::from_bits(b).is_nan() {
        0x7fc0_0000
    } else {
        b
    }
}

#[test]
fn c_float_functions_are_the_runtimes() {
    let cc = c_compiler();
    let dir = work_dir("c_single");
    let runtime = write_runtime(&dir);
    let drv = dir.join("single_drive.c");
    std::fs::write(&drv, DRIVER).expect("write driver");
    let exe = dir.join("single_drive");
    build(&cc, &[drv, runtime], &exe, &["-O2", "-ffp-contract=off"]);
    let mut args: Vec<f32> = vec![
        0.0,
        -0.0,
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::MAX,
        -f32::MAX,
        f32::MIN_POSITIVE,
        f32::from_bits(1),
        88.722_83,
        89.0,
        -103.972_08,
        -104.0,
        0.5,
        -0.5,
        0.125,
        2.4375,
        67_108_864.0,
        f32::from_bits(0x3f49_0fda), // pi/4 rounded down: the kernel boundary
        core::f32::consts::FRAC_PI_2,
        core::f32::consts::PI,
        math::SINCF_SMALL,
    ];
    for k in 0..=80 {
        args.push(k as f32 / 32.0);
        args.push(k as f32 * core::f32::consts::FRAC_PI_4);
    }
    for b in args.clone() {
        if b.is_finite() && b != 0.0 {
            args.push(f32::from_bits(b.to_bits() - 1));
            args.push(f32::from_bits(b.to_bits() + 1));
        }
    }
    let mut rng = Rng::new(0x5e32);
    for _ in 0..400_000 {
        args.push(rng.uniform(-4.0, 4.0) as f32);
    }
    for _ in 0..400_000 {
        args.push(rng.uniform(-110.0, 110.0) as f32);
    }
    for _ in 0..600_000 {
        // Any bit pattern: every exponent, subnormals, NaNs.
        args.push(f32::from_bits((rng.next_u64() >> 32) as u32));
    }
    let mut input = String::new();
    for v in &args {
        let _ = writeln!(input, "{:x}", v.to_bits());
    }
    let input_path = dir.join("single_args.txt");
    std::fs::write(&input_path, input).expect("write args");
    let out = run_driver(&exe, &input_path);
    let names = ["expf", "sqrtf", "atanf", "sinf", "cosf", "sincf", "exprelf"];
    let mut lines = 0usize;
    for (line, &v) in out.lines().zip(&args) {
        let c: Vec<u32> = line
            .split(' ')
            .map(|w| canonical(u32::from_str_radix(w, 16).expect("bits")))
            .collect();
        let r = rust_bits(v);
        for (k, name) in names.iter().enumerate() {
            assert_eq!(
                c.get(k).copied(),
                Some(r[k]),
                "{name}({v:e}) = {:e} in C, {:e} in the runtime",
                f32::from_bits(c.get(k).copied().unwrap_or(0)),
                f32::from_bits(r[k])
            );
        }
        lines += 1;
    }
    assert_eq!(lines, args.len(), "one line per argument");
    println!(
        "{} arguments x {} functions: C and the runtime bit-identical",
        args.len(),
        names.len()
    );
}
