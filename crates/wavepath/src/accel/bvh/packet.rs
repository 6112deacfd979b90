//! Any-hit for packets of shadow rays: up to eight consecutive rays of the shadow queue, made
//! of whole runs of rays that leave one point (the `-l N` samples of one shading point toward
//! one light; the lane kernel queues them together). The packet is traversed once: one
//! stack, one node fetch and one decision per node for all of its rays, instead of one
//! traversal per ray that repeats the same loads and branches. Shadow rays of different points
//! still share the nodes near the light they all aim at, which is why whole runs are merged.
//!
//! Every ray still gets its own box test (its own [`BoxRay`] values, the same operations as
//! [`BoxTest::test`] in [`traverse::any_hit_with`]) and its own leaf tests (the filter and
//! exact test of `leaf_any`, or, where more rays than triangles enter a leaf, the eight-ray
//! kernel whose hits are that exact test's); a ray enters a child only if its own test of
//! that child passed at every level above. So a ray tests a subset of what its single-ray
//! traversal could reach and the same leaves that matter: the boolean is the single-ray one,
//! bit for bit, whatever the ISA.
//!
//! Per-ray set-up is done for the whole packet at once ([`PacketBoxRays`] at the start,
//! [`PacketShear`] at the first leaf; on AVX2 one ray per lane, with each lane's operations
//! those of the single-ray set-up, so the same values), and the leaf filter starts from the
//! set-up instead of deriving the shear's values again at every leaf. On CBbunny that took
//! the shadow stage from 779 to 640 instructions per ray (docs/decisions.md, "Shadow packets").
use super::Bvh;
use super::boxtest::{BoxRay, BoxTest, TIE_SCALE};
use super::leaf::Tri4;
use super::traverse::{self, lane_hit, prefetch_child};
use super::wide::{LEAF_BIT, Node8, WIDTH, leaf_range};
use crate::accel::TraceCounters;
use crate::accel::triangle::{ShearedRay, range_end};
use crate::geometry::Ray;

/// Rays per packet at most (one byte of a ray mask per child; 8 x 8 masks transpose in a u64).
pub const PACKET: usize = 8;

/// The packet kernels of an instruction set, beside its single-ray [`BoxTest`] (the scalar
/// versions here, set up ray by ray; the SIMD ones in `simd`).
pub(super) trait PacketTest: BoxTest {
    /// The box-test values of up to [`PACKET`] rays ([`BoxTest::box_ray`] of each, in its lane).
    #[inline(always)]
    fn packet_box_rays(self, rays: &[Ray]) -> PacketBoxRays {
        PacketBoxRays::each(self, rays)
    }

    /// [`BoxTest::test`] of `node` for lane `k` of `p` (with that ray's `tmax`), without the
    /// entry distances.
    #[inline(always)]
    fn test_lane(self, node: &Node8, p: &PacketBoxRays, k: usize) -> u32 {
        let b = p.lane(k);
        let mut tnear = [0f32; WIDTH];
        self.test(node, &b, b.octant, p.tmax[k], &mut tnear)
    }

    /// The leaf-test set-up of up to [`PACKET`] rays ([`PacketShear::set`] of each).
    #[inline(always)]
    fn packet_shear(self, rays: &[Ray]) -> PacketShear {
        PacketShear::each(rays)
    }

    /// [`BoxTest::tri_filter`] for lane `k` of `p` (ray `ray`); the SIMD paths start from the
    /// set-up's values instead of deriving them again at every leaf.
    #[inline(always)]
    fn tri_filter_lane(self, blk: &Tri4, p: &PacketShear, k: usize, ray: &Ray, lanes: u32) -> u32 {
        self.tri_filter(blk, &p.sheared(k, ray), ray.tmin, ray.tmax, lanes)
    }

