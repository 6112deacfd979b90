//! Denoising a rendered image with Intel Open Image Denoise (OIDN), loaded at run time: the
//! engine builds and runs without it, and a caller that wants it names the library (or a
//! folder holding it, such as an installed `pyoidn` package) to [`Denoiser::load`].
//!
//! The C API is in `oidn.rs`; everything here is safe Rust. Inputs are sanitised before they
//! reach OIDN (non-finite values to 0, colour non-negative, albedo in [0, 1], normals in
//! [-1, 1]) and the output is checked finite, so no NaN or Inf comes out.

mod oidn;

use std::ffi::CStr;
use std::mem::ManuallyDrop;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, PoisonError};

use anyhow::{Context, anyhow, bail};
use glam::Vec3;
use libloading::Library;

use crate::film::Film;
use oidn::{Api, Buffer, Device, Filter};

/// How to get the denoiser's runtime, for messages when there is none.
pub const OIDN_HELP: &str = "Open Image Denoise is loaded at run time: `pip install pyoidn` (its wheel carries the \
    library, its CPU device and TBB) into the active Python environment, or give the path of the \
    OpenImageDenoise library or of the folder holding it";

/// The auxiliary images the denoiser is fed.
#[derive(Clone, Copy, Debug, Default)]
pub struct Aux<'a> {
    /// Albedo (the surface's reflectance at the first non-specular hit), in [0, 1].
    pub albedo: Option<&'a Film>,
    /// Shading normals at the same hit, components in [-1, 1]; OIDN takes them only together
    /// with `albedo`.
    pub normal: Option<&'a Film>,
    /// The auxiliaries are noisy: denoise them first and then tell the main filter they are
    /// clean (OIDN's recommended prefiltering).
    pub prefilter: bool,
}

/// Open Image Denoise, loaded from a library file, with one committed CPU device.
///
/// `Send` and `Sync`: denoising from several threads is allowed; the calls on the device are
/// serialised (OIDN would serialise them anyway).
pub struct Denoiser {
    path: PathBuf,
    api: Api,
    device: Mutex<Device>,
    /// Never unloaded: OIDN's thread pool (TBB) may keep threads in the library's code after
    /// the device is released, so closing it could pull code from under them. The library
    /// stays mapped until the process ends (loading it again reuses the mapping).
    _library: ManuallyDrop<Library>,
}

impl std::fmt::Debug for Denoiser {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Denoiser").field("library", &self.path).finish_non_exhaustive()
    }
}

/// The library's file names on this system, most specific first.
const LIBRARY_NAMES: &[&str] = if cfg!(windows) {
    &["OpenImageDenoise.dll"]
} else if cfg!(target_vendor = "apple") {
    &["libOpenImageDenoise.2.dylib", "libOpenImageDenoise.dylib"]
} else {
    &["libOpenImageDenoise.so.2", "libOpenImageDenoise.so"]
};

/// Folders under a given folder where the library may sit: the folder itself, an install
/// prefix's, and an installed `pyoidn` package's.
const LIBRARY_FOLDERS: &[&str] =
    if cfg!(windows) { &["", "bin", "oidn/bin", "lib", "oidn/lib"] } else { &["", "lib", "oidn/lib"] };

/// The library file `path` names: itself, or the first library found in a folder.
fn library_file(path: &Path) -> anyhow::Result<PathBuf> {
    let meta = std::fs::metadata(path).map_err(|e| {
        let problem =
            if e.kind() == std::io::ErrorKind::NotFound { "no such file or folder".into() } else { e.to_string() };
        anyhow!("{}: {problem}; {OIDN_HELP}", path.display())
    })?;
    if !meta.is_dir() {
        return Ok(path.to_path_buf());
    }
    for folder in LIBRARY_FOLDERS {
        for name in LIBRARY_NAMES {
            let file = path.join(folder).join(name);
            if file.is_file() {
                return Ok(file);
            }
        }
    }
    bail!(
        "{}: no Open Image Denoise library in this folder (looked for {} in {}); {OIDN_HELP}",
        path.display(),
        LIBRARY_NAMES.join(", "),
        LIBRARY_FOLDERS.iter().map(|f| if f.is_empty() { "." } else { f }).collect::<Vec<_>>().join(", ")
    )
}

