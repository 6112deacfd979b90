//! A glTF cutout written by a test: a square facing +z whose base colour texture carries an
//! alpha channel, and a camera looking at it.
use base64::Engine;

fn b64(bytes: &[u8]) -> String {
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

/// A PNG of `w` x `h` texels, rows top first: white (or `rgb`) with the alpha of `alpha`
/// (none: an RGB image), as a data URI.
pub fn png_uri(w: u32, h: u32, alpha: Option<&[u8]>, rgb: [u8; 3]) -> String {
    let mut out = std::io::Cursor::new(Vec::new());
    match alpha {
        Some(a) => {
            image::RgbaImage::from_fn(w, h, |x, y| image::Rgba([rgb[0], rgb[1], rgb[2], a[(y * w + x) as usize]]))
                .write_to(&mut out, image::ImageFormat::Png)
        }
        None => image::RgbImage::from_fn(w, h, |_, _| image::Rgb(rgb)).write_to(&mut out, image::ImageFormat::Png),
    }
    .expect("a PNG in memory");
    format!("data:image/png;base64,{}", b64(&out.into_inner()))
}

/// A square of corners (+-`half`, +-`half`, 0) facing +z, uv (0, 0) at its top-left corner
/// (-`half`, `half`) and (1, 1) at (`half`, -`half`), of material 0; a perspective camera at
/// (0, 0, `eye`) looking down -z (vertical field of view `yfov` radians, square image);
/// `extra` adds top-level members (materials, textures, images, samplers).
pub fn square_doc(half: f32, eye: f32, yfov: f32, extra: &str) -> String {
    let pos = [[-half, half, 0.0f32], [half, half, 0.0], [half, -half, 0.0], [-half, -half, 0.0]];
    let uv = [[0.0f32, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    let idx: [u16; 6] = [0, 3, 2, 0, 2, 1];
    let mut bytes: Vec<u8> = pos.iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
    bytes.extend(uv.iter().flatten().flat_map(|c| c.to_le_bytes()));
    bytes.extend(idx.iter().flat_map(|i| i.to_le_bytes()));
    format!(
        r#"{{"asset":{{"version":"2.0"}},
          "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1}},"indices":2,"material":0}}]}}],
          "cameras":[{{"type":"perspective","perspective":{{"yfov":{yfov},"aspectRatio":1.0,"znear":0.01}}}}],
          "nodes":[{{"mesh":0}},{{"camera":0,"translation":[0,0,{eye}]}}],"scenes":[{{"nodes":[0,1]}}],
          "buffers":[{{"byteLength":{len},"uri":"data:application/octet-stream;base64,{uri}"}}],
          "bufferViews":[{{"buffer":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":32}},{{"buffer":0,"byteOffset":80,"byteLength":12}}],
          "accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[{lo},{lo},0],"max":[{half},{half},0]}},
                       {{"bufferView":1,"componentType":5126,"count":4,"type":"VEC2"}},
                       {{"bufferView":2,"componentType":5123,"count":6,"type":"SCALAR"}}],
          {extra}}}"#,
        lo = -half,
        len = bytes.len(),
        uri = b64(&bytes)
    )
}

/// Members for [`square_doc`]: `materials` (JSON objects separated by commas; the square
/// uses the first), texture 0 being the image `png` through a nearest-filtering sampler.
pub fn textured(materials: &str, png: &str) -> String {
    format!(
        r#""materials":[{materials}],
           "textures":[{{"source":0,"sampler":0}}],
           "samplers":[{{"magFilter":9728,"minFilter":9728}}],
           "images":[{{"uri":"{png}"}}]"#
    )
}
