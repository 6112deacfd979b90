//! The kernels of the traversal, per instruction set: the box tests, the ray set-ups, the leaf
//! filter and the packet kernels, as two traits ([`BoxTest`], [`PacketTest`]) implemented by
//! the plain reference ([`Scalar`], whose bits every SIMD kernel gives) and by the CPU tokens
//! ([`crate::cpu::Sse`], [`crate::cpu::Avx2`]; all in `x86`, the one place that needs the
//! target). A traversal is written once over the traits, as a value implementing
//! [`WithKernels`], and [`Tokens::dispatch`] runs it with the best kernels the tree may use.
mod cut;
#[cfg(not(target_arch = "x86_64"))]
mod other;
mod packet;
mod ray;
mod scalar;
#[cfg(target_arch = "x86_64")]
mod x86;

pub use cut::Cut;
pub use packet::{PACKET, PacketBoxRays, PacketShear, TriRays};
pub use ray::{BoxRay, EXIT_SCALE, Frustum, RootBox, TIE_SCALE, far, near};
#[cfg(target_arch = "x86_64")]
pub use ray::{PLANES, PREFETCH_BYTES};
pub use scalar::Scalar;

use crate::accel::bvh::tree::{Node8, Tri4, WIDTH};
use crate::accel::cutout::Cutouts;
use crate::accel::triangle::ShearedRay;
use crate::cpu::{Avx2, Isa, Sse};
use crate::geometry::Ray;

/// A computation written once over the kernel traits, run by [`Tokens::dispatch`] with the
/// kernels of one instruction set.
pub trait WithKernels {
    type Output;
    /// Runs with the kernels of `isa`. Implementations are `#[inline(always)]`, down to every
    /// kernel they call, so the AVX2 run compiles inside `cpu::with_avx2`'s target-feature
    /// context: a body left out of line there was compiled for the baseline set and ran 2-6x
    /// slower.
    fn run<K: PacketTest>(self, isa: K) -> Self::Output;
}

/// The kernel tokens an [`Isa`] allows on this CPU, made once per tree (not per ray).
#[derive(Clone, Copy, Debug)]
pub struct Tokens {
    sse: Option<Sse>,
    avx2: Option<Avx2>,
}

impl Tokens {
    pub fn of(isa: Isa) -> Tokens {
        Tokens { sse: isa.sse(), avx2: isa.avx2() }
    }

    /// Runs `w` with the best kernels these tokens allow: each instruction set's copy of it is
    /// compiled on its own (AVX2's inlined into one target-feature context), and the choice is
    /// made once per call, never per node.
    #[inline(always)]
    pub fn dispatch<W: WithKernels>(self, w: W) -> W::Output {
        match (self.sse, self.avx2) {
            (_, Some(avx)) => crate::cpu::with_avx2(
                avx,
                #[inline(always)]
                |t| w.run(t),
            ),
            (Some(sse), None) => w.run(sse),
            _ => w.run(Scalar),
        }
    }

    /// [`Tokens::dispatch`] with the alpha test of `cutouts` where the tree has any (the
    /// kernels wrapped in [`Cut`]); without, the bare kernels, so a scene without cutouts
    /// runs exactly the loops it ran before they existed. Decided once per call.
    #[inline(always)]
    pub fn dispatch_cut<W: WithKernels>(self, cutouts: Option<&Cutouts>, w: W) -> W::Output {
        let Some(cutouts) = cutouts else { return self.dispatch(w) };
        match (self.sse, self.avx2) {
            (_, Some(avx)) => crate::cpu::with_avx2(
                avx,
                #[inline(always)]
                |k| w.run(Cut { k, cutouts }),
            ),
            (Some(k), None) => w.run(Cut { k, cutouts }),
            _ => w.run(Cut { k: Scalar, cutouts }),
        }
    }
}

/// [`BoxTest::set_up`], one ray at a time with `isa`'s [`BoxTest::box_ray`].
#[inline(always)]
pub fn set_up_each<B: BoxTest>(isa: B, root: Option<&RootBox>, rays: &[Ray], out: &mut [BoxRay]) -> u32 {
    let mut mask = 0;
    for (i, (r, o)) in rays.iter().zip(out).enumerate() {
        *o = isa.box_ray(r);
        mask |= (root.is_none_or(|root| root.admits(o, r.tmax)) as u32) << i;
    }
    mask
}

