//! The part file: an OpenEXR image whose R, G, B channels are the part's mean radiance (so
//! it opens in any viewer) and whose extra channels hold each pixel's exact running sums,
//! with a header attribute naming the part, the scene and the settings.
//!
//! Exactness: every f64 sum is stored as its 64 bits in two u32 channels (`<name>.hi`,
//! `<name>.lo`), never rounded to f32, so a merge sees the very numbers the part computed.

use super::spec::PartSpec;
use super::stats::PartStats;
use anyhow::{Context, Result, anyhow, bail};
use exr::prelude::*;
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};
use wavepath::{Accumulator, PixelSums};

/// Version of the part-file layout; a merge refuses any other.
pub const FORMAT: u32 = 2;
/// The header attribute that holds [`PartMeta`] as JSON.
pub const META_ATTRIBUTE: &str = "wavepath.part";

/// Everything about a part besides its pixels.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct PartMeta {
    pub format: u32,
    pub part: PartSpec,
    pub scene: String,
    pub scene_hash: String,
    /// [`super::identity::settings_key`] of the render.
    pub settings: String,
    pub width: usize,
    pub height: usize,
    pub spp: u32,
    /// The render sampled adaptively (`-a`): the merge then writes the sample-rate image, as
    /// the render of the whole would (absent in older part files: false).
    #[serde(default)]
    pub adaptive: bool,
    pub stats: PartStats,
    /// [`super::identity::pixels_hash`] of the sums, set when the part is encoded and
    /// checked when it is read.
    pub pixels: String,
}

/// The f64 fields of [`PixelSums`], in channel order.
const F64_FIELDS: [&str; 8] = ["sum.R", "sum.G", "sum.B", "sumsq.R", "sumsq.G", "sumsq.B", "s1", "s2"];

fn f64_fields(p: &PixelSums) -> [f64; 8] {
    [p.sum.x, p.sum.y, p.sum.z, p.sum_sq.x, p.sum_sq.y, p.sum_sq.z, p.s1, p.s2]
}

fn set_f64_fields(p: &mut PixelSums, v: [f64; 8]) {
    p.sum = glam::DVec3::new(v[0], v[1], v[2]);
    p.sum_sq = glam::DVec3::new(v[3], v[4], v[5]);
    p.s1 = v[6];
    p.s2 = v[7];
}

/// EXR text is Latin-1 bytes; JSON escapes keep any scene name within ASCII.
fn ascii_json(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        if c.is_ascii() {
            out.push(c);
        } else {
            let mut units = [0u16; 2];
            for u in c.encode_utf16(&mut units) {
                out.push_str(&format!("\\u{u:04x}"));
            }
        }
    }
    out
}

/// File rows run top-down, film rows bottom-up: the film row of file row `r`.
fn film_row(r: usize, height: usize) -> usize {
    height - 1 - r
}

/// Encodes the part in memory.
pub fn encode(meta: &PartMeta, acc: &Accumulator) -> Result<Vec<u8>> {
    let (w, h) = (acc.width, acc.height);
    let n = w * h;
    let mut rgb = [Vec::with_capacity(n), Vec::with_capacity(n), Vec::with_capacity(n)];
    let mut counts = [Vec::with_capacity(n), Vec::with_capacity(n)];
    let mut halves: Vec<Vec<u32>> = vec![Vec::with_capacity(n); 2 * F64_FIELDS.len()];
    for r in 0..h {
        let y = film_row(r, h);
        for p in &acc.pixels[y * w..(y + 1) * w] {
            let m = p.mean();
            for (c, v) in rgb.iter_mut().zip([m.x, m.y, m.z]) {
                c.push(v);
            }
            counts[0].push(p.taken);
            counts[1].push(p.valid);
            for (k, v) in f64_fields(p).into_iter().enumerate() {
                let bits = v.to_bits();
                halves[2 * k].push((bits >> 32) as u32);
                halves[2 * k + 1].push(bits as u32);
            }
        }
    }
    let mut channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    for (name, c) in ["R", "G", "B"].into_iter().zip(rgb) {
        channels.push(AnyChannel::new(name, FlatSamples::F32(c)));
    }
    for (name, c) in ["wavepath.taken", "wavepath.valid"].into_iter().zip(counts) {
        channels.push(AnyChannel::new(name, FlatSamples::U32(c)));
    }
    for (k, name) in F64_FIELDS.iter().enumerate() {
        let hi = std::mem::take(&mut halves[2 * k]);
        let lo = std::mem::take(&mut halves[2 * k + 1]);
        channels.push(AnyChannel::new(format!("wavepath.{name}.hi").as_str(), FlatSamples::U32(hi)));
        channels.push(AnyChannel::new(format!("wavepath.{name}.lo").as_str(), FlatSamples::U32(lo)));
    }
    let mut attrs = LayerAttributes::named("wavepath part");
    let meta = PartMeta { pixels: super::identity::pixels_hash(acc), ..meta.clone() };
    let json = ascii_json(&serde_json::to_string(&meta)?);
    attrs.other.insert(Text::from(META_ATTRIBUTE), AttributeValue::Text(Text::new_or_panic(json)));
    let layer = Layer::new((w, h), attrs, Encoding::SMALL_LOSSLESS, AnyChannels::sort(channels));
    let mut bytes = Vec::new();
    Image::from_layer(layer)
        .write()
        .to_buffered(std::io::Cursor::new(&mut bytes))
        .map_err(|e| anyhow!("cannot encode the part file: {e}"))?;
    Ok(bytes)
}

