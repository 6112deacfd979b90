//! Midpoint subdivision: each triangle split into four at its edges' midpoints, each edge's
//! midpoint made once and shared by the triangles on both sides. The surface is unchanged
//! (every new vertex lies on an old triangle) and a closed mesh stays closed, so test meshes
//! of any size come from any mesh without a download.

use super::Mesh;
use glam::Vec3;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// A multiplicative hash for the edge keys (two vertex indices in one u64): SipHash costs
/// more than the rest of a subdivision step.
#[derive(Default)]
struct EdgeHasher(u64);

impl Hasher for EdgeHasher {
    fn finish(&self) -> u64 {
        self.0 ^ (self.0 >> 29)
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x100_0000_01b3);
        }
    }

    fn write_u64(&mut self, x: u64) {
        self.0 = x.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
}

/// The most triangles a subdivision makes: 2^30, about 25 GB with its vertices and edge
/// table while it runs (and 40 times the full Lucy).
pub const MAX_TRIANGLES: usize = 1 << 30;

/// Triangles after `levels` rounds, `None` on overflow.
pub fn subdivided_count(triangles: usize, levels: u32) -> Option<usize> {
    4usize.checked_pow(levels).and_then(|f| f.checked_mul(triangles))
}

/// `levels` rounds of midpoint subdivision: 4^levels times the triangles, in order (each
/// triangle's four children replace it, winding kept: corner a, corner b, corner c, middle),
/// the old vertices first. `None` when the result would have more than [`MAX_TRIANGLES`].
pub fn subdivide(positions: &[Vec3], triangles: &[[u32; 3]], levels: u32) -> Option<(Vec<Vec3>, Vec<[u32; 3]>)> {
    let mesh = Mesh { positions: positions.to_vec(), triangles: triangles.to_vec(), ..Mesh::default() };
    let out = mesh.subdivided(levels)?;
    Some((out.positions, out.triangles))
}

/// Appends one value per new vertex, made from the values at its edge's ends.
fn extend_at_midpoints<T: Copy>(v: &mut Vec<T>, ends: &[[u32; 2]], mix: impl Fn(T, T) -> T) {
    v.reserve(ends.len());
    for &[i, j] in ends {
        v.push(mix(v[i as usize], v[j as usize]));
    }
}

impl Mesh {
    /// This mesh after `levels` rounds of [`subdivide`]: each triangle's children keep its
    /// material, and a new vertex's normal, uv and colour are the means of its edge's two
    /// (normals renormalised), so shading is continuous where it was. `None` as
    /// [`subdivide`]. Takes the mesh so that no copy of it is held beside the result.
    pub fn subdivided(self, levels: u32) -> Option<Mesh> {
        // Refused before anything is allocated.
        let total = subdivided_count(self.triangles.len(), levels)?;
        if total > MAX_TRIANGLES {
            return None;
        }
        let mut m = self;
        for _ in 0..levels {
            let next_tris = m.triangles.len().checked_mul(4).filter(|&n| n <= u32::MAX as usize)?;
            // A closed mesh has 3/2 edges per triangle; an open one at most 3.
            if m.positions.len() + 3 * m.triangles.len() > u32::MAX as usize {
                return None;
            }
            let mut mid: HashMap<u64, u32, BuildHasherDefault<EdgeHasher>> =
                HashMap::with_capacity_and_hasher(m.triangles.len() * 3 / 2 + 16, Default::default());
            let mut ends: Vec<[u32; 2]> = Vec::new();
            let first_new = m.positions.len();
            let mut out = Vec::with_capacity(next_tris);
            let p = &mut m.positions;
            for &[a, b, c] in &m.triangles {
                let mut mid_of = |i: u32, j: u32| -> u32 {
                    let key = (i.min(j) as u64) << 32 | i.max(j) as u64;
                    *mid.entry(key).or_insert_with(|| {
                        p.push(0.5 * (p[i as usize] + p[j as usize]));
                        ends.push([i, j]);
                        (p.len() - 1) as u32
                    })
                };
                let (ab, bc, ca) = (mid_of(a, b), mid_of(b, c), mid_of(c, a));
                out.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
            }
            debug_assert_eq!(first_new + ends.len(), m.positions.len());
            if let Some(n) = &mut m.normals {
                extend_at_midpoints(n, &ends, |a, b| (a + b).normalize_or_zero());
            }
            if let Some(uv) = &mut m.uvs {
                extend_at_midpoints(uv, &ends, |a, b| 0.5 * (a + b));
            }
            if let Some(c) = &mut m.colors {
                extend_at_midpoints(c, &ends, |a, b| 0.5 * (a + b));
            }
            m.material_ids = m.material_ids.repeated(4);
            m.triangles = out;
        }
        Some(m)
    }
}
