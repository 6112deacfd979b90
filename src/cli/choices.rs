//! The command line's names for the library's choices. clap lives on the binary side, so
//! each library enum gets a twin here that clap can list and parse (with each value's help),
//! and turns into the library's value.

/// A clap value enum mirroring a library enum variant by variant.
macro_rules! choice {
    ($(#[$doc:meta])* $name:ident => $lib:path { $($(#[$vdoc:meta])* $variant:ident),+ $(,)? }) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
        pub enum $name {
            $($(#[$vdoc])* $variant),+
        }

        impl From<$name> for $lib {
            fn from(c: $name) -> $lib {
                match c {
                    $($name::$variant => <$lib>::$variant),+
                }
            }
        }
    };
}

choice! {
    /// What a pixel shows.
    Shading => wavepath::Shading {
        /// The shading normal as n * 0.5 + 0.5 (the seed's debug mode).
        Normals,
        /// Emission plus direct light (depth 1).
        Direct,
        /// Full global illumination up to the maximum depth.
        Global,
    }
}

choice! {
    /// How each pixel's samples spread over the path space.
    Sampler => wavepath::SamplerKind {
        /// Independent hashed numbers (the seed's).
        Independent,
        /// Jittered strata: one sample per cell of each dimension pair's grid.
        Stratified,
        /// Owen-scrambled Sobol points, one scrambled sequence per dimension pair.
        Sobol,
    }
}

choice! {
    /// How the BVH's tree is built (same hits either way).
    BvhBuild => wavepath::BvhBuild {
        /// Binned SAH: the fastest tree to trace.
        Sah,
        /// Morton order: a fraction of the build time, slower rays.
        Fast,
    }
}

choice! {
    /// How the BVH's leaves hold their triangles (same hits either way).
    Leaves => wavepath::LeafLayout {
        /// Packed from 16 million primitives, corners below.
        Auto,
        /// Triangle corners copied into the leaves: no lookup, 192 bytes a leaf.
        Corners,
        /// Each leaf's distinct vertices once, with byte indices: about two thirds.
        Packed,
    }
}

choice! {
    /// Which light-transport implementation runs.
    Integrator => wavepath::IntegratorKind {
        /// Structure-of-arrays queues through generate, traverse, shade, shadow, compact.
        Wavefront,
        /// The simple recursive single-ray reference.
        Recursive,
    }
}

choice! {
    /// How linear radiance becomes 8-bit PNG values.
    Tonemap => wavepath::Tonemap {
        /// The reference renderer's transfer: clamp((sqrt(2) L)^(1/2.2), 0, 1).
        Cs184,
        /// Plain sRGB encoding of clamp(L, 0, 1).
        Srgb,
    }
}

choice! {
    /// Which camera a COLLADA file gets.
    Camera => wavepath::CameraMode {
        /// The CS184 reference placement (see COLLADA-CS184.md): the seed's pictures use it.
        Cs184,
        /// The file's camera exactly as written.
        File,
    }
}

choice! {
    /// How a render is cut into parts.
    Split => wavepath_apps::parts::Split {
        /// Bands of rows, dealt round-robin to the parts: every pixel is rendered by one part
        /// exactly as a single process renders it, so the merge is bit-identical.
        Tiles,
        /// Every part renders every pixel with its own range of sample indices; the merge adds
        /// the per-pixel sums (identical up to floating-point summation order).
        Samples,
    }
}

choice! {
    /// The setting a study varies.
    Sweep => wavepath_apps::study::SweepKind {
        /// Samples per pixel 1, 2, 4, ... up to the cap: one curve.
        Spp,
        /// Samples per area light (-l) 1 ... 64, each over the spp ladder.
        LightSamples,
        /// Uniform hemisphere (-H) against light importance sampling, each over the spp ladder.
        Sampling,
        /// Maximum depth (-m) 1 ... 16, without Russian roulette and with it.
        Depth,
        /// Russian roulette continue probability at the deepest depth.
        Roulette,
        /// Adaptive sampling (-a 64 T) for T from 0.2 to 0.01, against fixed spp.
        Adaptive,
        /// Independent numbers, stratified and Sobol samples, each over the spp ladder.
        Sampler,
        /// MIS of light and BSDF samples against light sampling alone (--no-mis).
        Mis,
    }
}

/// How a CS184 camera's field of view follows `-r` (a command-line choice only: it picks
/// between [`Camera::fit_to`] as loaded and [`Camera::whole_frame`] first).
///
/// [`Camera::fit_to`]: wavepath::Camera::fit_to
/// [`Camera::whole_frame`]: wavepath::Camera::whole_frame
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Fov {
    /// The reference renderer's rule: its 800x600 picture's angle per pixel, so `-r W H` shows
    /// the centre W x H window of that picture (more than it beyond 800x600).
    Cs184,
    /// The whole 800x600 picture at any resolution (its vertical field kept).
    Frame,
}

impl Fov {
    /// Fits `cam` to a `width x height` image by this rule.
    pub fn apply(self, cam: &mut wavepath::Camera, width: usize, height: usize) {
        if self == Fov::Frame {
            cam.whole_frame();
        }
        cam.fit_to(width as f32, height as f32);
    }
}

/// How Russian roulette decides (a command-line choice: it sets `Roulette::kind`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Roulette {
    /// Continue with the fixed probability `--rr` from the second bounce on (the seed's rule).
    Fixed,
    /// Continue with the path's throughput (its largest component, at most 1), as pbrt-v4.
    Throughput,
}

impl From<Roulette> for wavepath::RouletteKind {
    fn from(r: Roulette) -> Self {
        match r {
            Roulette::Fixed => wavepath::RouletteKind::Fixed,
            Roulette::Throughput => wavepath::RouletteKind::Throughput,
        }
    }
}
