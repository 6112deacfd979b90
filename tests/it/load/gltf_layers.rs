//! glTF material extensions through the command line: `wavepath info --json` reports each
//! extension's values as the file writes them (and the specification's defaults where it
//! writes none), and names only the extensions it still ignores in its one warning.

use crate::common::{run_wavepath, temp_dir};
use serde_json::Value;

/// One triangle (with uvs) whose primitive uses material 0, the buffer in a `.bin` beside.
fn gltf(dir: &std::path::Path, extra: &str) -> std::path::PathBuf {
    let pos = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let bytes: Vec<u8> = pos.iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
    std::fs::write(dir.join("t.bin"), &bytes).unwrap();
    let doc = format!(
        r#"{{"asset":{{"version":"2.0"}},
          "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"material":0}}]}}],
          "nodes":[{{"mesh":0}}],"scenes":[{{"nodes":[0]}}],
          "buffers":[{{"byteLength":36,"uri":"t.bin"}}],
          "bufferViews":[{{"buffer":0,"byteLength":36}}],
          "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}],
          {extra}}}"#
    );
    let path = dir.join("t.gltf");
    std::fs::write(&path, doc).unwrap();
    path
}

#[test]
fn info_reports_each_material_extension() {
    let dir = temp_dir("it-gltf-layers");
    let path = gltf(
        &dir,
        r#""extensionsUsed":["KHR_materials_transmission","KHR_materials_ior","KHR_materials_volume","KHR_materials_specular","KHR_materials_clearcoat","KHR_materials_sheen","KHR_materials_iridescence"],
           "materials":[
             {"extensions":{
               "KHR_materials_transmission":{"transmissionFactor":0.5},
               "KHR_materials_ior":{"ior":1.7},
               "KHR_materials_volume":{"thicknessFactor":0.25,"attenuationDistance":2.0,"attenuationColor":[0.5,0.25,1.0]},
               "KHR_materials_specular":{"specularFactor":0.75,"specularColorFactor":[1.0,0.5,0.5]},
               "KHR_materials_clearcoat":{"clearcoatFactor":0.5,"clearcoatRoughnessFactor":0.25},
               "KHR_materials_sheen":{"sheenColorFactor":[0.25,0.5,0.75],"sheenRoughnessFactor":0.5},
               "KHR_materials_iridescence":{"iridescenceFactor":1}}},
             {"extensions":{"KHR_materials_clearcoat":{}}}
           ]"#,
    );
    let o = run_wavepath(["info", "--json", path.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let info: Value = serde_json::from_slice(&o.stdout).unwrap();
    let l = &info["materials"][0]["layers"];
    let num = |k: &str| l[k].as_f64().unwrap_or_else(|| panic!("{k}: {l}"));
    let col = |k: &str| -> Vec<f64> { l[k].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect() };
    for (k, v) in [
        ("transmission", 0.5),
        ("ior", 1.7),
        ("thickness", 0.25),
        ("attenuation_distance", 2.0),
        ("specular", 0.75),
        ("clearcoat", 0.5),
        ("clearcoat_roughness", 0.25),
        ("sheen_roughness", 0.5),
    ] {
        assert!((num(k) - v).abs() < 1e-6, "{k}: {} vs {v}", num(k));
    }
    assert_eq!(col("attenuation_color"), [0.5, 0.25, 1.0]);
    assert_eq!(col("specular_color"), [1.0, 0.5, 0.5]);
    assert_eq!(col("sheen_color"), [0.25, 0.5, 0.75]);
    // An empty clearcoat: factor 0 (no coat), the core model's ior 1.5.
    let d = &info["materials"][1]["layers"];
    assert_eq!(
        (d["clearcoat"].as_f64(), d["ior"].as_f64(), d["transmission"].as_f64()),
        (Some(0.0), Some(1.5), Some(0.0))
    );
    // The one warning names only the extension still ignored.
    let err = String::from_utf8_lossy(&o.stderr);
    let warnings: Vec<&str> = err.lines().filter(|l| l.contains("not rendered")).collect();
    assert_eq!(warnings.len(), 1, "{err}");
    assert!(warnings[0].contains("KHR_materials_iridescence") && !warnings[0].contains("clearcoat"), "{err}");
}
