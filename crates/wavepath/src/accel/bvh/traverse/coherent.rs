//! Closest hits of coherent rays: runs of rays that leave one point with nearly parallel
//! directions in one octant (a pinhole camera's samples of one pixel, or of a block of
//! neighbouring pixels). Such a packet is traversed once: one box test per node for all of
//! its rays, by the interval of their reciprocal directions ([`Frustum`]), one stack and one
//! visiting order. Only at the leaves is each ray tested on its own, with its own closest
//! hit so far (rays whose own entry could not come before their closest hit are skipped).
//!
//! The packet's test enters every box that any of its rays' own (unfused) tests would enter
//! (see [`Frustum`]), with the largest closest-hit distance of the packet, so each ray's
//! leaf tests cover every leaf its single-ray traversal could find a closer hit in; the
//! closest hit does not depend on the order leaves are tested in (ties go to the lower
//! primitive id at any order), so each ray's hit is its single-ray hit, bit for bit.
use super::leaf::Best;
use super::{BigStack, Tracer, Walker};
use crate::accel::bvh::simd::{BoxRay, Frustum, PACKET, PacketBoxRays, PacketShear, PacketTest, TIE_SCALE, TriRays};
use crate::accel::bvh::tree::{LEAF_BIT, Tri4, WIDTH, leaf_range};
use crate::geometry::{Hit, Ray};

/// Rays per packet at most (a 4 x 4 block of pixels, or two pixels of eight samples).
pub const COHERENT: usize = 16;

/// A set of a packet's rays (bit `k`: ray `k`).
pub type Rays = u32;
const _: () = assert!(COHERENT <= Rays::BITS as usize && COHERENT.is_multiple_of(PACKET));

/// Groups of [`PACKET`] rays in a packet: the SIMD kernels take one group at a time.
const GROUPS: usize = COHERENT / PACKET;

/// Rays a packet needs at least: the packet's node test costs about two single-ray tests.
pub const MIN_RAYS: usize = 4;

/// Smallest cosine of the angle between a packet's first direction and any other's. Wider
/// packets enter boxes few of their rays hit, and every ray then tests those leaves; camera
/// rays of neighbouring pixels are far closer (a 4 x 4 block of an 800 x 600 image with a 45
/// degree field of view spans 0.3 degrees).
const MIN_COS: f32 = 0.9995;

/// How many leading rays of `slot` (places in `rays`, whose box-test values are `prep`) form
/// a packet with the first one (at most [`COHERENT`]): live, from the same origin, in the same
/// octant and within the cone of [`MIN_COS`].
#[inline(always)]
pub fn packet_len(rays: &[Ray], slot: &[u8], prep: &[BoxRay]) -> usize {
    let lead = &prep[slot[0] as usize];
    // Most rays of a batch are not coherent (diffuse bounces): they fail here, before any
    // arithmetic.
    if slot.len() < 2 || !Frustum::joins(lead, &prep[slot[1] as usize]) {
        return 1;
    }
    let d0 = rays[slot[0] as usize].dir;
    let l0 = d0.length_squared();
    let mut n = 1;
    while n < slot.len().min(COHERENT) && Frustum::joins(lead, &prep[slot[n] as usize]) {
        let d = rays[slot[n] as usize].dir;
        let dot = d0.dot(d);
        if !(dot > 0.0 && dot * dot >= MIN_COS * MIN_COS * l0 * d.length_squared()) {
            break;
        }
        n += 1;
    }
    n
}

