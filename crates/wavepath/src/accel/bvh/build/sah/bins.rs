//! The bins of a SAH split: one pass over a set's primitives (or a sample of them) and a
//! sweep over the bin boundaries for the cheapest cut.
use super::PrimRef;
use super::sampled::{Largest, SAMPLE};
use crate::accel::bvh::build::binary::{MAX_LEAF, area};
use crate::sampling::splitmix64;
use glam::{Vec3, Vec3A};

/// Bins per axis for the SAH sweep.
pub(super) const BINS: usize = 16;

/// A box that grows (a bin's, or the centroids' of one side of a split); lo and hi side by
/// side, so one cache line holds a bin of one axis.
#[derive(Clone, Copy)]
pub(super) struct Box3 {
    pub(super) lo: Vec3A,
    pub(super) hi: Vec3A,
}

impl Box3 {
    pub(super) const EMPTY: Box3 = Box3 { lo: Vec3A::INFINITY, hi: Vec3A::NEG_INFINITY };

    #[inline]
    pub(super) fn grow(&mut self, lo: Vec3A, hi: Vec3A) {
        self.lo = self.lo.min(lo);
        self.hi = self.hi.max(hi);
    }

    #[inline]
    pub(super) fn union(mut self, o: Box3) -> Box3 {
        self.grow(o.lo, o.hi);
        self
    }

    #[inline]
    pub(super) fn area(&self) -> f32 {
        area(self.lo.into(), self.hi.into())
    }
}

/// Per axis and bin: primitive count and box, gathered in one pass over the primitives (SIMD
/// boxes: one min and one max per axis per primitive). The centroid bounds of the two sides
/// are not binned: the partition sees every centroid anyway and takes them exactly there.
pub(super) struct Bins {
    pub(super) cnt: [[u32; BINS]; 3],
    pub(super) bin: [[Box3; BINS]; 3],
}

/// Sets of bins at least this large are gathered into two interleaved sets (even and odd
/// primitives), merged at the end: neighbours in a mesh mostly fall into the same bin, and
/// one set would make every primitive wait for the previous one's min/max to be stored.
const TWO_SETS_MIN: usize = 64;

impl Bins {
    pub(super) fn empty() -> Bins {
        Bins { cnt: [[0; BINS]; 3], bin: [[Box3::EMPTY; BINS]; 3] }
    }

    #[inline]
    pub(super) fn add(&mut self, r: &PrimRef, clo: Vec3A, scale: Vec3A) {
        let (lo, hi) = (Vec3A::from(r.lo), Vec3A::from(r.hi));
        let k = bins_of(0.5 * (lo + hi), clo, scale);
        for (ax, &k) in k.iter().enumerate() {
            self.cnt[ax][k] += 1;
            self.bin[ax][k].grow(lo, hi);
        }
    }

    #[inline]
    pub(super) fn merge(&mut self, o: &Bins) {
        for ax in 0..3 {
            for k in 0..BINS {
                self.cnt[ax][k] += o.cnt[ax][k];
                self.bin[ax][k] = self.bin[ax][k].union(o.bin[ax][k]);
            }
        }
    }

    /// Empties the bins, in place (building a new set moved it through `memcpy` twice).
    #[inline]
    pub(super) fn clear(&mut self) {
        for ax in 0..3 {
            self.cnt[ax] = [0; BINS];
            for b in &mut self.bin[ax] {
                *b = Box3::EMPTY;
            }
        }
    }

    /// Fills these bins with `refs` (`odd`: scratch for the second set). Bins are filled in
    /// place, not returned: a set is 1.7 KB, and making and moving one per split was a
    /// twentieth of the build's instructions, in `memcpy`.
    #[inline]
    pub(super) fn gather(&mut self, refs: &[PrimRef], clo: Vec3, scale: Vec3, odd: &mut Bins) {
        let (clo, scale) = (Vec3A::from(clo), Vec3A::from(scale));
        self.clear();
        if refs.len() < TWO_SETS_MIN {
            refs.iter().for_each(|r| self.add(r, clo, scale));
            return;
        }
        odd.clear();
        let mut pairs = refs.chunks_exact(2);
        for p in &mut pairs {
            self.add(&p[0], clo, scale);
            odd.add(&p[1], clo, scale);
        }
        pairs.remainder().iter().for_each(|r| self.add(r, clo, scale));
        self.merge(odd);
    }

