//! Binary PLY read in bulk: the layout the header declares turned into fixed strides and
//! offsets, and every vertex and face converted in parallel straight from the file's bytes,
//! with no per-element allocation. It takes the files scanners and converters write (vertex
//! properties all scalars; triangle faces whose only list is the vertex indices; other
//! elements of scalars); for any other layout it declines and the general parser reads the
//! file.

use crate::scene::Mesh;
use glam::{Vec2, Vec3};
use ply_rs_bw::ply::{ElementDef, Encoding, Header, PropertyType, ScalarType};
use rayon::prelude::*;

/// Elements converted per parallel task.
const CHUNK: usize = 1 << 16;

/// A scalar type, copyable (ply-rs-bw's is not).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Ty {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Ty {
    fn of(t: &ScalarType) -> Ty {
        match t {
            ScalarType::Char => Ty::I8,
            ScalarType::UChar => Ty::U8,
            ScalarType::Short => Ty::I16,
            ScalarType::UShort => Ty::U16,
            ScalarType::Int => Ty::I32,
            ScalarType::UInt => Ty::U32,
            ScalarType::Float => Ty::F32,
            ScalarType::Double => Ty::F64,
        }
    }

    fn size(self) -> usize {
        match self {
            Ty::I8 | Ty::U8 => 1,
            Ty::I16 | Ty::U16 => 2,
            Ty::I32 | Ty::U32 | Ty::F32 => 4,
            Ty::F64 => 8,
        }
    }
}

/// A scalar property's place in its element and how to read it.
#[derive(Clone, Copy)]
struct Field {
    offset: usize,
    ty: Ty,
}

/// The scalar of type `ty` at the start of `b` (`big`: big-endian). Every PLY scalar is
/// exact in f64, so converting from it rounds once, as a direct conversion would.
#[inline(always)]
fn value(b: &[u8], ty: Ty, big: bool) -> f64 {
    macro_rules! num {
        ($t:ty, $n:expr) => {{
            let mut a = [0u8; $n];
            a.copy_from_slice(&b[..$n]);
            (if big { <$t>::from_be_bytes(a) } else { <$t>::from_le_bytes(a) }) as f64
        }};
    }
    match ty {
        Ty::I8 => b[0] as i8 as f64,
        Ty::U8 => b[0] as f64,
        Ty::I16 => num!(i16, 2),
        Ty::U16 => num!(u16, 2),
        Ty::I32 => num!(i32, 4),
        Ty::U32 => num!(u32, 4),
        Ty::F32 => num!(f32, 4),
        Ty::F64 => num!(f64, 8),
    }
}

/// A property of an element as f32.
#[inline(always)]
fn read(b: &[u8], f: Field, big: bool) -> f32 {
    value(&b[f.offset..], f.ty, big) as f32
}

/// The integer types of face lists and counts, read without a per-value switch on the type
/// (the loops over tens of millions of faces are compiled once per type and byte order).
trait Int {
    fn get<const BIG: bool>(b: &[u8]) -> i64;
}

macro_rules! int {
    ($($t:ty),*) => {$(
        impl Int for $t {
            #[inline(always)]
            fn get<const BIG: bool>(b: &[u8]) -> i64 {
                let mut a = [0u8; std::mem::size_of::<$t>()];
                a.copy_from_slice(&b[..std::mem::size_of::<$t>()]);
                (if BIG { <$t>::from_be_bytes(a) } else { <$t>::from_le_bytes(a) }) as i64
            }
        }
    )*};
}
int!(i8, u8, i16, u16, i32, u32);

/// Runs `$f::<T, BIG>($args)` with `T` the integer type `$ty` (never a float: `face_layout`
/// declines float lists) and `BIG` the byte order.
macro_rules! by_int {
    ($ty:expr, $big:expr, $f:ident($($args:expr),*)) => {
        match ($ty, $big) {
            (Ty::I8, false) => $f::<i8, false>($($args),*),
            (Ty::I8, true) => $f::<i8, true>($($args),*),
            (Ty::U8, false) => $f::<u8, false>($($args),*),
            (Ty::U8, true) => $f::<u8, true>($($args),*),
            (Ty::I16, false) => $f::<i16, false>($($args),*),
            (Ty::I16, true) => $f::<i16, true>($($args),*),
            (Ty::U16, false) => $f::<u16, false>($($args),*),
            (Ty::U16, true) => $f::<u16, true>($($args),*),
            // (Float counts and indices are declined by `face_layout`: never taken.)
            (Ty::I32 | Ty::F32 | Ty::F64, false) => $f::<i32, false>($($args),*),
            (Ty::I32 | Ty::F32 | Ty::F64, true) => $f::<i32, true>($($args),*),
            (Ty::U32, false) => $f::<u32, false>($($args),*),
            (Ty::U32, true) => $f::<u32, true>($($args),*),
        }
    };
}

