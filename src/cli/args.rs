//! Command-line syntax: the CS184 flags plus wavepath's own.

use super::choices::{Split, named};
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;
use wavepath::{
    Aov, BvhBuild, CameraMode, FovRule, IntegratorKind, Isa, LeafLayout, RouletteKind, SamplerKind, Shading, Tonemap,
};

#[derive(Parser, Debug)]
#[command(
    name = "wavepath",
    version,
    about = "A physically based wavefront path tracer for the CPU (CS184-compatible flags).",
    long_about = "Renders SCENE (.dae, .obj, .ply, .gltf, .glb) or, with no SCENE, the embedded \
                  Cornell box with two spheres. The flags follow the CS184 pathtracer.",
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true,
    allow_negative_numbers = true
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    #[command(flatten)]
    pub render: RenderArgs,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Show what was loaded: counts, camera, lights, materials, effects, load time.
    Info(InfoArgs),
    /// Write or trace ray files (the format of ../shared/peers).
    #[command(subcommand)]
    Rays(RaysCommand),
    /// Merge part files written by `--part` into the image one process would have rendered.
    Merge(MergeArgs),
    /// What accuracy costs in time: sweep a setting, measure time and error vs a reference.
    Study(crate::cli::study_cmd::StudyArgs),
    /// Subdivide a mesh at its edges' midpoints into a binary PLY (the same surface, 4^N
    /// times the triangles): large test meshes from any scene file.
    Subdivide(SubdivideArgs),
    /// Watch the render converge in a browser: orbit, pan and zoom the camera, change
    /// settings, save images, copy the command that renders the view offline.
    View(Box<ViewArgs>),
}

#[derive(Args, Debug)]
pub struct ViewArgs {
    /// Port to serve on (0: a free one, printed).
    #[arg(long, default_value_t = 0)]
    pub port: u16,
    /// Address to listen on. The default, loopback, is reachable from this machine only (or
    /// through an SSH tunnel); another address exposes the viewer to the network.
    #[arg(long, value_name = "ADDR", default_value = "127.0.0.1")]
    pub listen: std::net::IpAddr,
    /// Folder where the page's "save" buttons write images (default: saving is off).
    #[arg(long, value_name = "DIR")]
    pub save_dir: Option<PathBuf>,
    /// The render flags (as for a render). `-s` is the samples-per-pixel cap at which the
    /// view stops refining; with the default 1 it refines to 1024. `--aov NAME`: the output
    /// variable shown first (the page switches between them); `--denoise`: denoise from the
    /// start; `--oidn PATH`: the denoiser's runtime (default: python3's pyoidn; without one
    /// the page's denoise box is off).
    #[command(flatten)]
    pub render: RenderArgs,
}

#[derive(Args, Debug)]
pub struct SubdivideArgs {
    /// Scene file whose mesh is subdivided (materials, lights and spheres are dropped).
    #[arg(value_name = "MESH")]
    pub input: PathBuf,
    /// Output file (.ply, binary little endian).
    #[arg(value_name = "OUT")]
    pub output: PathBuf,
    /// Levels: each multiplies the triangles by 4 (0 writes the mesh as it is: a conversion to
    /// binary PLY, so that every size of a series is read by the same loader).
    #[arg(short = 'n', value_name = "LEVELS", value_parser = clap::value_parser!(u32).range(0..=12))]
    pub levels: u32,
}

