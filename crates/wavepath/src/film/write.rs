use super::{AovImage, Film};
use anyhow::{Context, Result, bail};
use std::io::Write;
use std::path::Path;

/// How linear radiance becomes 8-bit PNG values.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Tonemap {
    /// The reference renderer's transfer: clamp((sqrt(2) L)^(1/2.2), 0, 1), truncated to
    /// 8 bits as the reference writes its bytes (the rules: [`crate::cs184`]).
    #[default]
    Cs184,
    /// Plain sRGB encoding of clamp(L, 0, 1), rounded to the nearest 8-bit level.
    Srgb,
}

crate::choice::named!(Tonemap, "tonemap", {
    Cs184 => "cs184", "the reference renderer's transfer: clamp((sqrt(2) L)^(1/2.2), 0, 1)";
    Srgb => "srgb", "plain sRGB encoding of clamp(L, 0, 1)";
});

impl Tonemap {
    #[inline]
    pub fn apply(self, l: f32) -> f32 {
        let l = if l.is_finite() { l.max(0.0) } else { 0.0 };
        match self {
            Tonemap::Cs184 => crate::cs184::transfer(l),
            Tonemap::Srgb => {
                let l = l.min(1.0);
                if l <= 0.003_130_8 { 12.92 * l } else { 1.055 * l.powf(1.0 / 2.4) - 0.055 }
            }
        }
    }

    /// The 8-bit value of linear radiance `l`: the reference truncates (`(uint8_t)(v * 255)`),
    /// so `cs184` reproduces its bytes; `srgb` rounds, as image encoders do.
    #[inline]
    pub fn byte(self, l: f32) -> u8 {
        let v = self.apply(l) * 255.0;
        match self {
            Tonemap::Cs184 => crate::cs184::byte(v),
            Tonemap::Srgb => (v + 0.5) as u8,
        }
    }
}

/// Writes the film; the format follows the extension: .png (tone-mapped), .exr, .hdr, .pfm
/// (linear, never tone-mapped). Writes to a temporary name and renames, so a killed render
/// never leaves a half-written image under the final name.
pub fn write_image(film: &Film, path: &Path, tonemap: Tonemap) -> Result<()> {
    let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).unwrap_or_default();
    let tmp = path.with_extension(format!("tmp.{ext}"));
    let (w, h) = (film.width as u32, film.height as u32);
    let top_down = |f: &dyn Fn(glam::Vec3) -> [f32; 3]| -> Vec<f32> {
        let mut out = Vec::with_capacity(film.pixels.len() * 3);
        for y in (0..film.height).rev() {
            for x in 0..film.width {
                out.extend(f(film.get(x, y)));
            }
        }
        out
    };
    let linear = |p: glam::Vec3| {
        let q = if p.is_finite() { p } else { glam::Vec3::ZERO };
        [q.x, q.y, q.z]
    };
    let result = match ext.as_str() {
        "png" => {
            let data: Vec<u8> = top_down(&|p| [p.x, p.y, p.z]).into_iter().map(|v| tonemap.byte(v)).collect();
            let img = image::RgbImage::from_raw(w, h, data).context("image size mismatch")?;
            img.save_with_format(&tmp, image::ImageFormat::Png).map_err(anyhow::Error::from)
        }
        "exr" | "hdr" => {
            let img = image::Rgb32FImage::from_raw(w, h, top_down(&linear)).context("image size mismatch")?;
            let fmt = if ext == "exr" { image::ImageFormat::OpenExr } else { image::ImageFormat::Hdr };
            image::DynamicImage::ImageRgb32F(img).save_with_format(&tmp, fmt).map_err(anyhow::Error::from)
        }
        "pfm" => write_pfm(film, &tmp),
        "" => bail!("{}: output has no extension; use .png, .exr, .hdr or .pfm", path.display()),
        other => bail!("{}: unknown image format '.{other}'; use .png, .exr, .hdr or .pfm", path.display()),
    };
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(e.context(format!("{}: cannot write image", path.display())));
    }
    std::fs::rename(&tmp, path).with_context(|| format!("{}: cannot write image", path.display()))
}

/// Portable float map: little-endian (negative scale), rows bottom to top, which is the
/// film's own row order.
fn write_pfm(film: &Film, path: &Path) -> Result<()> {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
    write!(f, "PF\n{} {}\n-1.0\n", film.width, film.height)?;
    for p in &film.pixels {
        let q = if p.is_finite() { *p } else { glam::Vec3::ZERO };
        for c in [q.x, q.y, q.z] {
            f.write_all(&c.to_le_bytes())?;
        }
    }
    f.flush()?;
    Ok(())
}