    /// The rays of `p` (bit `k`: lane `k`, live, direction octant `oct`, closest hit so far
    /// at `closest[k]`) whose own unfused box test (the [`super::boxtest::Scalar`] one)
    /// enters child `slot` of `node`: one child for eight rays instead of eight children for
    /// one ray.
    #[inline(always)]
    fn slot_rays(self, node: &Node8, slot: usize, p: &PacketBoxRays, oct: u32, closest: &[f32; PACKET]) -> u32 {
        let mut rays = 0;
        for (k, &t) in closest.iter().enumerate() {
            let b = p.lane(k);
            if b.live {
                let mut tnear = [0f32; WIDTH];
                rays |= (super::boxtest::Scalar.test(node, &b, oct, t, &mut tnear) >> slot & 1) << k;
            }
        }
        rays
    }

    /// The watertight test of triangle `lane` of `blk` for the rays of `p` (lane `k`, whose
    /// closest hit so far is at `closest[k]`), one ray per lane instead of one triangle per
    /// lane: see [`TriRays`]. Every lane's axes must be those of lane 0 (`rows`). None where
    /// the instruction set has no such kernel: the caller tests ray by ray.
    #[inline(always)]
    fn tri_rays(self, blk: &Tri4, lane: usize, p: &PacketShear, closest: &[f32; PACKET]) -> Option<TriRays> {
        let _ = (blk, lane, p, closest);
        None
    }
}

/// What the eight-ray triangle kernel decided for one triangle. Its operations are the scalar
/// watertight test's (`intersect_sheared`: same operands, same order, no fused multiply-add),
/// so where it can finish the test its hit is the scalar one bit for bit; it leaves to the
/// scalar test only the rays that need more than those operations: an edge function that is
/// exactly zero (the f64 fallback) and hits whose triangle reaches back to the origin's depth
/// (the bound on t's rounding error). Every other ray misses.
#[derive(Clone, Copy, Debug)]
pub(super) struct TriRays {
    /// Rays (bit `k`: lane `k`) whose hit is `(t[k], u[k], v[k])`.
    pub(super) exact: u32,
    /// Rays the scalar test decides.
    pub(super) unsure: u32,
    pub(super) t: [f32; PACKET],
    pub(super) u: [f32; PACKET],
    pub(super) v: [f32; PACKET],
}

impl PacketTest for super::boxtest::Scalar {}

/// Any-hit for `rays`, traced as packets of consecutive runs of rays with the same origin
/// (bit for bit, see [`run_len`]); a ray alone is traced as a single ray. `occluded[i]` as [`crate::accel::Intersector::any_hits`].
pub fn any_hits(bvh: &Bvh, rays: &[Ray], occluded: &mut [bool], counters: &mut TraceCounters) {
    let mut stack =
        Stack { nodes: vec![0u32; bvh.stack_need], masks: vec![0u32; bvh.stack_need], leaf: Tri4::default() };
    let mut single = traverse::BigStack::boxed();
    // The loop is spelled out in the macro and every closure is `#[inline(always)]`: anything
    // left out of line would be compiled outside the AVX2 context (see `Bvh::closest_hits`).
    macro_rules! run {
        ($isa:expr) => {{
            let mut i = 0;
            while i < rays.len() {
                let n = run_len(&rays[i..]);
                if n == 1 {
                    occluded[i] = traverse::any_hit_with(bvh, $isa, &rays[i], counters, &mut single);
                } else {
                    packet_any(bvh, $isa, &rays[i..i + n], &mut occluded[i..i + n], counters, &mut stack);
                }
                i += n;
            }
        }};
    }
    on_isa!(bvh, |isa| run!(isa))
}

/// The packet stack: node references and, per entry, the rays that entered it.
struct Stack {
    nodes: Vec<u32>,
    masks: Vec<u32>,
    /// The block of the leaf being tested, when the tree's leaves index their corners.
    leaf: Tri4,
}

