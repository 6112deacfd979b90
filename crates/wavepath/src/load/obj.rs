//! Wavefront OBJ (+ MTL) through tobj; files of positions and faces only (scans) through a
//! parallel reader ([`bulk`]) that gives the same triangles.
//!
//! Triangle numbering is the file's: tobj splits the file into models at each `o`, `g` or
//! material change, in order, and fan-triangulates each polygon as (v0,v1,v2), (v0,v2,v3), ...,
//! so concatenating the models gives the numbering the peers and ray files use. Positions are
//! shared inside a model (tobj keeps one vertex per distinct position/uv/normal triple).

mod bulk;
mod dissolve;
mod mtl;
mod relief;

use crate::scene::{Material, Mesh, Scene};
use anyhow::{Context, Result, anyhow, bail};
use glam::{Vec2, Vec3};
use std::borrow::Cow;
use std::cell::RefCell;
use std::io::{BufRead, Read};
use std::path::Path;

/// What the material callback learnt while tobj parsed the OBJ.
#[derive(Default)]
struct MtlState {
    materials: Vec<Material>,
    error: Option<String>,
    notes: Vec<String>,
}

/// [`crate::scene::SceneSource::reader`] of a file the parallel reader read.
pub const BULK_READER: &str = "obj-bulk";
/// [`crate::scene::SceneSource::reader`] of a file tobj read: anything beyond positions and
/// faces (groups, materials, normals, colours) and every damaged file, silently but for
/// this name.
pub const GENERAL_READER: &str = "tobj";

pub fn load(path: &Path) -> Result<Scene> {
    let shown = path.display();
    let bytes = std::fs::read(path).with_context(|| format!("{shown}: cannot open"))?;
    if let Some(mesh) = bulk::parse(&decode_text(&bytes)) {
        let mut scene = Scene { mesh, materials: vec![Material::default()], ..Scene::default() };
        scene.source.reader = BULK_READER;
        super::finish_mesh_only(&mut scene, false);
        return Ok(scene);
    }
    let (text, skipped) = prepare(&bytes);
    let dir = path.parent().unwrap_or(Path::new("."));
    let state = RefCell::new(MtlState::default());
    let mut reader = LineCounter { inner: std::io::Cursor::new(text.as_bytes()), newlines: 0, at_line_start: true };
    let opts = tobj::LoadOptions { single_index: true, triangulate: true, ignore_points: true, ignore_lines: true };
    // tobj computes face indices with plain arithmetic; absurd indices overflow (a panic in
    // builds with overflow checks). Catch it so bad input stays an error.
    let parsed = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        tobj::load_obj_buf(&mut reader, &opts, |rel| load_mtllib(dir, rel, &state))
    }));
    let models = match parsed {
        Ok(Ok((models, _))) => models,
        Ok(Err(e)) => bail!("{shown}: {}", describe(&e, reader.line())),
        Err(_) => bail!("{shown}: a face index is far out of range"),
    };
    let state = state.into_inner();
    if let Some(e) = state.error {
        bail!("{shown}: {e}");
    }
    let mut scene = build_scene(path, models, state.materials).map_err(|e| anyhow!("{shown}: {e}"))?;
    scene.notes = state.notes;
    if skipped.lines + skipped.points > 0 {
        scene.notes.push(format!(
            "warning: {shown}: skipped {} line and {} point elements (only faces are rendered)",
            skipped.lines, skipped.points
        ));
    }
    Ok(scene)
}

/// Elements of the file that are not rendered.
#[derive(Default)]
struct Skipped {
    lines: usize,
    points: usize,
}

/// Text as exporters write it: UTF-8, or else Latin-1 (a single accented byte in a material
/// name would otherwise refuse the whole file, and the MTL is decoded the same way, so the
/// names still match).
pub(super) fn decode_text(bytes: &[u8]) -> Cow<'_, str> {
    match std::str::from_utf8(bytes) {
        Ok(t) => Cow::Borrowed(t),
        Err(_) => Cow::Owned(bytes.iter().map(|&b| b as char).collect()),
    }
}

