//! Binary PLY read in bulk against the general parser: the same meshes written as ascii
//! (always the general parser) and as binary in either byte order, in the layouts scanners
//! write and in awkward ones (doubles, extra properties and elements, short counts, big
//! endian); polygons fall back to the general parser; damaged indices and coordinates give
//! the same one-line errors.

use crate::load::ply::{BULK_READER, GENERAL_READER, parse};
use crate::scene::Mesh;
use crate::tests::common::Xorshift;

/// One property: name, PLY type, and how to get its value for vertex `i`.
struct Prop {
    name: &'static str,
    ty: &'static str,
}

/// A PLY layout: vertex properties, an optional extra element of `extra` ints between
/// vertices and faces, the face list's count and index types, and a trailing face scalar.
struct Layout {
    vertex: Vec<Prop>,
    extra_element: bool,
    count_ty: &'static str,
    index_ty: &'static str,
    face_flag: bool,
}

/// `v` as PLY type `ty`, in the byte order asked.
fn bytes(v: f64, ty: &str, big: bool) -> Vec<u8> {
    macro_rules! b {
        ($x:expr) => {
            if big { $x.to_be_bytes().to_vec() } else { $x.to_le_bytes().to_vec() }
        };
    }
    match ty {
        "char" => b!(v as i8),
        "uchar" => b!(v as u8),
        "short" => b!(v as i16),
        "ushort" => b!(v as u16),
        "int" => b!(v as i32),
        "uint" => b!(v as u32),
        "float" => b!(v as f32),
        "double" => b!(v),
        _ => unreachable!(),
    }
}

/// The file: `values[i][k]` is vertex i's property k; `faces` index lists.
fn write(l: &Layout, values: &[Vec<f64>], faces: &[Vec<i64>], format: &str) -> Vec<u8> {
    let mut h = format!("ply\nformat {format} 1.0\ncomment test\nelement vertex {}\n", values.len());
    for p in &l.vertex {
        h += &format!("property {} {}\n", p.ty, p.name);
    }
    if l.extra_element {
        h += "element edge 2\nproperty int vertex1\nproperty int vertex2\n";
    }
    h += &format!("element face {}\nproperty list {} {} vertex_indices\n", faces.len(), l.count_ty, l.index_ty);
    if l.face_flag {
        h += "property uchar flags\n";
    }
    h += "end_header\n";
    let mut out = h.into_bytes();
    let ascii = format == "ascii";
    let big = format == "binary_big_endian";
    let put = |out: &mut Vec<u8>, v: f64, ty: &str| {
        if ascii {
            let text = if matches!(ty, "float") {
                format!("{} ", v as f32)
            } else if ty == "double" {
                format!("{v} ")
            } else {
                format!("{} ", v as i64)
            };
            out.extend(text.as_bytes());
        } else {
            out.extend(bytes(v, ty, big));
        }
    };
    for row in values {
        for (p, &v) in l.vertex.iter().zip(row) {
            put(&mut out, v, p.ty);
        }
        if ascii {
            out.push(b'\n');
        }
    }
    if l.extra_element {
        for e in [[0.0, 1.0], [1.0, 2.0]] {
            put(&mut out, e[0], "int");
            put(&mut out, e[1], "int");
            if ascii {
                out.push(b'\n');
            }
        }
    }
    for f in faces {
        put(&mut out, f.len() as f64, l.count_ty);
        for &i in f {
            put(&mut out, i as f64, l.index_ty);
        }
        if l.face_flag {
            put(&mut out, 7.0, "uchar");
        }
        if ascii {
            out.push(b'\n');
        }
    }
    out
}

fn random_mesh(r: &mut Xorshift, l: &Layout, n: usize, m: usize, quads: bool) -> (Vec<Vec<f64>>, Vec<Vec<i64>>) {
    let unit = |r: &mut Xorshift| (r.below(1 << 20) as f64 / (1 << 20) as f64) * 2.0 - 1.0;
    let values = (0..n)
        .map(|_| {
            l.vertex
                .iter()
                .map(|p| match p.ty {
                    "uchar" => r.below(256) as f64,
                    "float" => unit(r) * 100.0,
                    "double" => unit(r) * 1e3 + unit(r) * 1e-9,
                    _ => r.below(100) as f64,
                })
                .collect()
        })
        .collect();
    let faces = (0..m)
        .map(|k| {
            let corners = if quads && k % 3 == 0 { 4 } else { 3 };
            (0..corners).map(|_| r.below(n) as i64).collect()
        })
        .collect();
    (values, faces)
}

