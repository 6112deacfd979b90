//! OBJ files of positions and faces read by the parallel reader against tobj: the same file
//! with one `g` statement (which only tobj takes) must give the same triangles, corner for
//! corner, through fans, negative indices, comments, CRLF and chunk boundaries; files with
//! more (colours) or damage go to tobj and keep its results and errors.

use crate::load::{LoadOptions, load};
use crate::scene::Scene;
use crate::tests::common::{Xorshift, temp_dir};

fn load_text(name: &str, text: &str) -> Result<Scene, String> {
    // One directory per test thread: the tests run in parallel and `temp_dir` empties it.
    let d = temp_dir(&format!("obj-bulk-{:?}", std::thread::current().id()));
    std::fs::write(d.join(name), text).unwrap();
    load(&d.join(name), &LoadOptions::default()).map_err(|e| format!("{e:#}"))
}

/// A random mesh's text: `n` vertices, faces of 3 to 6 corners, some with negative indices,
/// comments and blank lines, lines ending in `eol`.
fn random_obj(r: &mut Xorshift, n: usize, faces: usize, eol: &str) -> String {
    let mut out = String::from("# a scan\n");
    let mut seen = 0;
    let coord = |r: &mut Xorshift| (r.below(2_000_001) as f64 / 1000.0 - 1000.0) as f32;
    for k in 0..faces {
        // Vertices arrive in batches between faces, so negative indices have something to
        // count back over.
        while seen < n && (seen < 8 || r.below(3) == 0) {
            out += &format!("v {} {} {}{eol}", coord(r), coord(r), coord(r));
            seen += 1;
        }
        let corners = 3 + r.below(4);
        let idx: Vec<String> = (0..corners)
            .map(|_| {
                let i = r.below(seen);
                if k % 5 == 0 { format!("-{}", seen - i) } else { format!("{}", i + 1) }
            })
            .collect();
        out += &format!("f {}{eol}", idx.join(" "));
        if k % 97 == 0 {
            out += &format!("# note {k}{eol}{eol}");
        }
    }
    while seen < n {
        out += &format!("v 0 0 {seen}{eol}");
        seen += 1;
    }
    out
}

fn assert_same_triangles(a: &Scene, b: &Scene, what: &str) {
    assert_eq!(a.mesh.triangles.len(), b.mesh.triangles.len(), "{what}: triangle count");
    for i in 0..a.mesh.triangles.len() {
        assert_eq!(a.mesh.corners(i), b.mesh.corners(i), "{what}: triangle {i}");
    }
    assert_eq!(a.materials, b.materials, "{what}: materials");
    assert_eq!(a.mesh.normals, b.mesh.normals, "{what}: normals");
}

#[test]
fn parallel_obj_reader_gives_tobjs_triangles() {
    let mut r = Xorshift(0xdecaf);
    for (eol, n, faces) in [("\n", 40, 60), ("\r\n", 5000, 9000), ("\n", 20000, 30000)] {
        let text = random_obj(&mut r, n, faces, eol);
        let fast = load_text("fast.obj", &text).unwrap();
        // One group statement: tobj's path, the same geometry.
        let slow = load_text("slow.obj", &format!("g scan{eol}{text}")).unwrap();
        let what = format!("{n} vertices, eol {eol:?}");
        // Two readers, so the comparison is not of one reader with itself.
        assert_eq!((fast.source.reader, slow.source.reader), ("obj-bulk", "tobj"), "{what}");
        assert_same_triangles(&fast, &slow, &what);
        assert!(fast.mesh.triangles.len() >= faces);
    }
}

#[test]
fn obj_with_more_than_positions_and_faces_keeps_tobjs_reading() {
    // Colours on `v` lines: read by tobj (the parallel reader declines), kept.
    let s = load_text("c.obj", "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n").unwrap();
    assert!(s.mesh.colors.is_some());
    assert_eq!(s.source.reader, "tobj");
    // Damage: the same errors as before.
    let e = load_text("oob.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n").unwrap_err();
    assert!(e.ends_with("oob.obj: a face refers to a vertex that does not exist"), "{e}");
    let e = load_text("nan.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n").unwrap_err();
    assert!(e.contains("nan.obj") && !e.contains('\n'), "{e}");
    let e = load_text("bad.obj", "v 0 0 0\nv 1 x 0\nv 0 1 0\nf 1 2 3\n").unwrap_err();
    assert!(e.contains("bad.obj: line 2"), "{e}");
}
