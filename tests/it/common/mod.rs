//! Helpers shared by the test modules: the scenes folder, the binary, bit-exact hit
//! comparison, and the submodules below.

pub mod agree;
pub mod cdp;
pub mod chi2;
pub mod gltf_brdf;
pub mod meshgen;
pub mod render;

use std::path::PathBuf;
use std::process::{Command, Output};
use wavepath::geometry::Hit;
use wavepath::load::{LoadOptions, load};
use wavepath::scene::Scene;

/// Whether two traversals found the same hit, bit for bit (t, primitive, barycentrics).
pub fn same_hit(a: Option<Hit>, b: Option<Hit>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => {
            a.t.to_bits() == b.t.to_bits()
                && a.prim == b.prim
                && a.u.to_bits() == b.u.to_bits()
                && a.v.to_bits() == b.v.to_bits()
        }
        _ => false,
    }
}

/// The shared scenes folder: `WAVEPATH_SCENES`, else `../shared/scenes` beside the repo.
///
/// When `WAVEPATH_SCENES` is set (CI sets it), a missing folder fails the test; when it is
/// unset and the default folder is absent, returns `None` and the caller skips.
pub fn scenes_dir() -> Option<PathBuf> {
    match std::env::var_os("WAVEPATH_SCENES") {
        Some(p) => {
            let p = PathBuf::from(p);
            assert!(p.is_dir(), "WAVEPATH_SCENES={} is not a folder", p.display());
            Some(p)
        }
        None => {
            let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/scenes");
            if p.is_dir() {
                Some(p)
            } else {
                eprintln!("skipped: no ../shared/scenes and WAVEPATH_SCENES is unset");
                None
            }
        }
    }
}

/// A file in the shared scenes folder (None: skip, see [`scenes_dir`]).
pub fn scene(rel: &str) -> Option<PathBuf> {
    scenes_dir().map(|d| d.join(rel))
}

/// A file in the shared scenes folder loaded with the default options (None: skip, see
/// [`scenes_dir`]); a file that does not load fails the test.
pub fn load_scene(rel: &str) -> Option<Scene> {
    scene(rel).map(|p| load(&p, &LoadOptions::default()).unwrap_or_else(|e| panic!("{}: {e:#}", p.display())))
}

/// Every file under `dir` with one of the extensions, sorted.
pub fn files_with_ext(dir: &std::path::Path, exts: &[&str]) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if let Some(x) = p.extension().and_then(|x| x.to_str())
                && exts.contains(&x.to_ascii_lowercase().as_str())
            {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// Form factor from a differential area to a parallel rectangle with one corner straight
/// above it at height h (sides x, y; signed, so rectangles combine by superposition).
pub fn corner_form_factor(x: f64, y: f64, h: f64) -> f64 {
    let (a, b) = ((h * h + x * x).sqrt(), (h * h + y * y).sqrt());
    (x / a * (y / a).atan() + y / b * (x / b).atan()) / (2.0 * std::f64::consts::PI)
}

/// Form factor from a point at height h below the rectangle [x0, x1] x [z0, z1] (relative
/// to the point's x and z), parallel to it.
pub fn rect_form_factor(x0: f64, x1: f64, z0: f64, z1: f64, h: f64) -> f64 {
    let f = |x, z| corner_form_factor(x, z, h);
    f(x1, z1) - f(x0, z1) - f(x1, z0) + f(x0, z0)
}

/// Moeller-Trumbore in f64: (t, u, v) of the ray o + t d on the plane of triangle a b c
/// (u, v barycentric toward b and c, not checked against the triangle's edges); `None` when
/// the ray is parallel to it.
pub fn triangle_f64(o: glam::DVec3, d: glam::DVec3, [a, b, c]: [glam::DVec3; 3]) -> Option<(f64, f64, f64)> {
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let s = o - a;
    let q = s.cross(e1);
    Some((e2.dot(q) / det, s.dot(p) / det, d.dot(q) / det))
}

/// Path of the built `wavepath` binary (integration tests only).
pub fn wavepath_bin() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_wavepath"))
}

/// Runs the built `wavepath` binary with `args` (strings or paths) and waits for it.
pub fn run_wavepath<S: AsRef<std::ffi::OsStr>>(args: impl IntoIterator<Item = S>) -> Output {
    Command::new(wavepath_bin()).args(args).output().expect("wavepath runs")
}

/// xorshift64: a fixed, reproducible stream for damaging files (not a sampler: tests of
/// sampling use the renderer's own streams or `common::chi2`).
pub struct Xorshift(pub u64);

impl Xorshift {
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    /// Uniform in 0..n (n > 0; 0 is treated as 1).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// A fresh, empty folder under the system temp dir, unique to `name` and this process (the
/// tests run side by side in one process, so `name` starts with its module's name).
pub fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("wavepath-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}
