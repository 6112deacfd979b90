//! The CS184 reference's rules inside the engine that no command shows directly: its
//! half-edge vertex normals.

use crate::scene::cs184_vertex_normals;
use crate::tests::common::meshgen::icosphere;
use glam::vec3;

// ---------------------------------------------------------------------------------------
// Normal view and bytes
// ---------------------------------------------------------------------------------------

/// The reference's half-edge normals: an open quad (all four corners on the boundary) gets
/// its face normal reversed at every corner; on a closed mesh they are the area-weighted
/// normals; an edge shared by three triangles is a mesh the reference refuses.
#[test]
fn half_edge_normals_as_the_reference_computes_them() {
    let quad = [vec3(0.0, 0.0, 0.0), vec3(2.0, 0.0, 0.0), vec3(2.0, 1.0, 0.0), vec3(0.0, 1.0, 0.0)];
    let n = cs184_vertex_normals(&quad, &[[0, 1, 2], [0, 2, 3]]).unwrap();
    assert!(n.iter().all(|v| (*v - vec3(0.0, 0.0, -1.0)).length() < 1e-6), "{n:?}");
    let ico = icosphere(2);
    let a = cs184_vertex_normals(&ico.positions, &ico.triangles).unwrap();
    let b = crate::scene::area_weighted_vertex_normals(&ico.positions, &ico.triangles);
    assert!(a.iter().zip(&b).all(|(x, y)| (*x - *y).length() < 1e-5));
    let fin =
        [vec3(0.0, 0.0, 0.0), vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0), vec3(0.0, -1.0, 0.0), vec3(0.0, 0.0, 1.0)];
    assert!(cs184_vertex_normals(&fin, &[[0, 1, 2], [1, 0, 3], [0, 1, 4]]).is_none());
}
