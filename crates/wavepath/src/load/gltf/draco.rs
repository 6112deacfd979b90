//! `KHR_draco_mesh_compression`: a primitive whose attributes and indices are one Draco
//! bitstream in a buffer view, decoded by the draco-core crate (a Rust port of Google's
//! decoder). The extension maps glTF attribute names to the stream's attribute ids; the
//! decoded values replace the primitive's accessors, which then only describe them.

use draco_core::{DataType, DecoderBuffer, Mesh as DracoMesh, MeshDecoder};
use glam::{Vec2, Vec3};

/// A decoded primitive: per-point attributes and triangle corners.
pub struct Decoded {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub uvs: Option<Vec<Vec2>>,
    pub colors: Option<Vec<Vec3>>,
    pub indices: Vec<u32>,
}

/// Decodes `prim`'s Draco stream, if it has one; uvs from set `uv_set`.
pub fn decode(
    prim: &gltf::Primitive,
    doc: &gltf::Document,
    buffers: &[gltf::buffer::Data],
    uv_set: u32,
) -> Result<Option<Decoded>, String> {
    let Some(ext) = prim.extension_value("KHR_draco_mesh_compression") else { return Ok(None) };
    let what = |m: &str| format!("KHR_draco_mesh_compression: {m}");
    let view = ext["bufferView"]
        .as_u64()
        .and_then(|i| doc.views().nth(i as usize))
        .ok_or_else(|| what("its buffer view does not exist"))?;
    let bytes = buffers
        .get(view.buffer().index())
        .and_then(|b| b.0.get(view.offset()..view.offset().checked_add(view.length())?))
        .ok_or_else(|| what("its buffer view lies outside its buffer"))?;
    let attributes = ext["attributes"].as_object().ok_or_else(|| what("no attributes"))?;
    let mut mesh = DracoMesh::new();
    MeshDecoder::new()
        .decode(&mut DecoderBuffer::new(bytes), &mut mesh)
        .map_err(|e| what(&format!("the compressed data cannot be decoded ({e})")))?;
    let n = mesh.num_points();
    let read = |name: &str, components: usize| -> Result<Option<Vec<f32>>, String> {
        let Some(id) = attributes.get(name) else { return Ok(None) };
        let id = id.as_u64().and_then(|i| u32::try_from(i).ok()).ok_or_else(|| what(&format!("{name} id")))?;
        let att = mesh
            .attribute_by_unique_id(id)
            .ok_or_else(|| what(&format!("{name} is attribute {id}, which the stream does not have")))?;
        // Normalised integers (colours) scale to [0, 1] as their glTF accessors would.
        let scale = match (att.normalized(), att.data_type()) {
            (true, DataType::Uint8) => 1.0 / 255.0,
            (true, DataType::Uint16) => 1.0 / 65535.0,
            _ => 1.0,
        };
        let mut v = att.read_f32s(n, components);
        v.iter_mut().for_each(|x| *x *= scale);
        Ok(Some(v))
    };
    let positions: Vec<Vec3> = read("POSITION", 3)?
        .ok_or_else(|| what("no POSITION attribute"))?
        .chunks_exact(3)
        .map(Vec3::from_slice)
        .collect();
    let normals = read("NORMAL", 3)?.map(|v| v.chunks_exact(3).map(Vec3::from_slice).collect());
    let uvs = read(&format!("TEXCOORD_{uv_set}"), 2)?.map(|v| v.chunks_exact(2).map(Vec2::from_slice).collect());
    let colors = read("COLOR_0", 3)?.map(|v| v.chunks_exact(3).map(Vec3::from_slice).collect());
    let indices = mesh.faces().iter().flat_map(|f| f.map(|p| p.0)).collect();
    Ok(Some(Decoded { positions, normals, uvs, colors, indices }))
}

/// Gives the accessors of Draco primitives that have no buffer view of their own (their
/// data is in the stream) the stream's view, so that the gltf crate's validation, which
/// requires a view of every non-sparse accessor, accepts the file. Nothing reads them
/// through it: [`decode`] replaces their data.
pub fn attach_views(json: &mut gltf::json::Root) {
    use gltf::json::Index;
    let mut views = Vec::new();
    for m in &json.meshes {
        for p in &m.primitives {
            let ext = p.extensions.as_ref().and_then(|e| e.others.get("KHR_draco_mesh_compression"));
            let Some(view) = ext.and_then(|e| e["bufferView"].as_u64()) else { continue };
            for a in p.attributes.values().chain(p.indices.as_ref()) {
                views.push((a.value(), view as u32));
            }
        }
    }
    for (accessor, view) in views {
        if let Some(a) = json.accessors.get_mut(accessor)
            && a.buffer_view.is_none()
            && a.sparse.is_none()
        {
            a.buffer_view = Some(Index::new(view));
        }
    }
}
