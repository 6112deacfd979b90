use glam::Vec3;

/// Smooth vertex normals: each vertex gets the sum of its faces' normals weighted by face
/// area (the unnormalised cross product), normalised — what the CS184 half-edge mesh
/// computes, but from the index triples alone so non-manifold meshes work too.
///
/// A vertex whose faces cancel out or that no face uses gets the normal of its first face,
/// or +Y when it has none, so no NaN ever reaches shading.
pub fn area_weighted_vertex_normals(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    let mut sum = vec![Vec3::ZERO; positions.len()];
    let mut first = vec![Vec3::ZERO; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let n = (b - a).cross(c - a);
        for &i in t {
            sum[i as usize] += n;
            if first[i as usize] == Vec3::ZERO {
                first[i as usize] = n;
            }
        }
    }
    sum.iter().zip(&first).map(|(&s, &f)| s.try_normalize().or_else(|| f.try_normalize()).unwrap_or(Vec3::Y)).collect()
}
