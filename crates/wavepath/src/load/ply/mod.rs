//! PLY (ascii, binary little and big endian) through ply-rs-bw.
//!
//! Vertices give positions and, when the header declares them, normals (nx ny nz) and uvs
//! (u v, s t or texture_u texture_v); faces are index lists of any length, fan-triangulated in
//! file order. Before parsing, the header's element counts are checked against the file size,
//! so a header that promises more data than the file holds is an error, not a long loop or
//! a large allocation.

mod bulk;
mod write;

pub use write::write_binary;

use crate::scene::{Material, Mesh, Scene};
use anyhow::{Context, Result, anyhow};
use glam::{Vec2, Vec3};
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{
    ElementDef, Encoding, Header, Property, PropertyAccess, PropertyAccessResult, PropertyType, ScalarType,
};
use std::io::Cursor;
use std::path::Path;

pub fn load(path: &Path) -> Result<Scene> {
    let shown = path.display();
    let bytes = read_parallel(path).with_context(|| format!("{shown}: cannot read"))?;
    let (mesh, reader) = parse(&bytes).map_err(|e| anyhow!("{shown}: {e}"))?;
    let mut scene = Scene { mesh, materials: vec![Material::default()], ..Scene::default() };
    scene.source.reader = reader;
    super::finish_mesh_only(&mut scene, false);
    Ok(scene)
}

/// The whole file, read by all threads at once: each chunk's page faults and copy from the
/// page cache run in parallel, about twice as fast as one `read` on two cores for the
/// half-gigabyte scans this format carries.
fn read_parallel(path: &Path) -> std::io::Result<Vec<u8>> {
    #[cfg(unix)]
    {
        use rayon::prelude::*;
        use std::os::unix::fs::FileExt;
        let file = std::fs::File::open(path)?;
        let len = usize::try_from(file.metadata()?.len()).map_err(std::io::Error::other)?;
        let mut bytes = vec![0u8; len];
        const CHUNK: usize = 8 << 20;
        bytes.par_chunks_mut(CHUNK).enumerate().try_for_each(|(k, c)| file.read_exact_at(c, (k * CHUNK) as u64))?;
        Ok(bytes)
    }
    #[cfg(not(unix))]
    std::fs::read(path)
}

/// [`crate::scene::SceneSource::reader`] of a file the bulk reader read.
pub const BULK_READER: &str = "ply-bulk";
/// [`crate::scene::SceneSource::reader`] of a file the general parser read.
pub const GENERAL_READER: &str = "ply-general";

/// Parses a whole PLY file held in memory; also says which reader did
/// ([`BULK_READER`] or [`GENERAL_READER`]): the bulk reader declines layouts it does not
/// know, and the general parser then reads them, silently but for this name.
pub fn parse(bytes: &[u8]) -> Result<(Mesh, &'static str), String> {
    if !bytes.starts_with(b"ply") {
        return Err("not a PLY file (it does not start with 'ply')".into());
    }
    let mut reader = Reader::new(Cursor::new(bytes));
    let header = Parser::<Skip>::new().read_header(&mut reader).map_err(|e| match sentence(&e.to_string()) {
        Some((line, text, _)) => format!("header line {line}: '{text}' is not a valid header line"),
        None => format!("bad header: {}", one_line(&e.to_string())),
    })?;
    let payload = &bytes[header_len(bytes)?..];
    check_counts(&header, payload.len())?;
    if let Some(mesh) = bulk::parse(&header, payload) {
        return mesh.map(|m| (m, BULK_READER));
    }
    parse_general(&header, &mut reader).map(|m| (m, GENERAL_READER))
}

