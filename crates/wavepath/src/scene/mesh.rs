use super::MaterialIds;
use glam::{Vec2, Vec3, Vec4};

/// All triangles of a scene in world space, as parallel arrays (structure of arrays).
///
/// Vertex attributes are indexed by the `[u32; 3]` triples; `normals` and `uvs`, when
/// present, have exactly one entry per position. Triangle `i` keeps its file order
/// (polygons fan-triangulated (v0,v1,v2), (v0,v2,v3), ...), which is the numbering that
/// ray files and the peers use.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub uvs: Option<Vec<Vec2>>,
    /// Linear RGB per vertex (glTF `COLOR_0`, OBJ `v x y z r g b`, PLY red green blue): it
    /// multiplies the material's base colour.
    pub colors: Option<Vec<Vec3>>,
    /// Per-vertex tangents (xyz, and w = +-1 the bitangent's handedness) for normal maps:
    /// kept only when some material has a normal map (a scanned mesh gets none).
    pub tangents: Option<Vec<Vec4>>,
    pub triangles: Vec<[u32; 3]>,
    pub material_ids: MaterialIds,
}

/// An analytic sphere (CS184 spheres stay exact, never tessellated).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    pub center: Vec3,
    pub radius: f32,
    pub material: u32,
}

impl Mesh {
    /// Bytes its arrays hold (lengths, not capacities: what a load should leave resident).
    pub fn bytes(&self) -> usize {
        fn of<T>(v: &[T]) -> usize {
            std::mem::size_of_val(v)
        }
        of(&self.positions)
            + self.normals.as_deref().map_or(0, of)
            + self.uvs.as_deref().map_or(0, of)
            + self.colors.as_deref().map_or(0, of)
            + self.tangents.as_deref().map_or(0, of)
            + of(&self.triangles)
            + self.material_ids.bytes()
    }

    /// Appends another mesh (already in world space), shifting its indices; attributes that
    /// only one side has are filled with zeros so the arrays stay parallel.
    pub fn append(&mut self, other: Mesh) {
        let base = self.positions.len() as u32;
        let had = self.positions.len();
        let add = other.positions.len();
        merge_attr(&mut self.normals, other.normals, had, add, Vec3::ZERO);
        merge_attr(&mut self.uvs, other.uvs, had, add, Vec2::ZERO);
        // A part without colours is white: its base colour unchanged.
        merge_attr(&mut self.colors, other.colors, had, add, Vec3::ONE);
        merge_attr(&mut self.tangents, other.tangents, had, add, Vec4::ZERO);
        self.positions.extend(other.positions);
        self.triangles.extend(other.triangles.into_iter().map(|t| [t[0] + base, t[1] + base, t[2] + base]));
        for (start, end, id) in other.material_ids.runs() {
            self.material_ids.push_run(id, end - start);
        }
    }

    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The three corner positions of triangle `i`.
    #[inline]
    pub fn corners(&self, i: usize) -> [Vec3; 3] {
        let [a, b, c] = self.triangles[i];
        [self.positions[a as usize], self.positions[b as usize], self.positions[c as usize]]
    }

    /// Checks index ranges, array lengths and finiteness.
    pub fn validate(&self, material_count: usize) -> Result<(), String> {
        let n = self.positions.len();
        if let Some(i) = first_bad(&self.positions, |p| !p.is_finite()) {
            return Err(format!("vertex {i} has a non-finite coordinate"));
        }
        if let Some(normals) = &self.normals {
            if normals.len() != n {
                return Err(format!("{} normals for {n} vertices", normals.len()));
            }
            if normals.iter().any(|v| !v.is_finite()) {
                return Err("a vertex normal is not finite".into());
            }
        }
        if let Some(c) = &self.colors {
            if c.len() != n {
                return Err(format!("{} vertex colours for {n} vertices", c.len()));
            }
            if c.iter().any(|v| !v.is_finite() || v.min_element() < 0.0) {
                return Err("a vertex colour is negative or not finite".into());
            }
        }
        if let Some(t) = &self.tangents {
            if t.len() != n {
                return Err(format!("{} tangents for {n} vertices", t.len()));
            }
            if t.iter().any(|v| !v.is_finite()) {
                return Err("a vertex tangent is not finite".into());
            }
        }
        if let Some(uvs) = &self.uvs {
            if uvs.len() != n {
                return Err(format!("{} uvs for {n} vertices", uvs.len()));
            }
            if uvs.iter().any(|v| !v.is_finite()) {
                return Err("a texture coordinate is not finite".into());
            }
        }
        if self.material_ids.len() != self.triangles.len() {
            return Err(format!("{} material ids for {} triangles", self.material_ids.len(), self.triangles.len()));
        }
        if let Some(i) = first_bad(&self.triangles, |t| t.iter().any(|&v| v as usize >= n)) {
            let bad = self.triangles[i].iter().find(|&&v| v as usize >= n).copied().unwrap_or_default();
            return Err(format!("triangle {i} uses vertex {bad}, but there are only {n}"));
        }
        if let Some((_, _, m)) = self.material_ids.runs().find(|&(_, _, m)| m as usize >= material_count) {
            return Err(format!("a triangle uses material {m}, but there are only {material_count}"));
        }
        Ok(())
    }
}

fn merge_attr<T: Copy>(mine: &mut Option<Vec<T>>, theirs: Option<Vec<T>>, had: usize, add: usize, zero: T) {
    match (mine.as_mut(), theirs) {
        (Some(m), Some(t)) => m.extend(t),
        (Some(m), None) => m.extend(std::iter::repeat_n(zero, add)),
        (None, Some(t)) => {
            let mut v = vec![zero; had];
            v.extend(t);
            *mine = Some(v);
        }
        (None, None) => {}
    }
}

/// Index of the first element of `v` for which `bad` holds, scanned in parallel chunks (a
/// scanned mesh has tens of millions of vertices and triangles; per-element parallel
/// searches cost more than the test).
pub fn first_bad<T: Sync>(v: &[T], bad: impl Fn(&T) -> bool + Sync) -> Option<usize> {
    use rayon::prelude::*;
    const CHUNK: usize = 1 << 16;
    v.par_chunks(CHUNK).enumerate().find_map_first(|(k, c)| c.iter().position(&bad).map(|j| k * CHUNK + j))
}
