//! The leaf tests every loop shares: the SIMD filter drops certain misses, then the exact
//! (watertight) test decides each remaining lane, and the alpha test of the kernels
//! ([`BoxTest::keeps`]: always true without cutouts) whether its hit counts; and the closest
//! hit so far.
use super::Tracer;
use crate::accel::bvh::simd::{BoxTest, PacketShear, PacketTest, TriRays};
use crate::accel::bvh::tree::{Tri4, leaf_range};
use crate::accel::sphere;
use crate::accel::triangle::{ShearedRay, intersect_sheared, range_end};
use crate::geometry::{Hit, Ray};
use glam::Vec3;

/// The closest hit so far.
pub struct Best {
    pub t: f32,
    /// `range_end(t)`, the end the leaf filter checks against: kept beside `t` (which changes
    /// at a hit, a few times a ray) rather than derived at every leaf.
    pub end: f32,
    prim: u32,
    u: f32,
    v: f32,
    found: bool,
}

impl Best {
    /// Nothing found yet within `[tmin, tmax]`.
    #[inline(always)]
    pub fn new(tmax: f32) -> Best {
        Best { t: tmax, end: range_end(tmax), prim: u32::MAX, u: 0.0, v: 0.0, found: false }
    }

    /// Takes a hit at `t` (barycentrics `u`, `v`) on primitive `id` if it is closer, or as
    /// close with a lower id: the same closest hit whatever order the hits come in.
    #[inline(always)]
    pub fn offer(&mut self, (t, u, v): (f32, f32, f32), id: u32) {
        if !self.found || t < self.t || (t == self.t && id < self.prim) {
            *self = Best { t, end: range_end(t), prim: id, u, v, found: true };
        }
    }

    /// The hit on `prim` at `t` (`u`, `v`), or nothing found yet within `[tmin, t]` where
    /// `prim` is `u32::MAX`.
    #[inline(always)]
    pub fn found_or_new(t: f32, prim: u32, u: f32, v: f32) -> Best {
        Best { t, end: range_end(t), prim, u, v, found: prim != u32::MAX }
    }

    /// `(t, prim, u, v)`, `prim` `u32::MAX` where nothing was found: what
    /// [`Best::found_or_new`] takes.
    #[inline(always)]
    pub fn parts(&self) -> (f32, u32, f32, f32) {
        (self.t, if self.found { self.prim } else { u32::MAX }, self.u, self.v)
    }

    #[inline(always)]
    pub fn hit(&self) -> Option<Hit> {
        self.found.then_some(Hit { t: self.t, prim: self.prim, u: self.u, v: self.v })
    }
}

/// The ray's shear, set up at its first leaf (many rays never reach one). Not
/// `Option::get_or_insert_with`: its closure was compiled out of line, a call (and a leave
/// of the AVX2 context) at every leaf.
#[inline(always)]
pub fn shear<'a>(sr: &'a mut Option<ShearedRay>, ray: &Ray) -> &'a ShearedRay {
    match sr {
        Some(sr) => sr,
        None => sr.insert(ShearedRay::of(ray)),
    }
}

