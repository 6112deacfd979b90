//! The per-ray values of a packet's kernels, one array per field (lane `k` is ray `k`), so the
//! AVX2 path sets up eight rays with one register per field; each lane holds exactly the
//! values of the ray's own single-ray set-up.
use super::{BoxRay, BoxTest, TIE_SCALE};
use crate::accel::triangle::{ShearedRay, range_end};
use crate::geometry::Ray;

/// Rays per packet at most (one byte of a ray mask per child; 8 x 8 masks transpose in a u64).
pub const PACKET: usize = 8;

/// What the eight-ray triangle kernel decided for one triangle. Its operations are the scalar
/// watertight test's (`intersect_sheared`: same operands, same order, no fused multiply-add),
/// so where it can finish the test its hit is the scalar one bit for bit; it leaves to the
/// scalar test only the rays that need more than those operations: an edge function that is
/// exactly zero (the f64 fallback) and hits whose triangle reaches back to the origin's depth
/// (the bound on t's rounding error). Every other ray misses. The one-ray kernel for four
/// triangles ([`PacketTest::tri_hits_lane`]) reports the same way, bit `l` for triangle `l`,
/// and settles those hits too.
#[derive(Clone, Copy, Debug)]
pub struct TriRays {
    /// Rays (bit `k`: lane `k`) whose hit is `(t[k], u[k], v[k])`.
    pub exact: u32,
    /// Rays the scalar test decides.
    pub unsure: u32,
    pub t: [f32; PACKET],
    pub u: [f32; PACKET],
    pub v: [f32; PACKET],
}

impl TriRays {
    /// Nothing settled yet: the rays (or triangles) `unsure` for the scalar test.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))] // for the x86 kernels
    #[inline(always)]
    pub fn undecided(unsure: u32) -> TriRays {
        TriRays { exact: 0, unsure, t: [0.0; PACKET], u: [0.0; PACKET], v: [0.0; PACKET] }
    }
}

/// The box-test values ([`BoxRay`]) of a packet's rays, one array per field (lane `k` is ray
/// `k`), so the AVX2 path sets up eight rays with one register per field; each lane holds
/// exactly the values of the ray's own [`BoxRay`] (dead or absent rays: not live, zeros).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct PacketBoxRays {
    pub org: [[f32; PACKET]; 3],
    pub inv: [[f32; PACKET]; 3],
    pub oi_near: [[f32; PACKET]; 3],
    pub oi_far: [[f32; PACKET]; 3],
    pub tmin: [f32; PACKET],
    /// `tmax * TIE_SCALE`, the bound the box test compares entries with.
    pub tie: [f32; PACKET],
    pub tmax: [f32; PACKET],
    pub octant: [u32; PACKET],
    /// [`BoxRay::planes`] of each ray (two bytes of padding each).
    pub planes: [[u8; 8]; PACKET],
    /// Bit `k`: [`BoxRay::fma`] of ray `k`.
    pub fma: u32,
    /// Bit `k`: [`BoxRay::live`] of ray `k`.
    pub live: u32,
}

impl PacketBoxRays {
    pub const EMPTY: PacketBoxRays = PacketBoxRays {
        org: [[0.0; PACKET]; 3],
        inv: [[0.0; PACKET]; 3],
        oi_near: [[0.0; PACKET]; 3],
        oi_far: [[0.0; PACKET]; 3],
        tmin: [0.0; PACKET],
        tie: [0.0; PACKET],
        tmax: [0.0; PACKET],
        octant: [0; PACKET],
        planes: [[0; 8]; PACKET],
        fma: 0,
        live: 0,
    };

    /// Lanes `0..n` set up one ray at a time with `isa`'s [`BoxTest::box_ray`].
    #[inline(always)]
    pub fn each<B: BoxTest>(isa: B, rays: &[Ray]) -> PacketBoxRays {
        let mut p = PacketBoxRays::EMPTY;
        for (k, r) in rays.iter().enumerate().take(PACKET) {
            p.set(k, &isa.box_ray(r), r.tmax);
        }
        p
    }

