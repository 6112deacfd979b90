//! Render settings: everything the command line can change about a render.

use crate::choice::{Choice, UnknownName};
use crate::cs184::Dialect;
use crate::scene::{Camera, FovRule};

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

crate::choice::named!(Shading, "shading", {
    Normals => "normals", "the shading normal as n * 0.5 + 0.5 (the seed's debug mode)";
    Direct => "direct", "emission plus direct light (depth 1)";
    Global => "global", "full global illumination up to the maximum depth";
});

impl Shading {
    /// What a pixel shows when the caller names no shading: direct light alone at depth 1
    /// (and 0), global illumination beyond. The command line and the Python package both
    /// follow this rule, so the same depth gives the same image through either.
    pub fn for_depth(max_depth: u32) -> Shading {
        if max_depth > 1 { Shading::Global } else { Shading::Direct }
    }
}

/// Which light-transport implementation runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum IntegratorKind {
    /// The scene's choice ([`Effects`](crate::effects::Effects)' integrator rule): the path
    /// tracer, or path+light where the scene has caustics it can trace. Resolved when a
    /// render's plan is made; a plan's settings never hold it.
    #[default]
    Auto,
    /// Structure-of-arrays queues through generate, traverse, shade, shadow, compact.
    Wavefront,
    /// The simple recursive single-ray reference.
    Recursive,
    /// Light tracing alone: paths from the lights, splatted where the camera sees them.
    Light,
    /// Bidirectional path tracing: camera and light subpaths joined by every connection.
    Bdpt,
    /// Vertex connection and merging: BDPT plus merging with light vertices nearby.
    Vcm,
    /// The path tracer plus light tracing, weighted by MIS, without connections.
    PathLight,
}

crate::choice::named!(IntegratorKind, "integrator", {
    Auto => "auto", "the scene's choice: path+light where mirrors or glass carry light from emissive triangles (caustics), the path tracer otherwise";
    Wavefront => "wavefront" | "path", "the path tracer: structure-of-arrays queues through generate, traverse, shade, shadow, compact";
    Recursive => "recursive", "the path tracer's simple recursive single-ray reference";
    Light => "light", "light tracing alone: paths from the lights splatted onto the film (a reference for caustics)";
    Bdpt => "bdpt", "bidirectional path tracing: camera and light paths joined by every connection, weighted by MIS";
    Vcm => "vcm", "vertex connection and merging: bdpt plus merging with nearby light vertices (caustics seen in mirrors and glass)";
    PathLight => "path+light" | "pt+lt", "the path tracer's strategies plus light tracing, weighted by MIS (caustics on diffuse surfaces; no connections)";
});

/// An image-space rectangle to render (`-p X Y DX DY`), in pixels, bottom-left origin.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cell {
    pub x: usize,
    pub y: usize,
    pub w: usize,
    pub h: usize,
}

/// Everything about a render that is not the scene, in groups a caller changes together.
///
/// Start from [`Settings::for_scene`] (the defaults of the scene's dialect) rather than
/// [`Settings::default`], so that a library caller renders a file as the command line does.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Settings {
    /// The picture: its size and the part of it to render.
    pub image: ImageSettings,
    /// How many samples each pixel takes and how they spread.
    pub sampling: Sampling,
    /// What a path does at each vertex: depth, direct-light strategy, roulette.
    pub paths: PathRules,
    /// How rays find their hits (same hits either way; only time and memory differ).
    pub accel: AccelSettings,
    /// Where and how the work runs (same image whatever is chosen, except the integrator,
    /// which is the same in expectation).
    pub execution: Execution,
    /// The CS184 course renderer's deliberate deviations, opt-in (`crate::cs184` lists all
    /// the course's rules).
    pub cs184: Cs184Compat,
}

/// The picture's size and the part of it to render.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImageSettings {
    pub width: usize,
    pub height: usize,
    /// Only this rectangle of the image (`-p`); `None`: all of it.
    pub cell: Option<Cell>,
    /// How a CS184 camera's field of view follows the image size (`--fov`). A setting of the
    /// image, not of the scene: the render plan fits a copy of the scene's camera by it
    /// ([`ImageSettings::camera`]), so one scene renders at any size and rule unchanged.
    pub fov: FovRule,
    /// Output variables kept beside the picture (`--aov`); none by default, and then the
    /// render records nothing more.
    pub aovs: AovSet,
}

