//! `wavepath info SCENE [--json]`.

use super::args::InfoArgs;
use anyhow::Result;
use serde_json::json;
use std::time::Instant;
use wavepath::Effects;
use wavepath::LoadOptions;
use wavepath::Settings;
use wavepath::{Environment, Scene};

pub fn run(a: &InfoArgs) -> Result<()> {
    let t0 = Instant::now();
    let mut scene = super::load_scene(&a.scene, &LoadOptions { camera: a.camera, ..LoadOptions::default() })?;
    if let Some(e) = &a.envmap {
        scene.set_environment(Environment::Map(std::sync::Arc::new(wavepath::EnvMap::load(e)?)));
    }
    let load_s = t0.elapsed().as_secs_f64();
    // The settings a render of this file starts from (its dialect's defaults), as the
    // command line uses them.
    let settings = Settings::for_scene(&scene);
    let effects = Effects::of(&scene, &settings);
    let text = if a.json {
        format!("{}\n", summary_json(&scene, &settings, &effects, load_s))
    } else {
        text(&scene, &settings, &effects, load_s)
    };
    // A closed pipe (`wavepath info ... | head`) is not an error worth a panic.
    use std::io::Write;
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(()),
    }
}

fn v3(v: glam::Vec3) -> [f32; 3] {
    v.to_array()
}

/// What arrives from outside the scene, in words.
fn environment(env: &Environment) -> String {
    match env {
        Environment::None => "none".into(),
        Environment::Constant(c) => format!("constant {c}"),
        Environment::Map(m) => format!("map {} ({}x{})", m.path.display(), m.width, m.height),
    }
}

pub fn summary_json(scene: &Scene, settings: &Settings, effects: &Effects, load_s: f64) -> serde_json::Value {
    // The camera as a render with these settings sees it.
    let c = &settings.image.camera(&scene.camera);
    let lights: Vec<_> = scene.lights.iter().map(|l| json!({ "kind": l.kind(), "detail": format!("{l:?}") })).collect();
    let materials: Vec<_> = scene
        .materials
        .iter()
        .map(|m| {
            json!({
                "name": m.name,
                "bsdf": m.bsdf.kind(),
                "emission": v3(m.emission),
                "detail": format!("{:?}", m.bsdf),
                "layers": m.layers.as_deref().map(|l| json!({
                    "transmission": l.transmission,
                    "ior": l.ior,
                    "thickness": l.thickness,
                    "attenuation_color": v3(l.attenuation_color),
                    "attenuation_distance": l.attenuation_distance,
                    "specular": l.specular,
                    "specular_color": v3(l.specular_color),
                    "clearcoat": l.clearcoat,
                    "clearcoat_roughness": l.clearcoat_roughness,
                    "sheen_color": v3(l.sheen_color),
                    "sheen_roughness": l.sheen_roughness,
                })),
                "relief": m.relief.as_ref().map(|r| format!("{:?}", r.relief)),
            })
        })
        .collect();
    json!({
        "scene": scene.name,
        "reader": scene.source.reader,
        "dialect": scene.source.dialect.name(),
        "defaults": {
            "sampler": settings.sampling.sampler.name(),
            "roulette": wavepath::roulette_json(&settings.paths.roulette),
        },
        "triangles": scene.mesh.triangle_count(),
        "vertices": scene.mesh.positions.len(),
        "has_normals": scene.mesh.normals.is_some(),
        "has_uvs": scene.mesh.uvs.is_some(),
        "spheres": scene.spheres.len(),
        "lights": lights,
        "materials": materials,
        "camera": {
            "position": v3(c.position),
            "view_direction": v3(-c.c2w.z_axis),
            "up": v3(c.c2w.y_axis),
            "hfov_deg": c.hfov_deg,
            "vfov_deg": c.vfov_deg,
            "nclip": c.nclip,
            "fclip": c.fclip,
        },
        "environment": environment(&scene.env),
        "bounds": scene.bounds().map(|(lo, hi)| json!({ "min": v3(lo), "max": v3(hi) })),
        "effects": effects.names(),
        "load_s": load_s,
    })
}

fn text(scene: &Scene, settings: &Settings, effects: &Effects, load_s: f64) -> String {
    use std::fmt::Write;
    let mut o = String::new();
    // The camera as a render with these settings sees it.
    let c = &settings.image.camera(&scene.camera);
    let _ = writeln!(o, "scene:      {}", scene.name);
    let _ = writeln!(o, "load time:  {load_s:.4} s");
    let _ = writeln!(o, "read by:    {} ({} dialect)", scene.source.reader, scene.source.dialect.name());
    let r = &settings.paths.roulette;
    let _ = writeln!(
        o,
        "defaults:   --sampler {} --roulette {} --rr-depth {}",
        settings.sampling.sampler.name(),
        r.kind.name(),
        r.start_depth
    );
    let _ = writeln!(o, "triangles:  {}", scene.mesh.triangle_count());
    let _ = writeln!(o, "vertices:   {}", scene.mesh.positions.len());
    let _ = writeln!(o, "spheres:    {}", scene.spheres.len());
    if let Some((lo, hi)) = scene.bounds() {
        let _ = writeln!(o, "bounds:     {lo:?} .. {hi:?}");
    }
    let _ = writeln!(
        o,
        "camera:     at {:?} looking {:?}, fov {:.3} x {:.3} deg at 800x600, clip [{}, {}]",
        c.position, -c.c2w.z_axis, c.hfov_deg, c.vfov_deg, c.nclip, c.fclip
    );
    let _ = writeln!(o, "lights:     {}", scene.lights.len());
    for l in &scene.lights {
        let _ = writeln!(o, "  {l:?}");
    }
    let _ = writeln!(o, "environment: {}", environment(&scene.env));
    let _ = writeln!(o, "materials:  {}", scene.materials.len());
    for m in &scene.materials {
        let _ = writeln!(o, "  {}: {:?}, emission {:?}", m.name, m.bsdf, m.emission);
        if let Some(r) = &m.relief {
            let _ = writeln!(o, "    relief map {:?} ({})", r.relief, r.texture.path.display());
        }
        if let Some(l) = &m.layers {
            let _ = writeln!(o, "    layers {l:?}");
        }
        let a = &m.alpha;
        if !a.is_opaque() {
            let map = a.map.as_ref().filter(|m| m.image.is_some());
            let map = map.map_or(String::new(), |m| format!(" x {}", m.path.display()));
            let _ = writeln!(o, "    alpha {:?} of {}{map}", a.mode, a.factor);
        }
    }
    let _ = writeln!(o, "effects (at the scene's default settings):");
    for e in &effects.on {
        let _ = writeln!(o, "  {} ({})", e.name, e.reason);
    }
    o
}
