//! Binary PLY output: the layout scanners write (float x y z; uchar-counted int indices),
//! which the bulk reader takes back at the speed of memory.

use glam::Vec3;
use std::io::Write;
use std::path::Path;

/// Writes `positions` and `triangles` as a little-endian binary PLY.
pub fn write_binary(path: &Path, positions: &[Vec3], triangles: &[[u32; 3]]) -> std::io::Result<()> {
    let mut w = std::io::BufWriter::with_capacity(1 << 22, std::fs::File::create(path)?);
    write!(
        w,
        "ply\nformat binary_little_endian 1.0\ncomment written by wavepath\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\nelement face {}\n\
         property list uchar int vertex_indices\nend_header\n",
        positions.len(),
        triangles.len()
    )?;
    for p in positions {
        w.write_all(bytemuck::cast_slice(&p.to_array().map(f32::to_le_bytes)))?;
    }
    let mut face = [0u8; 13];
    face[0] = 3;
    for t in triangles {
        for (k, &i) in t.iter().enumerate() {
            face[1 + 4 * k..5 + 4 * k].copy_from_slice(&(i as i32).to_le_bytes());
        }
        w.write_all(&face)?;
    }
    w.flush()
}
