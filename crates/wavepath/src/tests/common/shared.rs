//! The helpers both test crates use: the scenes folder, bit-exact hit comparison, form
//! factors, a reproducible stream for damaging files, temporary folders (the face only).

use std::path::PathBuf;
use wavepath::Hit;
use wavepath::Scene;
use wavepath::{LoadOptions, load};

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
            let p = repo_root().join("../shared/scenes");
            if p.is_dir() {
                Some(p)
            } else {
                eprintln!("skipped: no ../shared/scenes and WAVEPATH_SCENES is unset");
                None
            }
        }
    }
}

/// The repository's root (the workspace's folder, whichever crate's tests run).
pub fn repo_root() -> PathBuf {
    let here = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    here.ancestors().find(|d| d.join("Cargo.lock").is_file()).unwrap_or(&here).to_path_buf()
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

    /// Uniform in [0, 1), 24 bits.
    #[allow(dead_code)] // the applications' tests use it
    pub fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
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

/// The Open Image Denoise runtime the real-denoiser tests use: `WAVEPATH_OIDN` when set (CI
/// sets it to pyoidn's folder: the tests must then load it), else the folder of the `pyoidn`
/// package of `python3` on the PATH (as `find_oidn` asks for it), else `None`, said on one
/// line naming `what` is skipped, so that a machine without pyoidn passes.
pub fn oidn_for_tests(what: &str) -> Option<PathBuf> {
    if let Some(path) = std::env::var_os("WAVEPATH_OIDN") {
        return Some(PathBuf::from(path));
    }
    let found = (|| {
        let out = std::process::Command::new("python3")
            .args(["-c", "import importlib.util as u; print(u.find_spec('pyoidn').submodule_search_locations[0])"])
            .stdin(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .output()
            .ok()?;
        let folder = PathBuf::from(String::from_utf8(out.stdout).ok()?.trim());
        (out.status.success() && folder.is_dir()).then_some(folder)
    })();
    if found.is_none() {
        println!("no Open Image Denoise (WAVEPATH_OIDN unset, no pyoidn for python3): {what} skipped");
    }
    found
}
