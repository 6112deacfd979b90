//! The one place a lane kernel's width and instructions are chosen. Every kernel in lanes
//! (the wavefront's Lambertian hits, other materials, escaped paths and camera rays; the light
//! subpaths' starts) is written once, generic over its lane count, as a [`LaneKernel`];
//! [`ShadeWidth::dispatch`] runs it at the width the render chose (the wavefront's `Lanes`),
//! compiled for that width's instructions, as the BVH's `Tokens::dispatch` runs its traversal
//! loops. Below both integrators that use it, so neither reaches into the other for it.

#[cfg(target_arch = "x86_64")]
use crate::cpu::{Avx2, Avx512};
use crate::sampling::rng8::{Hasher, Portable};

/// How many paths a shading group holds, and what its code is compiled for.
#[derive(Clone, Copy, Debug)]
pub enum ShadeWidth {
    /// Eight lanes in plain code, vectorised by the compiler for the target's baseline
    /// (NEON on aarch64, SSE2 on x86-64): the lane kernels on every CPU.
    Portable,
    /// Eight lanes in 256-bit registers.
    #[cfg(target_arch = "x86_64")]
    Eight(Avx2),
    /// Sixteen lanes in 512-bit registers.
    #[cfg(target_arch = "x86_64")]
    Sixteen(Avx512),
}

/// A shading kernel over groups of `L` paths, drawing its random numbers with `h`.
pub trait LaneKernel {
    fn run<H: Hasher, const L: usize>(self, h: H);
}

impl ShadeWidth {
    /// The widest shading this CPU and instruction-set cap allow.
    pub fn best(isa: crate::cpu::Isa) -> ShadeWidth {
        #[cfg(target_arch = "x86_64")]
        if let Some(avx512) = isa.avx512() {
            return ShadeWidth::Sixteen(avx512);
        } else if let Some(avx2) = isa.avx2() {
            return ShadeWidth::Eight(avx2);
        }
        let _ = isa;
        ShadeWidth::Portable
    }

    /// Every width this CPU has, the portable one first (for tests that compare them all).
    pub fn all() -> Vec<ShadeWidth> {
        #[allow(unused_mut)]
        let mut widths = vec![ShadeWidth::Portable];
        #[cfg(target_arch = "x86_64")]
        {
            widths.extend(Avx2::new().map(ShadeWidth::Eight));
            widths.extend(Avx512::new().map(ShadeWidth::Sixteen));
        }
        widths
    }

    /// Runs `k` at this width.
    #[inline]
    pub fn dispatch(self, k: impl LaneKernel) {
        match self {
            ShadeWidth::Portable => k.run::<Portable, 8>(Portable),
            // SAFETY: the token proves the CPU has the instruction sets `eight` enables.
            #[cfg(target_arch = "x86_64")]
            ShadeWidth::Eight(avx2) => unsafe { eight(avx2, k) },
            // SAFETY: as above, for `sixteen`.
            #[cfg(target_arch = "x86_64")]
            ShadeWidth::Sixteen(avx512) => unsafe { sixteen(avx512, k) },
        }
    }
}

/// The kernel compiled with exactly the features it uses: run through `cpu::with_avx2` (which
/// also enables BMI1 and POPCNT, for the BVH) the diffuse kernel compiled to 4.7% more
/// instructions (callgrind, CBspheres_lambertian 128x96, shade stage).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn eight<K: LaneKernel>(avx: Avx2, k: K) {
    k.run::<Avx2, 8>(avx)
}

/// Sixteen paths per group: the lane-parallel loops fill 512-bit registers.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,fma")]
fn sixteen<K: LaneKernel>(avx: Avx512, k: K) {
    k.run::<Avx2, 16>(avx.avx2)
}
