//! The ray–box slab test for the eight children of a node, shared by every instruction set.
//!
//! Robustness (Ize 2013, "Robust BVH Ray Traversal"): distances are `(plane - origin) * inv`
//! (one rounding each, so relative error <= 3 ulp) and the exit distance is widened by
//! `1 + 2 gamma(3)`, so a box the ray touches is never rejected by rounding. The inverse
//! direction is never infinite: a zero (or tiny) component becomes +-f32::MAX with the
//! component's sign (so -0 and +0 give opposite signs), and `0 * MAX = 0` where `0 * inf`
//! would give NaN. Near and far planes are picked per axis by the sign of the direction, so
//! each lane needs no min/max between the two planes and an empty slot (lo = +inf,
//! hi = -inf) always gets entry +inf, exit -inf.
use crate::accel::bvh::tree::{Node8, Tri4, octant};
use crate::accel::triangle::ShearedRay;
use crate::geometry::Ray;
pub use crate::geometry::error_bound::TIE_SCALE;

/// 1 + 2 gamma(3) with gamma(n) = n u / (1 - n u), u = 2^-24, rounded up.
pub const EXIT_SCALE: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5) + f32::EPSILON;

/// Bytes a prefetch asks for: a whole node (a leaf block is 192 of them).
pub const PREFETCH_BYTES: usize = std::mem::size_of::<Node8>();
const _: () = assert!(PREFETCH_BYTES >= std::mem::size_of::<Tri4>());

/// Index into `Node8::b` of the near plane on `axis` for rays of octant `oct` (below 6 for
/// any `oct`, as the SIMD kernels index node planes with it unchecked).
#[inline(always)]
pub const fn near(oct: u32, axis: usize) -> usize {
    2 * (axis % 3) + (oct >> axis & 1) as usize
}

/// Index into `Node8::b` of the far plane on `axis` (see [`near`]).
#[inline(always)]
pub const fn far(oct: u32, axis: usize) -> usize {
    2 * (axis % 3) + 1 - (oct >> axis & 1) as usize
}

/// Per-ray values for the box test. The layout is fixed (two 32-byte halves) so the AVX2
/// set-up (`x86::setup::box_ray8`) writes each half with one store.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct BoxRay {
    pub org: [f32; 3],
    pub inv: [f32; 3],
    pub tmin: f32,
    /// Direction octant ([`octant`]): picks the near and far planes and the visiting order.
    pub octant: u32,
    /// `origin * inv` per axis, rounded up (near) and down (far) by more than its own rounding
    /// error, for the fused form `fma(plane, inv, -oi)` of the slab distance (see [`fma_terms`]).
    pub oi_near: [f32; 3],
    pub oi_far: [f32; 3],
    /// Whether every `oi` term is finite (else the kernels use the unfused form).
    pub fma: bool,
    /// Whether the ray can hit anything at all (finite origin, finite non-zero direction,
    /// ordered non-NaN range).
    pub live: bool,
    /// Byte offsets in `Node8::b` of the near planes (x, y, z) and then the far planes of
    /// the octant: `PLANES[octant]`, always. Set up with the ray, so the node loop does not
    /// recompute the plane indices at every node (the SIMD kernels load at these offsets
    /// unchecked: each is `32 * plane` with plane < 6).
    pub planes: [u8; 6],
}

/// [`BoxRay::planes`] of each octant.
pub const PLANES: [[u8; 6]; 8] = {
    let mut t = [[0u8; 6]; 8];
    let mut oct = 0;
    while oct < 8 {
        let mut axis = 0;
        while axis < 3 {
            t[oct][axis] = (32 * near(oct as u32, axis)) as u8;
            t[oct][axis + 3] = (32 * far(oct as u32, axis)) as u8;
            axis += 1;
        }
        oct += 1;
    }
    t
};

/// Safe reciprocal: `1 / d`, or `+-f32::MAX` with the sign of `d` where that is not finite.
#[inline(always)]
fn safe_inv(d: f32) -> f32 {
    let i = 1.0 / d;
    if i.is_finite() { i } else { f32::MAX.copysign(d) }
}

/// The fused slab distance `fma(plane, inv, -oi)` rounds once, after subtracting a rounded
/// `oi = origin * inv`; that product's error is absolute (a few ulps of |oi|), not relative to
/// the distance, so the near term is moved up and the far term down by 2^-20 |oi| (16 ulps,
/// which also covers the rounding of these sums) plus the smallest normal float (denormal
/// products). Then the fused near distance is never above, and the far one never below, the
/// unfused `(plane - origin) * inv` up to the final rounding, which [`EXIT_SCALE`] covers as
/// it does for the unfused form (two roundings instead of three).
#[inline(always)]
fn fma_terms(o: f32, inv: f32) -> (f32, f32) {
    let oi = o * inv;
    let e = oi.abs() * (1.0 / 1048576.0) + f32::MIN_POSITIVE;
    (oi + e, oi - e)
}

