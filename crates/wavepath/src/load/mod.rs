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
    keep_usable_colours(&mut scene, &shown);
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

/// Vertex colours no render can use leave the mesh drawn, with a warning, rather than the
/// file refused: a colour only tints a surface, so the mesh without it is still the file's
/// shape, whereas a NaN position is a shape nobody can guess and stays an error. A colour
/// with a NaN or infinite channel (trimesh's `nancolor.obj`, a scanner's unset vertices)
/// leaves its vertex uncoloured: white, the base colour unchanged, as a part without
/// colours is in [`crate::scene::Mesh::append`]; vertex by vertex, so that one bad vertex
/// of a painted scan keeps the rest of its paint. A negative channel (a float colour
/// rounded below zero) reflects nothing: read as 0. Every loader's colours pass here, so
/// none has its own rule.
fn keep_usable_colours(scene: &mut Scene, shown: &std::path::Display) {
    let Some(colours) = scene.mesh.colors.as_mut() else { return };
    if crate::scene::first_bad(colours, |c| !c.is_finite() || c.min_element() < 0.0).is_none() {
        return;
    }
    let (mut non_finite, mut negative) = (0usize, 0usize);
    for c in colours.iter_mut() {
        if !c.is_finite() {
            *c = glam::Vec3::ONE;
            non_finite += 1;
        } else if c.min_element() < 0.0 {
            *c = c.max(glam::Vec3::ZERO);
            negative += 1;
        }
    }
    let n = colours.len();
    if non_finite > 0 {
        scene.notes.push(format!(
            "warning: {shown}: {non_finite} of {n} vertex colours are NaN or infinite; those vertices are left \
             uncoloured"
        ));
    }
    if negative > 0 {
        scene
            .notes
            .push(format!("warning: {shown}: {negative} of {n} vertex colours have a negative channel; read as 0"));
    }
}
