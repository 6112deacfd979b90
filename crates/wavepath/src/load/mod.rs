//! Scene loaders: every format produces the same [`Scene`].
//!
//! Errors name the file and what is wrong with it; a loader never panics on bad input.

pub mod collada;
mod defaults;
pub mod gltf;
pub mod obj;
pub mod ply;

pub use defaults::{default_scene, finish_mesh_only};
pub use ply::write_binary as write_ply;

use crate::scene::Scene;
use anyhow::{Context, Result, bail};
use std::path::Path;

/// Which camera a COLLADA file gets.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CameraMode {
    /// The CS184 reference placement (see COLLADA-CS184.md): the seed's pictures use it.
    #[default]
    Cs184,
    /// The file's camera exactly as written.
    File,
}

crate::choice::named!(CameraMode, "camera", {
    Cs184 => "cs184", "the CS184 reference placement (see COLLADA-CS184.md): the seed's pictures use it";
    File => "file", "the file's camera exactly as written";
});

/// Choices that change how a file is read.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoadOptions {
    pub camera: CameraMode,
    /// COLLADA: replace the file's normals by smooth area-weighted vertex normals, as the
    /// reference renderer does (default for .dae).
    pub smooth_normals: bool,
    /// Every emitter emits from both faces, whatever its format says (for comparisons with
    /// renderers and scenes that treat all emitters so).
    pub two_sided_emission: bool,
    /// Rounds of midpoint subdivision applied to the loaded mesh (`--subdivide`): the same
    /// surface in 4^n times the triangles, to render scenes at the size of real scans.
    pub subdivide: u32,
}

impl Default for LoadOptions {
    fn default() -> Self {
        LoadOptions { camera: CameraMode::Cs184, smooth_normals: true, two_sided_emission: false, subdivide: 0 }
    }
}

/// Largest file a loader reads; anything larger is almost certainly not a scene.
pub const MAX_FILE_BYTES: u64 = 4 << 30;

/// Loads any supported scene file, chosen by extension, and checks the result.
pub fn load(path: &Path, opts: &LoadOptions) -> Result<Scene> {
    let shown = path.display();
    let meta = std::fs::metadata(path).with_context(|| format!("{shown}: cannot open"))?;
    if !meta.is_file() {
        bail!("{shown}: not a file");
    }
    if meta.len() > MAX_FILE_BYTES {
        bail!("{shown}: file is {} bytes, larger than the {} byte limit", meta.len(), MAX_FILE_BYTES);
    }
    let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).unwrap_or_default();
    let mut scene = match ext.as_str() {
        "dae" => collada::load(path, opts)?,
        "obj" => obj::load(path)?,
        "ply" => ply::load(path)?,
        "gltf" | "glb" => gltf::load(path)?,
        "" => bail!("{shown}: no file extension; expected .dae, .obj, .ply, .gltf or .glb"),
        other => bail!("{shown}: unknown scene format '.{other}'; expected .dae, .obj, .ply, .gltf or .glb"),
    };
    scene.name = path.display().to_string();
    if opts.two_sided_emission {
        scene.materials.iter_mut().for_each(|m| m.two_sided_emission = true);
    }
    if scene.mesh.triangles.is_empty() && scene.spheres.is_empty() {
        bail!("{shown}: the scene has no triangles and no spheres");
    }
    if opts.subdivide > 0 {
        let n = scene.mesh.triangle_count();
        scene.mesh = std::mem::take(&mut scene.mesh).subdivided(opts.subdivide).ok_or_else(|| {
            let out = crate::scene::subdivide::subdivided_count(n, opts.subdivide)
                .map_or("more than 2^64".to_string(), |c| c.to_string());
            anyhow::anyhow!(
                "{shown}: {n} triangles subdivided {} times would be {out}, more than the {} a subdivision makes",
                opts.subdivide,
                crate::scene::subdivide::MAX_TRIANGLES
            )
        })?;
    }
    scene.validate().map_err(|e| anyhow::anyhow!("{shown}: {e}"))?;
    Ok(scene)
}