impl BoxRay {
    /// A ray that hits nothing (filler for set-up buffers).
    pub const DEAD: BoxRay = BoxRay {
        org: [0.0; 3],
        inv: [0.0; 3],
        tmin: 0.0,
        oi_near: [0.0; 3],
        oi_far: [0.0; 3],
        fma: false,
        octant: 0,
        live: false,
        planes: PLANES[0],
    };

    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        let (o, d) = (ray.origin, ray.dir);
        let inv = [safe_inv(d.x), safe_inv(d.y), safe_inv(d.z)];
        let (nx, fx) = fma_terms(o.x, inv[0]);
        let (ny, fy) = fma_terms(o.y, inv[1]);
        let (nz, fz) = fma_terms(o.z, inv[2]);
        let octant = octant([d.x, d.y, d.z]);
        BoxRay {
            org: [o.x, o.y, o.z],
            inv,
            tmin: ray.tmin,
            oi_near: [nx, ny, nz],
            oi_far: [fx, fy, fz],
            fma: [nx, ny, nz, fx, fy, fz].iter().all(|t| t.is_finite()),
            octant,
            live: ShearedRay::traceable(ray) && !ray.tmin.is_nan() && !ray.tmax.is_nan() && ray.tmin <= ray.tmax,
            planes: PLANES[octant as usize & 7],
        }
    }
}

/// A box the batched traversal tests each ray against before its traversal (the root's
/// bounds, widened): most primary rays miss the whole tree, and this costs them about a
/// quarter of a node test plus the traversal's entry and exit.
#[derive(Clone, Copy, Debug)]
pub struct RootBox {
    pub lo: [f32; 3],
    pub hi: [f32; 3],
}

impl RootBox {
    /// `[lo, hi]` widened by 2^-10 of its largest extent plus 2^-16 of its largest
    /// coordinate, so a ray any child test could accept (they round differently, fused or
    /// not) always enters it; None for a box that is empty or not finite (no quick test).
    pub fn new(lo: glam::Vec3, hi: glam::Vec3) -> Option<RootBox> {
        if !(lo.is_finite() && hi.is_finite() && lo.cmple(hi).all()) {
            return None;
        }
        let m = (hi - lo).max_element() * (1.0 / 1024.0) + lo.abs().max(hi.abs()).max_element() * (1.0 / 65536.0);
        let (lo, hi) = (lo - glam::Vec3::splat(m), hi + glam::Vec3::splat(m));
        (lo.is_finite() && hi.is_finite()).then_some(RootBox { lo: lo.to_array(), hi: hi.to_array() })
    }

    /// Whether ray `r` (box-test values, and its `tmax`) may enter the box: the slab test of
    /// the nodes in its unfused form (no NaN for a live ray: `inv` is finite and non-zero,
    /// so min and max are exact and any order of them gives the same answer).
    #[inline(always)]
    pub fn admits(&self, r: &BoxRay, tmax: f32) -> bool {
        let (mut enter, mut exit) = (r.tmin, f32::INFINITY);
        for axis in 0..3 {
            let a = (self.lo[axis] - r.org[axis]) * r.inv[axis];
            let b = (self.hi[axis] - r.org[axis]) * r.inv[axis];
            enter = enter.max(a.min(b));
            exit = exit.min(a.max(b));
        }
        enter <= (exit * EXIT_SCALE).min(tmax * TIE_SCALE)
    }
}

/// The box-test bounds of a packet of rays that leave one point with directions in one
/// octant (the coherent packets of the traversal): each axis's reciprocal direction as an interval.
/// A ray's unfused slab distance is `fl(fl(plane - origin) * inv)`; with the origin shared,
/// `plane - origin` is one value for the whole packet, and a rounded product is monotone in
/// each factor, so the distances at the interval's ends bound every ray's own, exactly. The
/// packet therefore enters every box any of its rays' unfused tests enters (tested against
/// per-ray tests in the coherent traversal).
#[derive(Clone, Copy, Debug)]
pub struct Frustum {
    pub org: [f32; 3],
    pub inv_lo: [f32; 3],
    pub inv_hi: [f32; 3],
    /// The smallest `tmin` of the packet.
    pub tmin: f32,
    pub octant: u32,
    /// [`BoxRay::planes`] of the octant.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))] // for the x86 kernels
    pub planes: [u8; 6],
}