/// Closest hits of a packet: `out[k]` for `rays[k]` (at most [`COHERENT`], all joined by
/// [`packet_len`]), whose bounds are `f`.
///
/// Each child the packet enters also takes the box test of each ray (eight rays at a time,
/// each with its own closest hit), so a subtree is visited, and a leaf tested, only for the
/// rays that enter it. (Passing the packet's rays on to inner children unchecked cost nothing
/// on 100k-triangle meshes but a third of the speed on 25.6M triangles: there the triangles
/// are smaller than the rays' spacing, and the frustum between the rays enters many subtrees
/// none of them does.)
impl<K: PacketTest> Walker<'_, K, &mut BigStack<Rays>> {
    #[inline(always)]
    pub fn coherent(&mut self, rays: &[Ray], f: &Frustum, out: &mut [Option<Hit>]) {
        let t = self.t;
        let (bvh, isa) = (t.bvh, t.isa);
        // The node array in a local: the tree sits behind the walker, not behind an argument
        // of this function, so the compiler would reload it after every store to the stack.
        let nodes = &bvh.nodes[..];
        let stack = &mut *self.stack;
        let counters = &mut *self.counters;
        let m = rays.len();
        debug_assert!((1..=COHERENT).contains(&m) && out.len() == m);
        debug_assert!(BigStack::<Rays>::holds(bvh.stack_need));
        counters.rays += m as u64;
        // Each ray's closest hit so far, one array per field (its distance is `closest`).
        let mut found = Found::NONE;
        // The rays' shears are set up at the first leaf, eight at a time, each with whether
        // all its rays share the axes of the first (a pixel block's rays nearly always do).
        let mut shears: Option<[(PacketShear, bool); GROUPS]> = None;
        // And their box-test values, eight rays at a time, at the first node the packet enters
        // (many packets of camera rays enter the root's box and none of its children).
        let mut boxes: Option<[PacketBoxRays; GROUPS]> = None;
        // Each ray's closest-hit distance so far, for the eight-ray kernels (-inf past the
        // packet's rays: they enter nothing).
        let mut closest: [f32; COHERENT] = std::array::from_fn(|k| rays.get(k).map_or(f32::NEG_INFINITY, |r| r.tmax));
        // The largest closest-hit distance of the packet: what a box must be entered within.
        let mut reach = farthest(&closest);
        let all = Rays::MAX >> (Rays::BITS as usize - m);
        let (mut sp, mut cur, mut entry, mut act) = (0usize, 0u32, f.tmin, all);
        let (mut visited, mut tests) = (0u64, 0u64);
        let mut slots = [0u32; WIDTH];
        loop {
            if cur & LEAF_BIT == 0 {
                visited += 1;
                let node = &nodes[cur as usize];
                let top: &mut [u32; WIDTH] = (&mut stack.nodes[sp..sp + WIDTH]).try_into().expect("eight entries");
                let dists: &mut [f32; WIDTH] = (&mut stack.dists[sp..sp + WIDTH]).try_into().expect("eight entries");
                let n = isa.visit_frustum(node, f, reach, &mut *top, &mut *dists, &mut slots) as usize;
                if n > 0 {
                    // Rays per child, from each ray's own test, eight rays at a time.
                    if boxes.is_none() {
                        let mut b = [PacketBoxRays::EMPTY; GROUPS];
                        for (g, b) in b.iter_mut().enumerate() {
                            *b = isa.packet_box_rays(eighth(rays, g));
                        }
                        boxes = Some(b);
                    }
                    let Some(boxes) = &boxes else { unreachable!("set above") };
                    let sets = &mut stack.rays[sp..sp + n];
                    sets.fill(0);
                    for (h, p) in boxes.iter().enumerate() {
                        let lanes = act >> (PACKET * h) & 0xff;
                        if lanes != 0 {
                            let closest = eighth_of(&closest, h);
                            for (set, &slot) in sets.iter_mut().zip(&slots) {
                                let rays = isa.slot_rays(node, slot as usize, p, f.octant, closest) & lanes;
                                *set |= (rays as Rays) << (PACKET * h);
                            }
                        }
                    }
                    for &r in top.iter().take(n) {
                        t.prefetch_child(r);
                    }
                    // The pending children go on the stack, the nearest is taken now.
                    sp += n - 1;
                    (cur, entry, act) = (top[n - 1], dists[n - 1], stack.rays[sp]);
                    if act != 0 {
                        continue;
                    }
                }
            } else {
                let (first, count) = leaf_range(cur);
                let blk = bvh.block(first, &mut stack.leaf);
                let todo = act & within(entry, &closest);
                tests += (todo.count_ones() as usize * count) as u64;
                // (Not in a closure: one compiled out of line would leave the AVX2 context.)
                if shears.is_none() {
                    let mut p = [(PacketShear::EMPTY, false); GROUPS];
                    for (g, (p, all)) in p.iter_mut().enumerate() {
                        let group = eighth(rays, g);
                        *p = isa.packet_shear(group);
                        *all = p.rows[..group.len()].iter().all(|r| *r == p.rows[0]);
                    }
                    shears = Some(p);
                }
                let Some(shears) = &shears else { unreachable!("set above") };
                for (h, (p, all)) in shears.iter().enumerate() {
                    let lanes = todo >> (PACKET * h) & 0xff;
                    if lanes != 0 {
                        leaf_rays(
                            t,
                            Leaf { blk, count, p, all_shared: *all, rays: &rays[PACKET * h..] },
                            lanes,
                            &mut found,
                            &mut closest,
                            h,
                        );
                    }
                }
                reach = farthest(&closest);
            }
            // Pop the nearest pending child that some ray may still find something closer in.
            loop {
                if sp == 0 {
                    counters.nodes += visited;
                    counters.prim_tests += tests;
                    for (k, o) in out.iter_mut().enumerate() {
                        *o = found.hit(k, closest[k]);
                    }
                    return;
                }
                sp -= 1;
                if stack.rays[sp] != 0 && stack.dists[sp] <= reach * TIE_SCALE {
                    (cur, entry, act) = (stack.nodes[sp], stack.dists[sp], stack.rays[sp]);
                    break;
                }
            }
        }
    }
}

