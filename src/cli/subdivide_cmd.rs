//! `wavepath subdivide MESH OUT.ply -n LEVELS`: test meshes of every size from any mesh.

use super::SubdivideArgs;
use anyhow::{Result, bail};
use std::time::Instant;

pub fn run(a: &SubdivideArgs) -> Result<()> {
    if a.output.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() != Some("ply") {
        bail!("{}: the output is written as binary PLY; name it .ply", a.output.display());
    }
    let scene = super::load_scene(&a.input, &wavepath::LoadOptions::default())?;
    let m = &scene.mesh;
    if m.triangles.is_empty() {
        bail!("{}: no triangles to subdivide", a.input.display());
    }
    let start = Instant::now();
    let Some((p, t)) = wavepath::subdivide::subdivide(&m.positions, &m.triangles, a.levels) else {
        let n = wavepath::subdivide::subdivided_count(m.triangles.len(), a.levels)
            .map_or_else(|| "more than 2^64".to_string(), |n| n.to_string());
        bail!(
            "{}: {} triangles subdivided {} times would be {n}, more than the 2^30 this command makes; use fewer levels",
            a.input.display(),
            m.triangles.len(),
            a.levels
        );
    };
    let built = start.elapsed().as_secs_f64();
    wavepath::write_ply(&a.output, &p, &t).map_err(|e| anyhow::anyhow!("{}: cannot write: {e}", a.output.display()))?;
    eprintln!(
        "[wavepath] Subdivided {} triangles {} times: {} vertices, {} triangles in {built:.2} s; wrote {} in {:.2} s",
        m.triangles.len(),
        a.levels,
        p.len(),
        t.len(),
        a.output.display(),
        start.elapsed().as_secs_f64() - built
    );
    Ok(())
}