/// The OBJ text for tobj, and the line and point elements it skips. Line and point elements
/// become comments (tobj would fill a polyline of three or more points as a polygon); an
/// empty `usemtl` (Rhino and Blender write it for "no material"; tobj refuses it) becomes a
/// name no library can define, so those faces take the default material. Line numbers are
/// unchanged.
fn prepare(bytes: &[u8]) -> (Cow<'_, str>, Skipped) {
    let text = decode_text(bytes);
    let mut skipped = Skipped::default();
    let mut empty_usemtl = false;
    for line in text.lines() {
        let mut w = line.split_whitespace();
        match w.next() {
            Some("l") => skipped.lines += 1,
            Some("p") => skipped.points += 1,
            Some("usemtl") => empty_usemtl |= w.next().is_none(),
            _ => {}
        }
    }
    if !empty_usemtl && skipped.lines + skipped.points == 0 {
        return (text, skipped);
    }
    let mut out = String::with_capacity(text.len() + 64);
    for line in text.split_inclusive('\n') {
        let body = line.trim_end_matches(['\r', '\n']);
        let mut words = body.split_whitespace();
        match (words.next(), words.next()) {
            (Some("usemtl"), None) => out.push_str(NO_MATERIAL),
            // tobj fills a polyline of three or more points as a polygon.
            (Some("l" | "p"), _) => out.push('#'),
            _ => out.push_str(body),
        }
        out.push_str(&line[body.len()..]);
    }
    (Cow::Owned(out), skipped)
}

/// What an empty `usemtl` is read as: a name with a control character, which no `newmtl`
/// line can hold.
const NO_MATERIAL: &str = "usemtl \u{1}none";

/// One `mtllib` statement: the names it lists (several, separated by spaces, unless the whole
/// rest of the line names a file), with Windows separators (`.\\a.mtl`) read as `/`.
fn load_mtllib(dir: &Path, rel: &Path, state: &RefCell<MtlState>) -> tobj::MTLLoadResult {
    let rel = rel.to_string_lossy().replace('\\', "/");
    let whole = dir.join(&rel);
    let files: Vec<std::path::PathBuf> = if whole.is_file() || !rel.contains(char::is_whitespace) {
        vec![whole]
    } else {
        rel.split_whitespace().map(|r| dir.join(r)).collect()
    };
    let (mut names, mut pairs) = (Vec::new(), Vec::new());
    for f in files {
        let (n, m) = load_mtl(&f, state)?;
        let offset = names.len();
        names.extend(n);
        pairs.extend(m.into_iter().map(|(k, i)| (k, i + offset)));
    }
    Ok((names, pairs.into_iter().collect()))
}

/// tobj's errors carry no position; parse errors stop right after the offending line.
fn describe(e: &tobj::LoadError, line: usize) -> String {
    use tobj::LoadError::*;
    match e {
        PositionParseError | NormalParseError | TexcoordParseError | FaceParseError | ColorParseError
        | ScalingByZeroError | MaterialParseError | InvalidObjectName => format!("line {line}: {e}"),
        FaceVertexOutOfBounds => "a face refers to a vertex that does not exist".into(),
        FaceTexCoordOutOfBounds => "a face refers to a texture coordinate that does not exist".into(),
        FaceNormalOutOfBounds => "a face refers to a normal that does not exist".into(),
        _ => e.to_string(),
    }
}

/// The material callback: parses the .mtl itself and hands tobj only the names, so that
/// tobj's material ids index `state.materials`. A missing .mtl is a warning (the faces get
/// the default material); a malformed one is an error.
fn load_mtl(path: &Path, state: &RefCell<MtlState>) -> tobj::MTLLoadResult {
    let text = match std::fs::read(path) {
        Ok(b) => decode_text(&b).into_owned(),
        Err(e) => {
            state.borrow_mut().notes.push(format!(
                "warning: {}: cannot read material library ({e}); using the default material",
                path.display()
            ));
            return Err(tobj::LoadError::OpenFileFailed);
        }
    };
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut state = state.borrow_mut();
    match mtl::parse(&text, dir) {
        Ok(mut lib) => {
            let shown = path.display();
            for n in std::mem::take(&mut lib.notes) {
                state.notes.push(format!("warning: {shown}: {n}"));
            }
            for m in &mut lib.materials {
                dissolve::decode(&mut m.alpha, path, &m.name, &mut state.notes);
                relief::decode(m, path, &mut state.notes);
            }
            mtl::load_images(&mut lib, path, &mut state.notes);
            let mats = lib.materials;
            let names: Vec<tobj::Material> =
                mats.iter().map(|m| tobj::Material { name: m.name.clone(), ..Default::default() }).collect();
            let map = mats.iter().enumerate().map(|(i, m)| (m.name.clone(), i)).collect();
            state.materials.extend(mats);
            Ok((names, map))
        }
        Err(e) => {
            state.error.get_or_insert(format!("{}: {e}", path.display()));
            Err(tobj::LoadError::MaterialParseError)
        }
    }
}