    /// The cheapest split of `n` primitives: (SAH cost, axis, first bin on the right), the
    /// first minimum in axis then bin order; infinite when every split leaves a side empty
    /// (a flat axis has all its primitives in bin 0, so it offers none).
    #[inline]
    pub(super) fn cheapest(&self, n: usize) -> (f32, usize, usize) {
        let mut best = (f32::INFINITY, 0usize, 0usize);
        for ax in 0..3 {
            let (cnt, bin) = (&self.cnt[ax], &self.bin[ax]);
            // Only occupied bins are visited: an empty bin's boundary splits the primitives
            // as the one below it does (the same cost, and the sweep keeps the first of
            // equal costs), so small sets, which fill few of the bins, sweep few positions.
            let occupied = (0..BINS).fold(0u32, |m, i| m | ((cnt[i] != 0) as u32) << i);
            // Right-to-left: the cost of the right side from each occupied bin on.
            let mut right_cost = [0f32; BINS];
            let (mut side, mut c, mut m) = (Box3::EMPTY, 0u32, occupied);
            while m != 0 {
                let i = 31 - m.leading_zeros() as usize;
                m &= !(1 << i);
                side = side.union(bin[i]);
                c += cnt[i];
                right_cost[i] = side.area() * blocks(c);
            }
            let (mut side, mut c, mut m) = (Box3::EMPTY, 0u32, occupied);
            while m != 0 {
                let i = m.trailing_zeros() as usize;
                m &= m - 1;
                side = side.union(bin[i]);
                c += cnt[i];
                if c as usize == n {
                    break;
                }
                // The right side starts at the next occupied bin; its boundary is `i + 1`.
                let cost = side.area() * blocks(c) + right_cost[m.trailing_zeros() as usize];
                if cost < best.0 {
                    best = (cost, ax, i + 1);
                }
            }
        }
        best
    }

    /// Fills these bins with [`SAMPLE`] of `refs`: one from each of [`SAMPLE`] equal runs, at
    /// a place hashed from the run's index (not every `k`-th: a mesh's order can repeat with a
    /// period, a grid's rows, and a fixed stride would then see one column of it).
    #[inline]
    pub(super) fn gather_sample(&mut self, refs: &[PrimRef], big: &Largest, clo: Vec3, scale: Vec3, odd: &mut Bins) {
        let (clo, scale) = (Vec3A::from(clo), Vec3A::from(scale));
        let run = refs.len() / SAMPLE;
        debug_assert!(run >= 2);
        let pick = |i: usize| &refs[i * run + (splitmix64(i as u64) % run as u64) as usize];
        self.clear();
        odd.clear();
        for i in (0..SAMPLE).step_by(2) {
            self.add(pick(i), clo, scale);
            odd.add(pick(i + 1), clo, scale);
        }
        big.refs.iter().for_each(|(_, r)| self.add(r, clo, scale));
        self.merge(odd);
    }

    /// Box of the primitives in bins `range` of axis `ax`.
    #[inline]
    pub(super) fn union(&self, ax: usize, range: std::ops::Range<usize>) -> Box3 {
        self.bin[ax][range].iter().fold(Box3::EMPTY, |a, &b| a.union(b))
    }
}

/// SAH weight of `c` primitives: the leaf blocks of [`MAX_LEAF`] they fill (the SIMD filter
/// tests a block at about the cost of one primitive).
#[inline]
pub(super) fn blocks(c: u32) -> f32 {
    c.div_ceil(MAX_LEAF as u32) as f32
}

/// The bins of centroid `c` on the three axes (the same arithmetic for gathering and
/// partitioning, so both put every primitive in the same bin).
#[inline]
pub(super) fn bins_of(c: Vec3A, clo: Vec3A, scale: Vec3A) -> [usize; 3] {
    // Clamped in SIMD, then truncated by one SSE2 conversion of all lanes (glam's casts go
    // lane by lane with saturation checks, a tenth of the build). A NaN (0 x inf on a flat
    // axis) is clamped to bin 0.
    let x = ((c - clo) * scale).max(Vec3A::ZERO).min(Vec3A::splat(BINS as f32 - 1.0));
    #[cfg(target_arch = "x86_64")]
    // SAFETY: SSE2 is part of every x86-64 target.
    let k: [i32; 4] = bytemuck::cast(unsafe { std::arch::x86_64::_mm_cvttps_epi32(x.into()) });
    #[cfg(not(target_arch = "x86_64"))]
    let k = [x.x as i32, x.y as i32, x.z as i32];
    [k[0] as usize, k[1] as usize, k[2] as usize]
}