/// The per-instruction-set kernels of the traversal.
pub trait BoxTest: Copy {
    /// Whether [`BoxTest::keeps`] may refuse a hit (the kernels of a tree with cutouts): a
    /// constant, so loops compiled without it carry no trace of the test.
    const CUTS: bool = false;

    /// Whether the watertight test's hit on primitive `prim` at barycentrics (`u`, `v`)
    /// counts for `ray` (its alpha test); always, for kernels without cutouts.
    #[inline(always)]
    fn keeps(self, prim: u32, u: f32, v: f32, ray: &Ray) -> bool {
        let _ = (prim, u, v, ray);
        true
    }

    /// Tests the eight child boxes of a node: bit `i` of the result is set when child `i` is
    /// entered at a distance <= `tmax`; its entry distance goes to `tnear[i]`.
    fn test(self, node: &Node8, r: &BoxRay, oct: u32, tmax: f32, tnear: &mut [f32; WIDTH]) -> u32;

    /// [`BoxTest::test`] told the ray's form of the test (`fma` is [`BoxRay::fma`]), so a
    /// caller can compile its loop once per form instead of branching on it per node.
    #[inline(always)]
    fn test_form(self, node: &Node8, r: &BoxRay, oct: u32, fma: bool, tmax: f32, tnear: &mut [f32; WIDTH]) -> u32 {
        debug_assert_eq!(fma, r.fma);
        self.test(node, r, oct, tmax, tnear)
    }

    /// Tests the children of `node` (as [`BoxTest::test`]) and, when two or more are hit,
    /// pushes them in the node's order for the ray's octant, farthest first, so the nearest
    /// is on top: `nodes` their references, `dists` their entry distances (the eight free
    /// stack entries above the top: the SIMD path stores whole vectors). Returns the number
    /// hit and the nearest of them (when only one is hit, it is not pushed). `fma` as in
    /// [`BoxTest::test_form`].
    #[inline(always)]
    fn visit(
        self,
        node: &Node8,
        r: &BoxRay,
        fma: bool,
        tmax: f32,
        nodes: &mut [u32; WIDTH],
        dists: &mut [f32; WIDTH],
    ) -> (u32, u32) {
        debug_assert_eq!(fma, r.fma);
        let oct = r.octant;
        let mut tnear = [0f32; WIDTH];
        let mask = self.test(node, r, oct, tmax, &mut tnear);
        let n = mask.count_ones();
        if n == 1 {
            return (1, node.child[mask.trailing_zeros() as usize]);
        }
        let mut top = 0;
        if n > 1 {
            for k in node.perm {
                let slot = (k >> (3 * oct) & 7) as usize;
                if mask >> slot & 1 != 0 {
                    nodes[top] = node.child[slot];
                    dists[top] = tnear[slot];
                    top += 1;
                }
            }
            return (n, nodes[top - 1]);
        }
        (n, 0)
    }

    /// [`BoxTest::visit`] for a packet's [`Frustum`], with `tmax` the largest closest-hit
    /// distance of its rays: the children some ray of the packet may enter, pushed in the
    /// octant's order with the packet's entry distances and their slots in the node, all of
    /// them (also a single one, so the caller always finds the nearest's distance on the
    /// stack). Returns the number.
    #[inline(always)]
    fn visit_frustum(
        self,
        node: &Node8,
        f: &Frustum,
        tmax: f32,
        nodes: &mut [u32; WIDTH],
        dists: &mut [f32; WIDTH],
        slots: &mut [u32; WIDTH],
    ) -> u32 {
        let mut top = 0;
        for k in node.perm {
            let slot = (k >> (3 * f.octant) & 7) as usize;
            let (enter, exit) = f.span(node, slot);
            if enter <= exit && enter <= tmax * TIE_SCALE {
                nodes[top] = node.child[slot];
                dists[top] = enter;
                slots[top] = slot as u32;
                top += 1;
            }
        }
        top as u32
    }

