//! `<geometry>`: meshes in the geometry's own space, and CS184 spheres.
//!
//! A mesh is read into corners (position, normal and uv indices per triangle corner) so
//! that instancing can decide later which vertices to share. Every count in the file is
//! checked against the data actually present before anything is sized from it.

use super::xml::{Doc, child, children, cs184_extra, path};
use anyhow::Result;
use glam::{Vec2, Vec3};
use roxmltree::Node;
use std::collections::HashMap;

/// Marks an attribute a corner does not have.
pub const NONE: u32 = u32::MAX;

/// Indices of one triangle corner into [`LocalMesh`]'s arrays.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Corner {
    pub p: u32,
    pub n: u32,
    pub t: u32,
}

/// Consecutive triangles of one primitive element, which share a material symbol.
#[derive(Clone, Debug)]
pub struct Group {
    pub symbol: Option<String>,
    pub triangles: usize,
}

/// A mesh in its geometry's space, triangulated in file order.
#[derive(Clone, Debug, Default)]
pub struct LocalMesh {
    pub positions: Vec<Vec3>,
    /// Every normal source any primitive uses, concatenated.
    pub normals: Vec<Vec3>,
    /// Every texture-coordinate source any primitive uses, concatenated.
    pub uvs: Vec<Vec2>,
    /// Three per triangle.
    pub corners: Vec<Corner>,
    pub groups: Vec<Group>,
}

pub enum Geometry {
    Mesh(LocalMesh),
    /// A CS184 analytic sphere of this radius (before the node's scale).
    Sphere(f32),
}

/// Reads a `<geometry>` element.
pub fn parse_geometry(d: &Doc, geom: Node) -> Result<Geometry> {
    if let Some(mesh) = child(geom, "mesh") {
        return MeshReader::new(d, mesh).read();
    }
    if let Some(sphere) = cs184_extra(geom).filter(|s| s.tag_name().name() == "sphere") {
        let r = d.float(d.child(sphere, "radius")?)?;
        if r <= 0.0 {
            return Err(d.err(sphere, format!("sphere radius {r} is not positive")));
        }
        return Ok(Geometry::Sphere(r));
    }
    Err(d.err(geom, "has neither a <mesh> nor a CGL <sphere>; only those are supported"))
}

/// Where a primitive finds one attribute: its offset in the index tuple (or the vertex
/// index itself for attributes given in `<vertices>`), and the range in the pooled array.
#[derive(Clone, Copy)]
struct Attr {
    /// `None`: indexed by the VERTEX index.
    offset: Option<usize>,
    base: u32,
    count: u32,
}

struct Inputs {
    stride: usize,
    vertex: usize,
    normal: Option<Attr>,
    uv: Option<Attr>,
}

struct MeshReader<'d, 'a, 'input> {
    d: &'d Doc<'a, 'input>,
    mesh: Node<'a, 'input>,
    out: LocalMesh,
    /// Pooled sources by id, so primitives sharing a source share its entries.
    normal_sources: HashMap<&'a str, (u32, u32)>,
    uv_sources: HashMap<&'a str, (u32, u32)>,
    vertices: Option<Node<'a, 'input>>,
    vertex_normal: Option<Attr>,
    vertex_uv: Option<Attr>,
}

impl<'d, 'a, 'input> MeshReader<'d, 'a, 'input> {
    fn new(d: &'d Doc<'a, 'input>, mesh: Node<'a, 'input>) -> Self {
        MeshReader {
            d,
            mesh,
            out: LocalMesh::default(),
            normal_sources: HashMap::new(),
            uv_sources: HashMap::new(),
            vertices: None,
            vertex_normal: None,
            vertex_uv: None,
        }
    }