fn layouts() -> Vec<(&'static str, Layout)> {
    let p = |name, ty| Prop { name, ty };
    vec![
        (
            "scanner",
            Layout {
                vertex: vec![p("x", "float"), p("y", "float"), p("z", "float")],
                extra_element: false,
                count_ty: "uchar",
                index_ty: "int",
                face_flag: false,
            },
        ),
        (
            "attributes",
            Layout {
                vertex: vec![
                    p("x", "float"),
                    p("confidence", "float"),
                    p("y", "float"),
                    p("z", "float"),
                    p("nx", "float"),
                    p("ny", "float"),
                    p("nz", "float"),
                    p("s", "float"),
                    p("t", "float"),
                    p("red", "uchar"),
                    p("green", "uchar"),
                    p("blue", "uchar"),
                    p("alpha", "uchar"),
                ],
                extra_element: true,
                count_ty: "uchar",
                index_ty: "uint",
                face_flag: true,
            },
        ),
        (
            "doubles and shorts",
            Layout {
                vertex: vec![p("z", "double"), p("y", "double"), p("x", "double"), p("u", "short"), p("v", "ushort")],
                extra_element: false,
                count_ty: "ushort",
                index_ty: "ushort",
                face_flag: false,
            },
        ),
    ]
}

fn assert_same(a: &Mesh, b: &Mesh, what: &str) {
    assert_eq!(a.positions, b.positions, "{what}: positions");
    assert_eq!(a.normals, b.normals, "{what}: normals");
    assert_eq!(a.uvs, b.uvs, "{what}: uvs");
    assert_eq!(a.colors, b.colors, "{what}: colours");
    assert_eq!(a.triangles, b.triangles, "{what}: triangles");
    assert_eq!(a.material_ids, b.material_ids, "{what}: materials");
}

#[test]
fn binary_ply_in_bulk_equals_the_general_parser() {
    let mut r = Xorshift(0x5eed_f00d);
    for (name, l) in layouts() {
        for quads in [false, true] {
            let (values, faces) = random_mesh(&mut r, &l, 3000, 5000, quads);
            let (reference, reader) =
                parse(&write(&l, &values, &faces, "ascii")).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(reader, GENERAL_READER, "{name}: ascii");
            let expect_tris = faces.iter().map(|f| f.len() - 2).sum::<usize>();
            assert_eq!(reference.triangles.len(), expect_tris, "{name}: fan triangulation");
            for format in ["binary_little_endian", "binary_big_endian"] {
                let what = format!("{name}, {format}, quads {quads}");
                let (got, reader) =
                    parse(&write(&l, &values, &faces, format)).unwrap_or_else(|e| panic!("{name} {format}: {e}"));
                // Triangles in every layout here are the bulk reader's; quads the general one's,
                // so the comparison is of two different readers, not one with itself.
                assert_eq!(reader, if quads { GENERAL_READER } else { BULK_READER }, "{what}: reader");
                assert_same(&got, &reference, &what);
            }
        }
    }
}

#[test]
fn binary_ply_errors_match_the_general_parser() {
    let l = &layouts()[0].1;
    let mut r = Xorshift(7);
    let (mut values, mut faces) = random_mesh(&mut r, l, 50, 80, false);
    // Ascii and a binary file with one quad at the end go through the general parser, plain
    // binary files through the bulk reader.
    let files = |values: &[Vec<f64>], faces: &[Vec<i64>], ascii: bool| -> Vec<Vec<u8>> {
        let mut with_quad = faces.to_vec();
        with_quad.push(vec![0, 1, 2, 3]);
        let mut files = vec![
            write(l, values, faces, "binary_little_endian"),
            write(l, values, faces, "binary_big_endian"),
            write(l, values, &with_quad, "binary_little_endian"),
        ];
        if ascii {
            files.push(write(l, values, faces, "ascii"));
        }
        files
    };
    // Undamaged, the files go to the readers said above.
    let readers: Vec<_> = files(&values, &faces, true).iter().map(|f| parse(f).unwrap().1).collect();
    assert_eq!(readers, [BULK_READER, BULK_READER, GENERAL_READER, GENERAL_READER]);
    let errors = |values: &[Vec<f64>], faces: &[Vec<i64>], ascii: bool| -> Vec<String> {
        files(values, faces, ascii).iter().map(|f| parse(f).expect_err("damaged").to_string()).collect()
    };
    faces[61][1] = 50;
    let e = errors(&values, &faces, true);
    assert!(e.iter().all(|m| m == "face 61 uses vertex 50, but there are only 50"), "{e:?}");
    faces[61][1] = 0;
    faces[17][2] = -4;
    let e = errors(&values, &faces, true);
    assert!(e.iter().all(|m| m == "face 17: negative vertex index"), "{e:?}");
    faces[17][2] = 0;
    values[33][1] = f64::NAN;
    // (Ascii cannot carry a NaN the parser accepts.)
    let e = errors(&values, &faces, false);
    assert!(e.iter().all(|m| m == "vertex 33 has a NaN or infinite coordinate"), "{e:?}");
}
