//! The plain reference path of every kernel: the scalar twin the SIMD kernels give the bits
//! of (the trait defaults are its packet kernels, set up ray by ray).
use super::{BoxRay, BoxTest, EXIT_SCALE, PacketTest, TIE_SCALE, far, near};
use crate::accel::bvh::tree::{Node8, WIDTH};

/// The plain reference path.
#[derive(Clone, Copy, Debug)]
pub struct Scalar;

impl BoxTest for Scalar {
    #[inline(always)]
    fn test(self, node: &Node8, r: &BoxRay, oct: u32, tmax: f32, tnear: &mut [f32; WIDTH]) -> u32 {
        let mut mask = 0;
        for (i, tn) in tnear.iter_mut().enumerate() {
            let t0 = (node.b[near(oct, 0)][i] - r.org[0]) * r.inv[0];
            let t1 = (node.b[near(oct, 1)][i] - r.org[1]) * r.inv[1];
            let t2 = (node.b[near(oct, 2)][i] - r.org[2]) * r.inv[2];
            let u0 = (node.b[far(oct, 0)][i] - r.org[0]) * r.inv[0];
            let u1 = (node.b[far(oct, 1)][i] - r.org[1]) * r.inv[1];
            let u2 = (node.b[far(oct, 2)][i] - r.org[2]) * r.inv[2];
            // Same operation order as the SIMD paths, so every path visits the same nodes.
            let enter = t0.max(t1).max(t2).max(r.tmin);
            let exit = (u0.min(u1).min(u2) * EXIT_SCALE).min(tmax * TIE_SCALE);
            *tn = enter;
            mask |= ((enter <= exit) as u32) << i;
        }
        mask
    }
}

impl PacketTest for Scalar {}