    fn read(mut self) -> Result<Geometry> {
        let d = self.d;
        if let Some(vertices) = child(self.mesh, "vertices") {
            self.read_vertices(vertices)?;
        }
        for prim in self.mesh.children().filter(|c| c.is_element()) {
            match prim.tag_name().name() {
                "polylist" | "triangles" | "polygons" | "trifans" | "tristrips" => self.read_primitive(prim)?,
                // Lines have no surface; sources, vertices and extras are read on demand.
                _ => {}
            }
        }
        if u32::try_from(self.out.positions.len()).is_err() {
            return Err(d.err(self.mesh, "more than 2^32 vertices"));
        }
        Ok(Geometry::Mesh(self.out))
    }

    fn read_vertices(&mut self, vertices: Node<'a, 'input>) -> Result<()> {
        let d = self.d;
        self.vertices = Some(vertices);
        let mut have_position = false;
        for input in children(vertices, "input") {
            match input.attribute("semantic").unwrap_or("") {
                "POSITION" if !have_position => {
                    let src = d.resolve(input, "source", &["source"])?;
                    self.out.positions = read_tuples::<3>(d, src)?.into_iter().map(Vec3::from_array).collect();
                    have_position = true;
                }
                "NORMAL" if self.vertex_normal.is_none() => {
                    let (base, count) = self.pool_normals(input)?;
                    self.vertex_normal = Some(Attr { offset: None, base, count });
                }
                "TEXCOORD" if self.vertex_uv.is_none() => {
                    let (base, count) = self.pool_uvs(input)?;
                    self.vertex_uv = Some(Attr { offset: None, base, count });
                }
                _ => {}
            }
        }
        if !have_position {
            return Err(d.err(vertices, "has no POSITION input"));
        }
        Ok(())
    }

    fn pool_normals(&mut self, input: Node<'a, 'input>) -> Result<(u32, u32)> {
        let d = self.d;
        let src = d.resolve(input, "source", &["source"])?;
        let id = src.attribute("id").unwrap_or("");
        if let Some(&r) = self.normal_sources.get(id) {
            return Ok(r);
        }
        let v = read_tuples::<3>(d, src)?;
        let r = pool(d, src, &mut self.out.normals, v.into_iter().map(Vec3::from_array))?;
        self.normal_sources.insert(id, r);
        Ok(r)
    }

    fn pool_uvs(&mut self, input: Node<'a, 'input>) -> Result<(u32, u32)> {
        let d = self.d;
        let src = d.resolve(input, "source", &["source"])?;
        let id = src.attribute("id").unwrap_or("");
        if let Some(&r) = self.uv_sources.get(id) {
            return Ok(r);
        }
        let v = read_tuples::<2>(d, src)?;
        let r = pool(d, src, &mut self.out.uvs, v.into_iter().map(Vec2::from_array))?;
        self.uv_sources.insert(id, r);
        Ok(r)
    }

    fn read_inputs(&mut self, prim: Node<'a, 'input>) -> Result<Inputs> {
        let d = self.d;
        let mut max_offset = 0;
        let mut vertex = None;
        let mut normal = self.vertex_normal;
        let mut uv = self.vertex_uv;
        let (mut own_normal, mut own_uv) = (false, false);
        for input in children(prim, "input") {
            let offset = d.uint_attr(input, "offset")?.ok_or_else(|| d.err(input, "missing 'offset' attribute"))?;
            if offset > 1024 {
                return Err(d.err(input, format!("offset {offset} is implausibly large")));
            }
            max_offset = max_offset.max(offset);
            match input.attribute("semantic").unwrap_or("") {
                "VERTEX" if vertex.is_none() => {
                    let target = d.resolve(input, "source", &["vertices"])?;
                    if Some(target) != self.vertices {
                        return Err(d.err(input, "VERTEX must refer to this mesh's <vertices>"));
                    }
                    vertex = Some(offset);
                }
                "NORMAL" if !own_normal => {
                    let (base, count) = self.pool_normals(input)?;
                    normal = Some(Attr { offset: Some(offset), base, count });
                    own_normal = true;
                }
                "TEXCOORD" if !own_uv => {
                    let (base, count) = self.pool_uvs(input)?;
                    uv = Some(Attr { offset: Some(offset), base, count });
                    own_uv = true;
                }
                _ => {}
            }
        }
        let vertex = vertex.ok_or_else(|| d.err(prim, "has no VERTEX input"))?;
        Ok(Inputs { stride: max_offset + 1, vertex, normal, uv })
    }

