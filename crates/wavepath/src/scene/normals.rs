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

/// (A CS184 rule: [`crate::cs184`] lists them all.)
/// The vertex normals the CS184 reference renderer computes for a COLLADA mesh, so that its
/// normal view and its shading are reproduced: it builds a half-edge mesh and, at an
/// interior vertex, sums the area vectors of the faces around it (as
/// [`area_weighted_vertex_normals`]); at a boundary vertex its loop steps with
/// `h = h->next()->twin()` from the vertex's boundary half-edge, which walks around the
/// *neighbouring* boundary vertex instead, adding `cross(pj - pi, pk - pi)` for that
/// neighbour's faces and its boundary loop. On a flat open patch (a Cornell-box wall) that
/// sum is the face normal reversed, which is why the reference shows every wall's normal
/// pointing into the box although the walls are wound facing out.
///
/// `None` when the reference would refuse the mesh (a directed edge used twice, a triangle
/// with a repeated vertex, a vertex whose faces do not form one fan); the caller then uses
/// the area-weighted normals.
pub fn cs184_vertex_normals(positions: &[Vec3], triangles: &[[u32; 3]]) -> Option<Vec<Vec3>> {
    const NONE: u32 = u32::MAX;
    let interior = triangles.len() * 3;
    // Half-edge h of triangle h / 3 runs from corner h % 3 to the next corner.
    let mut from: Vec<u32> = triangles.iter().flatten().copied().collect();
    let mut next: Vec<u32> = (0..interior as u32).map(|h| h - h % 3 + (h % 3 + 1) % 3).collect();
    let mut by_edge = std::collections::HashMap::with_capacity(interior);
    for (h, &a) in from.iter().enumerate() {
        let b = from[next[h] as usize];
        if a == b || by_edge.insert((a, b), h as u32).is_some() {
            return None;
        }
    }
    let mut twin: Vec<u32> =
        (0..interior).map(|h| by_edge.get(&(from[next[h] as usize], from[h])).map_or(NONE, |&t| t)).collect();
    // Each interior half-edge without a twin gets one on the boundary loop, running back.
    // The loop's half-edge out of vertex a is the twin of the interior boundary half-edge
    // into a, which must be unique for the mesh to be a manifold with boundary.
    let mut boundary_into = vec![NONE; positions.len()];
    for h in 0..interior {
        if twin[h] == NONE {
            let to = from[next[h] as usize] as usize;
            if boundary_into[to] != NONE {
                return None;
            }
            boundary_into[to] = h as u32;
        }
    }
    for h in 0..interior {
        if twin[h] == NONE {
            let t = from.len() as u32;
            from.push(from[next[h] as usize]);
            next.push(NONE);
            twin.push(h as u32);
            twin[h] = t;
        }
    }
    for t in interior..from.len() {
        // Boundary half-edge b -> a continues with the one out of a.
        let a = from[twin[t] as usize] as usize;
        let into_a = boundary_into[a];
        if into_a == NONE {
            return None;
        }
        next[t] = twin[into_a as usize];
    }
    // One fan per vertex: walking around it meets every face that uses it.
    let mut faces_at = vec![0u32; positions.len()];
    let mut out_of = vec![NONE; positions.len()];
    for (h, &a) in from.iter().enumerate().take(interior) {
        faces_at[a as usize] += 1;
        out_of[a as usize] = h as u32;
    }
    let root = |h: u32| positions[from[h as usize] as usize];
    let mut normals = Vec::with_capacity(positions.len());
    for v in 0..positions.len() {
        if out_of[v] == NONE {
            normals.push(Vec3::Y);
            continue;
        }
        let on_boundary = boundary_into[v] != NONE;
        let start = if on_boundary { twin[boundary_into[v] as usize] } else { out_of[v] };
        // Around v itself, counting its faces (boundary half-edges have no face).
        let (mut h, mut fan) = (start, 0u32);
        loop {
            fan += u32::from((h as usize) < interior);
            h = next[twin[h as usize] as usize];
            if h == start || fan > faces_at[v] {
                break;
            }
        }
        if fan != faces_at[v] {
            return None;
        }
        let pi = positions[v];
        let mut n = Vec3::ZERO;
        let mut h = start;
        for _ in 0..from.len() {
            let hn = next[h as usize];
            n += (root(hn) - pi).cross(root(next[hn as usize]) - pi);
            h = if on_boundary { twin[hn as usize] } else { next[twin[h as usize] as usize] };
            if h == start {
                break;
            }
        }
        normals.push(n.try_normalize().unwrap_or(Vec3::Y));
    }
    Some(normals)
}
