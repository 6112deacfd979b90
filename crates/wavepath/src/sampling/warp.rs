//! Warps from the unit square to directions and points, each with its density.

use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, PI, TAU};

/// Cosine-weighted direction about +Z (Malley's method on the concentric disk); pdf = z / pi.
#[inline(always)]
pub fn cosine_hemisphere(u: f32, v: f32) -> Vec3 {
    let d = concentric_disk(u, v);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

#[inline(always)]
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * FRAC_1_PI
}

/// Uniform direction about +Z; pdf = 1 / (2 pi).
#[inline]
pub fn uniform_hemisphere(u: f32, v: f32) -> Vec3 {
    uniform_hemisphere_at(u, (TAU * v).sin_cos())
}

/// [`uniform_hemisphere`] from `u` and the sine and cosine of its azimuth `2 pi v` (made
/// apart: a lane kernel makes them one lane at a time, the rest in its loops).
#[inline(always)]
pub fn uniform_hemisphere_at(u: f32, (sin, cos): (f32, f32)) -> Vec3 {
    let z = u;
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(r * cos, r * sin, z)
}

pub const UNIFORM_HEMISPHERE_PDF: f32 = 1.0 / TAU;

/// Shirley–Chiu concentric map from [0,1)^2 to the unit disk (area preserving, low distortion).
/// Branch-free (selects only) so that a loop over lanes vectorises; the angle is always
/// pi/4 times a ratio in [-1, 1], so [`sin_cos_quarter`] replaces `sin`/`cos`.
#[inline(always)]
pub fn concentric_disk(u: f32, v: f32) -> Vec2 {
    let a = 2.0 * u - 1.0;
    let b = 2.0 * v - 1.0;
    let wide = a.abs() > b.abs();
    let (r, num) = if wide { (a, b) } else { (b, a) };
    // r is the larger magnitude: zero only at the centre, which maps to the centre.
    let ratio = if r == 0.0 { 0.0 } else { num / r };
    let (s, c) = sin_cos_quarter(PI / 4.0 * ratio);
    // Narrow case: theta = pi/2 - x, so cos(theta) = sin(x) and sin(theta) = cos(x).
    let (x, y) = if wide { (c, s) } else { (s, c) };
    Vec2::new(r * x, r * y)
}

/// `(sin x, cos x)` for |x| <= pi/4, from the minimax polynomials of Cephes' `sinf`/`cosf`
/// (errors within about one ulp of the correctly rounded values; no range reduction, no
/// branches, so it vectorises).
#[inline(always)]
pub fn sin_cos_quarter(x: f32) -> (f32, f32) {
    let z = x * x;
    let s = ((-1.951_529_6e-4 * z + 8.332_161e-3) * z - 1.666_665_5e-1) * z * x + x;
    let c = ((2.443_315_7e-5 * z - 1.388_731_6e-3) * z + 4.166_664_6e-2) * z * z - 0.5 * z + 1.0;
    (s, c)
}

/// Uniform barycentric coordinates (weights of corners 1 and 2) on a triangle.
#[inline]
pub fn uniform_triangle(u: f32, v: f32) -> (f32, f32) {
    let su = u.sqrt();
    (su * (1.0 - v), su * v)
}

/// An orthonormal frame whose third axis is `n` (Duff et al. 2017, branch-free).
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub t: Vec3,
    pub b: Vec3,
    pub n: Vec3,
}

impl Frame {
    #[inline(always)]
    pub fn new(n: Vec3) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let bb = n.x * n.y * a;
        let t = Vec3::new(1.0 + sign * n.x * n.x * a, sign * bb, -sign * n.x);
        let b = Vec3::new(bb, sign + n.y * n.y * a, -n.y);
        Frame { t, b, n }
    }

    #[inline(always)]
    pub fn to_world(self, v: Vec3) -> Vec3 {
        self.t * v.x + self.b * v.y + self.n * v.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Sampler;

    #[test]
    fn cosine_hemisphere_has_the_right_moments() {
        // For pdf cos/pi: E[z] = 2/3, E[z^2] = 1/2, and x, y average to zero.
        let mut s = Sampler::for_sample(7, 0, 0);
        let n = 200_000;
        let (mut ez, mut ez2, mut ex) = (0.0f64, 0.0f64, 0.0f64);
        for _ in 0..n {
            let (u, v) = s.next_2d();
            let d = cosine_hemisphere(u, v);
            assert!((d.length() - 1.0).abs() < 1e-4 && d.z >= 0.0);
            ez += d.z as f64;
            ez2 += (d.z * d.z) as f64;
            ex += d.x as f64;
        }
        let n = n as f64;
        assert!((ez / n - 2.0 / 3.0).abs() < 0.003, "{}", ez / n);
        assert!((ez2 / n - 0.5).abs() < 0.003);
        assert!((ex / n).abs() < 0.004);
    }

    #[test]
    fn uniform_hemisphere_has_the_right_moments() {
        // Uniform on the hemisphere: z is U(0,1).
        let mut s = Sampler::for_sample(8, 0, 0);
        let n = 200_000;
        let mut ez2 = 0.0f64;
        for _ in 0..n {
            let (u, v) = s.next_2d();
            let d = uniform_hemisphere(u, v);
            assert!((d.length() - 1.0).abs() < 1e-4);
            ez2 += (d.z * d.z) as f64;
        }
        assert!((ez2 / n as f64 - 1.0 / 3.0).abs() < 0.003);
    }

    #[test]
    fn sin_cos_quarter_matches_std() {
        let n = 100_000;
        for i in 0..=n {
            let x = std::f32::consts::FRAC_PI_4 * (2.0 * i as f32 / n as f32 - 1.0);
            let (s, c) = sin_cos_quarter(x);
            let (es, ec) = ((x as f64).sin(), (x as f64).cos());
            // One ulp of numbers below 1 is at most 6e-8.
            assert!((s as f64 - es).abs() <= 1.2e-7 && (c as f64 - ec).abs() <= 1.2e-7, "{x}: {s} {c}");
        }
    }

    #[test]
    fn frame_is_orthonormal() {
        for n in [Vec3::Z, -Vec3::Z, Vec3::X, Vec3::new(0.3, -0.8, 0.2).normalize()] {
            let f = Frame::new(n);
            assert!(f.t.dot(f.b).abs() < 1e-5 && f.t.dot(n).abs() < 1e-5 && f.b.dot(n).abs() < 1e-5);
            assert!((f.t.cross(f.b) - n).length() < 1e-5);
        }
    }

    #[test]
    fn disk_and_triangle_stay_inside() {
        let mut s = Sampler::for_sample(9, 0, 0);
        let mut r2 = 0.0f64;
        let n = 100_000;
        for _ in 0..n {
            let (u, v) = s.next_2d();
            let d = concentric_disk(u, v);
            assert!(d.length() <= 1.0 + 1e-6);
            r2 += d.length_squared() as f64;
            let (a, b) = uniform_triangle(u, v);
            assert!(a >= 0.0 && b >= 0.0 && a + b <= 1.0 + 1e-6);
        }
        // Uniform on the disk: E[r^2] = 1/2.
        assert!((r2 / n as f64 - 0.5).abs() < 0.004);
    }
}
