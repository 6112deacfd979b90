//! Watertight ray–triangle intersection (Woop, Benthin, Wald 2013, "Watertight
//! Ray/Triangle Intersection", JCGT 2(1)).
//!
//! The ray is sheared so it runs along +z through the origin; each triangle is then tested
//! with three 2D edge functions that are evaluated identically for the two triangles that
//! share an edge (same operands, same order), so a ray can never slip between them. Edge
//! functions that round to exactly zero are recomputed in f64, where the products of the f32
//! inputs are exact, which settles rays through edges and vertices.
use crate::geometry::Ray;
use glam::Vec3;

/// The per-ray part of the watertight test: the shear that maps the ray onto +z.
#[derive(Clone, Copy, Debug)]
pub struct ShearedRay {
    pub org: Vec3,
    /// Permuted axes: `kz` is the dominant direction axis; `kx`, `ky` keep the winding.
    pub kx: usize,
    pub ky: usize,
    pub kz: usize,
    pub sx: f32,
    pub sy: f32,
    pub sz: f32,
    /// `org` in the order `kx`, `ky`, `kz` (the SIMD filter broadcasts these at every leaf).
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))] // for the x86 kernels
    pub org_k: [f32; 3],
}

impl ShearedRay {
    /// None for a direction that is zero or not finite (such a ray hits nothing).
    #[inline]
    pub fn new(ray: &Ray) -> Option<Self> {
        Self::traceable(ray).then(|| Self::of(ray))
    }

    /// Whether a ray can hit anything: finite origin and a finite, non-zero direction.
    #[inline]
    pub fn traceable(ray: &Ray) -> bool {
        ray.dir.is_finite() && ray.origin.is_finite() && ray.dir != Vec3::ZERO
    }

    /// The shear of a [`traceable`](Self::traceable) ray (callers that test no triangle
    /// never pay for it).
    #[inline(always)]
    pub fn of(ray: &Ray) -> Self {
        let d = ray.dir.to_array();
        let a = ray.dir.abs();
        // kz: x where |x| >= |y| and |x| >= |z|, else y where |y| >= |z|, else z; then kx, ky
        // the next two axes, swapped when d[kz] < 0 (keeps the winding). Chosen by table, not
        // by branches: a random direction mispredicted them about once per ray.
        let x_wins = (a.x >= a.y) & (a.x >= a.z);
        let y_wins = !x_wins & (a.y >= a.z);
        let kz = 2 - 2 * x_wins as usize - y_wins as usize;
        let [kx, ky] = AXES[2 * kz + (d[kz] < 0.0) as usize];
        let o = ray.origin.to_array();
        ShearedRay {
            org: ray.origin,
            kx,
            ky,
            kz,
            sx: d[kx] / d[kz],
            sy: d[ky] / d[kz],
            sz: 1.0 / d[kz],
            org_k: [o[kx], o[ky], o[kz]],
        }
    }
}

/// (kx, ky) for each dominant axis kz (row 2 kz), and with the two swapped (row 2 kz + 1).
const AXES: [[usize; 2]; 6] = [[1, 2], [2, 1], [2, 0], [0, 2], [0, 1], [1, 0]];

/// `tmax` widened by a few ulps for the range checks done before the division (`tt` against
/// `tmax * det`), which round differently from the exact check `t <= tmax` on the divided
/// value: a pre-check that rejected a `t` the exact check accepts would make a tie at the
/// closest hit (a ray through a shared vertex, a range ending on a surface) depend on the
/// order triangles are tested in, and so on the traversal and the instruction set.
#[inline(always)]
pub fn range_end(tmax: f32) -> f32 {
    tmax + tmax.abs() * (8.0 * f32::EPSILON)
}

