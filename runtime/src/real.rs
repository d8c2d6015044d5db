//! The [`Real`] scalar trait: the only arithmetic the runtime uses.

use core::ops::{Add, AddAssign, Div, Mul, Neg, Sub};

/// A floating-point scalar (`f64` or `f32`) with the elementary functions of
/// [`crate::math`].
///
/// All runtime algorithms are generic over `Real`; the `f32` elementary
/// functions are evaluated in binary32 arithmetic only (see [`crate::math`]).
pub trait Real:
    Copy
    + PartialOrd
    + Default
    + core::fmt::Debug
    + Add<Output = Self>
    + AddAssign
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// `0`.
    const ZERO: Self;
    /// `1`.
    const ONE: Self;
    /// `1/2`.
    const HALF: Self;
    /// `2/pi`, rounded to nearest.
    const FRAC_2_PI: Self;
    /// Largest finite value.
    const MAX: Self;
    /// A power of two `s` such that `((a*s) - (b*s))^2` cannot overflow for
    /// any finite `a`, `b` (used to rescale distances that overflowed).
    const TINY_SCALE: Self;

    /// Conversion from `f64` (rounds to nearest for `f32`).
    fn from_f64(v: f64) -> Self;
    /// Conversion to `f64` (exact).
    fn to_f64(self) -> f64;
    /// `true` unless NaN or infinite.
    fn is_finite(self) -> bool;
    /// `true` if NaN.
    fn is_nan(self) -> bool;
    /// Absolute value (clears the sign bit; NaN stays NaN).
    fn abs(self) -> Self;
    /// `e^self`, see [`crate::math::exp`].
    fn exp(self) -> Self;
    /// Square root, correctly rounded, see [`crate::math::sqrt`].
    fn sqrt(self) -> Self;
    /// Arc tangent in `[-pi/2, pi/2]`, see [`crate::math::atan`].
    fn atan(self) -> Self;
    /// Sine, see [`crate::math::sin`].
    fn sin(self) -> Self;
    /// Cosine, see [`crate::math::cos`].
    fn cos(self) -> Self;
    /// `sin(v)/v` with 1 at 0, see [`crate::math::sinc`].
    fn sinc(self) -> Self;
    /// `(e^v - 1)/v` with 1 at 0, see [`crate::math::exprel`].
    fn exprel(self) -> Self;
}

macro_rules! impl_real {
    ($t:ty, $bits:ty, $scale:expr, $exp:expr, $sqrt:expr, $atan:expr, $sin:expr, $cos:expr, $sinc:expr, $exprel:expr) => {
        impl Real for $t {
            const ZERO: Self = 0.0;
            const ONE: Self = 1.0;
            const HALF: Self = 0.5;
            const FRAC_2_PI: Self = core::f64::consts::FRAC_2_PI as $t;
            const MAX: Self = <$t>::MAX;
            const TINY_SCALE: Self = $scale;

            #[inline]
            fn from_f64(v: f64) -> Self {
                v as $t
            }
            #[inline]
            fn to_f64(self) -> f64 {
                self as f64
            }
            #[inline]
            fn is_finite(self) -> bool {
                <$t>::is_finite(self)
            }
            #[inline]
            fn is_nan(self) -> bool {
                <$t>::is_nan(self)
            }
            #[inline]
            fn abs(self) -> Self {
                <$t>::from_bits(self.to_bits() & (<$bits>::MAX >> 1))
            }
            #[inline]
            fn exp(self) -> Self {
                $exp(self)
            }
            #[inline]
            fn sqrt(self) -> Self {
                $sqrt(self)
            }
            #[inline]
            fn atan(self) -> Self {
                $atan(self)
            }
            #[inline]
            fn sin(self) -> Self {
                $sin(self)
            }
            #[inline]
            fn cos(self) -> Self {
                $cos(self)
            }
            #[inline]
            fn sinc(self) -> Self {
                $sinc(self)
            }
            #[inline]
            fn exprel(self) -> Self {
                $exprel(self)
            }
        }
    };
}

// 2^-520 for f64 (MAX * 2^-519 squared is ~1e304); 2^-70 for f32.
impl_real!(
    f64,
    u64,
    1.0 / (1u128 << 104) as f64
        / (1u128 << 104) as f64
        / (1u128 << 104) as f64
        / (1u128 << 104) as f64
        / (1u128 << 104) as f64,
    crate::math::exp,
    crate::math::sqrt,
    crate::math::atan,
    crate::math::sin,
    crate::math::cos,
    crate::math::sinc,
    crate::math::exprel
);
impl_real!(
    f32,
    u32,
    1.0 / (1u128 << 70) as f32,
    crate::math::expf,
    crate::math::sqrtf,
    crate::math::atanf,
    crate::math::sinf,
    crate::math::cosf,
    crate::math::sincf,
    crate::math::exprelf
);
