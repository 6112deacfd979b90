//! Where a ray that leaves a surface starts and where a ray toward a light point stops,
//! from per-point floating-point error bounds (pbrt-v3 3.9, pbrt-v4 6.8).
//!
//! A reconstructed hit point `p` is within `p_error` (per component) of a point on the true
//! surface. Moving `p` along the geometric normal by `dot(|n|, p_error)` puts the whole error
//! box on one side of the surface's tangent plane, and rounding each component of the moved
//! point away from the surface keeps the rounding of that move from undoing it. The offset is
//! thus as small as the point's own error allows: no fixed fraction of |p| that is too small
//! for large triangles and too large for small features far from the origin.

#[cfg(test)]
use super::Ray;
use crate::geometry::error_bound::TIE_SCALE;
use glam::Vec3;

/// Absolute offset added to every error bound before it is used. Bounds are relative to
/// the magnitudes that enter a computation, so a point computed exactly (a vertex at the
/// origin, a sphere centred there) gets a zero bound, and a ray starting exactly on its plane
/// leaves the triangle test nothing but the sign of a rounded zero. 2^-100 (~8e-31) is far
/// above f32's smallest normal (so it survives a multiplication by a unit normal component)
/// and far below any feature size a scene can express next to a non-zero coordinate.
const ERROR_FLOOR: f32 = 7.888_609e-31;

/// The origin of a ray that leaves the surface point `p` (error bound `p_error`, geometric
/// normal `ng`, any orientation) in direction `dir`: on the side of the surface `dir` points
/// to, outside `p`'s error box, so the ray cannot find its own surface again.
#[inline(always)]
pub fn offset_origin(p: Vec3, p_error: Vec3, ng: Vec3, dir: Vec3) -> Vec3 {
    let d = ng.abs().dot(p_error) + ERROR_FLOOR;
    let offset = if ng.dot(dir) < 0.0 { -d * ng } else { d * ng };
    let po = p + offset;
    // `p + offset` rounds to nearest, which may move it back toward the surface by half an
    // ulp; rounding away from it instead keeps the full offset.
    Vec3::new(away(po.x, offset.x), away(po.y, offset.y), away(po.z, offset.z))
}

/// `x` moved one ulp toward the sign of `o` (unchanged when `o` is zero): `next_up` /
/// `next_down` for finite `x`, done on the bits without branches (a finite float's bits
/// ordered by magnitude: one more is one ulp farther from zero, one less one ulp nearer;
/// from either zero the step is the smallest subnormal with `o`'s sign).
#[inline(always)]
pub(crate) fn away(x: f32, o: f32) -> f32 {
    let (xb, ob) = (x.to_bits(), o.to_bits());
    let from_zero = (ob & 0x8000_0000) | 1;
    // Same sign: farther from zero (+1); opposite signs: nearer (-1).
    let step = xb.wrapping_add(1).wrapping_sub(((xb ^ ob) >> 31) << 1);
    let moved = if x == 0.0 { from_zero } else { step };
    f32::from_bits(if o == 0.0 || !x.is_finite() { xb } else { moved })
}

/// Relative shortening of a shadow ray. Its unit direction and length are each a few
/// roundings (~1e-7 relative) away from the exact segment, so its end can drift past the
/// light point by that much of the distance; and the BVH's box tests accept boxes entered up
/// to `tmax * TIE_SCALE` (2^-16 beyond the range, for ties at shared vertices). Four times
/// that margin (2^-14, 6.1e-5) puts the end of the box tests' range short of the light's own
/// surface, so the leaf holding it, which every shadow ray toward the light reaches, fails
/// the box test instead of having its triangles tested (CBbunny: 5.75 -> 3.04 triangle tests
/// per ray over all rays). A blocker within 6.1e-5 of the distance from the light (0.1 mm
/// at 2 m) is not resolvable from the shading point anyway (the CS184 scenes put emissive
/// quads exactly on their area lights).
const SHADOW_SHORTEN: f32 = 4.0 * (TIE_SCALE - 1.0);

/// The `tmax` of a unit-direction shadow ray from `origin` toward the light point `target`
/// (error bound `target_error`): it stops before the light's own surface, so the surface
/// the light point lies on does not occlude it.
#[inline]
pub fn shadow_tmax(origin: Vec3, target: Vec3, target_error: Vec3) -> f32 {
    shadow_tmax_at((target - origin).length(), shadow_margin(target_error))
}

/// What a shadow ray toward a light point with error bound `target_error` stops short of
/// it by, besides the relative shortening: twice the error box's diagonal (the target may
/// lie that far in front of the surface it was sampled on, and the surface's own hit point
/// as far again). Constant per light: computed once per render.
#[inline]
pub fn shadow_margin(target_error: Vec3) -> f32 {
    2.0 * (target_error.length() + ERROR_FLOOR)
}

/// [`shadow_tmax`] from the distance to the target and the light's [`shadow_margin`].
#[inline(always)]
pub fn shadow_tmax_at(dist: f32, margin: f32) -> f32 {
    dist * (1.0 - SHADOW_SHORTEN) - margin
}

/// The shadow ray from `origin` (already offset) along `dir`, or, for a light point
/// `target` (with its error bound), aimed from `origin` itself at the target: a direction
/// computed from the surface point before the offset runs parallel to the true segment,
/// `offset / cos` too far, and can reach the light's surface before its `tmax`. `None`
/// when the origin is already at the light.
#[cfg(test)]
pub fn shadow_ray(origin: Vec3, dir: Vec3, target: Option<(Vec3, Vec3)>) -> Option<Ray> {
    let Some((q, q_error)) = target else {
        return Some(Ray { origin, dir, tmin: 0.0, tmax: f32::INFINITY });
    };
    let dir = (q - origin).try_normalize()?;
    let tmax = shadow_tmax(origin, q, q_error);
    (tmax > 0.0).then_some(Ray { origin, dir, tmin: 0.0, tmax })
}

#[cfg(test)]
mod tests {
    use super::away;

    /// The bit-level step is std's `next_up` / `next_down` on every finite value, including
    /// zeros, subnormals and the largest finite numbers.
    #[test]
    fn away_matches_next_up_and_down() {
        let mut xs = vec![0.0f32, -0.0, f32::MIN_POSITIVE, -f32::MIN_POSITIVE, f32::MAX, -f32::MAX, 1.0, -1.0];
        xs.extend([f32::from_bits(1), f32::from_bits(0x8000_0001), 1e-40, -3e-39, 0.3, -552.25]);
        let mut h = 0x1234_5678u32;
        for _ in 0..10_000 {
            h = h.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
            let x = f32::from_bits(h);
            if x.is_finite() {
                xs.push(x);
            }
        }
        for &x in &xs {
            for o in [1e-30f32, 2.0, -1e-30, -0.5] {
                let want = if o > 0.0 { x.next_up() } else { x.next_down() };
                assert_eq!(away(x, o).to_bits(), want.to_bits(), "x {x:e} o {o}");
            }
            assert_eq!(away(x, 0.0).to_bits(), x.to_bits());
            assert_eq!(away(x, -0.0).to_bits(), x.to_bits());
        }
    }
}
