//! Elementary functions in f32 without a branch or a library call, so that the lane
//! kernels' loops over the models that use them vectorise (a call to `expf` or `powf` keeps
//! a loop scalar). The one-path code calls the same functions, so both give the same bits.

/// e^x in f32 without a branch or a library call (Cephes' `expf`: x = n ln 2 + r with
/// |r| <= ln 2 / 2, a degree-5 polynomial for e^r, 2^n from the exponent bits), so that the
/// loops that evaluate Beckmann's D vectorise; within 2 ulp of e^x. Below -87.3 (where e^x
/// leaves the normal numbers) it is 0, above 88 it stays at e^88; a NaN gives e^-87.3.
#[inline(always)]
pub fn exp(x: f32) -> f32 {
    const ROUND: f32 = 12_582_912.0; // 1.5 * 2^23: adding and subtracting it rounds to an integer
    let underflow = x < -87.3;
    // Not `clamp`, which keeps a NaN.
    #[allow(clippy::manual_clamp)]
    let x = x.max(-87.3).min(88.0);
    let n = (x * std::f32::consts::LOG2_E + ROUND) - ROUND;
    let r = x - n * 0.693_359_4 - n * -2.121_944_4e-4;
    let p = ((((1.987_569_1e-4 * r + 1.398_199_9e-3) * r + 8.333_452e-3) * r + 4.166_579_6e-2) * r + 0.166_666_65) * r
        + 0.5;
    let e = (p * (r * r) + r + 1.0) * f32::from_bits(((n as i32 + 127) as u32) << 23);
    if underflow { 0.0 } else { e }
}

/// ln x in f32 without a branch or a library call (Cephes' `logf`: x = m 2^e with m in
/// [sqrt(1/2), sqrt(2)), a degree-9 polynomial in m - 1, e ln 2 in two parts). Within 2 ulp
/// of ln x for normal and subnormal x; ln 0 = -inf, ln inf = inf, and NaN for x < 0 or NaN.
#[inline(always)]
pub fn ln(x: f32) -> f32 {
    const SQRT_HALF: f32 = std::f32::consts::FRAC_1_SQRT_2;
    // Subnormals scaled into the normal range first (by 2^23).
    let tiny = x < f32::MIN_POSITIVE;
    let scaled = if tiny { x * 8_388_608.0 } else { x };
    let bits = scaled.to_bits();
    let e = ((bits >> 23) & 0xff) as i32 - 126 - if tiny { 23 } else { 0 };
    // The mantissa in [0.5, 1).
    let m = f32::from_bits((bits & 0x007f_ffff) | 0x3f00_0000);
    let small = m < SQRT_HALF;
    let e = (e - small as i32) as f32;
    let m = if small { m + m - 1.0 } else { m - 1.0 };
    let z = m * m;
    let p = ((((((((7.037_683_6e-2 * m - 1.151_461_1e-1) * m + 1.167_699_9e-1) * m - 1.242_014_1e-1) * m
        + 1.424_932_3e-1)
        * m
        - 1.666_805_8e-1)
        * m
        + 2.000_071_5e-1)
        * m
        - 2.499_999_4e-1)
        * m
        + 3.333_333e-1)
        * m
        * z;
    let y = p + -2.121_944_4e-4 * e - 0.5 * z;
    let r = (m + y) + 0.693_359_4 * e;
    let r = if x == f32::INFINITY { x } else { r };
    let r = if x == 0.0 { f32::NEG_INFINITY } else { r };
    if x < 0.0 || x.is_nan() { f32::NAN } else { r }
}

/// x^y for x >= 0 and y > 0, as e^(y ln x) through [`exp`] and [`ln`]: 0^y = 0. Its
/// relative error grows with |y ln x| (the exponent's own rounding): about
/// (|y ln x| + 4) 2^-23, so 1e-5 at most where the result is a normal number.
#[inline(always)]
pub fn pow(x: f32, y: f32) -> f32 {
    exp(y * ln(x))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The branch-free e^x against f64's, relative error within 2 ulp over the whole range
    /// Beckmann's D uses (and beyond), exact at 0, and 0 below the normal numbers.
    #[test]
    fn exp_is_within_two_ulp() {
        let mut worst = 0.0f64;
        for i in 0..=2_000_000 {
            let x = -87.0 + 175.0 * i as f32 / 2_000_000.0;
            let want = (x as f64).exp();
            let err = ((exp(x) as f64 - want) / want).abs();
            worst = worst.max(err);
        }
        assert!(worst < 2.0 * f32::EPSILON as f64, "worst relative error {worst:e}");
        assert_eq!(exp(0.0), 1.0);
        assert_eq!(exp(-100.0), 0.0);
        assert_eq!(exp(f32::NEG_INFINITY), 0.0);
        assert!(exp(f32::NAN).is_finite());
        assert!(exp(200.0).is_finite() && exp(200.0) > 1e38);
    }

    /// ln against f64's over the normal and subnormal numbers (a geometric sweep), within
    /// 2 ulp of the result, or 2^-24 absolute next to 1 (where ln x -> 0 and the result's ulp
    /// is smaller than the input's); the special values as `f32::ln` gives them.
    #[test]
    fn ln_is_within_two_ulp() {
        let mut worst = 0.0f64;
        let n = 2_000_000;
        for i in 0..=n {
            let x = (2f64.powf(-149.0 + 277.0 * i as f64 / n as f64)) as f32;
            let want = (x as f64).ln();
            let got = ln(x) as f64;
            let err = (got - want).abs() / (want.abs() * f32::EPSILON as f64).max(f32::EPSILON as f64 / 2.0);
            worst = worst.max(err);
        }
        for x in [1.0f32, 1.0 + f32::EPSILON, 1.0 - f32::EPSILON / 2.0, 0.75, 1.4, 2.0, 0.5] {
            let err = (ln(x) as f64 - (x as f64).ln()).abs() / f32::EPSILON as f64;
            worst = worst.max(err);
        }
        assert!(worst <= 2.0, "worst error {worst} ulp");
        assert_eq!(ln(1.0), 0.0);
        assert_eq!(ln(0.0), f32::NEG_INFINITY);
        assert_eq!(ln(f32::INFINITY), f32::INFINITY);
        assert!(ln(-1.0).is_nan() && ln(f32::NAN).is_nan() && ln(-0.0).is_infinite());
    }

    /// pow against f64's over the sheen's range (x in (0, 1], y in [0.5, 500]), within the
    /// documented bound wherever the result is a normal number; 0^y = 0.
    #[test]
    fn pow_is_within_its_bound() {
        let mut checked = 0;
        for i in 1..=2000 {
            let x = i as f32 / 2000.0;
            for k in 0..=200 {
                let y = 0.5 * 1000f32.powf(k as f32 / 200.0);
                let want = (x as f64).powf(y as f64);
                if want < f32::MIN_POSITIVE as f64 * 4.0 {
                    continue;
                }
                let bound = ((y * x.ln()).abs() as f64 + 4.0) * f32::EPSILON as f64;
                let err = ((pow(x, y) as f64 - want) / want).abs();
                assert!(err <= bound, "pow({x}, {y}): relative error {err:e} > {bound:e}");
                checked += 1;
            }
        }
        assert!(checked > 100_000, "{checked}");
        assert_eq!(pow(0.0, 0.5), 0.0);
        assert_eq!(pow(1.0, 300.0), 1.0);
    }
}