/// Watertight test of one triangle; returns (t, u, v) with `t` in `[tmin, tmax]` and `u`, `v`
/// the weights of corners 1 and 2. Degenerate (zero-area or edge-on) triangles never hit.
///
/// Always inlined: the BVH calls it from inside its AVX2 context, and an out-of-line copy
/// would be compiled for the baseline instruction set (and cost a call and a `vzeroupper`).
#[inline(always)]
pub fn intersect_sheared(
    r: &ShearedRay,
    tmin: f32,
    tmax: f32,
    p0: Vec3,
    p1: Vec3,
    p2: Vec3,
) -> Option<(f32, f32, f32)> {
    // Arrays, not `Vec3`: indexing a `Vec3` by a run-time axis is a three-way branch.
    let a = (p0 - r.org).to_array();
    let b = (p1 - r.org).to_array();
    let c = (p2 - r.org).to_array();
    let (kx, ky, kz) = (r.kx, r.ky, r.kz);
    let ax = a[kx] - r.sx * a[kz];
    let ay = a[ky] - r.sy * a[kz];
    let bx = b[kx] - r.sx * b[kz];
    let by = b[ky] - r.sy * b[kz];
    let cx = c[kx] - r.sx * c[kz];
    let cy = c[ky] - r.sy * c[kz];
    let mut u = cx * by - cy * bx;
    let mut v = ax * cy - ay * cx;
    let mut w = bx * ay - by * ax;
    if u == 0.0 || v == 0.0 || w == 0.0 {
        // Products of two f32 are exact in f64, so the sign of each edge function is exact.
        let (ax, ay, bx, by, cx, cy) = (ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64);
        u = (cx * by - cy * bx) as f32;
        v = (ax * cy - ay * cx) as f32;
        w = (bx * ay - by * ax) as f32;
    }
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + v + w;
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let az = r.sz * a[kz];
    let bz = r.sz * b[kz];
    let cz = r.sz * c[kz];
    let tt = u * az + v * bz + w * cz;
    // Range check before the division, with the sign of det folded in (no division for misses).
    let (tt_s, det_s) = if det < 0.0 { (-tt, -det) } else { (tt, det) };
    if tt_s < tmin * det_s || tt_s > range_end(tmax) * det_s {
        return None;
    }
    let inv = 1.0 / det;
    let t = tt * inv;
    // The exact check on the value callers will see.
    if !(t >= tmin && t <= tmax) {
        return None;
    }
    // A hit this close could be the rounding of a plane behind the origin (a ray leaving
    // the surface it starts on): reject t within the bound of its own rounding error
    // (pbrt-v3 3.9.6). Ray origins are offset by the hit point's error bound, which puts
    // their own surface strictly behind them, so this is what keeps them off it.
    // That bound grows as 1 / det: for a triangle seen edge-on from far away it exceeds the
    // whole distance, and real hits were lost (a 25.6M-triangle Lucy leaked one primary ray
    // in 55,000 that Embree's robust mode hit). But `t` is a mean of the corners' depths
    // weighted by edge functions of one sign, so a triangle whose every corner lies ahead of
    // the origin by more than the depths' own rounding is in front wherever rounding puts the
    // hit: it is never the surface a ray leaves, and only triangles that reach back to the
    // origin's depth face the bound.
    let (near, far) = (az.min(bz).min(cz), az.abs().max(bz.abs()).max(cz.abs()));
    if near <= crate::geometry::error_bound::gamma(3) * far
        && t <= t_error_bound([ax, bx, cx], [ay, by, cy], [az, bz, cz], [u, v, w], inv, r)
    {
        return None;
    }
    Some((t, v * inv, w * inv))
}

/// pbrt-v3's conservative bound on the rounding error of the `t` computed above from the
/// sheared corners (x, y, z scaled by `sz`), the edge functions `e` and `1 / det`. The shear
/// x - sx z rounds with an error of a few ulps of |x| + |sx z|, with z in world units: pbrt
/// uses the scaled z instead, which mixes units and, for directions far from unit length,
/// rejects real hits (a 1e-4 mesh traced with unnormalised rays) or leaves too little margin.
#[inline(always)]
fn t_error_bound(x: [f32; 3], y: [f32; 3], z: [f32; 3], e: [f32; 3], inv_det: f32, r: &ShearedRay) -> f32 {
    use crate::geometry::error_bound::gamma;
    let amax = |a: [f32; 3]| a[0].abs().max(a[1].abs()).max(a[2].abs());
    let (max_x, max_y, max_z, max_e) = (amax(x), amax(y), amax(z), amax(e));
    let max_z_world = max_z / r.sz.abs();
    let delta_z = gamma(3) * max_z;
    let delta_x = gamma(5) * (max_x + r.sx.abs() * max_z_world);
    let delta_y = gamma(5) * (max_y + r.sy.abs() * max_z_world);
    let delta_e = 2.0 * (gamma(2) * max_x * max_y + delta_y * max_x + delta_x * max_y);
    3.0 * (gamma(3) * max_e * max_z + delta_e * max_z + delta_z * max_e) * inv_det.abs()
}