/// Whether every face of `fbytes` has three vertices (its count field at `at`).
fn all_triangles<T: Int, const BIG: bool>(fbytes: &[u8], stride: usize, at: usize) -> bool {
    fbytes.par_chunks(stride * CHUNK).all(|c| c.chunks_exact(stride).all(|f| T::get::<BIG>(&f[at..]) == 3))
}

/// The faces' vertex indices (`first`: the first index's offset) into `triangles`; the first
/// face with an index outside `0..n`, and that index, if any.
fn face_indices<T: Int, const BIG: bool>(
    fbytes: &[u8],
    stride: usize,
    first: usize,
    n: usize,
    triangles: &mut [[u32; 3]],
) -> Option<(usize, i64)> {
    let size = std::mem::size_of::<T>();
    triangles
        .par_chunks_mut(CHUNK)
        .zip(fbytes.par_chunks(stride * CHUNK))
        .enumerate()
        .filter_map(|(k, (o, src))| {
            for (j, (t, f)) in o.iter_mut().zip(src.chunks_exact(stride)).enumerate() {
                let f = &f[first..];
                let i = [T::get::<BIG>(f), T::get::<BIG>(&f[size..]), T::get::<BIG>(&f[2 * size..])];
                if let Some(&bad) = i.iter().find(|&&i| i < 0 || i as u64 >= n as u64) {
                    return Some((k * CHUNK + j, bad));
                }
                *t = i.map(|i| i as u32);
            }
            None
        })
        .min_by_key(|&(face, _)| face)
}

/// Bytes of an element made of scalars only, and each property's field; `None` when it has a
/// list.
fn scalar_layout(def: &ElementDef) -> Option<(usize, Vec<(&str, Field)>)> {
    let mut offset = 0;
    let mut fields = Vec::new();
    for (name, p) in &def.properties {
        let PropertyType::Scalar(ty) = &p.data_type else { return None };
        let ty = Ty::of(ty);
        fields.push((name.as_str(), Field { offset, ty }));
        offset += ty.size();
    }
    Some((offset, fields))
}

/// The triangle faces' layout: bytes per face, the count field, the first index's offset
/// and the index type; `None` unless the element's one list is `vertex_indices` (or
/// `vertex_index`) and the rest are scalars.
fn face_layout(def: &ElementDef) -> Option<(usize, Field, usize, Ty)> {
    let mut offset = 0;
    let mut list = None;
    for (name, p) in &def.properties {
        match &p.data_type {
            PropertyType::Scalar(ty) => offset += Ty::of(ty).size(),
            PropertyType::List(count, index) => {
                let (count, index) = (Ty::of(count), Ty::of(index));
                if list.is_some() || (name != "vertex_indices" && name != "vertex_index") {
                    return None;
                }
                if matches!(count, Ty::F32 | Ty::F64) || matches!(index, Ty::F32 | Ty::F64) {
                    return None;
                }
                list = Some((Field { offset, ty: count }, index));
                offset += count.size() + 3 * index.size();
            }
        }
    }
    let (count, index) = list?;
    let first = count.offset + count.ty.size();
    Some((offset, count, first, index))
}

/// The mesh of a binary PLY whose payload (the bytes after `end_header`) is `payload`, or
/// `None` when the layout is not one this reader takes (including faces that are not all
/// triangles): then the general parser reads the file.
pub fn parse(header: &Header, payload: &[u8]) -> Option<Result<Mesh, String>> {
    let big = match header.encoding {
        Encoding::BinaryLittleEndian => false,
        Encoding::BinaryBigEndian => true,
        Encoding::Ascii => return None,
    };
    let mut offset = 0usize;
    let mut vertices = None;
    let mut faces = None;
    for (name, def) in &header.elements {
        let size = match name.as_str() {
            "face" => {
                let (stride, count, first, index) = face_layout(def)?;
                faces = Some((offset, def.count, stride, count, first, index));
                stride
            }
            _ => {
                let (stride, fields) = scalar_layout(def)?;
                if name == "vertex" {
                    vertices = Some((offset, def.count, stride, fields));
                }
                stride
            }
        };
        offset = offset.checked_add(size.checked_mul(def.count)?)?;
        if offset > payload.len() {
            return None;
        }
    }
    let (v_at, n, v_stride, fields) = vertices?;
    let (f_at, nf, f_stride, count, first, index) = faces?;
    let field = |names: &[&str]| fields.iter().find(|(n, _)| names.contains(n)).map(|&(_, f)| f);
    let (x, y, z) = (field(&["x"])?, field(&["y"])?, field(&["z"])?);
    let vbytes = &payload[v_at..v_at + n * v_stride];
    let fbytes = &payload[f_at..f_at + nf * f_stride];
    // Every face a triangle, or the general parser triangulates.
    let triangles_only = by_int!(count.ty, big, all_triangles(fbytes, f_stride, count.offset));
    if !triangles_only {
        return None;
    }
    Some(convert(vbytes, v_stride, [x, y, z], &field, fbytes, f_stride, first, index, big))
}

