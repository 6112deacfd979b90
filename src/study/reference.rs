//! The converged reference image, rendered once and kept in a cache folder under a key that
//! changes whenever the scene file or a setting that changes the image changes.

use super::metrics::Reference;
use anyhow::{Context, Result};
use std::path::{Path, PathBuf};
use wavepath::Intersector;
use wavepath::Scene;
use wavepath::Settings;
use wavepath::{Film, Tonemap, write_image};

/// Added to the base seed for the reference, so the reference never shares random numbers
/// with the renders it judges (shared samples would make their errors look smaller).
pub const REFERENCE_SEED_OFFSET: u64 = 0x005E_ED0F_2EF0;

/// 64-bit FNV-1a: a stable hash (std's `DefaultHasher` may change between Rust releases,
/// which would silently invalidate or, worse, alias cache entries).
#[derive(Clone, Copy, Debug)]
pub struct Fnv(pub u64);

impl Default for Fnv {
    fn default() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    pub fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= b as u64;
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }
}

/// What identifies a scene's content for the cache: the file's bytes (or a label for a scene
/// built in code, e.g. the embedded default).
pub fn scene_identity(path: Option<&Path>) -> Result<Vec<u8>> {
    match path {
        Some(p) => std::fs::read(p).with_context(|| format!("{}: cannot read", p.display())),
        None => Ok(b"embedded default scene".to_vec()),
    }
}

/// The settings of the reference: those of `base` with `spp` samples and its own seed.
pub fn reference_settings(base: &Settings, spp: u32) -> Settings {
    base.clone().with(|s| {
        s.sampling.spp = spp;
        s.sampling.adaptive = None;
        s.paths.hemisphere = false;
        s.sampling.seed = base.sampling.seed.wrapping_add(REFERENCE_SEED_OFFSET);
        s.sampling.sample_range = None;
        s.image.cell = None
    })
}

/// The cache key: scene content, camera choice and every setting that changes the image.
pub fn cache_key(identity: &[u8], camera_label: &str, s: &Settings) -> u64 {
    let mut h = Fnv::default();
    h.write(identity);
    let r = s.paths.roulette;
    let text = format!(
        "v2 {} {camera_label} {}x{} spp {} l {} m {} o {} roulette {} {} from {} sampler {} mis {} seed {} shading {:?}",
        env!("CARGO_PKG_VERSION"),
        s.image.width,
        s.image.height,
        s.sampling.spp,
        s.sampling.light_samples,
        s.paths.max_depth,
        s.paths.accumulate,
        r.kind.name(),
        r.continue_prob,
        r.start_depth,
        s.sampling.sampler.name(),
        s.paths.mis,
        s.sampling.seed,
        s.paths.shading
    );
    h.write(text.as_bytes());
    h.0
}

/// Paths of a cache entry: mean image, variance image, and a small description.
pub fn cache_paths(dir: &Path, stem: &str, key: u64) -> (PathBuf, PathBuf, PathBuf) {
    let base = format!("{stem}-{key:016x}");
    (dir.join(format!("{base}.exr")), dir.join(format!("{base}_var.exr")), dir.join(format!("{base}.txt")))
}

/// Reads a linear EXR written by [`write_image`] back into a film (bottom row first).
pub fn read_exr(path: &Path) -> Result<Film> {
    let img = image::open(path).with_context(|| format!("{}: cannot read image", path.display()))?.to_rgb32f();
    let (w, h) = (img.width() as usize, img.height() as usize);
    let mut film = Film::new(w, h);
    for (x, y, p) in img.enumerate_pixels() {
        film.set(x as usize, h - 1 - y as usize, glam::Vec3::from(p.0));
    }
    Ok(film)
}

/// Where a reference came from, for the log and the report.
#[derive(Clone, Debug)]
pub struct ReferenceInfo {
    pub path: PathBuf,
    pub cached: bool,
    pub seconds: f64,
}

/// Returns the reference for `scene` at `settings` (already the reference settings), from
/// the cache when present, else renders and stores it.
pub fn reference(
    scene: &Scene,
    accel: &dyn Intersector,
    settings: &Settings,
    identity: &[u8],
    camera_label: &str,
    cache_dir: &Path,
    stem: &str,
) -> Result<(Reference, ReferenceInfo)> {
    let key = cache_key(identity, camera_label, settings);
    let (mean_p, var_p, info_p) = cache_paths(cache_dir, stem, key);
    if mean_p.is_file() && var_p.is_file() {
        let mean = read_exr(&mean_p)?;
        let variance = read_exr(&var_p)?;
        if (mean.width, mean.height) == (settings.image.width, settings.image.height)
            && variance.pixels.len() == mean.pixels.len()
        {
            return Ok((Reference { mean, variance }, ReferenceInfo { path: mean_p, cached: true, seconds: 0.0 }));
        }
    }
    std::fs::create_dir_all(cache_dir)
        .with_context(|| format!("{}: cannot create cache folder", cache_dir.display()))?;
    let t0 = std::time::Instant::now();
    let (acc, _) = wavepath::render_sums(scene, accel, settings, &|_| {})?;
    let seconds = t0.elapsed().as_secs_f64();
    let r = Reference::from_accumulator(&acc);
    write_image(&r.mean, &mean_p, Tonemap::Cs184)?;
    write_image(&r.variance, &var_p, Tonemap::Cs184)?;
    let about = format!(
        "reference for {stem}: {}x{} at {} spp, -l {} -m {} --rr {} seed {}; {seconds:.2} s\n",
        settings.image.width,
        settings.image.height,
        settings.sampling.spp,
        settings.sampling.light_samples,
        settings.paths.max_depth,
        settings.paths.roulette.continue_prob,
        settings.sampling.seed
    );
    std::fs::write(&info_p, about).with_context(|| format!("{}: cannot write", info_p.display()))?;
    // Reading back what was written keeps cached and fresh runs bit-identical (EXR is f32).
    let r = Reference { mean: read_exr(&mean_p)?, variance: read_exr(&var_p)? };
    Ok((r, ReferenceInfo { path: mean_p, cached: false, seconds }))
}