/// The general parser (ply-rs-bw, element by element): ascii files, polygons, and layouts
/// the bulk reader declines. `reader` stands at the payload.
fn parse_general(header: &Header, reader: &mut Reader<Cursor<&[u8]>>) -> Result<Mesh, String> {
    let mut verts: Vec<Vertex> = Vec::new();
    let mut faces: Vec<Face> = Vec::new();
    for (name, def) in &header.elements {
        let what = |e: ply_rs_bw::parser::ParseError| match sentence(&e.to_string()) {
            Some((line, text, Some(reason))) => format!("line {line} ('{text}', element '{name}'): {reason}"),
            Some((line, text, None)) => {
                format!("line {line} ('{text}', element '{name}'): not the values the header declares")
            }
            None => format!("element '{name}': {}", one_line(&e.to_string())),
        };
        match name.as_str() {
            "vertex" => verts = Parser::<Vertex>::new().read_payload_for_element(reader, def, header).map_err(what)?,
            "face" => faces = Parser::<Face>::new().read_payload_for_element(reader, def, header).map_err(what)?,
            _ => {
                Parser::<Skip>::new().read_payload_for_element(reader, def, header).map_err(what)?;
            }
        }
    }
    let vdef = header.elements.get("vertex").ok_or("no 'vertex' element")?;
    for axis in ["x", "y", "z"] {
        if !vdef.properties.contains_key(axis) {
            return Err(format!("vertex has no property '{axis}'"));
        }
    }
    build(header, verts, faces)
}

fn build(header: &Header, verts: Vec<Vertex>, faces: Vec<Face>) -> Result<Mesh, String> {
    let vdef = &header.elements["vertex"];
    let has = |k: &str| vdef.properties.contains_key(k);
    let with_normals = has("nx") && has("ny") && has("nz");
    let with_uvs = (has("u") && has("v")) || (has("s") && has("t")) || (has("texture_u") && has("texture_v"));
    let with_colors = has("red") && has("green") && has("blue");
    if let Some(i) = verts.iter().position(|v| !v.p.iter().all(|c| c.is_finite())) {
        return Err(format!("vertex {i} has a NaN or infinite coordinate"));
    }
    let n = verts.len();
    let mut triangles = Vec::with_capacity(faces.len());
    for (fi, f) in faces.iter().enumerate() {
        if let Some(bad) = f.error {
            return Err(format!("face {fi}: {bad}"));
        }
        if let Some(&i) = f.idx.iter().find(|&&i| i as usize >= n) {
            return Err(format!("face {fi} uses vertex {i}, but there are only {n}"));
        }
        for k in 1..f.idx.len().saturating_sub(1) {
            triangles.push([f.idx[0], f.idx[k], f.idx[k + 1]]);
        }
    }
    if triangles.is_empty() {
        return Err("no faces".into());
    }
    let normals = with_normals.then(|| verts.iter().map(|v| Vec3::from(v.n)).collect());
    let uvs = with_uvs.then(|| verts.iter().map(|v| Vec2::from(v.uv)).collect());
    let colors = with_colors.then(|| verts.iter().map(|v| Vec3::from(v.c)).collect());
    let positions = verts.iter().map(|v| Vec3::from(v.p)).collect();
    let material_ids = crate::scene::MaterialIds::uniform(0, triangles.len());
    Ok(Mesh { positions, normals, uvs, colors, tangents: None, triangles, material_ids })
}

/// ply-rs-bw's messages span several lines (message, offending text, cause); errors here are one line.
/// The parser's message ("Line N: Couldn't ...; String: 'TEXT; '; Error: ...") as its line
/// number, the offending text, and the innermost reason when it is a sentence (not a debug
/// dump of the grammar's state).
fn sentence(msg: &str) -> Option<(usize, String, Option<String>)> {
    let msg = one_line(msg);
    let rest = msg.split_once("Line ")?.1;
    let line: usize = rest.split(|c: char| !c.is_ascii_digit()).next()?.parse().ok()?;
    let text = msg.split_once("String: '")?.1.split_once("; '")?.0.trim().to_string();
    let reason = msg
        .rsplit_once("Error: ")
        .map(|(_, r)| r.trim().trim_end_matches('.').to_string())
        .filter(|r| !r.is_empty() && !r.contains('{') && !r.starts_with("error at") && !r.starts_with("Couldn't"));
    Some((line, text, reason.map(|r| r.to_lowercase())))
}

fn one_line(msg: &str) -> String {
    let joined = msg.lines().map(str::trim).filter(|l| !l.is_empty()).collect::<Vec<_>>().join("; ");
    match joined.char_indices().nth(200) {
        Some((cut, _)) => format!("{}...", &joined[..cut]),
        None => joined,
    }
}

/// Bytes up to and including the `end_header` line.
fn header_len(bytes: &[u8]) -> Result<usize, String> {
    let key = b"end_header";
    let at = bytes.windows(key.len()).position(|w| w == key).ok_or("no 'end_header' line")?;
    let nl = bytes[at..].iter().position(|&b| b == b'\n').ok_or("nothing after 'end_header'")?;
    Ok(at + nl + 1)
}