/// A leaf's block as a packet's eight rays test it: `count` primitives of `blk`, and the
/// rays with their leaf set-up `p`.
#[derive(Clone, Copy)]
struct Leaf<'a> {
    blk: &'a Tri4,
    count: usize,
    p: &'a PacketShear,
    /// Whether every ray of `p` has the axes of its lane 0.
    all_shared: bool,
    rays: &'a [Ray],
}

/// The closest hits of a packet's rays so far, one array per field: ray `k` has found
/// primitive `prim[k]` (`u32::MAX`: nothing yet; no primitive has that id) at `u[k]`, `v[k]`;
/// its distance is the packet's `closest[k]`. Kept apart from [`Best`]: a triangle's hits for
/// eight rays are taken in one pass over the lanes, by selects, not ray by ray (camera rays
/// 15-20% faster).
struct Found {
    prim: [u32; COHERENT],
    u: [f32; COHERENT],
    v: [f32; COHERENT],
}

impl Found {
    const NONE: Found = Found { prim: [u32::MAX; COHERENT], u: [0.0; COHERENT], v: [0.0; COHERENT] };

    /// Takes the hits `r` of the eight rays `8 h ..` (bit `k` of `exact`: lane `k`) on
    /// primitive `id` where they are closer, or as close with a lower id: [`Best::offer`]
    /// lane by lane (a settled hit is never past the ray's closest, so "nothing yet" needs no
    /// flag of its own).
    #[inline(always)]
    fn offer(&mut self, closest: &mut [f32; COHERENT], h: usize, exact: u32, r: &TriRays, id: u32) {
        let at = PACKET * h;
        let closest: &mut [f32; PACKET] = (&mut closest[at..at + PACKET]).try_into().expect("eight values");
        let prim: &mut [u32; PACKET] = (&mut self.prim[at..at + PACKET]).try_into().expect("eight values");
        let u: &mut [f32; PACKET] = (&mut self.u[at..at + PACKET]).try_into().expect("eight values");
        let v: &mut [f32; PACKET] = (&mut self.v[at..at + PACKET]).try_into().expect("eight values");
        // Every lane (a loop over the set bits, or operators that do not short-circuit, were
        // 5-10% slower), and separate arrays (eight-lane groups of all four fields: 4%).
        for k in 0..PACKET {
            let take = exact >> k & 1 != 0 && (r.t[k] < closest[k] || (r.t[k] == closest[k] && id < prim[k]));
            closest[k] = if take { r.t[k] } else { closest[k] };
            prim[k] = if take { id } else { prim[k] };
            u[k] = if take { r.u[k] } else { u[k] };
            v[k] = if take { r.v[k] } else { v[k] };
        }
    }

