//! COLLADA loader for the CS184 dialect (see COLLADA-CS184.md in the shared scenes) and
//! the common subset other exporters write. The scenes it reads are of the CS184 dialect
//! (`crate::cs184` lists the course's rules, those of this reader among them).
//!
//! The visual scene is walked in document order, so triangles keep the file's order
//! (instances in node order, primitives in order, polygons fan-triangulated): ray files
//! and the peers number triangles that way. Skinned and morphed geometry
//! (`<instance_controller>`) is placed in its bind pose; orthographic cameras render as
//! parallel projections.

mod camera;
mod common;
mod dialect;
mod geometry;
mod instance;
mod lights;
mod materials;
mod transform;
mod xml;

use super::LoadOptions;
use crate::cs184::Dialect;
use crate::scene::{Camera, Scene, SceneSource, Sphere};
use anyhow::{Context, Result, anyhow, bail};
use geometry::Geometry;
use glam::Mat4;
use materials::Materials;
use roxmltree::{Node, NodeId};
use std::collections::HashMap;
use std::path::Path;
use xml::{Doc, child, children};

/// Deepest node nesting accepted; real files nest a handful of levels, and the limit
/// also stops `instance_node` cycles.
pub const MAX_NODE_DEPTH: usize = 256;

/// Loads a `.dae` file.
pub fn load(path: &Path, opts: &LoadOptions) -> Result<Scene> {
    let shown = path.display().to_string();
    let bytes = std::fs::read(path).with_context(|| format!("{shown}: cannot read"))?;
    let text = String::from_utf8(bytes)
        .map_err(|e| anyhow!("{shown}: not UTF-8 text (invalid byte at offset {})", e.utf8_error().valid_up_to()))?;
    parse_str(&text, &shown, opts)
}

/// Loads COLLADA text; `name` stands for the file in error messages and `Scene::name`.
pub fn parse_str(text: &str, name: &str, opts: &LoadOptions) -> Result<Scene> {
    let parse_opts = roxmltree::ParsingOptions { allow_dtd: false, ..Default::default() };
    let doc = roxmltree::Document::parse_with_options(text, parse_opts).map_err(|e| match e {
        roxmltree::Error::DtdDetected => {
            anyhow!("{name}: the XML has a DTD (<!DOCTYPE>); DTDs and entity definitions are refused")
        }
        e => anyhow!("{name}: malformed XML: {e}"),
    })?;
    let root = doc.root_element();
    if root.tag_name().name() != "COLLADA" {
        bail!("{name}: not a COLLADA file (the root element is <{}>)", root.tag_name().name());
    }
    let d = Doc::new(name, &doc);
    let mut b = Builder {
        d: &d,
        opts,
        g: transform::up_axis_matrix(&d, root)?,
        scene: Scene {
            name: name.to_owned(),
            source: SceneSource { dialect: Dialect::Cs184, reader: "collada", default_sky: false },
            ..Scene::default()
        },
        mats: Materials::new(
            !dialect::is_course_file(root),
            Path::new(name).parent().map(Path::to_path_buf).unwrap_or_default(),
        ),
        geometries: HashMap::new(),
        camera: None,
    };
    let vs = visual_scene(&d, root)?;
    for n in children(vs, "node") {
        b.walk(n, Mat4::IDENTITY, 1)?;
    }
    b.finish()
}

/// The scene's `instance_visual_scene`, or the first visual scene when there is none.
fn visual_scene<'a, 'input>(d: &Doc<'a, 'input>, root: Node<'a, 'input>) -> Result<Node<'a, 'input>> {
    if let Some(ivs) = child(root, "scene").and_then(|s| child(s, "instance_visual_scene")) {
        return d.resolve(ivs, "url", &["visual_scene"]);
    }
    child(root, "library_visual_scenes")
        .and_then(|l| child(l, "visual_scene"))
        .ok_or_else(|| anyhow!("{}: no <visual_scene>", d.file))
}

struct Builder<'d, 'a, 'input> {
    d: &'d Doc<'a, 'input>,
    opts: &'d LoadOptions,
    /// Axis conversion to +Y up.
    g: Mat4,
    scene: Scene,
    mats: Materials,
    /// Parsed geometries by element, so instancing one twice reads it once.
    geometries: HashMap<NodeId, Geometry>,
    /// The last camera met (the reference renderer uses the last one): its optics and world
    /// matrix (conversion included).
    camera: Option<(camera::Optics, Mat4)>,
}

