//! What must agree between parts before they may be merged: the scene they rendered and
//! the settings they rendered it with.

use wavepath::Accumulator;
use wavepath::Scene;
use wavepath::Settings;

/// FNV-1a, 64 bit: stable across runs, platforms and Rust versions (unlike `DefaultHasher`),
/// which is all a check that two processes loaded the same scene needs.
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
    fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 = (self.0 ^ x as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    /// FNV-1a over 64-bit words: eight times fewer steps than bytes, and still a bijection
    /// per step, so any one changed word changes the hash.
    fn word(&mut self, w: u64) {
        self.0 = (self.0 ^ w).wrapping_mul(0x0000_0100_0000_01b3);
    }
    fn tagged(&mut self, tag: &str, b: &[u8]) {
        self.bytes(tag.as_bytes());
        self.bytes(&(b.len() as u64).to_le_bytes());
        self.bytes(b);
    }
}

/// Checksum of a part's exact sums (counts and f64 bits, film order): a part file whose
/// pixels were damaged after it was written is refused instead of merged into a wrong image.
pub fn pixels_hash(acc: &Accumulator) -> String {
    let mut h = Fnv::new();
    h.word(acc.width as u64);
    h.word(acc.height as u64);
    for p in &acc.pixels {
        h.word((p.taken as u64) << 32 | p.valid as u64);
        for v in [p.sum.x, p.sum.y, p.sum.z, p.sum_sq.x, p.sum_sq.y, p.sum_sq.z, p.s1, p.s2] {
            h.word(v.to_bits());
        }
    }
    format!("{:016x}", h.0)
}

/// Hash of the scene as loaded and prepared (camera file and lens applied; the camera's fit
/// to the image is the settings', in [`settings_key`]): the mesh arrays byte for byte,
/// everything else through its `Debug` form (floats print round-trip).
pub fn scene_hash(scene: &Scene) -> String {
    let mut h = Fnv::new();
    let m = &scene.mesh;
    h.tagged("positions", bytemuck::cast_slice(&m.positions));
    h.tagged("triangles", bytemuck::cast_slice(&m.triangles));
    h.tagged("material_runs", bytemuck::cast_slice(&m.material_ids.words().collect::<Vec<u32>>()));
    if let Some(n) = &m.normals {
        h.tagged("normals", bytemuck::cast_slice(n));
    }
    if let Some(uv) = &m.uvs {
        h.tagged("uvs", bytemuck::cast_slice(uv));
    }
    if let Some(c) = &m.colors {
        h.tagged("colors", bytemuck::cast_slice(c));
    }
    let rest =
        format!("{:?}|{:?}|{:?}|{:?}|{:?}", scene.spheres, scene.materials, scene.lights, scene.camera, scene.env);
    h.tagged("rest", rest.as_bytes());
    format!("{:016x}", h.0)
}

/// The settings that decide the image, as text: everything except what only decides how
/// it is computed (threads) or which part is computed (cell, sample range).
pub fn settings_key(s: &Settings) -> String {
    let mut canonical = s.clone();
    canonical.execution.threads = 0;
    canonical.image.cell = None;
    canonical.sampling.sample_range = None;
    canonical.execution.isa = Default::default();
    format!("{canonical:?}")
}