/// The error and its causes on one line.
fn one_line(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        text = format!("{text}: {s}");
        source = s.source();
    }
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Loads the library file itself, its dependencies found next to it.
fn open(file: &Path) -> Result<Library, libloading::Error> {
    #[cfg(windows)]
    {
        use libloading::os::windows::{
            LOAD_LIBRARY_SEARCH_DEFAULT_DIRS, LOAD_LIBRARY_SEARCH_DLL_LOAD_DIR, Library as WinLibrary,
        };
        let flags = LOAD_LIBRARY_SEARCH_DLL_LOAD_DIR | LOAD_LIBRARY_SEARCH_DEFAULT_DIRS;
        // The CPU device module first (as pyoidn does): the core loads it by name, which then
        // finds it loaded, its own dependencies (TBB) found beside it.
        if let Some(device) = file.parent().map(|d| d.join("OpenImageDenoise_device_cpu.dll")).filter(|d| d.is_file()) {
            // SAFETY: as below; a module of the same distribution, kept loaded for good.
            if let Ok(module) = unsafe { WinLibrary::load_with_flags(&device, flags) } {
                std::mem::forget(module);
            }
        }
        // SAFETY: loading runs the library's initialisers; the file is the user's choice of
        // Open Image Denoise, whose initialisers have no requirements on the caller.
        unsafe { WinLibrary::load_with_flags(file, flags) }.map(Library::from)
    }
    #[cfg(not(windows))]
    {
        // SAFETY: loading runs the library's initialisers; the file is the user's choice of
        // Open Image Denoise, whose initialisers have no requirements on the caller. Its
        // dependencies are found through its own RPATH (`$ORIGIN` in the official builds).
        unsafe { Library::new(file) }
    }
}

impl Denoiser {
    /// `path`: the library file itself (libOpenImageDenoise.so.2 / .so / .dylib /
    /// OpenImageDenoise.dll) or a folder holding it; a folder that is an installed `pyoidn`
    /// package (has oidn/lib/) is accepted too.
    pub fn load(path: &Path) -> anyhow::Result<Denoiser> {
        let file = library_file(path)?;
        let shown = file.display();
        let library = open(&file).map_err(|e| {
            // The system's message often starts with the file's name already.
            let why = one_line(&e);
            let why = why.strip_prefix(&format!("{shown}: ")).unwrap_or(&why);
            anyhow!("{shown}: cannot load Open Image Denoise ({why}); {OIDN_HELP}")
        })?;
        // SAFETY: the symbols of these names in a library that has them are OIDN 2.x's C API
        // (OIDN 1.x lacks `oidnSetFilterBool` and `oidnWriteBuffer`, so it fails here); the
        // library is never unloaded.
        let api = unsafe { Api::resolve(&library) }.map_err(|symbol| {
            anyhow!("{shown}: not Open Image Denoise 2: it has no function `{symbol}`; {OIDN_HELP}")
        })?;
        // SAFETY: plain call with a valid device type; a null result is handled below.
        let raw = unsafe { (api.new_device)(oidn::DEVICE_TYPE_CPU) };
        if raw.is_null() {
            let why = api.take_error(std::ptr::null_mut()).unwrap_or_else(|| "no reason given".into());
            bail!("{shown}: Open Image Denoise has no CPU device ({why}); is its device_cpu module beside it?");
        }
        let device = Device(raw);
        // SAFETY: `raw` is a new, live device.
        unsafe { (api.commit_device)(raw) };
        if let Err(e) = api.check(raw, "cannot start the CPU device") {
            // SAFETY: the device is live and released once, here.
            unsafe { (api.release_device)(raw) };
            bail!("{shown}: Open Image Denoise {e}");
        }
        Ok(Denoiser { path: file, api, device: Mutex::new(device), _library: ManuallyDrop::new(library) })
    }

    /// The library file actually loaded.
    pub fn library(&self) -> &Path {
        &self.path
    }

