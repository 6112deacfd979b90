//! A cutout model through the binary: a glTF square whose base colour texture's alpha cuts
//! two of its four quarters (`MASK`) shows the background there, and the same file with
//! `alphaMode` `OPAQUE` shows the square everywhere.

use crate::common::cutout::{png_uri, square_doc, textured};
use crate::common::pfm::read_pfm;
use crate::common::{run_wavepath, temp_dir};
use std::path::Path;

/// Renders `file` in the normals view, 32 x 32, one sample per pixel (its centre): per pixel,
/// whether it shows the square (the normal +z as 0.5 0.5 1) rather than the background
/// (black), rows top first.
fn square_seen(file: &Path) -> Vec<bool> {
    let out = file.with_extension("pfm");
    let o = run_wavepath([
        file.to_str().unwrap(),
        "--shading",
        "normals",
        "-r",
        "32",
        "32",
        "-s",
        "1",
        "-f",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let p = read_pfm(&out);
    assert_eq!((p.width, p.height), (32, 32));
    (0..32)
        .flat_map(|y| (0..32).map(move |x| (x, y)))
        .map(|(x, y)| {
            let px = p.pixels[(31 - y) * 32 + x];
            let square = (px[0] - 0.5).abs() < 1e-3 && (px[1] - 0.5).abs() < 1e-3 && (px[2] - 1.0).abs() < 1e-3;
            let background = px == [0.0; 3];
            assert!(square || background, "pixel ({x}, {y}) is {px:?}");
            square
        })
        .collect()
}

#[test]
fn a_cutout_shows_the_background_through_its_holes() {
    let d = temp_dir("cutouts-render");
    // 2 x 2 texels: alpha 0 in the top-left and bottom-right ones. The square (side 2, seen
    // from 3 away with a field of view of 0.5 rad) fills the picture, texel by quarter.
    let png = png_uri(2, 2, Some(&[0, 255, 255, 0]), [255; 3]);
    let material =
        |mode: &str| format!(r#"{{"alphaMode":"{mode}","pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}}}}}}"#);
    for (mode, holes) in [("MASK", true), ("OPAQUE", false)] {
        let file = d.join(format!("{mode}.gltf"));
        std::fs::write(&file, square_doc(1.0, 3.0, 0.5, &textured(&material(mode), &png))).unwrap();
        let seen = square_seen(&file);
        for (i, &s) in seen.iter().enumerate() {
            let (x, y) = (i % 32, i / 32);
            let cut = (x < 16) == (y < 16);
            assert_eq!(s, !(holes && cut), "{mode}: pixel ({x}, {y})");
        }
    }
}