impl Default for ImageSettings {
    fn default() -> Self {
        ImageSettings { width: 800, height: 600, cell: None, fov: FovRule::default(), aovs: AovSet::NONE }
    }
}

impl ImageSettings {
    /// The camera this image sees through: `camera` (the scene's) fitted to the image's size
    /// by its rule. Every render-time reader of the camera goes through this, so they all
    /// see the same fields of view.
    pub fn camera(&self, camera: &Camera) -> Camera {
        camera.fitted(self.fov, self.width, self.height)
    }
}

/// How many samples a pixel takes and how they spread over the path space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sampling {
    /// Camera rays per pixel (`-s`).
    pub spp: u32,
    /// Samples per area light (`-l`).
    pub light_samples: u32,
    /// Adaptive sampling: batch size and tolerance (`-a B T`).
    pub adaptive: Option<(u32, f32)>,
    /// How each pixel's samples spread over the path space (`--sampler`).
    pub sampler: crate::sampling::SamplerKind,
    /// Every random number is a function of (seed, pixel, sample, depth): the same seed gives
    /// the same image.
    pub seed: u64,
    /// Render only camera samples with these indices, `[first, end)`, of the `spp` per
    /// pixel (a `--split samples` part); `None`: all of them.
    pub sample_range: Option<(u32, u32)>,
    /// Light subpaths per pixel and sample for light tracing and `path+light`
    /// (`--light-paths`); `None`: each integrator's default. BDPT and VCM trace one per
    /// pixel, since a camera path joins the light subpath of its own pixel.
    pub light_paths: Option<f32>,
}

impl Default for Sampling {
    fn default() -> Self {
        Sampling {
            spp: 1,
            light_samples: 1,
            adaptive: None,
            sampler: crate::sampling::SamplerKind::Independent,
            seed: 0,
            sample_range: None,
            light_paths: None,
        }
    }
}

/// The rules of light transport a path follows: what a pixel shows, how deep paths go, how
/// direct light is estimated and when a path stops.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathRules {
    pub shading: Shading,
    /// Maximum ray depth (`-m`).
    pub max_depth: u32,
    /// Accumulate all bounces (`-o 1`) or show only bounce `max_depth` (`-o 0`).
    pub accumulate: bool,
    /// Uniform hemisphere sampling for direct light instead of light sampling (`-H`).
    pub hemisphere: bool,
    /// Combine light sampling with the diffuse BSDF's own sample by multiple importance
    /// sampling (`--no-mis` turns it off: light sampling alone, as the seed).
    pub mis: bool,
    /// When a path may stop early (Russian roulette).
    pub roulette: Roulette,
}

impl Default for PathRules {
    fn default() -> Self {
        PathRules {
            shading: Shading::Global,
            max_depth: 1,
            accumulate: true,
            hemisphere: false,
            mis: true,
            roulette: Roulette::default(),
        }
    }
}

/// Russian roulette: a path continues past a vertex with some probability and is weighted
/// by its inverse, which bounds the work of long paths without biasing the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Roulette {
    /// How the continue probability is chosen (`--roulette`).
    pub kind: RouletteKind,
    /// The continue probability of [`RouletteKind::Fixed`] (`--rr`).
    pub continue_prob: f32,
    /// The first depth whose continuation plays roulette (`--rr-depth`): 1, the seed's rule,
    /// never stops the first indirect bounce; Mitsuba's default is 5.
    pub start_depth: u32,
}

impl Default for Roulette {
    /// The CS184 rule ([`crate::cs184`]): a fixed 0.65 from depth 1.
    fn default() -> Self {
        Roulette {
            kind: RouletteKind::Fixed,
            continue_prob: crate::cs184::RR_CONTINUE,
            start_depth: crate::cs184::RR_START_DEPTH,
        }
    }
}

/// How the roulette's continue probability is chosen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RouletteKind {
    /// The fixed [`Roulette::continue_prob`] at every depth (the seed's rule).
    #[default]
    Fixed,
    /// `min(1, max component of the path's throughput)`, as pbrt-v4 does: dim paths stop
    /// sooner, bright ones never.
    Throughput,
}

