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
    Scalar,
    Sse,
    /// What the CPU has ([`Isa::detect`]) resolves to at most this.
    #[default]
    Avx2,
}

impl Isa {
    /// The best instruction set this CPU supports.
    pub fn detect() -> Isa {
        Isa::Avx2.effective()
    }

    /// The instruction set a name asks for. `avx512` is accepted and means [`Isa::Avx2`]:
    /// there is no AVX-512 kernel (8 boxes or 8 paths fill one 256-bit register, so 512-bit
    /// lanes would sit half empty), and the best kernels there are run instead.
    pub fn parse(s: &str) -> Option<Isa> {
        match s.trim().to_ascii_lowercase().as_str() {
            "scalar" => Some(Isa::Scalar),
            "sse" | "sse4" | "sse4.1" => Some(Isa::Sse),
            "avx2" | "avx512" => Some(Isa::Avx2),
            _ => None,
        }
    }

    /// The path that actually runs for this request on this CPU (never one it lacks).
    pub fn effective(self) -> Isa {
        match self {
            Isa::Avx2 if Avx2::new().is_some() => Isa::Avx2,
            Isa::Avx2 | Isa::Sse if Sse::new().is_some() => Isa::Sse,
            _ => Isa::Scalar,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Isa::Scalar => "scalar",
            Isa::Sse => "sse",
            Isa::Avx2 => "avx2",
        }
    }

    /// The SSE4.1 token, if this request allows it and the CPU has it.
    pub fn sse(self) -> Option<Sse> {
        match self.effective() {
            Isa::Scalar => None,
            _ => Sse::new(),
        }
    }

    /// The AVX2 token, if this request allows it and the CPU has it.
    pub fn avx2(self) -> Option<Avx2> {
        match self.effective() {
            Isa::Avx2 => Avx2::new(),
            _ => None,
        }
    }
}

/// Proof that the CPU has SSE4.1 (constructed only after detection).
#[derive(Clone, Copy, Debug)]
pub struct Sse(());

/// Proof that the CPU has AVX2, FMA, BMI1 and POPCNT (constructed only after detection;
/// every AVX2 CPU has the last two, and without them a popcount is five instructions).
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