impl Frustum {
    /// The bounds of `rays` (live, at least one, one origin and one octant: see
    /// [`Frustum::joins`]).
    #[inline(always)]
    pub fn of<'a>(rays: impl IntoIterator<Item = &'a BoxRay>) -> Frustum {
        let mut rays = rays.into_iter();
        let first = rays.next().expect("a packet of at least one ray");
        let mut f = Frustum {
            org: first.org,
            inv_lo: first.inv,
            inv_hi: first.inv,
            tmin: first.tmin,
            octant: first.octant,
            planes: first.planes,
        };
        // Plain comparisons, not `f32::min`, whose NaN handling costs a blend per value: a
        // live ray's values are never NaN.
        for r in rays {
            debug_assert!(Frustum::joins(first, r));
            for axis in 0..3 {
                if r.inv[axis] < f.inv_lo[axis] {
                    f.inv_lo[axis] = r.inv[axis];
                }
                if r.inv[axis] > f.inv_hi[axis] {
                    f.inv_hi[axis] = r.inv[axis];
                }
            }
            if r.tmin < f.tmin {
                f.tmin = r.tmin;
            }
        }
        f
    }

    /// Whether `r` may share a packet with `lead`: both live, the same origin bit for bit and
    /// the same octant.
    #[inline(always)]
    pub fn joins(lead: &BoxRay, r: &BoxRay) -> bool {
        let same = |a: [f32; 3], b: [f32; 3]| a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits());
        lead.live && r.live && lead.octant == r.octant && same(lead.org, r.org)
    }

    /// The entry distance (at most any ray's) and the exit distance (at least any ray's) of
    /// child `i` of `node`, by the operations of [`Scalar`]'s test at the interval's ends.
    #[inline(always)]
    pub fn span(&self, node: &Node8, i: usize) -> (f32, f32) {
        let oct = self.octant;
        let (mut enter, mut exit) = (self.tmin, f32::INFINITY);
        for axis in 0..3 {
            let dn = node.b[near(oct, axis)][i] - self.org[axis];
            let df = node.b[far(oct, axis)][i] - self.org[axis];
            enter = enter.max((dn * self.inv_lo[axis]).min(dn * self.inv_hi[axis]));
            exit = exit.min((df * self.inv_lo[axis]).max(df * self.inv_hi[axis]));
        }
        (enter, exit * EXIT_SCALE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh::simd::{BoxTest, Scalar};
    use crate::accel::bvh::tree::WIDTH;
    use glam::Vec3;

    /// The quick root test never rejects a ray the node test accepts for a child of the
    /// root: eight random child boxes, their union as the root box, and rays aimed at the
    /// children's corners, edges and faces (where rounding decides) from random origins.
    #[test]
    #[allow(clippy::needless_range_loop)]
    fn root_box_admits_every_ray_a_child_test_accepts() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let (mut accepted, mut rejected) = (0, 0);
        for scale in [1e-4f32, 1.0, 1e5] {
            let mut b = [[0f32; WIDTH]; 6];
            let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
            for slot in 0..WIDTH {
                let c = Vec3::new(next(), next(), next()) * scale + Vec3::splat(scale * 3.0);
                let e = Vec3::new(next(), next(), next()) * scale * 0.3;
                for axis in 0..3 {
                    b[2 * axis][slot] = c[axis] - e[axis];
                    b[2 * axis + 1][slot] = c[axis] + e[axis];
                }
                lo = lo.min(c - e);
                hi = hi.max(c + e);
            }
            let node = Node8 { b, child: [0; WIDTH], perm: [0; WIDTH] };
            let root = RootBox::new(lo, hi).unwrap();
            for _ in 0..20000 {
                let slot = (next() * WIDTH as f32) as usize % WIDTH;
                let pick = |axis: usize, t: f32, u: f32| {
                    let (l, h) = (b[2 * axis][slot], b[2 * axis + 1][slot]);
                    if t < 0.33 {
                        l
                    } else if t < 0.66 {
                        h
                    } else {
                        l + (h - l) * u
                    }
                };
                let mut p = [0f32; 3];
                for (axis, v) in p.iter_mut().enumerate() {
                    let (t, u) = (next(), next());
                    *v = pick(axis, t, u);
                }
                let target = Vec3::from(p);
                let o = target + (Vec3::new(next(), next(), next()) - Vec3::splat(0.5)) * scale * 20.0;
                let mut d = target - o;
                if next() < 0.2 {
                    d[(next() * 3.0) as usize % 3] = 0.0;
                }
                let tmax = if next() < 0.5 { f32::INFINITY } else { 1.0 };
                let ray = Ray { origin: o, dir: d, tmin: 0.0, tmax };
                let br = BoxRay::new(&ray);
                if !br.live {
                    continue;
                }
                let mut tnear = [0f32; WIDTH];
                if Scalar.test(&node, &br, br.octant, tmax, &mut tnear) != 0 {
                    assert!(root.admits(&br, tmax), "{ray:?}");
                    accepted += 1;
                } else {
                    rejected += root.admits(&br, tmax) as u32 ^ 1;
                }
            }
        }
        assert!(accepted > 10000, "too few rays hit a child: {accepted}");
        assert!(rejected > 100, "the root test never rejects: {rejected}");
    }
}