impl<K: BoxTest> Tracer<'_, K> {
    /// Lanes of a leaf's block that need the scalar test for a range from `tmin` to `end`
    /// (`range_end` of its far end).
    #[inline(always)]
    pub fn block_candidates(self, blk: &Tri4, sr: &ShearedRay, tmin: f32, end: f32) -> u32 {
        self.isa.tri_filter(blk, sr, tmin, end, blk.tri_lanes) | blk.other_lanes
    }

    /// The exact test of lane `lane` of a leaf. Triangle corners come from the block the
    /// filter just read (already in cache); spheres from the tree's sphere list.
    #[inline(always)]
    pub fn lane_hit(self, blk: &Tri4, lane: usize, sr: &ShearedRay, ray: &Ray, tmax: f32) -> Option<(f32, f32, f32)> {
        let bvh = self.bvh;
        if blk.tri_lanes >> lane & 1 != 0 {
            let corner = |k: usize| Vec3::new(blk.c[k][0][lane], blk.c[k][1][lane], blk.c[k][2][lane]);
            intersect_sheared(sr, ray.tmin, tmax, corner(0), corner(1), corner(2))
        } else {
            let (centre, radius) = bvh.spheres[(blk.ids[lane] - bvh.tri_count) as usize];
            let r = Ray { tmax, ..*ray };
            sphere::intersect(&r, centre, radius).map(|t| (t, 0.0, 0.0))
        }
    }

    /// Offers `best` the hits closer than it in a leaf's block, already at hand.
    #[inline(always)]
    pub fn closest_in_block(self, blk: &Tri4, sr: &ShearedRay, ray: &Ray, best: &mut Best) {
        let mut cand = self.block_candidates(blk, sr, ray.tmin, best.end);
        if cand & blk.tri_lanes != 0
            && let Some(r) = self.isa.tri_hits(blk, sr, ray.tmin, best.t, best.end)
        {
            cand = self.offer_hits(blk, &r, ray, best);
        }
        self.offer_lanes(blk, cand, sr, ray, best);
    }

    /// Offers `best` the hits of a leaf's block that the whole SIMD test `r` finished; returns
    /// the lanes it left for the exact test (edge functions of exactly zero, spheres). Their
    /// order does not change the result: `Best` keeps the least (t, id) whatever the order.
    #[inline(always)]
    fn offer_hits(self, blk: &Tri4, r: &TriRays, ray: &Ray, best: &mut Best) -> u32 {
        let mut exact = r.exact & blk.tri_lanes;
        while exact != 0 {
            let lane = exact.trailing_zeros() as usize;
            exact &= exact - 1;
            if self.isa.keeps(blk.ids[lane], r.u[lane], r.v[lane], ray) {
                best.offer((r.t[lane], r.u[lane], r.v[lane]), blk.ids[lane]);
            }
        }
        (r.unsure & blk.tri_lanes) | blk.other_lanes
    }

    /// Offers `best` the exact hits of the lanes `cand` of `blk` that count.
    #[inline(always)]
    fn offer_lanes(self, blk: &Tri4, mut cand: u32, sr: &ShearedRay, ray: &Ray, best: &mut Best) {
        while cand != 0 {
            let lane = cand.trailing_zeros() as usize;
            cand &= cand - 1;
            if let Some(h) = self.lane_hit(blk, lane, sr, ray, best.t)
                && self.isa.keeps(blk.ids[lane], h.1, h.2, ray)
            {
                best.offer(h, blk.ids[lane]);
            }
        }
    }

    /// The rays of `exact` (bit `k`: `rays[k]`, its hit on primitive `id` at `r.u[k]`,
    /// `r.v[k]`) whose hits count: all of them without cutouts.
    #[inline(always)]
    pub fn kept(self, exact: u32, id: u32, r: &TriRays, rays: &[Ray]) -> u32 {
        if !K::CUTS {
            return exact;
        }
        let (mut m, mut out) = (exact, 0);
        while m != 0 {
            let k = m.trailing_zeros() as usize;
            m &= m - 1;
            out |= (self.isa.keeps(id, r.u[k], r.v[k], &rays[k]) as u32) << k;
        }
        out
    }

    /// The lanes of `exact` (bit `l`: triangle `l` of `blk`, its hit at `r.u[l]`, `r.v[l]`)
    /// whose hits count for `ray`: all of them without cutouts.
    #[inline(always)]
    fn kept_lanes(self, blk: &Tri4, exact: u32, r: &TriRays, ray: &Ray) -> u32 {
        if !K::CUTS {
            return exact;
        }
        let (mut m, mut out) = (exact, 0);
        while m != 0 {
            let l = m.trailing_zeros() as usize;
            m &= m - 1;
            out |= (self.isa.keeps(blk.ids[l], r.u[l], r.v[l], ray) as u32) << l;
        }
        out
    }

    /// Whether any primitive of leaf `r` is hit in `[ray.tmin, ray.tmax]`.
    #[inline(always)]
    pub fn leaf_any(self, r: u32, sr: &ShearedRay, ray: &Ray, scratch: &mut Tri4) -> bool {
        let blk = self.bvh.block(leaf_range(r).0, scratch);
        let end = range_end(ray.tmax);
        let mut cand = self.block_candidates(blk, sr, ray.tmin, end);
        if cand & blk.tri_lanes != 0
            && let Some(h) = self.isa.tri_hits(blk, sr, ray.tmin, ray.tmax, end)
        {
            if self.kept_lanes(blk, h.exact & blk.tri_lanes, &h, ray) != 0 {
                return true;
            }
            cand = (h.unsure & blk.tri_lanes) | blk.other_lanes;
        }
        self.any_in_lanes(blk, cand, sr, ray)
    }

    /// Whether the exact test of a lane of `cand` finds a hit that counts in `[ray.tmin,
    /// ray.tmax]`, in lane order up to the first.
    #[inline(always)]
    fn any_in_lanes(self, blk: &Tri4, mut cand: u32, sr: &ShearedRay, ray: &Ray) -> bool {
        while cand != 0 {
            let lane = cand.trailing_zeros() as usize;
            cand &= cand - 1;
            if let Some((_, u, v)) = self.lane_hit(blk, lane, sr, ray, ray.tmax)
                && self.isa.keeps(blk.ids[lane], u, v, ray)
            {
                return true;
            }
        }
        false
    }
}