/// Writes the part under a temporary name beside `path` and renames it when complete, so a
/// part that crashes or is killed never leaves a file a merge would take, and a re-run
/// replaces the old part in one step.
pub fn write(path: &Path, meta: &PartMeta, acc: &Accumulator) -> Result<()> {
    write_via(path, meta, acc, |f| Box::new(f))
}

/// [`write`], with the bytes going through `wrap` around the temporary file: a test can
/// make the write fail part-way (a full disk, a lost mount) and check what is left.
pub fn write_via(
    path: &Path,
    meta: &PartMeta,
    acc: &Accumulator,
    wrap: impl FnOnce(std::fs::File) -> Box<dyn std::io::Write>,
) -> Result<()> {
    let bytes = encode(meta, acc).with_context(|| path.display().to_string())?;
    let tmp = temporary_name(path);
    let result = (|| -> std::io::Result<()> {
        let f = std::fs::File::create(&tmp)?;
        let mut w = wrap(f.try_clone()?);
        w.write_all(&bytes)?;
        w.flush()?;
        drop(w);
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        bail!("{}: cannot write the part file: {e}", path.display());
    }
    Ok(())
}

/// `.<name>.<pid>.partial` in the same folder (same file system, so the rename is atomic);
/// hidden and not ending in .exr, so a glob of parts never picks it up.
fn temporary_name(path: &Path) -> PathBuf {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("part.exr");
    path.with_file_name(format!(".{name}.{}.partial", std::process::id()))
}

/// A part read back: its header and its sums.
pub struct Part {
    pub path: PathBuf,
    pub meta: PartMeta,
    pub acc: Accumulator,
}

/// The part's header alone (cheap: no pixels), so a merge can check every part before it
/// reads any pixels and then read them one at a time.
pub fn read_meta(path: &Path) -> Result<PartMeta> {
    let name = path.display();
    let file = std::fs::File::open(path).with_context(|| format!("{name}: cannot read"))?;
    let meta = exr::meta::MetaData::read_from_buffered(std::io::BufReader::new(file), false)
        .map_err(|e| anyhow!("{name}: not a readable OpenEXR part file ({e})"))?;
    let header = meta.headers.first().ok_or_else(|| anyhow!("{name}: OpenEXR file without a layer"))?;
    parse_meta(path, header.own_attributes.other.get(&Text::from(META_ATTRIBUTE)))
}

fn parse_meta(path: &Path, attribute: Option<&AttributeValue>) -> Result<PartMeta> {
    let name = path.display();
    let meta = match attribute {
        Some(AttributeValue::Text(t)) => t.to_string(),
        _ => bail!("{name}: not a wavepath part file (no {META_ATTRIBUTE} header attribute)"),
    };
    let meta: PartMeta =
        serde_json::from_str(&meta).map_err(|e| anyhow!("{name}: damaged {META_ATTRIBUTE} header attribute ({e})"))?;
    if meta.format != FORMAT {
        bail!("{name}: part file format {} (this wavepath reads format {FORMAT})", meta.format);
    }
    PartSpec::new(meta.part.index, meta.part.count, meta.part.split).with_context(|| format!("{name}: bad part"))?;
    Ok(meta)
}

/// Reads a part file; anything that is not a complete part of this format is an error
/// naming the file.
pub fn read(path: &Path) -> Result<Part> {
    let name = path.display();
    let bytes = std::fs::read(path).with_context(|| format!("{name}: cannot read"))?;
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(&bytes))
        .map_err(|e| anyhow!("{name}: not a readable OpenEXR part file ({e})"))?;
    let layer = &image.layer_data;
    let meta = parse_meta(path, layer.attributes.other.get(&Text::from(META_ATTRIBUTE)))?;
    let (w, h) = (layer.size.x(), layer.size.y());
    if (w, h) != (meta.width, meta.height) {
        bail!("{name}: image is {w}x{h} but the header says {}x{}", meta.width, meta.height);
    }
    let channel = |cname: &str| -> Result<&[u32]> {
        let c = layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.to_string() == cname)
            .ok_or_else(|| anyhow!("{name}: channel {cname} is missing"))?;
        match &c.sample_data {
            FlatSamples::U32(v) if v.len() == w * h => Ok(v),
            _ => bail!("{name}: channel {cname} is not {w}x{h} u32 samples"),
        }
    };
    let taken = channel("wavepath.taken")?;
    let valid = channel("wavepath.valid")?;
    let mut halves = Vec::with_capacity(2 * F64_FIELDS.len());
    for f in F64_FIELDS {
        halves.push(channel(&format!("wavepath.{f}.hi"))?);
        halves.push(channel(&format!("wavepath.{f}.lo"))?);
    }
    let mut acc = Accumulator::new(w, h);
    for r in 0..h {
        let y = film_row(r, h);
        for x in 0..w {
            let i = r * w + x;
            let p = &mut acc.pixels[y * w + x];
            p.taken = taken[i];
            p.valid = valid[i];
            if p.valid > p.taken {
                bail!("{name}: pixel ({x}, {y}) has more valid samples than taken");
            }
            let mut v = [0.0; 8];
            for (k, slot) in v.iter_mut().enumerate() {
                *slot = f64::from_bits(((halves[2 * k][i] as u64) << 32) | halves[2 * k + 1][i] as u64);
            }
            if v.iter().any(|x| !x.is_finite()) {
                bail!("{name}: pixel ({x}, {y}) has a non-finite sum");
            }
            set_f64_fields(p, v);
        }
    }
    if super::identity::pixels_hash(&acc) != meta.pixels {
        bail!("{name}: the pixel data is damaged (its checksum does not match the header's)");
    }
    Ok(Part { path: path.to_path_buf(), meta, acc })
}
