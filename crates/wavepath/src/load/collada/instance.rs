//! Placing a [`LocalMesh`] in the world: transformed positions, the normals the options ask
//! for, and vertices shared wherever the corners agree.

use super::geometry::{Corner, LocalMesh, NONE};
use super::transform::normal_matrix;
use crate::scene::{Mesh, area_weighted_vertex_normals, cs184_vertex_normals};
use glam::{Mat4, Vec2, Vec3};
use std::collections::HashMap;

/// The world-space mesh of one geometry instance.
///
/// `smooth`: the reference renderer's vertex normals over the whole instance
/// ([`cs184_vertex_normals`]; area-weighted where it would refuse the mesh), else the file's
/// normals where it has them. `material_of_group[g]` is the
/// material of the triangles of group `g`.
pub fn place(local: &LocalMesh, world: Mat4, smooth: bool, material_of_group: &[u32]) -> Mesh {
    let positions: Vec<Vec3> = local.positions.iter().map(|&p| world.transform_point3(p)).collect();
    let pos_tris: Vec<[u32; 3]> = local.corners.chunks_exact(3).map(|c| [c[0].p, c[1].p, c[2].p]).collect();
    let file_normals = !smooth && local.corners.iter().any(|c| c.n != NONE);
    let has_uvs = local.corners.iter().any(|c| c.t != NONE);
    // Smooth normals are also the fallback for corners the file gives no usable normal.
    let smooth_n = smooth
        .then(|| cs184_vertex_normals(&positions, &pos_tris))
        .flatten()
        .unwrap_or_else(|| area_weighted_vertex_normals(&positions, &pos_tris));
    let mut material_ids = crate::scene::MaterialIds::default();
    for (g, &m) in local.groups.iter().zip(material_of_group) {
        material_ids.push_run(m, g.triangles);
    }

    if !file_normals && !has_uvs {
        // Vertices are exactly the file's positions.
        return Mesh {
            positions,
            normals: Some(smooth_n),
            uvs: None,
            colors: None,
            tangents: None,
            triangles: pos_tris,
            material_ids,
        };
    }

    let nm = normal_matrix(world);
    let key = |c: Corner| Corner { p: c.p, n: if file_normals { c.n } else { NONE }, t: c.t };
    let mut index: HashMap<Corner, u32> = HashMap::with_capacity(positions.len());
    let mut out_p = Vec::with_capacity(positions.len());
    let mut out_n = Vec::with_capacity(positions.len());
    let mut out_t = Vec::with_capacity(if has_uvs { positions.len() } else { 0 });
    let mut vertex = |c: Corner| -> u32 {
        *index.entry(key(c)).or_insert_with(|| {
            let p = c.p as usize;
            out_p.push(positions[p]);
            let from_file = (file_normals && c.n != NONE)
                .then(|| nm.and_then(|m| (m * local.normals[c.n as usize]).try_normalize()))
                .flatten();
            out_n.push(from_file.unwrap_or(smooth_n[p]));
            if has_uvs {
                out_t.push(if c.t == NONE { Vec2::ZERO } else { local.uvs[c.t as usize] });
            }
            (out_p.len() - 1) as u32
        })
    };
    let triangles: Vec<[u32; 3]> =
        local.corners.chunks_exact(3).map(|c| [vertex(c[0]), vertex(c[1]), vertex(c[2])]).collect();
    Mesh {
        positions: out_p,
        normals: Some(out_n),
        uvs: has_uvs.then_some(out_t),
        colors: None,
        tangents: None,
        triangles,
        material_ids,
    }
}