    /// Ray `k`'s closest hit so far (at `t`, its closest) as the scalar tests keep it.
    #[inline(always)]
    fn best(&self, k: usize, t: f32) -> Best {
        Best::found_or_new(t, self.prim[k], self.u[k], self.v[k])
    }

    /// Ray `k`'s closest hit back from the scalar tests.
    #[inline(always)]
    fn keep(&mut self, k: usize, b: &Best, closest: &mut [f32; COHERENT]) {
        (closest[k], self.prim[k], self.u[k], self.v[k]) = b.parts();
    }

    #[inline(always)]
    fn hit(&self, k: usize, t: f32) -> Option<Hit> {
        (self.prim[k] != u32::MAX).then_some(Hit { t, prim: self.prim[k], u: self.u[k], v: self.v[k] })
    }
}

/// The leaf tests of the rays `lanes` of eight `h` (bit `k`: `rays[k]`, lane `k` of `p`,
/// packet ray `8 h + k`) in `blk`, a leaf of `count` primitives, each ray with its own
/// closest hit so far (`found`, `closest`). Where the instruction set has the kernel and the
/// rays share their axes, each triangle is tested for all the rays at once
/// ([`crate::accel::bvh::simd::TriRays`]: the kernel's hits are the scalar test's, and the
/// rays it leaves undecided take the scalar test one by one), in any order (the closest hit
/// does not depend on it).
#[inline(always)]
fn leaf_rays<K: PacketTest>(
    t: Tracer<'_, K>,
    leaf: Leaf<'_>,
    lanes: u32,
    found: &mut Found,
    closest: &mut [f32; COHERENT],
    h: usize,
) {
    let Leaf { blk, count, p, all_shared, rays } = leaf;
    let at = PACKET * h;
    // The kernel reads the axes of lane 0: where not all rays share them, those of the first
    // ray here go there in a copy of the set-up, if these rays share them.
    let copy;
    let (shared, lead_shear) = if all_shared {
        (true, p)
    } else {
        let lead = lanes.trailing_zeros() as usize;
        let mut shared = true;
        let mut rest = lanes;
        while rest != 0 {
            shared &= p.rows[rest.trailing_zeros() as usize] == p.rows[lead];
            rest &= rest - 1;
        }
        copy = PacketShear { rows: [p.rows[lead]; PACKET], ..*p };
        (shared, &copy)
    };
    if shared {
        for lane in 0..count {
            let mut cand = lanes;
            if blk.tri_lanes >> lane & 1 != 0 {
                let Some(r) = t.isa.tri_rays(blk, lane, lead_shear, eighth_of(closest, h)) else {
                    break;
                };
                let exact = t.kept(r.exact & lanes, blk.ids[lane], &r, rays);
                if exact != 0 {
                    found.offer(closest, h, exact, &r, blk.ids[lane]);
                }
                cand &= r.unsure;
            }
            while cand != 0 {
                let k = cand.trailing_zeros() as usize;
                cand &= cand - 1;
                let ray = &rays[k];
                if let Some(hit) = t.lane_hit(blk, lane, &p.sheared(k, ray), ray, closest[at + k])
                    && t.isa.keeps(blk.ids[lane], hit.1, hit.2, ray)
                {
                    let mut b = found.best(at + k, closest[at + k]);
                    b.offer(hit, blk.ids[lane]);
                    found.keep(at + k, &b, closest);
                }
            }
            if lane + 1 == count {
                return;
            }
        }
    }
    // Ray by ray (no kernel, or rays of different axes).
    let mut rest = lanes;
    while rest != 0 {
        let k = rest.trailing_zeros() as usize;
        rest &= rest - 1;
        let mut b = found.best(at + k, closest[at + k]);
        t.closest_in_block(blk, &p.sheared(k, &rays[k]), &rays[k], &mut b);
        found.keep(at + k, &b, closest);
    }
}