    fn read_primitive(&mut self, prim: Node<'a, 'input>) -> Result<()> {
        let d = self.d;
        let kind = prim.tag_name().name();
        let inputs = self.read_inputs(prim)?;
        let stride = inputs.stride;
        let first_corner = self.out.corners.len();
        let count = d.uint_attr(prim, "count")?;
        let mut emit = Emitter { d, prim, inputs: &inputs, npos: self.out.positions.len(), out: &mut self.out.corners };
        match kind {
            "triangles" => {
                let p = match child(prim, "p") {
                    Some(p) => d.uints(p)?,
                    None => Vec::new(),
                };
                let tris = match count {
                    Some(c) => c,
                    None => p.len() / (3 * stride),
                };
                let need = (tris as u64) * 3 * stride as u64;
                if need > p.len() as u64 {
                    return Err(d.err(prim, format!("count={tris} needs {need} indices but <p> holds {}", p.len())));
                }
                emit.reserve(tris)?;
                for tri in p[..need as usize].chunks_exact(3 * stride) {
                    emit.polygon(tri)?;
                }
            }
            "polylist" => {
                let vcount = match child(prim, "vcount") {
                    Some(v) => d.uints(v)?,
                    None => Vec::new(),
                };
                let polys = count.unwrap_or(vcount.len());
                if polys > vcount.len() {
                    return Err(d.err(prim, format!("count={polys} but <vcount> lists {} polygons", vcount.len())));
                }
                let vcount = &vcount[..polys];
                let p = match child(prim, "p") {
                    Some(p) => d.uints(p)?,
                    None => Vec::new(),
                };
                let corners: u64 = vcount.iter().map(|&v| v as u64).sum();
                let need = corners * stride as u64;
                if need > p.len() as u64 {
                    return Err(d.err(prim, format!("<vcount> needs {need} indices but <p> holds {}", p.len())));
                }
                // Bounded by the index data just checked: at most one triangle per corner.
                let tris: u64 = vcount.iter().map(|&v| (v as u64).saturating_sub(2)).sum();
                emit.reserve(tris as usize)?;
                let mut at = 0usize;
                for &n in vcount {
                    let len = n as usize * stride;
                    emit.polygon(&p[at..at + len])?;
                    at += len;
                }
            }
            "polygons" | "trifans" | "tristrips" => {
                if let Some(ph) = child(prim, "ph") {
                    return Err(d.err(ph, "polygons with holes are not supported"));
                }
                for pe in children(prim, "p") {
                    let p = d.uints(pe)?;
                    if p.len() % stride != 0 {
                        return Err(d.err(pe, format!("{} indices is not a multiple of the stride {stride}", p.len())));
                    }
                    emit.reserve((p.len() / stride).saturating_sub(2))?;
                    if kind == "tristrips" { emit.strip(&p)? } else { emit.polygon(&p)? }
                }
            }
            _ => unreachable!("read_primitive is only called for the kinds above"),
        }
        let triangles = (self.out.corners.len() - first_corner) / 3;
        self.out.groups.push(Group { symbol: prim.attribute("material").map(str::to_owned), triangles });
        Ok(())
    }
}

/// Appends one source's values to a pool; returns (base, count).
fn pool<T>(d: &Doc, src: Node, pool: &mut Vec<T>, values: impl ExactSizeIterator<Item = T>) -> Result<(u32, u32)> {
    let base = pool.len();
    let count = values.len();
    match (u32::try_from(base + count), u32::try_from(count)) {
        (Ok(_), Ok(c)) => {
            pool.extend(values);
            Ok((base as u32, c))
        }
        _ => Err(d.err(src, "too many values")),
    }
}

/// Turns index tuples into checked triangle corners.
struct Emitter<'e, 'd, 'a, 'input> {
    d: &'e Doc<'a, 'input>,
    prim: Node<'d, 'input>,
    inputs: &'e Inputs,
    npos: usize,
    out: &'e mut Vec<Corner>,
}