/// The box-test values ([`BoxRay`]) of a packet's rays, one array per field (lane `k` is ray
/// `k`), so the AVX2 path sets up eight rays with one register per field; each lane holds
/// exactly the values of the ray's own [`BoxRay`] (dead or absent rays: not live, zeros).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub(super) struct PacketBoxRays {
    pub(super) org: [[f32; PACKET]; 3],
    pub(super) inv: [[f32; PACKET]; 3],
    pub(super) oi_near: [[f32; PACKET]; 3],
    pub(super) oi_far: [[f32; PACKET]; 3],
    pub(super) tmin: [f32; PACKET],
    /// `tmax * TIE_SCALE`, the bound the box test compares entries with.
    pub(super) tie: [f32; PACKET],
    pub(super) tmax: [f32; PACKET],
    pub(super) octant: [u32; PACKET],
    /// [`BoxRay::planes`] of each ray (two bytes of padding each).
    pub(super) planes: [[u8; 8]; PACKET],
    /// Bit `k`: [`BoxRay::fma`] of ray `k`.
    pub(super) fma: u32,
    /// Bit `k`: [`BoxRay::live`] of ray `k`.
    pub(super) live: u32,
}

impl PacketBoxRays {
    pub(super) const EMPTY: PacketBoxRays = PacketBoxRays {
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
    pub(super) fn each<B: BoxTest>(isa: B, rays: &[Ray]) -> PacketBoxRays {
        let mut p = PacketBoxRays::EMPTY;
        for (k, r) in rays.iter().enumerate().take(PACKET) {
            p.set(k, &isa.box_ray(r), r.tmax);
        }
        p
    }

    /// Stores `b` (the values of ray `k`, whose `tmax` is `tmax`) in lane `k`.
    #[inline(always)]
    pub(super) fn set(&mut self, k: usize, b: &BoxRay, tmax: f32) {
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
    pub(super) fn lane(&self, k: usize) -> BoxRay {
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
/// axes' rows in a [`super::leaf::Tri4`] corner), so each is derived once per ray, and on
/// AVX2 for eight rays at once.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub(super) struct PacketShear {
    /// The origin's kx, ky, kz coordinates.
    pub(super) org: [[f32; PACKET]; 3],
    /// `sx`, `sy`, `sz`.
    pub(super) shear: [[f32; PACKET]; 3],
    pub(super) tmin: [f32; PACKET],
    /// `range_end(tmax)`.
    pub(super) tend: [f32; PACKET],
    /// Byte offsets `16 * axis` (kx, ky, kz; always below 48) of the axes' rows in a corner
    /// (`Tri4::c[corner]`).
    pub(super) rows: [[u8; 4]; PACKET],
}

impl PacketShear {
    pub(super) const EMPTY: PacketShear = PacketShear {
        org: [[0.0; PACKET]; 3],
        shear: [[0.0; PACKET]; 3],
        tmin: [0.0; PACKET],
        tend: [0.0; PACKET],
        rows: [[0, 16, 32, 0]; PACKET],
    };

    /// Lanes `0..n` set up one ray at a time.
    #[inline(always)]
    pub(super) fn each(rays: &[Ray]) -> PacketShear {
        let mut p = PacketShear::EMPTY;
        for (k, r) in rays.iter().enumerate().take(PACKET) {
            p.set(k, r);
        }
        p
    }

    /// Lane `k` from `ray`'s shear.
    #[inline(always)]
    pub(super) fn set(&mut self, k: usize, ray: &Ray) {
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
    pub(super) fn sheared(&self, k: usize, ray: &Ray) -> ShearedRay {
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

/// Length of the next packet: whole runs of rays with one origin (the shadow rays of one
/// point), as many as fit in [`PACKET`] (a longer run is split). Rays of a few points share
/// the nodes near the light they all aim at, so merging runs measured ~10% faster on CBbunny
/// than one point per packet.
#[inline(always)]
fn run_len(rays: &[Ray]) -> usize {
    let mut n = run_len1(rays);
    while n < rays.len() {
        let m = run_len1(&rays[n..]);
        if n + m > PACKET {
            break;
        }
        n += m;
    }
    n
}

/// Number of leading rays (at most [`PACKET`]) that share the first ray's origin.
#[inline(always)]
fn run_len1(rays: &[Ray]) -> usize {
    let o = rays[0].origin;
    let mut n = 1;
    while n < PACKET && n < rays.len() {
        let p = rays[n].origin;
        if p.x.to_bits() != o.x.to_bits() || p.y.to_bits() != o.y.to_bits() || p.z.to_bits() != o.z.to_bits() {
            break;
        }
        n += 1;
    }
    n
}

/// Transposes an 8 x 8 bit matrix held as bit `8 r + c` (row `r` in byte `r`): afterwards byte
/// `c` holds column `c` (Hacker's Delight, `transpose8`).
#[inline(always)]
pub(super) fn transpose8(mut x: u64) -> u64 {
    let t = (x ^ (x >> 7)) & 0x00AA_00AA_00AA_00AA;
    x ^= t ^ (t << 7);
    let t = (x ^ (x >> 14)) & 0x0000_CCCC_0000_CCCC;
    x ^= t ^ (t << 14);
    let t = (x ^ (x >> 28)) & 0x0000_0000_F0F0_F0F0;
    x ^= t ^ (t << 28);
    x
}

/// Any-hit for 2..=[`PACKET`] rays at once (see the module comment).
#[inline(always)]
fn packet_any<B: PacketTest>(
    bvh: &Bvh,
    isa: B,
    rays: &[Ray],
    occluded: &mut [bool],
    counters: &mut TraceCounters,
    stack: &mut Stack,
) {
    let n = rays.len().min(PACKET);
    counters.rays += n as u64;
    let pb = isa.packet_box_rays(&rays[..n]);
    let live = pb.live;
    // The leaf set-up is made at the packet's first leaf (many rays never reach one), with
    // whether all its live rays share their shear axes (then the eight-ray triangle kernel,
    // which reads the axes of lane 0, may test a triangle for all of them at once).
    let mut shear: Option<(PacketShear, bool)> = None;
    let mut hit = 0u32;
    let (mut sp, mut cur, mut cur_rays) = (0usize, 0u32, live);
    let (mut visited, mut tests) = (0u64, 0u64);
    'trace: loop {
        let active = cur_rays & !hit;
        if active != 0 {
            let node = &bvh.nodes[cur as usize];
            // Row k: the children ray k enters.
            let (mut rows, mut any) = (0u64, 0u32);
            visited += active.count_ones() as u64;
            let mut m = active;
            while m != 0 {
                let k = m.trailing_zeros() as usize;
                m &= m - 1;
                let hm = isa.test_lane(node, &pb, k);
                rows |= (hm as u64) << (8 * k);
                any |= hm;
            }
            if any.count_ones() > 1 {
                let mut m = any;
                while m != 0 {
                    prefetch_child(bvh, isa, node.child[m.trailing_zeros() as usize]);
                    m &= m - 1;
                }
            }
            // Column i: the rays that enter child i.
            let cols = transpose8(rows);
            while any != 0 {
                let i = any.trailing_zeros() as usize;
                any &= any - 1;
                let child = node.child[i];
                let entered = (cols >> (8 * i)) as u32 & 0xff;
                if child & LEAF_BIT == 0 {
                    stack.nodes[sp] = child;
                    stack.masks[sp] = entered;
                    sp += 1;
                    continue;
                }
                let (first, count) = leaf_range(child);
                let blk = bvh.block(first, &mut stack.leaf);
                // As `leaf_any`: the filter's triangle lanes and every other lane, then the
                // exact test in lane order up to the first hit.
                let others = ((1u32 << count) - 1) & !blk.tri_lanes;
                let mut m = entered & !hit;
                if m == 0 {
                    continue;
                }
                tests += (count as u32 * m.count_ones()) as u64;
                let (sh, shared) = &*shear.get_or_insert_with(|| {
                    let mut sh = isa.packet_shear(&rays[..n]);
                    let lead = live.trailing_zeros() as usize % PACKET;
                    let mut rest = live;
                    let mut shared = true;
                    while rest != 0 {
                        shared &= sh.rows[rest.trailing_zeros() as usize] == sh.rows[lead];
                        rest &= rest - 1;
                    }
                    sh.rows[0] = sh.rows[lead];
                    (sh, shared)
                });
                // More rays than triangles: each triangle for all the rays at once (without
                // the kernel, the rays go on ray by ray below).
                if *shared
                    && m.count_ones() as usize > count
                    && let Some(h) = leaf_any_rays(bvh, isa, blk, count, sh, rays, &pb.tmax, m)
                {
                    hit |= h;
                    m = 0;
                }
                while m != 0 {
                    let k = m.trailing_zeros() as usize;
                    m &= m - 1;
                    let mut cand = isa.tri_filter_lane(blk, sh, k, &rays[k], blk.tri_lanes) | others;
                    while cand != 0 {
                        let lane = cand.trailing_zeros() as usize;
                        cand &= cand - 1;
                        let sr = sh.sheared(k, &rays[k]);
                        if lane_hit(bvh, blk, lane, &sr, &rays[k], rays[k].tmax).is_some() {
                            hit |= 1 << k;
                            break;
                        }
                    }
                }
                if hit == live {
                    break 'trace;
                }
            }
        }
        if sp == 0 {
            break;
        }
        sp -= 1;
        cur = stack.nodes[sp];
        cur_rays = stack.masks[sp];
    }
    counters.nodes += visited;
    counters.prim_tests += tests;
    for (k, o) in occluded.iter_mut().enumerate().take(n) {
        *o = hit >> k & 1 != 0;
    }
}

/// The rays of `m` (bit `k`: `rays[k]`, lane `k` of `sh`, range end `tmax[k]`) that hit a
/// primitive of `blk`, a leaf of `count`, each triangle tested for all of them at once by
/// [`PacketTest::tri_rays`] (its hits are the exact test's; the rays it leaves undecided and
/// the other primitives take the exact test ray by ray). None where the instruction set has
/// no such kernel.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn leaf_any_rays<B: PacketTest>(
    bvh: &Bvh,
    isa: B,
    blk: &Tri4,
    count: usize,
    sh: &PacketShear,
    rays: &[Ray],
    tmax: &[f32; PACKET],
    mut m: u32,
) -> Option<u32> {
    let mut hit = 0;
    for lane in 0..count {
        let mut unsure = m;
        if blk.tri_lanes >> lane & 1 != 0 {
            let r = isa.tri_rays(blk, lane, sh, tmax)?;
            hit |= r.exact & m;
            unsure &= r.unsure & !hit;
        }
        while unsure != 0 {
            let k = unsure.trailing_zeros() as usize;
            unsure &= unsure - 1;
            if lane_hit(bvh, blk, lane, &sh.sheared(k, &rays[k]), &rays[k], rays[k].tmax).is_some() {
                hit |= 1 << k;
            }
        }
        m &= !hit;
        if m == 0 {
            break;
        }
    }
    Some(hit)
}

#[cfg(test)]
mod tests {
    use super::super::boxtest::Scalar;
    use super::super::wide::{Node8, WIDTH};
    use super::*;
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

    #[test]
    fn transpose8_swaps_rows_and_columns() {
        let mut s = 0x9E37_79B9_7F4A_7C15u64;
        for _ in 0..1000 {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let x = s ^ (s >> 29);
            let t = transpose8(x);
            for r in 0..8 {
                for c in 0..8 {
                    assert_eq!(x >> (8 * r + c) & 1, t >> (8 * c + r) & 1, "{x:#x} ({r}, {c})");
                }
            }
        }
    }
}