impl RouletteKind {
    /// The depth this kind starts at unless told otherwise: the fixed rule from the first
    /// indirect bounce (the seed's), the throughput rule from depth 5, where paths have lost
    /// enough throughput for it to stop dim ones (Mitsuba's default).
    pub fn default_start_depth(self) -> u32 {
        match self {
            RouletteKind::Fixed => crate::cs184::RR_START_DEPTH,
            RouletteKind::Throughput => 5,
        }
    }
}

crate::choice::named!(RouletteKind, "roulette", {
    Fixed => "fixed", "continue with the fixed probability --rr (the seed's rule)";
    Throughput => "throughput", "continue with the path's throughput (its largest component, at most 1), as pbrt-v4";
});

/// How rays find their hits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AccelSettings {
    /// Use the BVH (false: brute force, `--no-bvh`, the reference the BVH is tested against).
    pub use_bvh: bool,
    /// How the BVH is built and its leaves stored (`--bvh-build`, `--bvh-leaves`).
    pub bvh: BvhOptions,
}

impl Default for AccelSettings {
    fn default() -> Self {
        AccelSettings { use_bvh: true, bvh: BvhOptions::default() }
    }
}

/// Where and how the work runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Execution {
    /// Worker threads; 0 = all cores. Images do not depend on it.
    pub threads: usize,
    pub integrator: IntegratorKind,
    /// The widest SIMD instruction set the kernels may use (`--isa`); every set gives the
    /// same image, so this only changes speed.
    pub isa: crate::cpu::Isa,
    /// Run every stage and kernel feature even when the scene does not need it
    /// (`--all-effects`, for benchmarking what [`crate::effects::Effects`] saves).
    pub all_effects: bool,
}

/// Opt-in deviations of the CS184 course renderer that change the estimate (the dialect's
/// defaults and the course's file conventions are elsewhere: [`crate::cs184`] lists them).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Cs184Compat {
    /// The course renderer's biased area-light pdf (`--cs184-light-pdf`): see
    /// [`crate::cs184::area_light_pdf_weight`].
    pub light_pdf: bool,
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

crate::choice::named!(BvhBuild, "bvh build", {
    Sah => "sah", "binned SAH: the fastest tree to trace";
    Fast => "fast", "Morton order: a fraction of the build time, slower rays";
});

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

crate::choice::named!(LeafLayout, "bvh leaves", {
    Auto => "auto", "packed from 16 million primitives, corners below";
    Corners => "corners", "triangle corners copied into the leaves: no lookup, 192 bytes a leaf";
    Packed => "packed", "each leaf's distinct vertices once, with byte indices: about two thirds";
});

impl Settings {
    /// The defaults for a scene of `dialect`: a CS184 scene keeps the seed's pictures (fixed
    /// roulette from depth 1, independent random numbers); any other file gets the
    /// estimator and pattern that reached a given error soonest in the end-to-end harness
    /// (docs/decisions.md, "Russian roulette" and "Samplers"): throughput roulette from
    /// depth 5 and Sobol points. The dialect's other rules: [`crate::cs184`].
    pub fn for_dialect(dialect: Dialect) -> Settings {
        let mut s = Settings::default();
        match dialect {
            Dialect::Cs184 => {
                s.paths.roulette.kind = RouletteKind::Fixed;
                s.sampling.sampler = crate::cs184::SAMPLER;
            }
            Dialect::Standard => {
                s.paths.roulette.kind = RouletteKind::Throughput;
                s.sampling.sampler = crate::sampling::SamplerKind::Sobol;
            }
        }
        s.paths.roulette.start_depth = s.paths.roulette.kind.default_start_depth();
        s
    }

    /// The defaults for `scene`: [`Settings::for_dialect`] of the dialect its loader
    /// recorded. The command line starts here and applies its flags on top.
    pub fn for_scene(scene: &crate::scene::Scene) -> Settings {
        Settings::for_dialect(scene.source.dialect)
    }

    /// These settings with `change` applied: `base.with(|s| s.sampling.spp = 4)`, for the
    /// renders that differ from a base in a field or two (a struct update would have to
    /// spell out the field's group).
    pub fn with(mut self, change: impl FnOnce(&mut Settings)) -> Settings {
        change(&mut self);
        self
    }