impl Emitter<'_, '_, '_, '_> {
    fn reserve(&mut self, tris: usize) -> Result<()> {
        let corners = tris.checked_mul(3).ok_or_else(|| self.d.err(self.prim, "too many triangles"))?;
        self.out.reserve(corners);
        Ok(())
    }

    fn corner(&self, tuple: &[u32]) -> Result<Corner> {
        let i = &self.inputs;
        let p = tuple[i.vertex];
        if p as usize >= self.npos {
            return Err(self.d.err(self.prim, format!("vertex index {p} is out of range ({} vertices)", self.npos)));
        }
        let attr = |a: Option<Attr>, what: &str| -> Result<u32> {
            let Some(a) = a else { return Ok(NONE) };
            let k = match a.offset {
                Some(o) => tuple[o],
                None => p,
            };
            if k >= a.count {
                return Err(self.d.err(self.prim, format!("{what} index {k} is out of range ({} values)", a.count)));
            }
            Ok(a.base + k)
        };
        Ok(Corner { p, n: attr(i.normal, "NORMAL")?, t: attr(i.uv, "TEXCOORD")? })
    }

    /// Fan-triangulates one polygon: (v0,v1,v2), (v0,v2,v3), ...
    fn polygon(&mut self, idx: &[u32]) -> Result<()> {
        let s = self.inputs.stride;
        let n = idx.len() / s;
        if n < 3 {
            return Ok(());
        }
        let v0 = self.corner(&idx[..s])?;
        let mut prev = self.corner(&idx[s..2 * s])?;
        for k in 2..n {
            let next = self.corner(&idx[k * s..(k + 1) * s])?;
            self.out.extend([v0, prev, next]);
            prev = next;
        }
        Ok(())
    }

    /// A triangle strip; every other triangle is flipped to keep one winding.
    fn strip(&mut self, idx: &[u32]) -> Result<()> {
        let s = self.inputs.stride;
        let n = idx.len() / s;
        let corners: Vec<Corner> = (0..n).map(|k| self.corner(&idx[k * s..(k + 1) * s])).collect::<Result<_>>()?;
        for k in 2..n {
            let (a, b, c) = (corners[k - 2], corners[k - 1], corners[k]);
            self.out.extend(if k % 2 == 0 { [a, b, c] } else { [b, a, c] });
        }
        Ok(())
    }
}

/// Reads a `<source>` through its accessor as `N`-component tuples (extra components
/// are skipped), checking the accessor against the array before allocating.
pub fn read_tuples<const N: usize>(d: &Doc, src: Node) -> Result<Vec<[f32; N]>> {
    let acc = path(src, &["technique_common", "accessor"])
        .ok_or_else(|| d.err(src, "missing <technique_common><accessor>"))?;
    let array = d.resolve(acc, "source", &["float_array"])?;
    let count = d.uint_attr(acc, "count")?.ok_or_else(|| d.err(acc, "missing 'count' attribute"))?;
    let stride = d.uint_attr(acc, "stride")?.unwrap_or(1);
    let offset = d.uint_attr(acc, "offset")?.unwrap_or(0);
    if stride < N {
        return Err(d.err(acc, format!("stride {stride} is less than the {N} components needed")));
    }
    let declared = d.uint_attr(array, "count")?;
    let data = d.floats(array, declared)?;
    if let Some(c) = declared
        && data.len() < c
    {
        return Err(d.err(array, format!("count={c} but the array holds {} numbers", data.len())));
    }
    if count == 0 {
        return Ok(Vec::new());
    }
    let need = (offset as u64) + (count as u64 - 1) * stride as u64 + N as u64;
    if need > data.len() as u64 {
        return Err(d.err(
            acc,
            format!(
                "count={count} stride={stride} offset={offset} needs {need} numbers but the array holds {}",
                data.len()
            ),
        ));
    }
    Ok((0..count)
        .map(|i| {
            let at = offset + i * stride;
            std::array::from_fn(|k| data[at + k])
        })
        .collect())
}