impl<K: PacketTest> Tracer<'_, K> {
    /// Whether the ray `ray` of lane `k` of `p` hits a primitive of `blk` in its range (`end`
    /// = `range_end(ray.tmax)`): [`Tracer::leaf_any`] from the packet's set-up.
    #[inline(always)]
    pub fn block_any_lane(self, blk: &Tri4, p: &PacketShear, k: usize, ray: &Ray, end: f32) -> bool {
        let mut cand = self.isa.tri_filter_lane(blk, p, k, ray, end, blk.tri_lanes) | blk.other_lanes;
        if cand & blk.tri_lanes != 0
            && let Some(h) = self.isa.tri_hits_lane(blk, p, k, ray, ray.tmax, end)
        {
            if self.kept_lanes(blk, h.exact & blk.tri_lanes, &h, ray) != 0 {
                return true;
            }
            cand = (h.unsure & blk.tri_lanes) | blk.other_lanes;
        }
        cand != 0 && self.any_in_lanes(blk, cand, &p.sheared(k, ray), ray)
    }

    /// Offers `best` the hits of leaf `r` closer than it (`scratch` holds the leaf's block
    /// when the leaves index their corners), with the ray's leaf set-up in lane `k` of `p` (its group's,
    /// made for eight rays at once ahead of their traversals): the filter reads it there, and
    /// only a leaf with a lane left builds the ray's [`ShearedRay`] for the exact test (the
    /// same values, `PacketShear::sheared`).
    #[inline(always)]
    pub fn leaf_closest_lane(self, r: u32, p: &PacketShear, k: usize, ray: &Ray, best: &mut Best, scratch: &mut Tri4) {
        let blk = self.bvh.block(leaf_range(r).0, scratch);
        let mut cand = self.isa.tri_filter_lane(blk, p, k, ray, best.end, blk.tri_lanes) | blk.other_lanes;
        // Most leaves keep no lane; one that keeps a triangle finishes the test of all four in
        // SIMD, which leaves the exact test only the lanes it cannot settle.
        if cand & blk.tri_lanes != 0
            && let Some(h) = self.isa.tri_hits_lane(blk, p, k, ray, best.t, best.end)
        {
            cand = self.offer_hits(blk, &h, ray, best);
        }
        if cand != 0 {
            self.offer_lanes(blk, cand, &p.sheared(k, ray), ray, best);
        }
    }
}
