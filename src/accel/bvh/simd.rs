//! The SIMD box tests. All `unsafe` of the BVH lives here: each kernel can only be reached
//! through a token whose constructor checked the CPU at run time.
use super::boxtest::{BoxRay, BoxTest, EXIT_SCALE};
use super::wide::{Node8, WIDTH};
#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

/// Proof that the CPU has SSE4.1 (constructed only after detection).
#[derive(Clone, Copy, Debug)]
pub struct Sse(());

/// Proof that the CPU has AVX2 and FMA (constructed only after detection).
#[derive(Clone, Copy, Debug)]
pub struct Avx2(());

impl Sse {
    pub fn new() -> Option<Self> {
        #[cfg(target_arch = "x86_64")]
        if is_x86_feature_detected!("sse4.1") {
            return Some(Sse(()));
        }
        None
    }
}

impl Avx2 {
    pub fn new() -> Option<Self> {
        #[cfg(target_arch = "x86_64")]
        if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
            return Some(Avx2(()));
        }
        None
    }
}

#[cfg(target_arch = "x86_64")]
impl BoxTest for Sse {
    #[inline(always)]
    fn test(self, node: &Node8, r: &BoxRay, tmax: f32, tnear: &mut [f32; WIDTH]) -> u32 {
        // SAFETY: `Sse` exists only if SSE4.1 was detected; loads/stores are unaligned ones on
        // in-bounds arrays of 8 f32 at offsets 0 and 4.
        unsafe {
            let mut mask = 0u32;
            for half in 0..2 {
                let o = half * 4;
                let lane = |plane: usize, axis: usize| {
                    let p = _mm_loadu_ps(node.b[plane].as_ptr().add(o));
                    _mm_mul_ps(_mm_sub_ps(p, _mm_set1_ps(r.org[axis])), _mm_set1_ps(r.inv[axis]))
                };
                let t0 = lane(r.near[0], 0);
                let t1 = lane(r.near[1], 1);
                let t2 = lane(r.near[2], 2);
                let u0 = lane(r.far[0], 0);
                let u1 = lane(r.far[1], 1);
                let u2 = lane(r.far[2], 2);
                let enter = _mm_max_ps(_mm_max_ps(_mm_max_ps(t0, t1), t2), _mm_set1_ps(r.tmin));
                let exit = _mm_min_ps(
                    _mm_mul_ps(_mm_min_ps(_mm_min_ps(u0, u1), u2), _mm_set1_ps(EXIT_SCALE)),
                    _mm_set1_ps(tmax),
                );
                _mm_storeu_ps(tnear.as_mut_ptr().add(o), enter);
                mask |= (_mm_movemask_ps(_mm_cmple_ps(enter, exit)) as u32) << o;
            }
            mask
        }
    }
}

#[cfg(target_arch = "x86_64")]
impl BoxTest for Avx2 {
    #[inline(always)]
    fn test(self, node: &Node8, r: &BoxRay, tmax: f32, tnear: &mut [f32; WIDTH]) -> u32 {
        // SAFETY: `Avx2` exists only if AVX2 and FMA were detected; loads/stores are unaligned
        // ones on in-bounds arrays of exactly 8 f32.
        unsafe {
            let lane = |plane: usize, axis: usize| {
                let p = _mm256_loadu_ps(node.b[plane].as_ptr());
                _mm256_mul_ps(_mm256_sub_ps(p, _mm256_set1_ps(r.org[axis])), _mm256_set1_ps(r.inv[axis]))
            };
            let t0 = lane(r.near[0], 0);
            let t1 = lane(r.near[1], 1);
            let t2 = lane(r.near[2], 2);
            let u0 = lane(r.far[0], 0);
            let u1 = lane(r.far[1], 1);
            let u2 = lane(r.far[2], 2);
            let enter = _mm256_max_ps(_mm256_max_ps(_mm256_max_ps(t0, t1), t2), _mm256_set1_ps(r.tmin));
            let exit = _mm256_min_ps(
                _mm256_mul_ps(_mm256_min_ps(_mm256_min_ps(u0, u1), u2), _mm256_set1_ps(EXIT_SCALE)),
                _mm256_set1_ps(tmax),
            );
            _mm256_storeu_ps(tnear.as_mut_ptr(), enter);
            _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(enter, exit)) as u32
        }
    }
}

// Other architectures: the tokens are never constructed; the impls only keep the code generic.
#[cfg(not(target_arch = "x86_64"))]
impl BoxTest for Sse {
    fn test(self, node: &Node8, r: &BoxRay, tmax: f32, tnear: &mut [f32; WIDTH]) -> u32 {
        super::boxtest::Scalar.test(node, r, tmax, tnear)
    }
}

#[cfg(not(target_arch = "x86_64"))]
impl BoxTest for Avx2 {
    fn test(self, node: &Node8, r: &BoxRay, tmax: f32, tnear: &mut [f32; WIDTH]) -> u32 {
        super::boxtest::Scalar.test(node, r, tmax, tnear)
    }
}

/// Runs `f` compiled with AVX2 and FMA enabled, so the inlined kernels use them.
#[cfg(target_arch = "x86_64")]
#[inline]
pub fn with_avx2<R>(tok: Avx2, f: impl FnOnce(Avx2) -> R) -> R {
    #[target_feature(enable = "avx2,fma")]
    fn inner<R>(tok: Avx2, f: impl FnOnce(Avx2) -> R) -> R {
        f(tok)
    }
    // SAFETY: the token proves AVX2 and FMA were detected on this CPU.
    unsafe { inner(tok, f) }
}

#[cfg(not(target_arch = "x86_64"))]
pub fn with_avx2<R>(tok: Avx2, f: impl FnOnce(Avx2) -> R) -> R {
    f(tok)
}