/// The rays that may still find a closer hit in a box the packet enters at `entry` (bit `k`:
/// ray `k`): `entry` is at most each ray's own entry distance, so past a ray's closest hit
/// (with the box test's tie margin) its own test would not enter the box.
#[inline(always)]
fn within(entry: f32, closest: &[f32; COHERENT]) -> Rays {
    let mut m = 0;
    for (k, &t) in closest.iter().enumerate() {
        m |= ((entry <= t * TIE_SCALE) as Rays) << k;
    }
    m
}

/// The largest closest-hit distance of the packet (none is NaN).
#[inline(always)]
fn farthest(closest: &[f32; COHERENT]) -> f32 {
    let mut r = f32::NEG_INFINITY;
    for &t in closest {
        if t > r {
            r = t;
        }
    }
    r
}

/// Values `8 h .. 8 h + 8` of a packet's per-ray values.
#[inline(always)]
fn eighth_of(v: &[f32; COHERENT], h: usize) -> &[f32; PACKET] {
    v[PACKET * h..PACKET * (h + 1)].try_into().expect("eight values")
}

/// Rays `8 g ..` of `rays`, at most eight (empty past the end).
#[inline(always)]
fn eighth(rays: &[Ray], g: usize) -> &[Ray] {
    let start = (PACKET * g).min(rays.len());
    &rays[start..(start + PACKET).min(rays.len())]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh::simd::{BoxTest, Scalar};
    use crate::accel::bvh::tree::Node8;
    #[cfg(target_arch = "x86_64")]
    use crate::accel::triangle::{ShearedRay, intersect_sheared};
    use glam::Vec3;

    struct Rng(u64);

    impl Rng {
        /// Uniform in [-0.5, 0.5).
        fn next(&mut self) -> f32 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 40) as f32 / (1u64 << 24) as f32 - 0.5
        }

        fn vec(&mut self) -> Vec3 {
            Vec3::new(self.next(), self.next(), self.next())
        }
    }

    /// Packets of up to 16 rays from one origin around a central direction, cut at the first
    /// ray that may not join: random ones, and rays along an axis (exactly, and tilted by
    /// 1e-30, 1e-8 and 1e-4, so reciprocals of f32::MAX and huge finite ones) from origins on
    /// the planes of the boxes' faces; ranges of every kind.
    fn packets(rng: &mut Rng) -> Vec<Vec<Ray>> {
        let mut out = Vec::new();
        for i in 0..600 {
            let axis_parallel = i % 3 == 0;
            let origin = if axis_parallel { (rng.vec() * 8.0).round() * 0.25 } else { rng.vec() * 6.0 };
            let centre = if axis_parallel {
                let mut d = [0.0; 3];
                d[i % 4 % 3] = if i % 2 == 0 { 1.0 } else { -1.0 };
                Vec3::from(d)
            } else {
                rng.vec() * 3.0 - origin
            };
            let spread = [0.0, 1e-30, 1e-8, 1e-4, 1e-3][i % 5];
            let rays: Vec<Ray> = (0..16)
                .map(|k| {
                    let dir =
                        centre + rng.vec() * spread * centre.length() + rng.vec().abs() * spread * centre.signum();
                    let (tmin, tmax) = [(0.0, f32::INFINITY), (0.0, 1.0 + rng.next()), (0.5, 4.0)][k % 3];
                    Ray { origin, dir, tmin, tmax }
                })
                .collect();
            let brs: Vec<BoxRay> = rays.iter().map(BoxRay::new).collect();
            let n = brs.iter().take_while(|b| Frustum::joins(&brs[0], b)).count();
            if n >= 2 {
                out.push(rays[..n].to_vec());
            }
        }
        out
    }

    /// Eight boxes around the origin, some flat on an axis, one empty.
    #[allow(clippy::needless_range_loop)]
    fn node(rng: &mut Rng) -> Node8 {
        let mut b = [[0f32; WIDTH]; 6];
        for slot in 0..WIDTH {
            let c = (rng.vec() * 8.0).round() * 0.25;
            for axis in 0..3 {
                let half = if (slot + axis) % 5 == 0 { 0.0 } else { (rng.next() + 0.6) * 0.5 };
                b[2 * axis][slot] = c[axis] - half;
                b[2 * axis + 1][slot] = c[axis] + half;
            }
        }
        for (plane, row) in b.iter_mut().enumerate() {
            row[3] = if plane % 2 == 0 { f32::INFINITY } else { f32::NEG_INFINITY };
        }
        let mut node = Node8 { b, child: std::array::from_fn(|k| 100 + k as u32), perm: [0; WIDTH] };
        node.set_order();
        node
    }

    /// The packet's node test enters every box any of its rays' own scalar tests enters, no
    /// later than that ray does, with the packet's largest range; and the AVX2 kernels give
    /// the scalar ones' answers (visit, and eight rays against one child).
    #[test]
    fn the_frustum_enters_every_box_its_rays_enter() {
        let mut rng = Rng(0x2545_f491_4f6c_dd1d);
        #[cfg_attr(not(target_arch = "x86_64"), allow(unused_mut))] // ties: counted by the x86 checks
        let (mut entered, mut tried, mut ties) = (0, 0, 0);
        for rays in packets(&mut rng) {
            let brs: Vec<BoxRay> = rays.iter().map(BoxRay::new).collect();
            let f = Frustum::of(&brs);
            let reach = rays.iter().fold(f32::NEG_INFINITY, |r, ray| r.max(ray.tmax));
            tried += 1;
            for _ in 0..8 {
                let node = node(&mut rng);
                let (mut nodes, mut dists, mut slots) = ([0u32; WIDTH], [0f32; WIDTH], [0u32; WIDTH]);
                let n = Scalar.visit_frustum(&node, &f, reach, &mut nodes, &mut dists, &mut slots) as usize;
                let mut at = [None; WIDTH];
                for j in 0..n {
                    assert_eq!(nodes[j], node.child[slots[j] as usize]);
                    at[slots[j] as usize] = Some(dists[j]);
                }
                for (k, (ray, br)) in rays.iter().zip(&brs).enumerate() {
                    let mut tnear = [0f32; WIDTH];
                    let mut mask = Scalar.test(&node, br, br.octant, ray.tmax, &mut tnear);
                    while mask != 0 {
                        let slot = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        entered += 1;
                        let d = at[slot]
                            .unwrap_or_else(|| panic!("ray {k} of {rays:?} enters slot {slot}, the packet not"));
                        assert!(d <= tnear[slot], "ray {k} enters slot {slot} at {}, the packet at {d}", tnear[slot]);
                    }
                }
                #[cfg(target_arch = "x86_64")]
                if let Some(avx) = crate::cpu::Avx2::new() {
                    let (mut n2, mut d2, mut s2) = ([0u32; WIDTH], [0f32; WIDTH], [0u32; WIDTH]);
                    let m =
                        crate::cpu::with_avx2(avx, |t| t.visit_frustum(&node, &f, reach, &mut n2, &mut d2, &mut s2));
                    assert_eq!(m as usize, n);
                    assert_eq!((&n2[..n], &s2[..n]), (&nodes[..n], &slots[..n]));
                    assert_eq!(d2.map(f32::to_bits)[..n], dists.map(f32::to_bits)[..n]);
                    for group in rays.chunks(PACKET) {
                        let p = Scalar.packet_box_rays(group);
                        for slot in 0..WIDTH {
                            // Each ray's own range, and ranges ending just before its entry
                            // (which only the tie margin lets in).
                            let entry = |k: usize| {
                                let (b, mut tnear) = (p.lane(k), [0f32; WIDTH]);
                                Scalar.test(&node, &b, b.octant, f32::INFINITY, &mut tnear);
                                tnear[slot] * (1.0 - 1.0 / 1048576.0)
                            };
                            for tie in [false, true] {
                                let closest: [f32; PACKET] = std::array::from_fn(|k| match group.get(k) {
                                    Some(r) if !tie => r.tmax,
                                    Some(_) => entry(k),
                                    None => 0.0,
                                });
                                let want = Scalar.slot_rays(&node, slot, &p, f.octant, &closest);
                                let got =
                                    crate::cpu::with_avx2(avx, |t| t.slot_rays(&node, slot, &p, f.octant, &closest));
                                assert_eq!(got, want, "slot {slot} of {group:?} up to {closest:?}");
                                ties += (tie && want != 0) as usize;
                            }
                        }
                    }
                }
            }
        }
        assert!(
            tried > 300 && entered > 10_000 && ties > 1000,
            "too little to compare: {tried} packets, {entered} entries, {ties} ties"
        );
    }

    /// The eight-ray triangle kernel gives every ray the scalar watertight test's answer (each
    /// with its own range): its hits bit for bit, its misses scalar misses, and the rays it
    /// leaves undecided include every scalar hit it did not finish. On fans of triangles
    /// around the rays (shared edges and corners), around the point a ray aims at exactly,
    /// around the rays' origin (a corner there: exact-zero edge functions) and just off it (a
    /// ray leaving the surface: the t bound decides).
    #[test]
    fn the_eight_ray_kernel_gives_the_scalar_answer() {
        #[cfg(target_arch = "x86_64")]
        if let Some(avx) = crate::cpu::Avx2::new() {
            let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
            let (mut exact, mut undecided) = (0, 0);
            for rays in packets(&mut rng) {
                for group in rays.chunks(PACKET) {
                    let p = Scalar.packet_shear(group);
                    if p.rows[..group.len()].iter().any(|r| *r != p.rows[0]) {
                        continue;
                    }
                    let aim = group[0].origin + group[0].dir * (1.0 + rng.next());
                    let scale = (group[0].dir.length() * 0.05).max(1e-3);
                    let grazing = group[0].origin + group[0].dir * (rng.next() * 1e-4);
                    for centre in [aim + rng.vec() * scale * 0.1, aim, group[0].origin, grazing] {
                        let ring: Vec<Vec3> = (0..5).map(|_| centre + rng.vec() * scale).collect();
                        let mut blk = Tri4 { tri_lanes: 0b1111, ids: [0, 1, 2, 3], ..Tri4::default() };
                        for lane in 0..4 {
                            for (c, v) in [centre, ring[lane], ring[lane + 1]].into_iter().enumerate() {
                                for axis in 0..3 {
                                    blk.c[c][axis][lane] = v[axis];
                                }
                            }
                        }
                        for lane in 0..4 {
                            let corner = |c: usize| Vec3::new(blk.c[c][0][lane], blk.c[c][1][lane], blk.c[c][2][lane]);
                            let test = |ray: &Ray, tmax: f32| {
                                intersect_sheared(&ShearedRay::of(ray), ray.tmin, tmax, corner(0), corner(1), corner(2))
                            };
                            // Each ray's own range, and ranges ending exactly at its hit (a
                            // tie with a hit found before).
                            for tie in [false, true] {
                                let closest: [f32; PACKET] = std::array::from_fn(|k| match group.get(k) {
                                    Some(r) if tie => test(r, r.tmax).map_or(r.tmax, |h| h.0),
                                    Some(r) => r.tmax,
                                    None => 0.0,
                                });
                                let got = crate::cpu::with_avx2(avx, |t| t.tri_rays(&blk, lane, &p, &closest))
                                    .expect("the AVX2 kernel");
                                assert_eq!(got.exact & got.unsure, 0);
                                for (k, ray) in group.iter().enumerate() {
                                    let want = test(ray, closest[k]).map(|(t, u, v)| [t, u, v].map(f32::to_bits));
                                    let why = || format!("ray {k} of {group:?}, triangle {lane}, by {closest:?}");
                                    if got.exact >> k & 1 != 0 {
                                        exact += 1;
                                        let mine = [got.t[k], got.u[k], got.v[k]].map(f32::to_bits);
                                        assert_eq!(Some(mine), want, "{}", why());
                                    } else if got.unsure >> k & 1 != 0 {
                                        undecided += want.is_some() as usize;
                                    } else {
                                        assert_eq!(want, None, "{}", why());
                                    }
                                }
                            }
                        }
                    }
                }
            }
            assert!(
                exact > 10_000 && undecided > 5_000,
                "too few hits to compare: {exact} exact, {undecided} undecided"
            );
        }
    }
}
