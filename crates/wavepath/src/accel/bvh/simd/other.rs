//! Other architectures: the tokens are never constructed there; these impls only keep the
//! generic code compiling.
use super::{BoxRay, BoxTest, PacketTest, Scalar};
use crate::accel::bvh::tree::{Node8, WIDTH};
use crate::cpu::{Avx2, Sse};

impl BoxTest for Sse {
    fn test(self, node: &Node8, r: &BoxRay, oct: u32, tmax: f32, tnear: &mut [f32; WIDTH]) -> u32 {
        Scalar.test(node, r, oct, tmax, tnear)
    }
}

impl BoxTest for Avx2 {
    fn test(self, node: &Node8, r: &BoxRay, oct: u32, tmax: f32, tnear: &mut [f32; WIDTH]) -> u32 {
        Scalar.test(node, r, oct, tmax, tnear)
    }
}

impl PacketTest for Sse {}

impl PacketTest for Avx2 {}
