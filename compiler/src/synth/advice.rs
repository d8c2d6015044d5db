//! Values advised to the user: short to write, and never beyond what was
//! certified (rounded toward the certified side, then re-solved by the caller).

/// `k * 10^e`, parsed from its decimal spelling (so it prints short).
fn decimal(k: i64, e: i32) -> f64 {
    format!("{k}e{e}").parse().unwrap_or(f64::NAN)
}

/// A duration or rate in an advice, four decimals (`0.0123`), or four
/// significant digits in exponent form below 1e-3 (`1.034e-5`, never `0.0000`).
pub fn about(x: f64) -> String {
    if x.abs() >= 1e-3 || x == 0.0 {
        format!("{x:.4}")
    } else {
        format!("{x:.3e}")
    }
}

/// The value nearest `x` on the side of `target` (between them, `x`
/// included) with three significant digits; `x` itself when it is 0, not
/// finite, or already `target`.
pub fn round_toward(x: f64, target: f64) -> f64 {
    if !x.is_finite() || x == 0.0 || x == target {
        return x;
    }
    let e = x.abs().log10().floor() as i32 - 2;
    let scaled = x / 10f64.powi(e);
    let k = if target > x {
        scaled.ceil()
    } else {
        scaled.floor()
    } as i64;
    let v = decimal(k, e);
    // Never past the target (a narrowing stays around it).
    if (target > x && v > target) || (target < x && v < target) {
        target
    } else {
        v
    }
}

/// The largest value `<= x` with three significant digits.
pub fn round_down(x: f64) -> f64 {
    if !(x.is_finite() && x > 0.0) {
        return x;
    }
    let e = x.log10().floor() as i32 - 2;
    let mut k = (x / 10f64.powi(e)).floor() as i64;
    while k > 0 && decimal(k, e) > x {
        k -= 1;
    }
    decimal(k, e)
}

/// The smallest value `>= x` with three significant digits.
pub fn round_up(x: f64) -> f64 {
    if !(x.is_finite() && x > 0.0) {
        return x;
    }
    let e = x.log10().floor() as i32 - 2;
    let mut k = (x / 10f64.powi(e)).ceil() as i64;
    while decimal(k, e) < x {
        k += 1;
    }
    decimal(k, e)
}

#[cfg(test)]
mod tests {
    #[test]
    fn tiny_intervals_are_not_printed_as_zero() {
        assert_eq!(super::about(0.01234), "0.0123");
        assert_eq!(super::about(1.0341e-5), "1.034e-5");
        assert_eq!(super::about(0.0), "0.0000");
    }

    use super::{round_down, round_toward, round_up};

    #[test]
    fn round_toward_stays_between_the_value_and_the_target() {
        for (x, t) in [
            (0.540302, 1.0),
            (-1.23456, 0.0),
            (1.98765, 0.0),
            (0.77, 1.0),
            (-2.0, 0.0),
        ] {
            let r = round_toward(x, t);
            assert!(
                (x..=t).contains(&r) || (t..=x).contains(&r),
                "{x} -> {t}: {r}"
            );
            assert!((r - x).abs() <= 0.01 * x.abs(), "{x}: {r}");
        }
        assert_eq!(round_toward(0.540302, 1.0), 0.541);
        assert_eq!(round_toward(-1.23456, 0.0), -1.23);
    }

    #[test]
    fn round_down_never_rounds_up_and_prints_short() {
        for x in [0.0009, 0.000_937_5, 1.5, 0.123_456, 9.999_9, 1e-7 * 3.3333] {
            let r = round_down(x);
            assert!(r <= x && r > 0.98 * x, "{x} -> {r}");
            assert!(format!("{r}").len() <= 12, "{x} -> {r}");
        }
        assert_eq!(round_down(0.123_456), 0.123);
        assert_eq!(round_down(0.099_999_9), 0.0999);
    }

    #[test]
    fn round_up_never_rounds_down_and_prints_short() {
        for x in [
            42.258_042,
            0.000_937_5,
            1.5,
            0.123_456,
            9.999_9,
            330.047_301,
        ] {
            let r = round_up(x);
            assert!(r >= x && r < 1.02 * x, "{x} -> {r}");
            assert!(format!("{r}").len() <= 12, "{x} -> {r}");
        }
        assert_eq!(round_up(42.258_042), 42.3);
    }
}