/// Rejects headers whose element counts need more bytes than the file has: every binary
/// element takes at least the size of its scalars and list counts, every ascii property at
/// least one character and one separator.
fn check_counts(header: &Header, payload_len: usize) -> Result<(), String> {
    let mut needed: u128 = 0;
    for (name, def) in &header.elements {
        let per = min_element_bytes(def, header.encoding) as u128;
        needed += per * def.count as u128;
        if needed > payload_len as u128 {
            return Err(format!(
                "header promises {} '{name}' elements, more than the {payload_len} bytes after the header can hold",
                def.count
            ));
        }
    }
    Ok(())
}

fn min_element_bytes(def: &ElementDef, enc: Encoding) -> usize {
    def.properties
        .values()
        .map(|p| match (enc, &p.data_type) {
            (Encoding::Ascii, _) => 2,
            (_, PropertyType::Scalar(s)) => scalar_size(s),
            (_, PropertyType::List(count, _)) => scalar_size(count),
        })
        .sum()
}

fn scalar_size(s: &ScalarType) -> usize {
    match s {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    }
}

/// One vertex as read; absent properties stay zero.
#[derive(Default)]
struct Vertex {
    p: [f32; 3],
    n: [f32; 3],
    uv: [f32; 2],
    /// Linear RGB: bytes are sRGB (as scanners and MeshLab write them), floats are taken as
    /// they are.
    c: [f32; 3],
}

impl PropertyAccess for Vertex {
    fn new() -> Self {
        Vertex::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        if let Some(k) = ["red", "green", "blue"].iter().position(|c| *c == name) {
            self.c[k] = match property {
                Property::UChar(v) => crate::scene::texture::srgb_to_linear(v as f32 / 255.0),
                Property::Float(v) => v,
                Property::Double(v) => v as f32,
                _ => return PropertyAccessResult::Ignored,
            };
            return PropertyAccessResult::Set;
        }
        let value = match property {
            Property::Float(v) => v,
            Property::Double(v) => v as f32,
            Property::Char(v) => v as f32,
            Property::UChar(v) => v as f32,
            Property::Short(v) => v as f32,
            Property::UShort(v) => v as f32,
            Property::Int(v) => v as f32,
            Property::UInt(v) => v as f32,
            _ => return PropertyAccessResult::Ignored,
        };
        let slot = match name {
            "x" => &mut self.p[0],
            "y" => &mut self.p[1],
            "z" => &mut self.p[2],
            "nx" => &mut self.n[0],
            "ny" => &mut self.n[1],
            "nz" => &mut self.n[2],
            "u" | "s" | "texture_u" => &mut self.uv[0],
            "v" | "t" | "texture_v" => &mut self.uv[1],
            _ => return PropertyAccessResult::Ignored,
        };
        *slot = value;
        PropertyAccessResult::Set
    }
}

/// One polygon's vertex indices; a negative index is remembered as an error.
#[derive(Default)]
struct Face {
    idx: Vec<u32>,
    error: Option<&'static str>,
}

impl Face {
    fn take<T: TryInto<u32> + Copy>(&mut self, list: &[T]) {
        self.idx.clear();
        for &i in list {
            match i.try_into() {
                Ok(v) => self.idx.push(v),
                Err(_) => self.error = Some("negative vertex index"),
            }
        }
    }
}

impl PropertyAccess for Face {
    fn new() -> Self {
        Face::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        if name != "vertex_indices" && name != "vertex_index" {
            return PropertyAccessResult::Ignored;
        }
        match property {
            Property::ListChar(l) => self.take(&l),
            Property::ListUChar(l) => self.take(&l),
            Property::ListShort(l) => self.take(&l),
            Property::ListUShort(l) => self.take(&l),
            Property::ListInt(l) => self.take(&l),
            Property::ListUInt(l) => self.take(&l),
            _ => return PropertyAccessResult::UnsupportedType,
        }
        PropertyAccessResult::Set
    }
}

/// Any element the loader does not use.
struct Skip;

impl PropertyAccess for Skip {
    fn new() -> Self {
        Skip
    }
}