    /// The set-up of a group of a batch: the rays that may enter `root` at all (bit `i`:
    /// [`RootBox::admits`] by the ray's box-test values; every ray when there is no root
    /// box), and those values in `out` (each [`BoxTest::box_ray`]; only the admitted rays'
    /// are read). The AVX2 path sets up eight rays at once, the same values, and leaves an
    /// eight none of which is admitted unwritten (one ray at a time, the set-up was 7% of a
    /// diffuse ray's instructions).
    #[inline(always)]
    fn set_up(self, root: Option<&RootBox>, rays: &[Ray], out: &mut [BoxRay]) -> u32 {
        set_up_each(self, root, rays, out)
    }

    /// The box-test values of `ray` ([`BoxRay::new`]; the AVX2 path computes the same values
    /// in one register).
    #[inline(always)]
    fn box_ray(self, ray: &Ray) -> BoxRay {
        BoxRay::new(ray)
    }

    /// Asks the cache for the [`PREFETCH_BYTES`] at `p` (a node or leaf block the traversal
    /// will read soon), so several misses overlap instead of following one another. No
    /// effect on results; the reference path does nothing. `p` need not be valid.
    #[inline(always)]
    fn prefetch_at(self, p: *const u8) {
        let _ = p;
    }

    /// The lanes of `lanes` whose triangle in `blk` the scalar watertight test might hit in
    /// `[tmin, tmax]`, given `end` = `range_end(tmax)` (the caller keeps it beside its `tmax`
    /// instead of deriving it at every leaf): a cleared bit is a certain miss. The reference
    /// keeps every lane.
    #[inline(always)]
    fn tri_filter(self, blk: &Tri4, sr: &ShearedRay, tmin: f32, end: f32, lanes: u32) -> u32 {
        let _ = (blk, sr, tmin, end);
        lanes
    }

    /// The whole watertight test of the four triangles of `blk` for one ray (set-up `sr`, range
    /// `[tmin, tmax]`, `end` = `range_end(tmax)`), one triangle per lane: see [`TriRays`] (bit
    /// `l` is triangle `l` here; padding and sphere lanes are the caller's to mask). None where
    /// the instruction set has no such kernel: the caller filters, then tests lane by lane.
    #[inline(always)]
    fn tri_hits(self, blk: &Tri4, sr: &ShearedRay, tmin: f32, tmax: f32, end: f32) -> Option<TriRays> {
        let _ = (blk, sr, tmin, tmax, end);
        None
    }
}

/// The packet kernels of an instruction set, beside its single-ray [`BoxTest`] (the scalar
/// versions here, set up ray by ray; the SIMD ones in `x86`).
pub trait PacketTest: BoxTest {
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

    /// [`BoxTest::tri_filter`] for lane `k` of `p` (ray `ray`) and the range end `end` (its
    /// `tend[k]`, or `range_end` of a closer hit); the SIMD paths start from the set-up's
    /// values instead of deriving them again at every leaf.
    #[inline(always)]
    fn tri_filter_lane(self, blk: &Tri4, p: &PacketShear, k: usize, ray: &Ray, end: f32, lanes: u32) -> u32 {
        self.tri_filter(blk, &p.sheared(k, ray), ray.tmin, end, lanes)
    }

    /// [`BoxTest::tri_hits`] for lane `k` of `p` (ray `ray`), with the closest hit so far at
    /// `tmax` and `end` = `range_end(tmax)`; the SIMD paths start from the set-up's values.
    #[inline(always)]
    fn tri_hits_lane(self, blk: &Tri4, p: &PacketShear, k: usize, ray: &Ray, tmax: f32, end: f32) -> Option<TriRays> {
        self.tri_hits(blk, &p.sheared(k, ray), ray.tmin, tmax, end)
    }

    /// The rays of `p` (bit `k`: lane `k`, live, direction octant `oct`, closest hit so far
    /// at `closest[k]`) whose own unfused box test (the [`Scalar`] one)
    /// enters child `slot` of `node`: one child for eight rays instead of eight children for
    /// one ray.
    #[inline(always)]
    fn slot_rays(self, node: &Node8, slot: usize, p: &PacketBoxRays, oct: u32, closest: &[f32; PACKET]) -> u32 {
        let mut rays = 0;
        for (k, &t) in closest.iter().enumerate() {
            let b = p.lane(k);
            if b.live {
                let mut tnear = [0f32; WIDTH];
                rays |= (Scalar.test(node, &b, oct, t, &mut tnear) >> slot & 1) << k;
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