    /// HDR colour (linear radiance, [`Film`] rows bottom-first as `film::Film` documents)
    /// denoised with OIDN's "RT" filter, hdr=true; albedo/normal when given (normal requires
    /// albedo in OIDN: refused without it). Returns a new Film of the same size; errors from
    /// OIDN carry its message on one line.
    pub fn denoise(&self, color: &Film, aux: Aux<'_>) -> anyhow::Result<Film> {
        let (w, h) = (color.width, color.height);
        if w == 0 || h == 0 {
            bail!("cannot denoise an empty {w}x{h} image");
        }
        let n = w.checked_mul(h).filter(|n| n.checked_mul(12).is_some()).context("image too large to denoise")?;
        if color.pixels.len() != n {
            bail!("the colour image claims {w}x{h} pixels but holds {}", color.pixels.len());
        }
        if aux.normal.is_some() && aux.albedo.is_none() {
            bail!("a normal image needs an albedo image too: Open Image Denoise takes normals only with albedo");
        }
        for (name, film) in [("albedo", aux.albedo), ("normal", aux.normal)] {
            if let Some(f) = film
                && (f.width, f.height, f.pixels.len()) != (w, h, n)
            {
                bail!(
                    "the {name} image is {}x{} ({} pixels), the colour image {w}x{h}",
                    f.width,
                    f.height,
                    f.pixels.len()
                );
            }
        }

        let color_data = pack(color, |c| if c.is_finite() { c.max(0.0) } else { 0.0 });
        let albedo_data = aux.albedo.map(|f| pack(f, |c| if c.is_finite() { c.clamp(0.0, 1.0) } else { 0.0 }));
        let normal_data = aux.normal.map(|f| pack(f, |c| if c.is_finite() { c.clamp(-1.0, 1.0) } else { 0.0 }));

        let device = self.device.lock().unwrap_or_else(PoisonError::into_inner);
        let fail = |e: String| anyhow!("{}: Open Image Denoise {e}", self.path.display());
        let api = &self.api;
        // Buffers before filters: the filters are dropped (released) first.
        let color_buf = Buffer::with_data(api, &device, &color_data).map_err(fail)?;
        let output_buf = Buffer::with_data(api, &device, &vec![0.0; 3 * n]).map_err(fail)?;
        let albedo_buf = albedo_data.map(|d| Buffer::with_data(api, &device, &d)).transpose().map_err(fail)?;
        let normal_buf = normal_data.map(|d| Buffer::with_data(api, &device, &d)).transpose().map_err(fail)?;

        let prefilter = aux.prefilter && albedo_buf.is_some();
        if prefilter {
            // Each auxiliary denoised in place by an RT filter that has it as its only input.
            for (name, buf) in [(c"albedo", &albedo_buf), (c"normal", &normal_buf)] {
                if let Some(buf) = buf {
                    let filter = Filter::rt(api, &device).map_err(fail)?;
                    filter.set_image(name, buf, w, h);
                    filter.set_image(c"output", buf, w, h);
                    filter.run(&device, &format!("prefiltering of the {} image", name_of(name))).map_err(fail)?;
                }
            }
        }

        let filter = Filter::rt(api, &device).map_err(fail)?;
        filter.set_image(c"color", &color_buf, w, h);
        if let Some(buf) = &albedo_buf {
            filter.set_image(c"albedo", buf, w, h);
        }
        if let Some(buf) = &normal_buf {
            filter.set_image(c"normal", buf, w, h);
        }
        filter.set_image(c"output", &output_buf, w, h);
        filter.set_bool(c"hdr", true);
        if prefilter {
            filter.set_bool(c"cleanAux", true);
        }
        filter.run(&device, "denoising").map_err(fail)?;
        let out = output_buf.read(&device).map_err(fail)?;
        drop(filter);
        drop(device);

        let mut film = unpack(w, h, &out);
        let bad = film.pixels.iter().filter(|p| !p.is_finite()).count();
        if bad > 0 {
            bail!("{}: Open Image Denoise returned {bad} non-finite pixels", self.path.display());
        }
        // Radiance is never negative; OIDN may round a dark pixel a hair below 0.
        for p in &mut film.pixels {
            *p = p.max(Vec3::ZERO);
        }
        Ok(film)
    }
}

impl Drop for Denoiser {
    fn drop(&mut self) {
        let device = self.device.get_mut().unwrap_or_else(PoisonError::into_inner);
        // SAFETY: the device is live, every buffer and filter of it is gone (they borrow the
        // denoiser), and it is released once, here.
        unsafe { (self.api.release_device)(device.0) };
    }
}

fn name_of(name: &CStr) -> &str {
    name.to_str().unwrap_or("auxiliary")
}

/// The film as packed RGB floats, rows top-first (the order of image files, which OIDN's
/// training data used), each component through `clean`.
fn pack(film: &Film, clean: impl Fn(f32) -> f32) -> Vec<f32> {
    let mut out = Vec::with_capacity(film.pixels.len() * 3);
    for row in film.pixels.chunks_exact(film.width).rev() {
        for p in row {
            out.extend([clean(p.x), clean(p.y), clean(p.z)]);
        }
    }
    out
}

/// The inverse of `pack`: packed RGB floats, rows top-first, as a film.
fn unpack(width: usize, height: usize, data: &[f32]) -> Film {
    let mut film = Film::new(width, height);
    for (y, row) in data.chunks_exact(width * 3).enumerate() {
        let dst = height - 1 - y;
        for (x, p) in row.chunks_exact(3).enumerate() {
            film.pixels[dst * width + x] = Vec3::new(p[0], p[1], p[2]);
        }
    }
    film
}
