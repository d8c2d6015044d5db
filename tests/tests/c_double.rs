//! Issue 36: the C runtime's double elementary functions (`tsf_exp`,
//! `tsf_sqrt`, `tsf_atan`, `tsf_sin`, `tsf_cos`, `tsf_sinc`, `tsf_exprel`) are
//! the Rust runtime's binary64 `math::<f>`, bit for bit, on every branch:
//! zeros, subnormals, NaN and infinities, the branch edges (`2^-28`, `2^-27`,
//! `2^-26`, `2^-13`, `pi/4`, the overflow and underflow limits of `exp`),
//! multiples of `pi/2` (the second and third Cody-Waite steps), the
//! Cody-Waite/Payne-Hanek boundary, huge arguments and about 1.2 million
//! seeded arguments over the double range.

use crate::c_codegen::{c_compiler, sanitizers_work, Rng, SANITIZE};
use crate::c_single::{assert_c_is_the_runtime, bits_driver, OPTIMISED};
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};
use tsf_runtime::math;

/// The driver of the double functions [`NAMES`].
fn driver() -> String {
    bits_driver("double", "unsigned long long", "%llx", &NAMES)
}

/// Zeros, NaNs, infinities, the smallest subnormal and normal, the largest
/// finite values.
pub(crate) const SPECIAL_F64: [f64; 10] = [
    0.0,
    -0.0,
    f64::NAN,
    -f64::NAN,
    f64::INFINITY,
    f64::NEG_INFINITY,
    5e-324,
    f64::MIN_POSITIVE,
    f64::MAX,
    -f64::MAX,
];

/// The functions the driver prints, in its order.
const NAMES: [&str; 7] = ["exp", "sqrt", "atan", "sin", "cos", "sinc", "exprel"];

/// The seven functions of the runtime at the double of bit pattern `b`.
fn rust_bits(b: u64) -> Vec<u64> {
    let fs: [fn(f64) -> f64; 7] = [
        math::exp,
        math::sqrt,
        math::atan,
        math::sin,
        math::cos,
        math::sinc,
        math::exprel,
    ];
    let v = f64::from_bits(b);
    fs.iter().map(|f| f(v).to_bits()).collect()
}

/// Special values and the edges of every branch, with their neighbours.
fn edge_arguments() -> Vec<f64> {
    let mut args = SPECIAL_F64.to_vec();
    args.extend([
        -f64::MIN_POSITIVE,
        -f64::from_bits(1),
        f64::from_bits(0x000f_ffff_ffff_ffff), // largest subnormal
        709.782_712_893_384,                   // exp's overflow limit
        709.79,
        -745.133_219_101_941_2, // exp's underflow limit
        -745.14,
        -708.4, // subnormal results of exp
        -740.0,
        1024.0 * std::f64::consts::LN_2,
        -1022.0 * std::f64::consts::LN_2,
        3.725_290_298_461_914e-9,   // 2^-28
        7.450_580_596_923_828e-9,   // 2^-27
        1.490_116_119_384_765_6e-8, // 2^-26
        math::SINC_SMALL,
        math::EXPREL_SMALL,
        -math::EXPREL_SMALL,
        0.125,
        2.4375,
        7.378_697_629_483_821e19, // 2^66, atan's limit
        FRAC_PI_4,
        FRAC_PI_2,
        PI,
        1_647_099.331_725_909, // Cody-Waite up to here, Payne-Hanek above
        // The double nearest a multiple of pi/2 (Muller, "Elementary
        // Functions", 2016, table 11.1): 6381956970095103 * 2^797.
        6_381_956_970_095_103.0 * 2f64.powi(797),
        1e22,
        1e300,
    ]);
    for k in -64..=64 {
        args.push(f64::from(k) * FRAC_PI_4);
        args.push(f64::from(k) * FRAC_PI_2 * 1024.0);
    }
    for e in -1074..=1023 {
        args.push(2f64.powi(e));
    }
    for b in args.clone() {
        if b.is_finite() && b != 0.0 {
            for d in 1..=2 {
                args.push(f64::from_bits(b.to_bits() - d));
                args.push(f64::from_bits(b.to_bits() + d));
            }
            args.push(-b);
        }
    }
    args
}

/// Edges, then about 1.2 million seeded arguments: the kernels' range, the
/// range of `exp`, the Cody-Waite range, near multiples of `pi/2` (where
/// the reduction cancels most bits), and any bit pattern (huge arguments
/// on the Payne-Hanek path, subnormals, NaNs).
fn arguments() -> Vec<u64> {
    let mut args = edge_arguments();
    let mut rng = Rng::new(0xd0b1e);
    for _ in 0..250_000 {
        args.push(rng.uniform(-4.0, 4.0));
    }
    for _ in 0..200_000 {
        args.push(rng.uniform(-800.0, 800.0));
    }
    for _ in 0..200_000 {
        args.push(rng.uniform(-2e6, 2e6));
    }
    for _ in 0..200_000 {
        // n pi/2 for n below 2^20, rounded, and a few ulp around it.
        let n = (rng.next_u64() >> 44) as f64;
        let x = n * FRAC_PI_2;
        let d = (rng.next_u64() % 9) as i64 - 4;
        args.push(f64::from_bits(x.to_bits().wrapping_add_signed(d)));
    }
    for _ in 0..350_000 {
        args.push(f64::from_bits(rng.next_u64()));
    }
    args.into_iter().map(f64::to_bits).collect()
}

/// The C runtime's double functions equal the Rust runtime's bit for bit on
/// every argument (and its double build holds no libm call but `sqrt`,
/// `fabs`).
#[test]
fn c_double_functions_are_the_runtimes() {
    let args = arguments();
    assert!(args.len() >= 1_000_000, "{} arguments", args.len());
    let n = assert_c_is_the_runtime(
        "double",
        &driver(),
        &args,
        &NAMES,
        &rust_bits,
        f64::from_bits,
        &OPTIMISED,
    );
    println!(
        "{n} arguments x {} functions: C and the runtime bit-identical",
        NAMES.len()
    );
}

/// Under UBSan and ASan (where the compiler has them), the double functions
/// run every 20th argument (edges and seeded, the Payne-Hanek reduction's
/// shifts and 128-bit words included) without undefined behaviour, and
/// still equal the runtime.
#[test]
fn c_double_functions_are_clean_under_sanitizers() {
    let cc = c_compiler();
    if !sanitizers_work(&cc) {
        println!("SKIP: {cc} cannot build with {SANITIZE:?}");
        return;
    }
    let args: Vec<u64> = arguments().into_iter().step_by(20).collect();
    let mut flags: Vec<&str> = SANITIZE.to_vec();
    flags.extend(["-O1", "-ffp-contract=off"]);
    let n = assert_c_is_the_runtime(
        "double_sanitized",
        &driver(),
        &args,
        &NAMES,
        &rust_bits,
        f64::from_bits,
        &flags,
    );
    println!("{n} arguments under sanitizers: clean, bit-identical");
}
