//! The alpha test where hits are found: a candidate hit on a cut triangle whose coverage
//! at the hit's uv fails the material's test (see [`crate::scene::alpha`]) is no hit, and
//! the ray goes on, in every traversal loop and in brute force alike.
//!
//! Built only for scenes where some triangle's material is cut ([`Cutouts::of`] is `None`
//! otherwise): the accelerators then run loops compiled without the test, the same code as
//! before cutouts existed. In a scene with cutouts, an opaque triangle's hit costs one
//! search over the mesh's material runs (a handful).
use crate::geometry::Ray;
use crate::scene::{Alpha, Scene};
use glam::Vec2;

/// Run index meaning "opaque".
const OPAQUE: u32 = u32::MAX;

/// The cut triangles of a scene: what the test needs at a hit, and nothing for the others.
#[derive(Clone, Debug)]
pub struct Cutouts {
    /// One past the last triangle of each material run of the mesh.
    ends: Vec<u32>,
    /// Per run: its material's place in `alphas`, or [`OPAQUE`].
    alpha_of: Vec<u32>,
    /// Per run: where its first triangle's uvs are in `uvs` (cut runs only).
    uv_at: Vec<u32>,
    /// The three corners' uvs of each cut triangle, run by run (the barycentric (u, v)
    /// frame, (0,0) (1,0) (0,1), where the mesh has none: what shading reads then).
    uvs: Vec<[Vec2; 3]>,
    alphas: Vec<Alpha>,
    tri_count: u32,
}

impl Cutouts {
    /// The table of `scene`'s cut triangles; `None` when none is cut.
    pub fn of(scene: &Scene) -> Option<Cutouts> {
        let cut = |m: u32| scene.materials.get(m as usize).is_some_and(|m| !m.alpha.is_opaque() && !m.is_emissive());
        let mesh = &scene.mesh;
        if !mesh.material_ids.runs().any(|(_, _, m)| cut(m)) {
            return None;
        }
        let mut t = Cutouts {
            ends: Vec::new(),
            alpha_of: Vec::new(),
            uv_at: Vec::new(),
            uvs: Vec::new(),
            alphas: Vec::new(),
            tri_count: mesh.triangle_count() as u32,
        };
        let mut index = std::collections::HashMap::new();
        for (start, end, m) in mesh.material_ids.runs() {
            t.ends.push(end as u32);
            t.uv_at.push(t.uvs.len() as u32);
            if !cut(m) {
                t.alpha_of.push(OPAQUE);
                continue;
            }
            let next = t.alphas.len() as u32;
            let a = *index.entry(m).or_insert_with(|| {
                t.alphas.push(scene.materials[m as usize].alpha.clone());
                next
            });
            t.alpha_of.push(a);
            t.uvs.extend((start..end).map(|i| {
                let [a, b, c] = mesh.triangles[i];
                match &mesh.uvs {
                    Some(uv) => [uv[a as usize], uv[b as usize], uv[c as usize]],
                    None => [Vec2::ZERO, Vec2::X, Vec2::Y],
                }
            }));
        }
        Some(t)
    }

    /// Whether the hit at barycentrics (`u`, `v`) of primitive `prim` counts for `ray`.
    #[inline]
    pub fn keeps(&self, prim: u32, u: f32, v: f32, ray: &Ray) -> bool {
        if prim >= self.tri_count {
            return true;
        }
        let run = self.ends.partition_point(|&e| e <= prim);
        let a = self.alpha_of[run];
        if a == OPAQUE {
            return true;
        }
        let start = if run == 0 { 0 } else { self.ends[run - 1] };
        let [ta, tb, tc] = self.uvs[(self.uv_at[run] + prim - start) as usize];
        // As shading interpolates (`Scene::surface_point`).
        let uv = (1.0 - u - v) * ta + u * tb + v * tc;
        let alpha = &self.alphas[a as usize];
        alpha.keeps(alpha.coverage(uv), uniform(ray, prim))
    }

    /// Bytes held (the cut triangles' uvs, mostly).
    pub fn bytes(&self) -> usize {
        std::mem::size_of_val(&self.uvs[..]) + 12 * self.ends.len()
    }
}

/// A number in [0, 1) fixed by the ray (its origin and direction, bit for bit) and the
/// primitive: the same in every kernel that meets this pair, independent between primitives
/// and between rays.
#[inline]
pub fn uniform(ray: &Ray, prim: u32) -> f32 {
    let o = ray.origin.to_array().map(f32::to_bits);
    let d = ray.dir.to_array().map(f32::to_bits);
    let mut h = 0x9e37_79b9_7f4a_7c15u64 ^ prim as u64;
    for w in [o[0], o[1], o[2], d[0], d[1], d[2]] {
        h = mix(h ^ w as u64);
    }
    (h >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
}

/// The SplitMix64 finaliser: every input bit flips each output bit about half the time.
#[inline]
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}