    /// Stores `b` (the values of ray `k`, whose `tmax` is `tmax`) in lane `k`.
    #[inline(always)]
    pub fn set(&mut self, k: usize, b: &BoxRay, tmax: f32) {
        for axis in 0..3 {
            self.org[axis][k] = b.org[axis];
            self.inv[axis][k] = b.inv[axis];
            self.oi_near[axis][k] = b.oi_near[axis];
            self.oi_far[axis][k] = b.oi_far[axis];
        }
        self.tmin[k] = b.tmin;
        self.tmax[k] = tmax;
        self.tie[k] = tmax * TIE_SCALE;
        self.octant[k] = b.octant;
        self.planes[k][..6].copy_from_slice(&b.planes);
        self.fma |= (b.fma as u32) << k;
        self.live |= (b.live as u32) << k;
    }

    /// The [`BoxRay`] of lane `k`.
    #[inline(always)]
    pub fn lane(&self, k: usize) -> BoxRay {
        let mut planes = [0u8; 6];
        planes.copy_from_slice(&self.planes[k][..6]);
        BoxRay {
            org: [self.org[0][k], self.org[1][k], self.org[2][k]],
            inv: [self.inv[0][k], self.inv[1][k], self.inv[2][k]],
            tmin: self.tmin[k],
            octant: self.octant[k],
            oi_near: [self.oi_near[0][k], self.oi_near[1][k], self.oi_near[2][k]],
            oi_far: [self.oi_far[0][k], self.oi_far[1][k], self.oi_far[2][k]],
            fma: self.fma >> k & 1 != 0,
            live: self.live >> k & 1 != 0,
            planes,
        }
    }
}

/// The packet's rays' set-up for their leaf tests, made at the packet's first leaf, one
/// array per field (lane `k` is ray `k`): the shear of the watertight test
/// ([`ShearedRay::of`]) and what the SIMD filter derives from it at every leaf in the
/// single-ray path (the origin on the sheared axes, `range_end(tmax)`, the offsets of the
/// axes' rows in a [`crate::accel::bvh::tree::Tri4`] corner), so each is derived once per ray, and on
/// AVX2 for eight rays at once.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct PacketShear {
    /// The origin's kx, ky, kz coordinates.
    pub org: [[f32; PACKET]; 3],
    /// `sx`, `sy`, `sz`.
    pub shear: [[f32; PACKET]; 3],
    pub tmin: [f32; PACKET],
    /// `range_end(tmax)`.
    pub tend: [f32; PACKET],
    /// Byte offsets `16 * axis` (kx, ky, kz; always below 48) of the axes' rows in a corner
    /// (`Tri4::c[corner]`).
    pub rows: [[u8; 4]; PACKET],
}

impl PacketShear {
    pub const EMPTY: PacketShear = PacketShear {
        org: [[0.0; PACKET]; 3],
        shear: [[0.0; PACKET]; 3],
        tmin: [0.0; PACKET],
        tend: [0.0; PACKET],
        rows: [[0, 16, 32, 0]; PACKET],
    };

    /// Lanes `0..n` set up one ray at a time.
    #[inline(always)]
    pub fn each(rays: &[Ray]) -> PacketShear {
        let mut p = PacketShear::EMPTY;
        for (k, r) in rays.iter().enumerate().take(PACKET) {
            p.set(k, r);
        }
        p
    }

    /// Lane `k` from `ray`'s shear.
    #[inline(always)]
    pub fn set(&mut self, k: usize, ray: &Ray) {
        let s = ShearedRay::of(ray);
        let o = s.org.to_array();
        let (kx, ky, kz) = (s.kx % 3, s.ky % 3, s.kz % 3);
        for (role, (axis, sh)) in [(kx, s.sx), (ky, s.sy), (kz, s.sz)].into_iter().enumerate() {
            self.org[role][k] = o[axis];
            self.shear[role][k] = sh;
            self.rows[k][role] = 16 * axis as u8;
        }
        self.tmin[k] = ray.tmin;
        self.tend[k] = range_end(ray.tmax);
    }

