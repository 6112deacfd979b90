//! Render settings: everything the command line can change about a render.

/// What a pixel shows.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Shading {
    /// The shading normal as n * 0.5 + 0.5 (the seed's debug mode).
    Normals,
    /// Emission plus direct light (depth 1).
    Direct,
    /// Full global illumination up to the maximum depth.
    #[default]
    Global,
}

/// Which light-transport implementation runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum IntegratorKind {
    /// Structure-of-arrays queues through generate, traverse, shade, shadow, compact.
    #[default]
    Wavefront,
    /// The simple recursive single-ray reference.
    Recursive,
}

/// An image-space rectangle to render (`-p X Y DX DY`), in pixels, bottom-left origin.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cell {
    pub x: usize,
    pub y: usize,
    pub w: usize,
    pub h: usize,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    pub width: usize,
    pub height: usize,
    /// Camera rays per pixel (`-s`).
    pub spp: u32,
    /// Samples per area light (`-l`).
    pub light_samples: u32,
    /// Maximum ray depth (`-m`).
    pub max_depth: u32,
    /// Accumulate all bounces (`-o 1`) or show only bounce `max_depth` (`-o 0`).
    pub accumulate: bool,
    /// Adaptive sampling: batch size and tolerance (`-a B T`).
    pub adaptive: Option<(u32, f32)>,
    /// Worker threads; 0 = all cores.
    pub threads: usize,
    /// Uniform hemisphere sampling for direct light instead of light sampling (`-H`).
    pub hemisphere: bool,
    pub shading: Shading,
    /// Russian roulette continue probability.
    pub rr_continue: f32,
    /// Use the BVH (false: brute force, `--no-bvh`).
    pub use_bvh: bool,
    /// How the BVH is built and its leaves stored (`--bvh-build`, `--bvh-leaves`).
    pub bvh: BvhOptions,
    pub seed: u64,
    pub cell: Option<Cell>,
    pub integrator: IntegratorKind,
    /// Render only camera samples with these indices, `[first, end)`, of the `spp` per
    /// pixel (a `--split samples` part); `None`: all of them.
    pub sample_range: Option<(u32, u32)>,
    /// Run every stage and kernel feature even when the scene does not need it
    /// (`--all-effects`, for benchmarking what [`crate::effects::Effects`] saves).
    pub all_effects: bool,
    /// The widest SIMD instruction set the kernels may use (`--isa`); every set gives the
    /// same image, so this only changes speed.
    pub isa: crate::cpu::Isa,
    /// The CS184 course renderer's biased area-light pdf (`--cs184-light-pdf`): see
    /// [`SampledLight::Area`](crate::lights::SampledLight::Area).
    pub cs184_light_pdf: bool,
    /// Combine light sampling with the diffuse BSDF's own sample by multiple importance
    /// sampling (`--no-mis` turns it off: light sampling alone, as the seed).
    pub mis: bool,
    /// Russian roulette by the path's throughput (`--roulette throughput`): continue with
    /// probability `min(1, max component of the throughput)`, as pbrt-v4 does, instead of the
    /// fixed `rr_continue`.
    pub rr_throughput: bool,
    /// The first depth whose continuation plays Russian roulette (`--rr-depth`): 1, the
    /// seed's rule, never stops the first indirect bounce; Mitsuba's default is 5.
    pub rr_depth: u32,
    /// How each pixel's samples spread over the path space (`--sampler`).
    pub sampler: crate::sampling::SamplerKind,
}

/// How the BVH is made: every choice gives the same hits, only time and memory differ.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BvhOptions {
    pub build: BvhBuild,
    pub leaves: LeafLayout,
}

/// How the BVH's tree is built: a trade of build time for trace time.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BvhBuild {
    /// Binned SAH: the tree rays traverse fastest.
    #[default]
    Sah,
    /// Morton order (LBVH): a fraction of the build time for a tree rays take longer in,
    /// for large meshes whose render is short next to their build.
    Fast,
}

/// How BVH leaves hold their triangles: the same hits either way, a trade of memory for
/// speed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LeafLayout {
    /// Packed for large meshes, corners otherwise.
    #[default]
    Auto,
    /// Each leaf holds its triangles' corners (192 bytes a leaf of up to four): no lookup.
    Corners,
    /// Each leaf one record of its distinct vertices and byte indices into them: about two
    /// thirds of the leaf memory, no lookup outside the leaf.
    Packed,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            width: 800,
            height: 600,
            spp: 1,
            light_samples: 1,
            max_depth: 1,
            accumulate: true,
            adaptive: None,
            threads: 0,
            hemisphere: false,
            shading: Shading::Global,
            rr_continue: 0.65,
            use_bvh: true,
            bvh: BvhOptions::default(),
            seed: 0,
            cell: None,
            integrator: IntegratorKind::Wavefront,
            sample_range: None,
            all_effects: false,
            isa: crate::cpu::Isa::default(),
            cs184_light_pdf: false,
            mis: true,
            rr_throughput: false,
            rr_depth: 1,
            sampler: crate::sampling::SamplerKind::Independent,
        }
    }
}

impl Settings {
    /// The sample indices this render takes for each pixel, `[first, end)`.
    pub fn sample_span(&self) -> (u32, u32) {
        let spp = self.spp.max(1);
        match self.sample_range {
            Some((a, b)) => (a.min(spp), b.min(spp)),
            None => (0, spp),
        }
    }

    /// The pixel rectangle to render: the `-p` cell clipped to the image, or the whole image.
    pub fn region(&self) -> Cell {
        match self.cell {
            Some(c) => {
                let x = c.x.min(self.width);
                let y = c.y.min(self.height);
                Cell { x, y, w: c.w.min(self.width - x), h: c.h.min(self.height - y) }
            }
            None => Cell { x: 0, y: 0, w: self.width, h: self.height },
        }
    }
}
