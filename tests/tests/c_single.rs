//! The C runtime's float elementary functions (`tsf_expf`, `tsf_sqrtf`,
//! `tsf_atanf`, `tsf_sinf`, `tsf_cosf`, `tsf_sincf`, `tsf_exprelf`) are the
//! Rust runtime's binary32 `math::<f>f`, bit for bit, on every branch: edges,
//! special values, and ~1.4 million seeded arguments over the f32 range.

use crate::c_codegen::{build, c_compiler, run_driver, work_dir, write_runtime, Rng};
use std::fmt::Write as _;
use tsf_runtime::math;

/// The flags of the bit-identity tests: optimised, no contraction into FMA.
pub(crate) const OPTIMISED: [&str; 2] = ["-O2", "-ffp-contract=off"];

/// A C driver that reads one hex bit pattern of a `real` (`float` or
/// `double`; `word` its unsigned integer type, `conv` that type's hex
/// conversion) per line and prints the hex bit patterns of the runtime's
/// `tsf_<name>` at it for each of `names`, space-separated.
pub(crate) fn bits_driver(real: &str, word: &str, conv: &str, names: &[&str]) -> String {
    let formats = vec![conv; names.len()].join(" ");
    let calls: Vec<String> = names.iter().map(|n| format!("bits(tsf_{n}(v))")).collect();
    format!(
        r#"#include "tsf_runtime.h"
#include <stdio.h>
#include <string.h>

static {word} bits({real} v) {{
    {word} b;
    memcpy(&b, &v, sizeof b);
    return b;
}}

int main(void) {{
    {word} b;
    while (scanf("{conv}", &b) == 1) {{
        {real} v;
        memcpy(&v, &b, sizeof v);
        printf("{formats}\n", {});
    }}
    return 0;
}}
"#,
        calls.join(", ")
    )
}

/// The seven functions of the runtime at the f32 of bit pattern `b`.
fn rust_bits(b: u64) -> Vec<u64> {
    let fs: [fn(f32) -> f32; 7] = [
        math::expf,
        math::sqrtf,
        math::atanf,
        math::sinf,
        math::cosf,
        math::sincf,
        math::exprelf,
    ];
    let v = f32::from_bits(b as u32);
    fs.iter().map(|f| u64::from(f(v).to_bits())).collect()
}

/// The value of an f32 bit pattern, widened (exactly) for messages and NaN tests.
fn f32_value(b: u64) -> f64 {
    f64::from(f32::from_bits(b as u32))
}

/// `b` unless it is a NaN of `value`'s format: every NaN is one pattern (C
/// and Rust may differ in NaN payloads).
fn canonical(b: u64, value: fn(u64) -> f64) -> u64 {
    if value(b).is_nan() {
        u64::MAX
    } else {
        b
    }
}

/// The functions `names` of a C runtime driver against the Rust runtime, bit
/// for bit: builds `driver` (one hex bit pattern in per line, the functions'
/// hex bit patterns out, space-separated) with the runtime source in the
/// work directory `tag` (C99, strict warnings, then `flags`), runs it on
/// `args` and asserts every output word equals `rust(arg)`'s (NaNs as one
/// pattern; `value` reads a bit pattern). Returns the count of arguments.
pub(crate) fn assert_c_is_the_runtime(
    tag: &str,
    driver: &str,
    args: &[u64],
    names: &[&str],
    rust: &dyn Fn(u64) -> Vec<u64>,
    value: fn(u64) -> f64,
    flags: &[&str],
) -> usize {
    let cc = c_compiler();
    let dir = work_dir(tag);
    let runtime = write_runtime(&dir);
    let drv = dir.join(format!("{tag}_drive.c"));
    std::fs::write(&drv, driver).expect("write driver");
    let exe = dir.join(format!("{tag}_drive"));
    build(&cc, &[drv, runtime], &exe, flags);
    let mut input = String::new();
    for b in args {
        let _ = writeln!(input, "{b:x}");
    }
    let input_path = dir.join(format!("{tag}_args.txt"));
    std::fs::write(&input_path, input).expect("write args");
    let out = run_driver(&exe, &input_path);
    let mut lines = 0usize;
    for (line, &b) in out.lines().zip(args) {
        let c: Vec<u64> = line
            .split(' ')
            .map(|w| canonical(u64::from_str_radix(w, 16).expect("bits"), value))
            .collect();
        let r: Vec<u64> = rust(b).into_iter().map(|w| canonical(w, value)).collect();
        for (k, name) in names.iter().enumerate() {
            assert_eq!(
                c.get(k).copied(),
                r.get(k).copied(),
                "{name}({:e}) = {:e} in C, {:e} in the runtime",
                value(b),
                value(c.get(k).copied().unwrap_or(0)),
                value(r.get(k).copied().unwrap_or(0))
            );
        }
        lines += 1;
    }
    assert_eq!(lines, args.len(), "one line per argument");
    lines
}

#[test]
fn c_float_functions_are_the_runtimes() {
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
    let bits: Vec<u64> = args.iter().map(|v| u64::from(v.to_bits())).collect();
    let names = ["expf", "sqrtf", "atanf", "sinf", "cosf", "sincf", "exprelf"];
    let n = assert_c_is_the_runtime(
        "single",
        &bits_driver("float", "unsigned", "%x", &names),
        &bits,
        &names,
        &rust_bits,
        f32_value,
        &OPTIMISED,
    );
    println!(
        "{n} arguments x {} functions: C and the runtime bit-identical",
        names.len()
    );
}
