//! Binary PLY read in bulk against the general parser: the same meshes written as ascii
//! (always the general parser) and as binary in either byte order, in the layouts scanners
//! write and in awkward ones (doubles, extra properties and elements, short counts, big
//! endian); polygons fall back to the general parser; damaged indices and coordinates give
//! the same one-line errors. Subdivided meshes from `wavepath subdivide` come back exactly.

use crate::common::{Xorshift, run_wavepath, temp_dir};
use glam::Vec3;
use std::collections::HashSet;
use wavepath::load::ply::parse;
use wavepath::scene::Mesh;

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
            let reference = parse(&write(&l, &values, &faces, "ascii")).unwrap_or_else(|e| panic!("{name}: {e}"));
            let expect_tris = faces.iter().map(|f| f.len() - 2).sum::<usize>();
            assert_eq!(reference.triangles.len(), expect_tris, "{name}: fan triangulation");
            for format in ["binary_little_endian", "binary_big_endian"] {
                let got = parse(&write(&l, &values, &faces, format)).unwrap_or_else(|e| panic!("{name} {format}: {e}"));
                assert_same(&got, &reference, &format!("{name}, {format}, quads {quads}"));
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
    let errors = |values: &[Vec<f64>], faces: &[Vec<i64>], ascii: bool| -> Vec<String> {
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
        files.iter().map(|f| parse(f).expect_err("damaged").to_string()).collect()
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

/// Subdivision through the command: 4^n triangles; on a closed mesh V + E vertices a level
/// (E counted here from the triangles); the same area; every vertex on the original
/// surface; and the PLY it writes reads back to exactly the mesh the library makes.
#[test]
fn subdivide_command_writes_meshes_that_read_back_exactly() {
    let d = temp_dir("subdivide");
    let sphere = crate::common::meshgen::icosphere(2);
    let obj: String = sphere.positions.iter().map(|p| format!("v {} {} {}\n", p.x, p.y, p.z)).collect::<String>()
        + &sphere.triangles.iter().map(|t| format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1)).collect::<String>();
    std::fs::write(d.join("s.obj"), obj).unwrap();
    let src = wavepath::load::load(&d.join("s.obj"), &Default::default()).unwrap().mesh;
    let out = d.join("s2.ply");
    let o = run_wavepath(["subdivide", d.join("s.obj").to_str().unwrap(), out.to_str().unwrap(), "-n", "2"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // No levels: the source mesh itself, converted.
    let same = d.join("s0.ply");
    let o = run_wavepath(["subdivide", d.join("s.obj").to_str().unwrap(), same.to_str().unwrap(), "-n", "0"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let got = parse(&std::fs::read(&same).unwrap()).unwrap();
    assert_eq!((&got.positions, &got.triangles), (&src.positions, &src.triangles));
    let got = parse(&std::fs::read(&out).unwrap()).unwrap();
    let (p, t) = wavepath::scene::subdivide::subdivide(&src.positions, &src.triangles, 2).unwrap();
    assert_eq!((&got.positions, &got.triangles), (&p, &t));
    assert_eq!(t.len(), src.triangles.len() * 16);
    let edges = |t: &[[u32; 3]]| -> usize {
        t.iter()
            .flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)])
            .map(|(i, j)| (i.min(j), i.max(j)))
            .collect::<HashSet<_>>()
            .len()
    };
    let (one_p, one_t) = wavepath::scene::subdivide::subdivide(&src.positions, &src.triangles, 1).unwrap();
    assert_eq!(one_p.len(), src.positions.len() + edges(&src.triangles));
    assert_eq!(p.len(), one_p.len() + edges(&one_t));
    let area = |p: &[Vec3], t: &[[u32; 3]]| -> f64 {
        t.iter()
            .map(|&[a, b, c]| {
                let (a, b, c) = (p[a as usize].as_dvec3(), p[b as usize].as_dvec3(), p[c as usize].as_dvec3());
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    };
    let (a0, a2) = (area(&src.positions, &src.triangles), area(&p, &t));
    assert!((a0 - a2).abs() < 1e-5 * a0, "area {a0} -> {a2}");
    // Each child lies in its parent's plane: the 16 children of triangle k are 16k..16k+16.
    for (k, tri) in src.triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|i| src.positions[i as usize]);
        let n = (b - a).cross(c - a).normalize();
        for child in &t[16 * k..16 * k + 16] {
            for &i in child {
                assert!((p[i as usize] - a).dot(n).abs() < 1e-5, "triangle {k}: a child vertex leaves its plane");
            }
        }
    }
    // Bad requests: one line each, non-zero exit.
    for (args, needle) in [
        (vec!["subdivide", d.join("s.obj").to_str().unwrap(), "x.obj", "-n", "1"], "name it .ply"),
        (vec!["subdivide", d.join("s.obj").to_str().unwrap(), out.to_str().unwrap(), "-n", "12"], "more than the 2^30"),
        (vec!["subdivide", "/nonexistent.obj", out.to_str().unwrap(), "-n", "1"], "/nonexistent.obj"),
    ] {
        let o = run_wavepath(args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(needle) && err.trim().lines().count() == 1, "{err}");
    }
}

/// `Mesh::subdivided` (behind `--subdivide`): children keep their parent's material, and
/// attributes that are linear over the surface stay exactly so (uv and colour set to
/// functions of the position); a constant normal stays that normal.
#[test]
fn subdivided_meshes_carry_materials_and_attributes() {
    let mut m = Mesh::default();
    let corners =
        [Vec3::new(0.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 1.0), Vec3::new(0.0, 0.0, 1.0)];
    m.positions = corners.to_vec();
    m.triangles = vec![[0, 1, 2], [0, 2, 3]];
    m.material_ids = vec![3, 5].into();
    m.normals = Some(vec![Vec3::Y; 4]);
    m.uvs = Some(corners.iter().map(|p| glam::Vec2::new(p.x / 2.0, p.z)).collect());
    m.colors = Some(corners.iter().map(|p| Vec3::new(p.x, p.z, 0.25)).collect());
    let s = m.clone().subdivided(3).unwrap();
    assert_eq!(s.triangles.len(), 2 * 64);
    assert_eq!(s.material_ids.iter().collect::<Vec<_>>(), [[3u32; 64], [5u32; 64]].concat());
    let (n, uv, c) = (s.normals.as_ref().unwrap(), s.uvs.as_ref().unwrap(), s.colors.as_ref().unwrap());
    assert!(n.len() == s.positions.len() && uv.len() == s.positions.len() && c.len() == s.positions.len());
    for (i, p) in s.positions.iter().enumerate() {
        assert_eq!(n[i], Vec3::Y, "vertex {i}");
        assert_eq!(uv[i], glam::Vec2::new(p.x / 2.0, p.z), "vertex {i}");
        assert_eq!(c[i], Vec3::new(p.x, p.z, 0.25), "vertex {i}");
    }
    assert_eq!(m.clone().subdivided(0).unwrap(), m);
    assert!(m.subdivided(15).is_none(), "2 x 4^15 triangles is past the limit");

    // Through the command line: the stats count the subdivided triangles; too many levels is
    // one line naming the file.
    let d = temp_dir("subdivide-render");
    let obj = d.join("quad.obj");
    std::fs::write(&obj, "v 0 0 0\nv 2 0 0\nv 2 0 1\nv 0 0 1\nf 1 2 3\nf 1 3 4\n").unwrap();
    let stats = d.join("stats.json");
    let (o, s) = (obj.to_str().unwrap(), stats.to_str().unwrap());
    let out =
        run_wavepath([o, "--subdivide", "2", "-r", "8", "6", "-f", d.join("q.png").to_str().unwrap(), "--stats", s]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    assert_eq!(json["triangles"], 32);
    let out = run_wavepath([o, "--subdivide", "15", "-r", "8", "6", "-f", d.join("q.png").to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("quad.obj") && err.trim().lines().count() == 1, "{err}");
}