    /// The sample indices this render takes for each pixel, `[first, end)`.
    pub fn sample_span(&self) -> (u32, u32) {
        let spp = self.sampling.spp.max(1);
        match self.sampling.sample_range {
            Some((a, b)) => (a.min(spp), b.min(spp)),
            None => (0, spp),
        }
    }

    /// The pixel rectangle to render: the `-p` cell clipped to the image, or the whole image.
    pub fn region(&self) -> Cell {
        let ImageSettings { width, height, cell, .. } = self.image;
        match cell {
            Some(c) => {
                let x = c.x.min(width);
                let y = c.y.min(height);
                Cell { x, y, w: c.w.min(width - x), h: c.h.min(height - y) }
            }
            None => Cell { x: 0, y: 0, w: width, h: height },
        }
    }
}

/// One output variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Aov {
    Albedo,
    Normal,
    Depth,
    Position,
    Variance,
}

crate::choice::named!(Aov, "AOV", {
    Albedo => "albedo", "reflectance at the first non-delta hit, in [0, 1] (OIDN's albedo)";
    Normal => "normal", "world-space shading normal at the first non-delta hit, facing the ray";
    Depth => "depth", "distance from the camera to the first hit along the camera ray";
    Position => "position", "world-space position of the first hit";
    Variance => "variance", "estimated variance of each pixel's mean, per channel";
});

impl Aov {
    /// The channels of its layer, named as OpenEXR readers expect (Blender's and OIDN's
    /// tools: colours R G B, vectors X Y Z, depth Z).
    pub fn channels(self) -> &'static [&'static str] {
        match self {
            Aov::Albedo | Aov::Variance => &["R", "G", "B"],
            Aov::Normal | Aov::Position => &["X", "Y", "Z"],
            Aov::Depth => &["Z"],
        }
    }
}

/// A set of output variables (`--aov albedo,normal`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AovSet(u8);

impl AovSet {
    pub const NONE: AovSet = AovSet(0);

    fn bit(a: Aov) -> u8 {
        1 << Aov::ALL.iter().position(|&b| b == a).unwrap_or(0)
    }

    pub fn with(self, a: Aov) -> AovSet {
        AovSet(self.0 | Self::bit(a))
    }

    pub fn union(self, o: AovSet) -> AovSet {
        AovSet(self.0 | o.0)
    }

    pub fn contains(self, a: Aov) -> bool {
        self.0 & Self::bit(a) != 0
    }

    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// The members, in the order [`Aov::ALL`] lists them.
    pub fn iter(self) -> impl Iterator<Item = Aov> {
        Aov::ALL.iter().copied().filter(move |&a| self.contains(a))
    }

    /// Whether the paths must record their first hits (every AOV but the variance, which
    /// comes from the beauty's own sums).
    pub fn traced(self) -> bool {
        self.iter().any(|a| a != Aov::Variance)
    }
}

impl std::str::FromStr for AovSet {
    type Err = UnknownName;

    /// A comma-separated list of names; an unknown name is refused with the list of known ones.
    fn from_str(s: &str) -> Result<AovSet, UnknownName> {
        let mut set = AovSet::NONE;
        for part in s.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            set = set.with(part.parse::<Aov>()?);
        }
        Ok(set)
    }
}

impl std::fmt::Display for AovSet {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let names: Vec<&str> = self.iter().map(|a| a.name()).collect();
        f.write_str(&names.join(","))
    }
}

#[cfg(test)]
mod aov_tests {
    use super::*;

    #[test]
    fn sets_parse_lists_and_refuse_unknown_names() {
        let s: AovSet = "albedo, depth,variance".parse().unwrap();
        assert_eq!(s.iter().collect::<Vec<_>>(), [Aov::Albedo, Aov::Depth, Aov::Variance]);
        assert!(s.traced());
        assert!(!"variance".parse::<AovSet>().unwrap().traced());
        assert_eq!(s.to_string(), "albedo,depth,variance");
        let e = "albedo,nromal".parse::<AovSet>().unwrap_err().to_string();
        assert!(e.contains("nromal") && e.contains("normal") && !e.contains('\n'), "{e}");
    }
}
