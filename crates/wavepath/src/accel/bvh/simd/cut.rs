//! The kernels of an instruction set with the alpha test of a scene's cut triangles
//! ([`Cutouts`]): every kernel is the wrapped one's, and only [`BoxTest::keeps`] differs. A
//! tree without cutouts is traced with the bare kernels, whose `keeps` is the constant
//! `true`: their loops compile as if the test did not exist.
use super::{BoxRay, BoxTest, Frustum, PACKET, PacketBoxRays, PacketShear, PacketTest, RootBox, TriRays};
use crate::accel::bvh::tree::{Node8, Tri4, WIDTH};
use crate::accel::cutout::Cutouts;
use crate::accel::triangle::ShearedRay;
use crate::geometry::Ray;

/// The kernels `K` with the alpha test of `cutouts`.
#[derive(Clone, Copy)]
pub struct Cut<'a, K> {
    pub k: K,
    pub cutouts: &'a Cutouts,
}

impl<K: BoxTest> BoxTest for Cut<'_, K> {
    const CUTS: bool = true;

    #[inline(always)]
    fn keeps(self, prim: u32, u: f32, v: f32, ray: &Ray) -> bool {
        self.cutouts.keeps(prim, u, v, ray)
    }

    #[inline(always)]
    fn test(self, node: &Node8, r: &BoxRay, oct: u32, tmax: f32, tnear: &mut [f32; WIDTH]) -> u32 {
        self.k.test(node, r, oct, tmax, tnear)
    }

    #[inline(always)]
    fn test_form(self, node: &Node8, r: &BoxRay, oct: u32, fma: bool, tmax: f32, tnear: &mut [f32; WIDTH]) -> u32 {
        self.k.test_form(node, r, oct, fma, tmax, tnear)
    }

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
        self.k.visit(node, r, fma, tmax, nodes, dists)
    }

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
        self.k.visit_frustum(node, f, tmax, nodes, dists, slots)
    }

    #[inline(always)]
    fn set_up(self, root: Option<&RootBox>, rays: &[Ray], out: &mut [BoxRay]) -> u32 {
        self.k.set_up(root, rays, out)
    }

    #[inline(always)]
    fn box_ray(self, ray: &Ray) -> BoxRay {
        self.k.box_ray(ray)
    }

    #[inline(always)]
    fn prefetch_at(self, p: *const u8) {
        self.k.prefetch_at(p)
    }

    #[inline(always)]
    fn tri_filter(self, blk: &Tri4, sr: &ShearedRay, tmin: f32, end: f32, lanes: u32) -> u32 {
        self.k.tri_filter(blk, sr, tmin, end, lanes)
    }

    #[inline(always)]
    fn tri_hits(self, blk: &Tri4, sr: &ShearedRay, tmin: f32, tmax: f32, end: f32) -> Option<TriRays> {
        self.k.tri_hits(blk, sr, tmin, tmax, end)
    }
}

impl<K: PacketTest> PacketTest for Cut<'_, K> {
    #[inline(always)]
    fn packet_box_rays(self, rays: &[Ray]) -> PacketBoxRays {
        self.k.packet_box_rays(rays)
    }

    #[inline(always)]
    fn test_lane(self, node: &Node8, p: &PacketBoxRays, k: usize) -> u32 {
        self.k.test_lane(node, p, k)
    }

    #[inline(always)]
    fn packet_shear(self, rays: &[Ray]) -> PacketShear {
        self.k.packet_shear(rays)
    }

    #[inline(always)]
    fn tri_filter_lane(self, blk: &Tri4, p: &PacketShear, k: usize, ray: &Ray, end: f32, lanes: u32) -> u32 {
        self.k.tri_filter_lane(blk, p, k, ray, end, lanes)
    }

    #[inline(always)]
    fn tri_hits_lane(self, blk: &Tri4, p: &PacketShear, k: usize, ray: &Ray, tmax: f32, end: f32) -> Option<TriRays> {
        self.k.tri_hits_lane(blk, p, k, ray, tmax, end)
    }

    #[inline(always)]
    fn slot_rays(self, node: &Node8, slot: usize, p: &PacketBoxRays, oct: u32, closest: &[f32; PACKET]) -> u32 {
        self.k.slot_rays(node, slot, p, oct, closest)
    }

    #[inline(always)]
    fn tri_rays(self, blk: &Tri4, lane: usize, p: &PacketShear, closest: &[f32; PACKET]) -> Option<TriRays> {
        self.k.tri_rays(blk, lane, p, closest)
    }
}
