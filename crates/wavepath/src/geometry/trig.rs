//! Trigonometry in plain `f32` arithmetic (multiplies, adds, `sqrt` and selects): a loop over
//! SIMD lanes that calls these vectorises, where the C library's `sinf`/`acosf`/`atan2f` are
//! calls made one lane at a time, and every instruction set gives the same bits (no fused
//! multiply-add, correctly rounded `sqrt`), so one lane and sixteen agree by construction.
//!
//! The polynomials are Cephes' single-precision minimax fits (`sinf.c`, `asinf.c`,
//! `atanf.c`): absolute error below 2e-7 on the ranges used here, which is far below what the
//! environment map's texels resolve (the only user, where an angle picks a texel).

// The coefficients as Cephes publishes them (some carry digits an f32 rounds away).
#![allow(clippy::excessive_precision)]

use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// `(sin, cos)` of the angle `turns * 2 pi` for `turns` in [0, 1] (a fraction of a full turn,
/// as image coordinates are): the argument is reduced exactly by quarter turns, then both
/// polynomials run on [-pi/4, pi/4] and the quadrant picks and signs them.
#[inline(always)]
pub fn sin_cos_turns(turns: f32) -> (f32, f32) {
    // Round to the nearest quarter by truncation (turns >= 0): plain SSE2, no rounding call.
    let quadrant = (turns * 4.0 + 0.5) as i32;
    let x = (turns - quadrant as f32 * 0.25) * (2.0 * PI);
    let z = x * x;
    let s = ((-1.951_529_6e-4 * z + 8.332_161e-3) * z - 1.666_665_5e-1) * z * x + x;
    let c = ((2.443_315_7e-5 * z - 1.388_731_6e-3) * z + 4.166_664_6e-2) * z * z - 0.5 * z + 1.0;
    // Quadrants 0..=4 (4 is a full turn, as 0): (s, c), (c, -s), (-s, -c), (-c, s), as selects.
    let (a, b) = if quadrant & 1 != 0 { (c, s) } else { (s, c) };
    let sin = if quadrant & 2 != 0 { -a } else { a };
    let cos = if (quadrant + 1) & 2 != 0 { -b } else { b };
    (sin, cos)
}

/// `asin(x)` for `x` in [0, 0.5] (Cephes' polynomial), the core of [`acos`].
#[inline(always)]
fn asin_small(x: f32) -> f32 {
    let z = x * x;
    ((((4.216_32e-2 * z + 2.418_131_1e-2) * z + 4.547_002_6e-2) * z + 7.495_300_3e-2) * z + 1.666_675_2e-1) * z * x + x
}

/// `acos(x)` in [0, pi] for `x` in [-1, 1] (clamped): near +-1 through the half-angle form
/// `2 asin(sqrt((1 - |x|) / 2))`, which keeps the relative accuracy where the angle is small.
#[inline(always)]
pub fn acos(x: f32) -> f32 {
    let x = x.clamp(-1.0, 1.0);
    let a = x.abs();
    let middle = FRAC_PI_2 - asin_small(x.abs().min(0.5)).copysign(x);
    let half = 2.0 * asin_small(((1.0 - a) * 0.5).sqrt());
    let outer = if x < 0.0 { PI - half } else { half };
    if a > 0.5 { outer } else { middle }
}

/// `atan2(y, x)` in [-pi, pi] (0 for the origin): the ratio of the smaller to the larger
/// magnitude in [0, 1], reduced once more about tan(pi/8), then the octant's reflections.
#[inline(always)]
pub fn atan2(y: f32, x: f32) -> f32 {
    let (ax, ay) = (x.abs(), y.abs());
    let (lo, hi) = (ax.min(ay), ax.max(ay));
    let t = if hi > 0.0 { lo / hi } else { 0.0 };
    // tan(pi/8): above it, atan(t) = pi/4 + atan((t - 1) / (t + 1)).
    let reduce = t > 0.414_213_57;
    let r = if reduce { (t - 1.0) / (t + 1.0) } else { t };
    let z = r * r;
    let p = (((8.053_744_5e-2 * z - 1.387_768_6e-1) * z + 1.997_771_1e-1) * z - 3.333_295e-1) * z * r + r;
    let a = if reduce { FRAC_PI_4 + p } else { p };
    let a = if ay > ax { FRAC_PI_2 - a } else { a };
    let a = if x < 0.0 { PI - a } else { a };
    a.copysign(y)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against the C library (f64) on a dense grid of each function's whole range.
    #[test]
    fn agree_with_the_c_library() {
        let n = 200_000;
        let (mut es, mut ec, mut ea, mut et) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for i in 0..=n {
            let f = i as f32 / n as f32;
            let (s, c) = sin_cos_turns(f);
            let a = f as f64 * std::f64::consts::TAU;
            es = es.max((s as f64 - a.sin()).abs());
            ec = ec.max((c as f64 - a.cos()).abs());
            let x = 2.0 * f - 1.0;
            ea = ea.max((acos(x) as f64 - (x as f64).acos()).abs());
            let (y, xx) = (a.sin() as f32 * 3.0, a.cos() as f32 * 3.0);
            et = et.max((atan2(y, xx) as f64 - (y as f64).atan2(xx as f64)).abs());
        }
        assert!(es < 3e-7 && ec < 3e-7, "sin {es}, cos {ec}");
        assert!(ea < 5e-7, "acos {ea}");
        assert!(et < 5e-7, "atan2 {et}");
    }

    /// The edges: exact quarter turns, +-1 and beyond for acos, the axes and the origin for
    /// atan2 (with the sign of zero the C library gives).
    #[test]
    fn edges() {
        assert_eq!(sin_cos_turns(0.0), (0.0, 1.0));
        assert_eq!(sin_cos_turns(0.25), (1.0, 0.0));
        assert_eq!(sin_cos_turns(0.5).1, -1.0);
        assert_eq!(sin_cos_turns(1.0), (0.0, 1.0));
        assert_eq!(acos(1.0), 0.0);
        assert_eq!(acos(2.0), 0.0);
        assert!((acos(-1.0) - PI).abs() < 1e-6 && acos(-3.0) == acos(-1.0));
        assert!((acos(0.0) - FRAC_PI_2).abs() < 1e-7);
        assert_eq!(atan2(0.0, 0.0), 0.0);
        assert_eq!(atan2(0.0, 1.0), 0.0);
        assert!((atan2(0.0, -1.0) - PI).abs() < 1e-6);
        assert!((atan2(-0.0, -1.0) + PI).abs() < 1e-6);
        assert!((atan2(1.0, 0.0) - FRAC_PI_2).abs() < 1e-7);
        assert!((atan2(-1.0, 0.0) + FRAC_PI_2).abs() < 1e-7);
        for v in [0.0f32, 1e-30, 1e30] {
            assert!(atan2(v, v).is_finite() && acos(v).is_finite());
        }
    }
}
