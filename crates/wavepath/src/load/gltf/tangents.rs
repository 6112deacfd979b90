//! Per-vertex tangents for primitives whose material has a normal map: the file's TANGENT
//! attribute, or MikkTSpace tangents where it has none (what the glTF specification asks
//! of a renderer, so that maps baked against MikkTSpace shade as they were baked).

use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};

/// The tangents of `prim` in world space (`None` when its material has no normal map, or
/// the primitive lacks the uvs or normals tangents need). `positions` and `normals` are
/// the primitive's in world space; `uvs` those its material's textures read.
pub fn of_primitive(
    prim: &gltf::Primitive,
    buffers: &[gltf::buffer::Data],
    world: &Mat4,
    positions: &[Vec3],
    normals: Option<&[Vec3]>,
    uvs: Option<&[Vec2]>,
    triangles: &[[u32; 3]],
) -> Option<Vec<Vec4>> {
    prim.material().normal_texture()?;
    let uvs = uvs?;
    let n = positions.len();
    let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    if let Some(t) = reader.read_tangents() {
        let m = Mat3::from_mat4(*world);
        // A mirroring transform flips the bitangent's handedness.
        let flip = if m.determinant() < 0.0 { -1.0 } else { 1.0 };
        let t: Vec<Vec4> = t
            .map(|[x, y, z, w]| {
                let v = (m * Vec3::new(x, y, z)).normalize_or_zero();
                v.extend(if w * flip < 0.0 { -1.0 } else { 1.0 })
            })
            .collect();
        if t.len() == n && t.iter().all(|v| v.is_finite()) {
            return Some(t);
        }
    }
    mikktspace_tangents(positions, normals?, uvs, triangles)
}

/// MikkTSpace tangents per triangle corner, averaged into the vertices they share (a
/// glTF mesh splits its vertices where uvs or normals are discontinuous, so corners of one
/// vertex have one tangent up to rounding). The uvs' v is turned up (1 - v), the
/// orientation of the image a normal map's +y points along.
fn mikktspace_tangents(
    positions: &[Vec3],
    normals: &[Vec3],
    uvs: &[Vec2],
    triangles: &[[u32; 3]],
) -> Option<Vec<Vec4>> {
    struct Corners<'a> {
        positions: &'a [Vec3],
        normals: &'a [Vec3],
        uvs: &'a [Vec2],
        triangles: &'a [[u32; 3]],
        out: Vec<Vec4>,
    }
    impl Corners<'_> {
        fn at(&self, face: usize, vert: usize) -> usize {
            self.triangles[face][vert] as usize
        }
    }
    impl mikktspace::Geometry for Corners<'_> {
        fn num_faces(&self) -> usize {
            self.triangles.len()
        }
        fn num_vertices_of_face(&self, _face: usize) -> usize {
            3
        }
        fn position(&self, face: usize, vert: usize) -> [f32; 3] {
            self.positions[self.at(face, vert)].to_array()
        }
        fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
            self.normals[self.at(face, vert)].to_array()
        }
        fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
            let t = self.uvs[self.at(face, vert)];
            [t.x, 1.0 - t.y]
        }
        fn set_tangent_encoded(&mut self, tangent: [f32; 4], face: usize, vert: usize) {
            self.out[face * 3 + vert] = Vec4::from_array(tangent);
        }
    }
    let mut g = Corners { positions, normals, uvs, triangles, out: vec![Vec4::ZERO; triangles.len() * 3] };
    if triangles.is_empty() || !mikktspace::generate_tangents(&mut g) {
        return None;
    }
    let mut sum = vec![Vec4::ZERO; positions.len()];
    for (corner, t) in g.out.iter().enumerate() {
        let v = triangles[corner / 3][corner % 3] as usize;
        if t.is_finite() {
            sum[v] += Vec4::new(t.x, t.y, t.z, t.w.signum());
        }
    }
    Some(sum.into_iter().map(|s| s.truncate().normalize_or_zero().extend(if s.w < 0.0 { -1.0 } else { 1.0 })).collect())
}