/// Watertight test of one triangle against a ray (convenience form; precompute
/// [`ShearedRay`] once per ray when testing many triangles).
#[cfg(test)]
pub fn intersect(ray: &Ray, p0: Vec3, p1: Vec3, p2: Vec3) -> Option<(f32, f32, f32)> {
    let r = ShearedRay::new(ray)?;
    intersect_sheared(&r, ray.tmin, ray.tmax, p0, p1, p2)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ray(o: [f32; 3], d: [f32; 3]) -> Ray {
        Ray::new(Vec3::from(o), Vec3::from(d))
    }

    /// A triangle of a 25.6M-triangle Lucy seen nearly edge-on from 2,100 units away (its
    /// projected area is a thousandth of the corners' spread): the rounding bound on t was
    /// larger than t, and the hit was rejected as if the ray were leaving it. An f64
    /// computation puts the hit well inside (weights 0.52, 0.18, 0.29) at t = 2126.6908.
    #[test]
    fn grazing_far_triangles_are_hit() {
        let r = Ray::new(Vec3::new(1998.4636, 1500.2167, 1429.0321), Vec3::new(-0.7249516, -0.3918208, -0.5664995));
        let a = Vec3::new(456.4309, 667.27136, 224.29294);
        let b = Vec3::new(456.81238, 666.6638, 224.17232);
        let c = Vec3::new(456.89792, 667.17206, 224.47525);
        let (t, u, v) = intersect(&r, a, b, c).expect("a hit well inside the triangle");
        assert!((t as f64 - 2126.6908).abs() < 0.01, "t {t}");
        assert!((u - 0.5239).abs() < 0.01 && (v - 0.1819).abs() < 0.01, "u {u} v {v}");
    }

    #[test]
    fn hits_centre_with_barycentrics() {
        let (a, b, c) = (Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0));
        let (t, u, v) = intersect(&ray([0.25, 0.25, 2.0], [0.0, 0.0, -1.0]), a, b, c).unwrap();
        assert_eq!(t, 2.0);
        assert!((u - 0.25).abs() < 1e-6 && (v - 0.25).abs() < 1e-6);
        // Back side, unnormalised direction: t in units of dir.
        let (t, _, _) = intersect(&ray([0.25, 0.25, -2.0], [0.0, 0.0, 4.0]), a, b, c).unwrap();
        assert_eq!(t, 0.5);
    }

    #[test]
    fn misses_outside_and_beyond_range() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        assert!(intersect(&ray([0.6, 0.6, 1.0], [0.0, 0.0, -1.0]), a, b, c).is_none());
        let mut r = ray([0.2, 0.2, 1.0], [0.0, 0.0, -1.0]);
        r.tmax = 0.999;
        assert!(intersect(&r, a, b, c).is_none());
        r.tmax = 1.0;
        assert!(intersect(&r, a, b, c).is_some());
    }

    #[test]
    fn degenerate_triangles_and_rays_never_hit() {
        let r = ray([0.0, 0.0, 1.0], [0.0, 0.0, -1.0]);
        assert!(intersect(&r, Vec3::ZERO, Vec3::ZERO, Vec3::ZERO).is_none());
        assert!(intersect(&r, Vec3::new(-1.0, 0.0, 0.0), Vec3::ZERO, Vec3::X).is_none());
        let zero = ray([0.0, 0.0, 1.0], [0.0, 0.0, 0.0]);
        assert!(intersect(&zero, Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::Y).is_none());
        let nan = ray([0.0, 0.0, 1.0], [f32::NAN, 0.0, -1.0]);
        assert!(intersect(&nan, Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::Y).is_none());
    }

    #[test]
    fn shared_edge_hits_exactly_one_side_or_both() {
        // Two triangles sharing the diagonal of the unit square; rays exactly on the diagonal.
        let (p00, p10, p01, p11) =
            (Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0), Vec3::new(1.0, 1.0, 0.0));
        for i in 1..1000 {
            let s = i as f32 / 1000.0;
            let target = Vec3::new(s, 1.0 - s, 0.0);
            let o = target + Vec3::new(-0.039 * s, 0.021, 3.0);
            let r = Ray::new(o, target - o);
            let h1 = intersect(&r, p10, p01, p00).is_some();
            let h2 = intersect(&r, p10, p11, p01).is_some();
            assert!(h1 || h2, "ray {i} slipped through the shared edge");
        }
    }

    /// A hit at `t` is still a hit when the range ends exactly at `t` (closest-hit searches
    /// shrink `tmax` to the best `t` so far; losing a tie there would make the triangle
    /// reported at a shared vertex depend on the order triangles are tested in).
    #[test]
    fn a_hit_survives_a_range_ending_at_its_own_t() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32 - 0.5
        };
        let mut hits = 0;
        for i in 0..200_000 {
            let scale = [1e-3f32, 1.0, 37.0, 1e4][i % 4];
            let p = |n: &mut dyn FnMut() -> f32| Vec3::new(n(), n(), n()) * scale;
            let (a, b, c) = (p(&mut next), p(&mut next), p(&mut next));
            let o = p(&mut next) * 3.0;
            // Aim at a corner, an edge point or an inside point, with unnormalised directions.
            let target = match i % 3 {
                0 => a,
                1 => a + (b - a) * (next() + 0.5),
                _ => a + (b - a) * 0.3 + (c - a) * 0.3,
            };
            let r = Ray::new(o, (target - o) * (1.0 + next()));
            if let Some((t, _, _)) = intersect(&r, a, b, c) {
                hits += 1;
                let at = Ray { tmax: t, ..r };
                assert!(intersect(&at, a, b, c).is_some(), "{r:?} hit {a} {b} {c} at {t}, not with tmax = t");
            }
        }
        assert!(hits > 100_000, "{hits}");
    }
}