impl<'a, 'input> Builder<'_, 'a, 'input> {
    /// Visits a node and its subtree in document order; `parent` is the parent's world
    /// matrix in file axes.
    fn walk(&mut self, node: Node<'a, 'input>, parent: Mat4, depth: usize) -> Result<()> {
        let d = self.d;
        if depth > MAX_NODE_DEPTH {
            return Err(d.err(node, format!("nodes nest deeper than {MAX_NODE_DEPTH} levels")));
        }
        let m = parent * transform::local_matrix(d, node, &mut self.scene.notes)?;
        let w = self.g * m;
        for c in node.children().filter(|c| c.is_element()) {
            match c.tag_name().name() {
                "node" => self.walk(c, m, depth + 1)?,
                "instance_node" => {
                    let target = d.resolve(c, "url", &["node"])?;
                    self.walk(target, m, depth + 1)?;
                }
                "instance_geometry" => {
                    let geom = d.resolve(c, "url", &["geometry"])?;
                    self.geometry(c, geom, w)?
                }
                "instance_controller" => {
                    let (geom, bind_shape) = controlled_geometry(d, c)?;
                    self.geometry(c, geom, w * bind_shape)?
                }
                "instance_light" => {
                    let l = d.resolve(c, "url", &["light"])?;
                    self.scene.lights.push(lights::light(d, l, w)?);
                }
                "instance_camera" => {
                    let cam = d.resolve(c, "url", &["camera"])?;
                    let optics = camera::optics(d, cam)?;
                    self.camera = Some((optics, w));
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// Places `geom`, instantiated by `inst` (whose `bind_material` binds its symbols), with
    /// world matrix `w`.
    fn geometry(&mut self, inst: Node<'a, 'input>, geom: Node<'a, 'input>, w: Mat4) -> Result<()> {
        let d = self.d;
        let binding = self.mats.binding(d, inst)?;
        let geometry = match self.geometries.entry(geom.id()) {
            std::collections::hash_map::Entry::Occupied(e) => e.into_mut(),
            std::collections::hash_map::Entry::Vacant(e) => e.insert(geometry::parse_geometry(d, geom)?),
        };
        match &*geometry {
            Geometry::Sphere(r) => {
                let material = binding.first(&mut self.mats);
                let scale = glam::Mat3::from_mat4(w).x_axis.length();
                self.scene.spheres.push(Sphere {
                    center: w.transform_point3(glam::Vec3::ZERO),
                    radius: r * scale,
                    material,
                });
            }
            Geometry::Mesh(local) => {
                let mats: Vec<u32> =
                    local.groups.iter().map(|g| binding.lookup(g.symbol.as_deref(), &mut self.mats)).collect();
                let placed = instance::place(local, w, self.opts.smooth_normals, &mats);
                let total = self.scene.mesh.positions.len() as u64 + placed.positions.len() as u64;
                if total > u32::MAX as u64 {
                    return Err(d.err(inst, "the scene has more than 2^32 vertices"));
                }
                self.scene.mesh.append(placed);
            }
        }
        Ok(())
    }

    fn finish(mut self) -> Result<Scene> {
        let name = self.d.file;
        self.scene.materials = std::mem::take(&mut self.mats.list);
        self.scene.notes.append(&mut self.mats.notes);
        let Some(bounds) = self.scene.bounds() else {
            bail!("{name}: the scene has no triangles and no spheres");
        };
        self.scene.camera = match &self.camera {
            Some((optics, w)) => {
                let (cam, note) = camera::place(optics, *w, self.opts.camera, bounds);
                if let Some(note) = note {
                    self.scene.notes.push(format!("note: {name}: {note}"));
                }
                cam
            }
            None => Camera::framing(bounds.0, bounds.1),
        };
        self.scene.validate().map_err(|e| anyhow!("{name}: {e}"))?;
        Ok(self.scene)
    }
}

/// The geometry an `<instance_controller>` deforms and the matrix that puts it in its bind
/// pose: a `<skin>`'s source under its bind-shape matrix (every joint at its bind
/// transform, the pose the inverse bind matrices are taken in, moves no vertex further), a
/// `<morph>`'s base geometry as it is. Animations are not read: a skinned mesh renders as
/// modelled.
fn controlled_geometry<'a, 'input>(d: &Doc<'a, 'input>, inst: Node<'a, 'input>) -> Result<(Node<'a, 'input>, Mat4)> {
    let mut ctrl = d.resolve(inst, "url", &["controller"])?;
    let mut bind = Mat4::IDENTITY;
    // A skin may deform a morph (and, in principle, another controller): follow the chain
    // to the geometry, at most as deep as there are controllers.
    for _ in 0..64 {
        let (source, shape) = if let Some(skin) = xml::child(ctrl, "skin") {
            let shape = match xml::child(skin, "bind_shape_matrix") {
                Some(m) => transform::matrix(d, m)?,
                None => Mat4::IDENTITY,
            };
            (d.resolve(skin, "source", &["geometry", "controller"])?, shape)
        } else if let Some(morph) = xml::child(ctrl, "morph") {
            (d.resolve(morph, "source", &["geometry", "controller"])?, Mat4::IDENTITY)
        } else {
            return Err(d.err(ctrl, "a controller without <skin> or <morph>"));
        };
        bind *= shape;
        if source.tag_name().name() == "geometry" {
            return Ok((source, bind));
        }
        ctrl = source;
    }
    Err(d.err(inst, "controllers refer to each other in a loop"))
}