#[derive(Args, Debug)]
pub struct MergeArgs {
    /// Part files (.exr written with --part), all N of them, in any order.
    #[arg(required = true, value_name = "PARTS")]
    pub parts: Vec<PathBuf>,
    /// Output image: .png (tone-mapped), .exr, .hdr, .pfm (linear).
    #[arg(short = 'f', value_name = "FILE", required = true)]
    pub output: PathBuf,
    /// PNG transfer curve.
    #[arg(long, value_parser = named::<Tonemap>(), default_value = "cs184")]
    pub tonemap: Tonemap,
    /// Write the merged statistics (JSON) to FILE.
    #[arg(long, value_name = "FILE")]
    pub stats: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct InfoArgs {
    /// Scene file.
    pub scene: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    /// COLLADA camera framing.
    #[arg(long, value_parser = named::<CameraMode>(), default_value = "cs184")]
    pub camera: CameraMode,
    /// Environment map (as `render -e`): loaded, its size and effects reported.
    #[arg(short = 'e', value_name = "FILE")]
    pub envmap: Option<PathBuf>,
}

#[derive(Subcommand, Debug)]
pub enum RaysCommand {
    /// Write the renderer's camera rays or first diffuse bounces as a ray file.
    Dump(DumpArgs),
    /// Build the BVH for MESH and trace RAYS, printing one JSON line (peer harness interface).
    Trace(TraceArgs),
}

#[derive(Args, Debug, Clone)]
pub struct RenderArgs {
    /// Scene file (.dae, .obj, .ply, .gltf, .glb); omitted: the embedded Cornell box.
    pub scene: Option<PathBuf>,
    /// Camera rays per pixel.
    #[arg(short = 's', value_name = "N", default_value_t = 1)]
    pub spp: i64,
    /// Samples per area light.
    #[arg(short = 'l', value_name = "N", default_value_t = 1)]
    pub light_samples: i64,
    /// Maximum ray depth (0: emission only, 1: direct light, >1: global illumination).
    #[arg(short = 'm', value_name = "N", default_value_t = 1)]
    pub max_depth: i64,
    /// 1: accumulate all bounces; 0: show only light that took exactly -m bounces.
    #[arg(short = 'o', value_name = "0|1", default_value_t = 1)]
    pub accumulate: i64,
    /// Adaptive sampling: every B samples stop a pixel once 1.96 sigma/sqrt(n) <= T mu.
    /// Also writes <out>_rate.png, each pixel's samples (written only with -a).
    #[arg(short = 'a', num_args = 2, value_names = ["B", "T"])]
    pub adaptive: Option<Vec<f64>>,
    /// Worker threads (default, or 0: all cores).
    #[arg(short = 't', value_name = "N")]
    pub threads: Option<i64>,
    /// Output resolution in pixels.
    #[arg(short = 'r', num_args = 2, value_names = ["W", "H"])]
    pub resolution: Option<Vec<i64>>,
    /// Output image: .png (tone-mapped), .exr, .hdr, .pfm (linear). Default: wavepath.png.
    #[arg(short = 'f', value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Render only the cell with bottom-left pixel (X, Y) and size DX x DY.
    #[arg(short = 'p', num_args = 4, value_names = ["X", "Y", "DX", "DY"])]
    pub cell: Option<Vec<i64>>,
    /// Camera settings file (the CS184 camera dump format).
    #[arg(short = 'c', value_name = "FILE")]
    pub camera_file: Option<PathBuf>,
    /// Environment map (equirectangular .exr/.hdr): lights the scene, camera misses see it.
    /// A file with no light of its own is lit by the map alone (no default sky beside it).
    #[arg(short = 'e', value_name = "FILE")]
    pub envmap: Option<PathBuf>,
    /// Thin-lens aperture radius (0: pinhole).
    #[arg(short = 'b', value_name = "R")]
    pub lens_radius: Option<f64>,
    /// Focal distance of the thin lens.
    #[arg(short = 'd', value_name = "D")]
    pub focal_distance: Option<f64>,
    /// Light subpaths per pixel and sample of --integrator light and path+light (default: 1
    /// for light, 0.25 for path+light; bdpt and vcm trace one per pixel).
    #[arg(long, value_name = "R")]
    pub light_paths: Option<f64>,
    /// Uniform hemisphere sampling for direct light (default: light importance sampling).
    #[arg(short = 'H')]
    pub hemisphere: bool,
    /// What pixels show; default: global when -m > 1, else direct.
    #[arg(long, value_parser = named::<Shading>())]
    pub shading: Option<Shading>,
    /// Russian roulette continue probability, in (0, 1].
    #[arg(long = "rr", value_name = "P", default_value_t = 0.65)]
    pub rr: f64,
    /// Russian roulette: fixed (continue with --rr, as the seed) or throughput (continue with
    /// the path's throughput, its largest component, as pbrt-v4 and Mitsuba). Default: fixed
    /// for .dae files and the embedded scene (the seed's pictures), throughput for other files.
    #[arg(long, value_parser = named::<RouletteKind>())]
    pub roulette: Option<RouletteKind>,
    /// First depth whose continuation plays Russian roulette (1: from the second bounce, the
    /// seed's rule). Default: 1 with fixed roulette, 5 with throughput roulette (Mitsuba's).
    #[arg(long, value_name = "D")]
    pub rr_depth: Option<i64>,
    /// How each pixel's samples spread over the path space: independent (the seed's numbers),
    /// stratified (jittered strata of -s samples) or sobol (Owen-scrambled Sobol points).
    /// Default: independent for .dae files and the embedded scene (the seed's pictures),
    /// sobol for other files.
    #[arg(long, value_parser = named::<SamplerKind>())]
    pub sampler: Option<SamplerKind>,
    /// Brute-force intersection (every ray against every primitive).
    #[arg(long)]
    pub no_bvh: bool,
    /// How the BVH is built: sah (binned surface area heuristic, the tree rays traverse
    /// fastest) or fast (Morton order: about a third less build time on large meshes, rays
    /// 6-12% slower; for large meshes rendered briefly). Same image either way.
    #[arg(long, value_parser = named::<BvhBuild>(), default_value = "sah")]
    pub bvh_build: BvhBuild,
    /// How the BVH's leaves hold their triangles: corners (three cache lines a leaf), packed
    /// (each distinct vertex once: two thirds of the memory, a gather per leaf test) or auto
    /// (packed from 16 million primitives). Same image either way.
    #[arg(long, value_parser = named::<LeafLayout>(), default_value = "auto")]
    pub bvh_leaves: LeafLayout,
    /// Widest SIMD instruction set the kernels may use: scalar, sse, avx2, avx512 (capped by
    /// what the CPU has; every choice gives the same image). avx512 shades sixteen paths per
    /// group; the BVH's kernels stop at avx2.
    #[arg(long, value_name = "ISA", value_parser = named::<Isa>(), default_value = "avx512")]
    pub isa: Isa,
    /// Base seed of all random numbers.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// PNG transfer curve.
    #[arg(long, value_parser = named::<Tonemap>(), default_value = "cs184")]
    pub tonemap: Tonemap,
    /// Light-transport implementation.
    #[arg(long, value_parser = named::<IntegratorKind>(), default_value = "auto")]
    pub integrator: IntegratorKind,
    /// COLLADA camera framing: cs184 (the reference renderer's placement) or the file's camera.
    #[arg(long, value_parser = named::<CameraMode>(), default_value = "cs184")]
    pub camera: CameraMode,
    /// How a COLLADA camera's field of view follows -r (other files keep theirs).
    #[arg(long, value_parser = named::<FovRule>(), default_value = "cs184")]
    pub fov: FovRule,
    /// The CS184 course renderer's area-light pdf, dist / (area cos) instead of
    /// dist^2 / (area cos): every light-sampled area-light estimate is multiplied by the
    /// distance to the light point. Wrong, but it is what renderers built on the course
    /// skeleton show (about 1.4x brighter Cornell boxes); for comparing with them.
    #[arg(long)]
    pub cs184_light_pdf: bool,
    /// Light sampling alone at diffuse surfaces (the seed's estimator) instead of combining it
    /// with the BSDF's sample by multiple importance sampling.
    #[arg(long)]
    pub no_mis: bool,
    /// Every emitter emits from both faces. Default: as its format says (CS184 .dae and
    /// double-sided glTF materials both faces; OBJ Ke and single-sided glTF materials the
    /// front face, the side the winding points to).
    #[arg(long)]
    pub two_sided_emission: bool,
    /// Subdivide the scene's mesh N times after loading (each triangle into four at its
    /// edges' midpoints: the same surface, 4^N times the triangles), e.g. `CBlucy.dae
    /// --subdivide 4` for a Cornell box around a 25.6-million-triangle Lucy.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub subdivide: u32,
    /// Refuse, before reading or building, a scene whose mesh or BVH would need more than
    /// this (bytes, or with K, M, G, T). Default: the memory the system has available.
    #[arg(long, value_name = "BYTES", value_parser = super::parse_bytes)]
    pub max_memory: Option<u64>,
    /// Force every effect (stage and kernel feature) on, even those the scene does not need;
    /// the image is the same, only slower: for measuring what specialisation saves.
    #[arg(long)]
    pub all_effects: bool,
    /// Write machine-readable statistics (JSON) to FILE.
    #[arg(long, value_name = "FILE")]
    pub stats: Option<PathBuf>,
    /// Output variables kept beside the picture, comma-separated: albedo and normal (at the
    /// first hit that is not a mirror or glass), depth and position (of the first hit),
    /// variance (of each pixel's mean). An .exr output holds them as layers of one image
    /// (albedo.R, normal.X, depth.Z...); other formats write <stem>.<aov>.<ext> beside it
    /// (.exr beside a .png).
    #[arg(long, value_name = "LIST", value_parser = named::<Aov>(), value_delimiter = ',')]
    pub aov: Vec<Aov>,
    /// Denoise the picture with Intel Open Image Denoise, fed the albedo and normal of the
    /// same render (prefiltered, as OIDN recommends for noisy auxiliaries). The library is
    /// loaded at run time: `pip install pyoidn`, or give it with --oidn.
    #[arg(long)]
    pub denoise: bool,
    /// Open Image Denoise's library, a folder holding it, or an installed pyoidn package.
    /// Default: the pyoidn that `python3` on the PATH imports.
    #[arg(long, value_name = "PATH")]
    pub oidn: Option<PathBuf>,
    /// Render only part I of N (0-based) into an .exr part file for `wavepath merge`;
    /// `auto`: I and N from a Slurm array job or a Kubernetes Indexed Job.
    #[arg(long, value_name = "I/N|auto")]
    pub part: Option<String>,
    /// N for `--part auto` under Kubernetes (else the WAVEPATH_PARTS variable).
    #[arg(long, value_name = "N")]
    pub parts: Option<u32>,
    /// How parts divide the render: bands of rows (exact merge) or sample ranges.
    #[arg(long, value_enum, default_value_t = Split::Tiles)]
    pub split: Split,
}

#[derive(Args, Debug, Clone)]
pub struct DumpArgs {
    /// Scene file.
    pub scene: PathBuf,
    /// primary: camera rays; diffuse: first diffuse bounces of the primary hits.
    #[arg(long, value_parser = ["primary", "diffuse"])]
    pub kind: String,
    /// Output ray file.
    #[arg(long)]
    pub out: PathBuf,
    /// Resolution of the camera rays.
    #[arg(short = 'r', num_args = 2, value_names = ["W", "H"])]
    pub resolution: Option<Vec<u32>>,
    /// Seed of the diffuse directions.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Camera settings file (the CS184 camera dump format), as the renderer's `-c`: the rays
    /// a render from that view traces.
    #[arg(short = 'c', value_name = "FILE")]
    pub camera_file: Option<PathBuf>,
}

#[derive(Args, Debug, Clone)]
#[command(allow_negative_numbers = true)]
pub struct TraceArgs {
    /// Mesh or scene file.
    pub mesh: PathBuf,
    /// Ray file.
    pub rays: PathBuf,
    /// Threads (positional form of -t).
    pub threads_pos: Option<usize>,
    /// Timed passes (positional form of -r).
    pub reps_pos: Option<usize>,
    #[arg(short = 't')]
    pub threads: Option<usize>,
    #[arg(short = 'r')]
    pub reps: Option<usize>,
    /// Untimed warm-up passes.
    #[arg(short = 'w', default_value_t = 1)]
    pub warmup: usize,
    /// Write the hits file here.
    #[arg(short = 'o')]
    pub hits: Option<PathBuf>,
    /// Variant label printed in the JSON line.
    #[arg(long, default_value = "bvh")]
    pub variant: String,
    /// Widest SIMD instruction set of the box tests: scalar, sse, avx2 (avx512 runs avx2: the
    /// BVH's kernels stop there).
    #[arg(long, value_name = "ISA", value_parser = named::<Isa>(), default_value = "avx2")]
    pub isa: Isa,
    /// How the BVH is built: sah or fast (Morton order).
    #[arg(long, value_parser = named::<BvhBuild>(), default_value = "sah")]
    pub bvh_build: BvhBuild,
    /// How the BVH's leaves hold their triangles: corners, packed or auto.
    #[arg(long, value_parser = named::<LeafLayout>(), default_value = "auto")]
    pub bvh_leaves: LeafLayout,
}