fn build_scene(path: &Path, models: Vec<tobj::Model>, mut materials: Vec<Material>) -> Result<Scene, String> {
    // Normals are kept only when every model has one per vertex: a model without them would
    // otherwise get zero normals when appended.
    let all_normals = models.iter().all(|m| has_per_vertex(&m.mesh.normals, &m.mesh.positions, 3));
    let any_uvs = models.iter().any(|m| has_per_vertex(&m.mesh.texcoords, &m.mesh.positions, 2));
    let mut default_id = None;
    let mut mesh = Mesh::default();
    for model in models {
        let m = model.mesh;
        if m.positions.iter().any(|c| !c.is_finite()) {
            return Err(non_finite_vertex_line(path));
        }
        let nverts = m.positions.len() / 3;
        let positions: Vec<Vec3> = m.positions.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect();
        let normals = (all_normals && !m.normals.is_empty())
            .then(|| m.normals.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect());
        let uvs = (any_uvs && has_per_vertex(&m.texcoords, &m.positions, 2))
            .then(|| m.texcoords.chunks_exact(2).map(|c| Vec2::new(c[0], c[1])).collect());
        let triangles: Vec<[u32; 3]> = m.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
        if let Some(t) = triangles.iter().find(|t| t.iter().any(|&i| i as usize >= nverts)) {
            return Err(format!("object '{}': triangle {t:?} uses a vertex that does not exist", model.name));
        }
        let id = match m.material_id {
            Some(i) if i < materials.len() => i as u32,
            // Faces before any `usemtl` in a file whose library defines exactly one material
            // take that material (tex_cube.obj relies on it, as its source renderer does).
            None if materials.len() == 1 => 0,
            _ => *default_id.get_or_insert_with(|| {
                materials.push(Material::default());
                materials.len() as u32 - 1
            }),
        };
        let material_ids = crate::scene::MaterialIds::uniform(id, triangles.len());
        // `v x y z r g b`: colours as written (0..1, taken as linear).
        let colors = (m.vertex_color.len() == m.positions.len())
            .then(|| m.vertex_color.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect());
        mesh.append(Mesh { positions, normals, uvs, colors, tangents: None, triangles, material_ids });
    }
    if mesh.triangles.is_empty() {
        return Err("no faces".into());
    }
    if !all_normals {
        mesh.normals = None;
    }
    let mut scene = Scene { mesh, materials, ..Scene::default() };
    scene.source.reader = GENERAL_READER;
    super::finish_mesh_only(&mut scene, false);
    Ok(scene)
}

/// Finds the first `v` line with a NaN or infinite coordinate (only on the error path, so the
/// normal load does not pay for a second pass).
fn non_finite_vertex_line(path: &Path) -> String {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    for (i, line) in text.lines().enumerate() {
        let mut w = line.split_whitespace();
        if w.next() == Some("v") && w.take(3).any(|x| x.parse::<f32>().is_ok_and(|v| !v.is_finite())) {
            return format!("line {}: vertex coordinate is NaN or infinite", i + 1);
        }
    }
    "a vertex coordinate is NaN or infinite".into()
}

fn has_per_vertex(attr: &[f32], positions: &[f32], n: usize) -> bool {
    !attr.is_empty() && attr.len() / n == positions.len() / 3
}

/// Counts the lines tobj has consumed, so that its position-less errors can name a line.
struct LineCounter<R> {
    inner: R,
    newlines: usize,
    /// True when the last byte consumed ended a line.
    at_line_start: bool,
}

impl<R> LineCounter<R> {
    /// The 1-based number of the line read last.
    fn line(&self) -> usize {
        if self.at_line_start { self.newlines.max(1) } else { self.newlines + 1 }
    }

    fn count(&mut self, bytes: &[u8]) {
        self.newlines += bytes.iter().filter(|&&b| b == b'\n').count();
        if let Some(&last) = bytes.last() {
            self.at_line_start = last == b'\n';
        }
    }
}

impl<R: BufRead> Read for LineCounter<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.count(&buf[..n]);
        Ok(n)
    }
}

impl<R: BufRead> BufRead for LineCounter<R> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        self.inner.fill_buf()
    }

    fn consume(&mut self, amt: usize) {
        let (newlines, last) = match self.inner.fill_buf() {
            Ok(buf) => {
                let seen = &buf[..amt.min(buf.len())];
                (seen.iter().filter(|&&b| b == b'\n').count(), seen.last().copied())
            }
            Err(_) => (0, None),
        };
        self.newlines += newlines;
        if let Some(last) = last {
            self.at_line_start = last == b'\n';
        }
        self.inner.consume(amt);
    }
}
