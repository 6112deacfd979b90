//! What materials become, through the binary: `wavepath info --json` on an OBJ whose library
//! uses each family of illumination models and the PBR keys, written here, reports each
//! material's model as the README's table says, and the load prints one warning naming the
//! keys it did not read.

use crate::common;
use serde_json::Value;

#[test]
fn info_reports_each_mtl_model_and_warns_of_keys_not_read() {
    let dir = common::temp_dir("mtl-models-info");
    let mtl = "newmtl matte\nKd 0.5\nillum 1\n\
               newmtl shiny\nKd 0.5\nKs 0.3\nNs 100\nillum 2\n\
               newmtl mirror\nKs 0.9\nillum 5\n\
               newmtl glass\nNi 1.5\nTf 0.9\nillum 7\n\
               newmtl pbr\nKd 0.5\nPr 0.4\nPm 1\naniso 0.5\nillum 2\n";
    std::fs::write(dir.join("m.mtl"), mtl).unwrap();
    let mut obj = String::from("mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n");
    for m in ["matte", "shiny", "mirror", "glass", "pbr"] {
        obj.push_str(&format!("usemtl {m}\nf 1 2 3 4\n"));
    }
    std::fs::write(dir.join("a.obj"), obj).unwrap();
    let out = common::run_wavepath(["info".as_ref(), "--json".as_ref(), dir.join("a.obj").as_os_str()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let info: Value = serde_json::from_slice(&out.stdout).unwrap();
    let kinds: Vec<(String, String)> = info["materials"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| (m["name"].as_str().unwrap().to_string(), m["bsdf"].as_str().unwrap().to_string()))
        .collect();
    let want = [
        ("matte", "diffuse"),
        ("shiny", "phong"),
        ("mirror", "mirror"),
        ("glass", "glass"),
        ("pbr", "metallic-roughness"),
    ];
    for (name, bsdf) in want {
        assert!(kinds.contains(&(name.to_string(), bsdf.to_string())), "{name}: {kinds:?}");
    }
    let stderr = String::from_utf8_lossy(&out.stderr);
    let warnings: Vec<&str> = stderr.lines().filter(|l| l.contains("keys not read")).collect();
    assert_eq!(warnings.len(), 1, "{stderr}");
    assert!(warnings[0].contains("m.mtl") && warnings[0].ends_with("keys not read: aniso"), "{}", warnings[0]);
}
