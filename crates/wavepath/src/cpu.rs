//! Which SIMD kernels may run: the CPU is checked once, and the answer travels as a value.
//!
//! A kernel compiled for an instruction set can only be reached through a token of that set
//! ([`Sse`], [`Avx2`]), and a token can only be made where detection found the set. The
//! render settings carry an [`Isa`] (`--isa`), which caps the tokens handed out, so one switch
//! forces every kernel (box tests, leaf filter, camera rays, shading lanes, random numbers)
//! onto its scalar path; the scalar paths give the same bits (tested per kernel).

/// The widest instruction set the kernels may use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Isa {
    /// Every kernel on its one-path-at-a-time reference.
    Scalar,
    /// Shading in lanes of plain code (what every CPU runs: NEON on aarch64 through the
    /// compiler), the BVH's kernels scalar.
    Portable,
    Sse,
    Avx2,
    /// What the CPU has ([`Isa::detect`]) resolves to at most this. Only the shading lanes
    /// have AVX-512 kernels (sixteen paths per group); the BVH's run at most AVX2 (8 boxes
    /// fill a 256-bit register).
    #[default]
    Avx512,
}

crate::choice::named!(Isa, "isa", {
    Scalar => "scalar", "no SIMD: every kernel's reference path";
    Portable => "portable", "shading in eight lanes of plain code (every CPU), the BVH scalar";
    Sse => "sse" | "sse4" | "sse4.1", "SSE4.1: four lanes";
    Avx2 => "avx2", "AVX2: eight lanes";
    Avx512 => "avx512", "the best the CPU has: sixteen shading lanes with AVX-512";
});

impl Isa {
    /// The best instruction set this CPU supports.
    pub fn detect() -> Isa {
        Isa::Avx512.effective()
    }

    /// The path that actually runs for this request on this CPU (never one it lacks).
    pub fn effective(self) -> Isa {
        match self {
            Isa::Avx512 if Avx512::new().is_some() => Isa::Avx512,
            Isa::Avx512 | Isa::Avx2 if Avx2::new().is_some() => Isa::Avx2,
            Isa::Avx512 | Isa::Avx2 | Isa::Sse if Sse::new().is_some() => Isa::Sse,
            Isa::Scalar => Isa::Scalar,
            _ => Isa::Portable,
        }
    }

    /// Whether shading runs paths in lanes (portable ones at least): every set but scalar.
    pub fn shades_in_lanes(self) -> bool {
        self.effective() != Isa::Scalar
    }

    /// [`effective`](Self::effective) for kernels whose widest version is AVX2 and that have
    /// no portable lanes (the BVH's).
    pub fn at_most_avx2(self) -> Isa {
        match self.effective() {
            Isa::Avx512 => Isa::Avx2,
            Isa::Portable => Isa::Scalar,
            isa => isa,
        }
    }

    /// The SSE4.1 token, if this request allows it and the CPU has it.
    pub fn sse(self) -> Option<Sse> {
        match self.effective() {
            Isa::Scalar | Isa::Portable => None,
            _ => Sse::new(),
        }
    }

    /// The AVX2 token, if this request allows it and the CPU has it.
    pub fn avx2(self) -> Option<Avx2> {
        match self.effective() {
            Isa::Avx2 | Isa::Avx512 => Avx2::new(),
            _ => None,
        }
    }

    /// The AVX-512 token, if this request allows it and the CPU has it.
    pub fn avx512(self) -> Option<Avx512> {
        match self.effective() {
            Isa::Avx512 => Avx512::new(),
            _ => None,
        }
    }
}

/// Starts loading the cache line holding `x` into every cache level: a hint that never
/// faults and changes no value (nothing off x86-64).
#[inline(always)]
pub fn prefetch<T>(x: &T) {
    prefetch_at((x as *const T).cast::<u8>())
}

/// [`prefetch`] of the cache line at `p`, which need not be a valid address (a node or leaf
/// the traversal may read soon).
#[inline(always)]
pub fn prefetch_at(p: *const u8) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch is a hint that never faults, whatever the address; SSE (which has
    // the instruction) is part of x86-64.
    unsafe {
        std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(p.cast::<i8>())
    };
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

/// Proof that the CPU has SSE4.1 (constructed only after detection).
#[derive(Clone, Copy, Debug)]
pub struct Sse(());

/// Proof that the CPU has AVX2, FMA, BMI1 and POPCNT (constructed only after detection;
/// every AVX2 CPU has the last two, and without them a popcount is five instructions).
#[derive(Clone, Copy, Debug)]
pub struct Avx2(());

/// Proof that the CPU has AVX-512 F, VL, DQ and BW besides everything [`Avx2`] proves
/// (constructed only after detection).
#[derive(Clone, Copy, Debug)]
pub struct Avx512 {
    pub avx2: Avx2,
}

impl Avx512 {
    pub fn new() -> Option<Self> {
        let avx2 = Avx2::new()?;
        #[cfg(target_arch = "x86_64")]
        if is_x86_feature_detected!("avx512f")
            && is_x86_feature_detected!("avx512vl")
            && is_x86_feature_detected!("avx512dq")
            && is_x86_feature_detected!("avx512bw")
        {
            return Some(Avx512 { avx2 });
        }
        let _ = avx2;
        None
    }
}

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
        if is_x86_feature_detected!("avx2")
            && is_x86_feature_detected!("fma")
            && is_x86_feature_detected!("bmi1")
            && is_x86_feature_detected!("popcnt")
        {
            return Some(Avx2(()));
        }
        None
    }
}

/// Runs `f` compiled with AVX2, FMA, BMI1 and POPCNT enabled, so the inlined kernels use them.
#[cfg(target_arch = "x86_64")]
#[inline]
pub fn with_avx2<R>(tok: Avx2, f: impl FnOnce(Avx2) -> R) -> R {
    #[target_feature(enable = "avx2,fma,bmi1,popcnt")]
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