    /// The [`ShearedRay`] of lane `k` (whose ray is `ray`).
    #[inline(always)]
    pub fn sheared(&self, k: usize, ray: &Ray) -> ShearedRay {
        let r = &self.rows[k];
        ShearedRay {
            org: ray.origin,
            kx: (r[0] / 16) as usize,
            ky: (r[1] / 16) as usize,
            kz: (r[2] / 16) as usize,
            sx: self.shear[0][k],
            sy: self.shear[1][k],
            sz: self.shear[2][k],
            org_k: [self.org[0][k], self.org[1][k], self.org[2][k]],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh::simd::{PacketTest, Scalar};
    use crate::accel::bvh::tree::{Node8, WIDTH};
    use glam::Vec3;

    /// Rays with zero, negative zero, denormal, huge, infinite and NaN components, empty and
    /// NaN ranges, in groups of every length 1..=8.
    fn hard_rays() -> Vec<Ray> {
        let vals = [0.0, -0.0, 1e-40, -1e-40, 1.0, -2.5, 3e38, -3e38, 1e-30, f32::INFINITY, f32::NAN, 0.75];
        let mut rays = Vec::new();
        for (i, &a) in vals.iter().enumerate() {
            for (j, &b) in vals.iter().enumerate() {
                for (k, &c) in vals.iter().enumerate() {
                    let o = Vec3::new(vals[(i + 4) % 12] * 0.5, b * 0.25 - 0.5, vals[(k + j) % 12] * 0.1);
                    let (tmin, tmax) = match (i + j + k) % 4 {
                        0 => (0.0, 1.0),
                        1 => (0.0, f32::INFINITY),
                        2 => (vals[(i + j) % 12], 2.0),
                        _ => (1.0, vals[(j + k) % 12]),
                    };
                    rays.push(Ray { origin: o, dir: Vec3::new(a, b, c), tmin, tmax });
                }
            }
        }
        // And ordinary rays from around the node toward points among its boxes.
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32 - 0.5
        };
        for i in 0..3000 {
            let o = Vec3::new(next(), next(), next()) * 6.0;
            let target = Vec3::new(next(), next(), next()) * 3.0;
            rays.push(Ray { origin: o, dir: target - o, tmin: 0.0, tmax: [1.0, 0.6, f32::INFINITY][i % 3] });
        }
        rays
    }

    /// A node with eight boxes around the origin (one empty slot), so the hard rays hit some.
    #[allow(clippy::needless_range_loop)]
    fn node() -> Node8 {
        let mut b = [[0f32; WIDTH]; 6];
        for slot in 0..WIDTH {
            let c = Vec3::new(slot as f32 * 0.3 - 1.0, (slot % 3) as f32 * 0.5 - 0.5, (slot % 2) as f32 - 0.5);
            for axis in 0..3 {
                b[2 * axis][slot] = c[axis] - 0.4;
                b[2 * axis + 1][slot] = c[axis] + 0.4;
            }
        }
        for (plane, row) in b.iter_mut().enumerate() {
            row[5] = if plane % 2 == 0 { f32::INFINITY } else { f32::NEG_INFINITY };
        }
        Node8 { b, child: [0; WIDTH], perm: [0; WIDTH] }
    }

    /// Every lane of a packet's box-test set-up is the ray's own `BoxRay` (bit for bit, NaN
    /// matching NaN) and the lane test gives the same ISA's `test` of the ray, for the
    /// scalar and the AVX2 paths (which sets up eight rays at once and tests in fused form).
    #[test]
    fn packet_box_rays_are_the_single_rays() {
        let rays = hard_rays();
        let node = node();
        let bits = |x: [f32; 3]| x.map(|v| if v.is_nan() { u32::MAX } else { v.to_bits() });
        let mut hits = 0;
        let mut check = |isa_name: &str,
                         group: &[Ray],
                         p: &PacketBoxRays,
                         lane_test: &dyn Fn(usize) -> u32,
                         ray_test: &dyn Fn(&BoxRay, f32) -> u32| {
            for (k, r) in group.iter().enumerate() {
                let (b, l) = (BoxRay::new(r), p.lane(k));
                assert_eq!(bits(b.org), bits(l.org), "{isa_name} {r:?}");
                assert_eq!(bits(b.inv), bits(l.inv), "{isa_name} {r:?}");
                assert_eq!(bits(b.oi_near), bits(l.oi_near), "{isa_name} {r:?}");
                assert_eq!(bits(b.oi_far), bits(l.oi_far), "{isa_name} {r:?}");
                assert_eq!(bits([b.tmin; 3]), bits([l.tmin; 3]), "{isa_name} {r:?}");
                assert_eq!(
                    (b.octant, b.fma, b.live, b.planes),
                    (l.octant, l.fma, l.live, l.planes),
                    "{isa_name} {r:?}"
                );
                if b.live {
                    let want = ray_test(&b, r.tmax);
                    assert_eq!(lane_test(k), want, "{isa_name} {r:?}");
                    hits += want.count_ones();
                }
            }
        };
        for len in 1..=PACKET {
            for group in rays.chunks(len) {
                let p = Scalar.packet_box_rays(group);
                let scalar_test = |b: &BoxRay, tmax: f32| Scalar.test(&node, b, b.octant, tmax, &mut [0.0; WIDTH]);
                check("scalar", group, &p, &|k| Scalar.test_lane(&node, &p, k), &scalar_test);
                #[cfg(target_arch = "x86_64")]
                if let Some(avx) = crate::cpu::Avx2::new() {
                    use crate::cpu::with_avx2;
                    let p = with_avx2(avx, |t| t.packet_box_rays(group));
                    let avx_test =
                        |b: &BoxRay, tmax: f32| with_avx2(avx, |t| t.test(&node, b, b.octant, tmax, &mut [0.0; WIDTH]));
                    check("avx2", group, &p, &|k| with_avx2(avx, |t| t.test_lane(&node, &p, k)), &avx_test);
                }
            }
        }
        assert!(hits > 20000, "too few box hits to compare: {hits}");
    }

    /// The AVX2 leaf set-up of eight rays equals the per-ray one (`ShearedRay::of` and
    /// `range_end`), bit for bit with NaN matching NaN, on the hard and ordinary rays.
    #[test]
    fn packet_shear_is_the_single_rays() {
        #[cfg(target_arch = "x86_64")]
        if let Some(avx) = crate::cpu::Avx2::new() {
            let bits = |x: f32| if x.is_nan() { u32::MAX } else { x.to_bits() };
            let mut n = 0;
            for group in hard_rays().chunks_exact(PACKET) {
                let want = Scalar.packet_shear(group);
                let got = crate::cpu::with_avx2(avx, |t| t.packet_shear(group));
                for (k, r) in group.iter().enumerate() {
                    for role in 0..3 {
                        assert_eq!(bits(want.org[role][k]), bits(got.org[role][k]), "{r:?}");
                        assert_eq!(bits(want.shear[role][k]), bits(got.shear[role][k]), "{r:?}");
                    }
                    assert_eq!(bits(want.tmin[k]), bits(got.tmin[k]), "{r:?}");
                    assert_eq!(bits(want.tend[k]), bits(got.tend[k]), "{r:?}");
                    assert_eq!(want.rows[k], got.rows[k], "{r:?}");
                    let s = ShearedRay::of(r);
                    assert_eq!([s.kx, s.ky, s.kz].map(|a| 16 * a as u8), got.rows[k][..3], "{r:?}");
                    n += 1;
                }
            }
            assert!(n > 4000, "too few rays: {n}");
        }
    }
}