/// Writes the film with the output variables `aovs` and, for a denoised film, the `noisy`
/// picture it was made from: an OpenEXR file holds them all as named layers of one image
/// beside the picture's `R`, `G`, `B` (`albedo.R`, `normal.X`, `depth.Z`, `position.X`,
/// `variance.R`, `noisy.R`...: the `layer.channel` names Nuke, Blender and OpenEXR's tools
/// group into layers); any other format writes each to a file of its own beside the image,
/// `<stem>.<layer>.<ext>` (`.exr` beside a PNG, whose bytes cannot hold them). Returns the
/// files written, the image first.
pub fn write_image_with_aovs(
    film: &Film,
    aovs: &[AovImage],
    noisy: Option<&Film>,
    path: &Path,
    tonemap: Tonemap,
) -> Result<Vec<std::path::PathBuf>> {
    let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).unwrap_or_default();
    let mut layers: Vec<Layer> = aovs
        .iter()
        .map(|a| Layer {
            name: a.aov.name(),
            channels: a.aov.channels(),
            width: a.width,
            height: a.height,
            data: a.data.clone(),
        })
        .collect();
    if let Some(n) = noisy {
        let data = n.pixels.iter().flat_map(|p| p.to_array()).collect();
        layers.push(Layer { name: "noisy", channels: &["R", "G", "B"], width: n.width, height: n.height, data });
    }
    if layers.is_empty() {
        write_image(film, path, tonemap)?;
        return Ok(vec![path.to_path_buf()]);
    }
    if ext == "exr" {
        write_layered_exr(film, &layers, path)?;
        return Ok(vec![path.to_path_buf()]);
    }
    write_image(film, path, tonemap)?;
    let mut written = vec![path.to_path_buf()];
    let side_ext = if ext == "png" { "exr" } else { ext.as_str() };
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("image");
    for l in &layers {
        let side = path.with_file_name(format!("{stem}.{}.{side_ext}", l.name));
        write_image(&l.to_film(), &side, tonemap)?;
        written.push(side);
    }
    Ok(written)
}

/// A named layer of an image file: its channels interleaved, rows bottom first.
struct Layer {
    name: &'static str,
    channels: &'static [&'static str],
    width: usize,
    height: usize,
    data: Vec<f32>,
}

impl Layer {
    fn to_film(&self) -> Film {
        let c = self.channels.len();
        let pixels = self
            .data
            .chunks_exact(c)
            .map(|p| if c == 1 { glam::Vec3::splat(p[0]) } else { glam::Vec3::new(p[0], p[1], p[2]) })
            .collect();
        Film { width: self.width, height: self.height, pixels }
    }
}

/// One OpenEXR image: the picture's R, G, B and every layer's channels under its name.
fn write_layered_exr(film: &Film, layers: &[Layer], path: &Path) -> Result<()> {
    use exr::prelude::{
        AnyChannel, AnyChannels, Encoding, FlatSamples, Image, LayerAttributes, SmallVec, WritableImage,
    };
    let (w, h) = (film.width, film.height);
    // File rows run top-down, film rows bottom-up.
    let top_down = |c: usize, channels: usize, data: &dyn Fn(usize) -> f32| -> Vec<f32> {
        let mut out = Vec::with_capacity(w * h);
        for y in (0..h).rev() {
            for x in 0..w {
                let v = data((y * w + x) * channels + c);
                out.push(if v.is_finite() { v } else { 0.0 });
            }
        }
        out
    };
    let beauty: Vec<f32> = film.pixels.iter().flat_map(|p| p.to_array()).collect();
    let mut channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
        channels.push(AnyChannel::new(name, FlatSamples::F32(top_down(c, 3, &|i| beauty[i]))));
    }
    for l in layers {
        if (l.width, l.height) != (w, h) {
            bail!("{}: the {} image is {}x{}, the picture {w}x{h}", path.display(), l.name, l.width, l.height);
        }
        let n = l.channels.len();
        for (c, ch) in l.channels.iter().enumerate() {
            let name = format!("{}.{ch}", l.name);
            channels.push(AnyChannel::new(name.as_str(), FlatSamples::F32(top_down(c, n, &|i| l.data[i]))));
        }
    }
    let layer = exr::prelude::Layer::new(
        (w, h),
        LayerAttributes::default(),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(channels),
    );
    let tmp = path.with_extension("tmp.exr");
    let result = Image::from_layer(layer).write().to_file(&tmp);
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        bail!("{}: cannot write image: {e}", path.display());
    }
    std::fs::rename(&tmp, path).with_context(|| format!("{}: cannot write image", path.display()))
}