#[allow(clippy::too_many_arguments)]
fn convert(
    vbytes: &[u8],
    v_stride: usize,
    [x, y, z]: [Field; 3],
    field: &dyn Fn(&[&str]) -> Option<Field>,
    fbytes: &[u8],
    f_stride: usize,
    first: usize,
    index: Ty,
    big: bool,
) -> Result<Mesh, String> {
    let n = vbytes.len() / v_stride.max(1);
    let vec3s = |[a, b, c]: [Field; 3]| -> Vec<Vec3> {
        let mut out = vec![Vec3::ZERO; n];
        // Little-endian floats (what scanners write) without the switch on the type.
        let le_floats = !big && [a, b, c].iter().all(|f| f.ty == Ty::F32);
        let f32_at = |v: &[u8], at: usize| {
            let mut x = [0u8; 4];
            x.copy_from_slice(&v[at..at + 4]);
            f32::from_le_bytes(x)
        };
        out.par_chunks_mut(CHUNK).zip(vbytes.par_chunks(v_stride * CHUNK)).for_each(|(o, src)| {
            if le_floats {
                for (p, v) in o.iter_mut().zip(src.chunks_exact(v_stride)) {
                    *p = Vec3::new(f32_at(v, a.offset), f32_at(v, b.offset), f32_at(v, c.offset));
                }
            } else {
                for (p, v) in o.iter_mut().zip(src.chunks_exact(v_stride)) {
                    *p = Vec3::new(read(v, a, big), read(v, b, big), read(v, c, big));
                }
            }
        });
        out
    };
    let positions = vec3s([x, y, z]);
    if let Some(i) = crate::scene::first_bad(&positions, |p| !p.is_finite()) {
        return Err(format!("vertex {i} has a NaN or infinite coordinate"));
    }
    let normals = match (field(&["nx"]), field(&["ny"]), field(&["nz"])) {
        (Some(a), Some(b), Some(c)) => Some(vec3s([a, b, c])),
        _ => None,
    };
    let uv =
        [["u", "v"], ["s", "t"], ["texture_u", "texture_v"]].iter().find_map(|[a, b]| field(&[a]).zip(field(&[b])));
    let uvs = uv.map(|(a, b)| {
        let mut out = vec![Vec2::ZERO; n];
        out.par_chunks_mut(CHUNK).zip(vbytes.par_chunks(v_stride * CHUNK)).for_each(|(o, src)| {
            for (t, v) in o.iter_mut().zip(src.chunks_exact(v_stride)) {
                *t = Vec2::new(read(v, a, big), read(v, b, big));
            }
        });
        out
    });
    let colors = match (field(&["red"]), field(&["green"]), field(&["blue"])) {
        (Some(r), Some(g), Some(b)) => {
            // Bytes are sRGB (as scanners write them), floats linear as written; other types
            // are not colours the general parser reads either.
            let lut: Vec<f32> = (0..256).map(|i| crate::scene::texture::srgb_to_linear(i as f32 / 255.0)).collect();
            let channel = |f: Field, v: &[u8]| match f.ty {
                Ty::U8 => lut[v[f.offset] as usize],
                Ty::F32 | Ty::F64 => read(v, f, big),
                _ => 0.0,
            };
            let mut out = vec![Vec3::ZERO; n];
            out.par_chunks_mut(CHUNK).zip(vbytes.par_chunks(v_stride * CHUNK)).for_each(|(o, src)| {
                for (c, v) in o.iter_mut().zip(src.chunks_exact(v_stride)) {
                    *c = Vec3::new(channel(r, v), channel(g, v), channel(b, v));
                }
            });
            Some(out)
        }
        _ => None,
    };
    let nf = fbytes.len() / f_stride.max(1);
    let mut triangles = vec![[0u32; 3]; nf];
    let bad = by_int!(index, big, face_indices(fbytes, f_stride, first, n, &mut triangles));
    if let Some((face, i)) = bad {
        return Err(if i < 0 {
            format!("face {face}: negative vertex index")
        } else {
            format!("face {face} uses vertex {i}, but there are only {n}")
        });
    }
    if triangles.is_empty() {
        return Err("no faces".into());
    }
    let material_ids = crate::scene::MaterialIds::uniform(0, triangles.len());
    Ok(Mesh { positions, normals, uvs, colors, tangents: None, triangles, material_ids })
}
