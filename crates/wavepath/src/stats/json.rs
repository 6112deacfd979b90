use super::RenderStats;
use crate::accel::BuildInfo;
use crate::effects::Effects;
use crate::scene::Scene;
use crate::settings::{Roulette, Settings};
use serde_json::{Value, json};

/// The `--stats` JSON object; the `json!` literal below is its schema.
pub fn to_json(scene: &Scene, s: &Settings, effects: &Effects, build: &BuildInfo, st: &RenderStats) -> Value {
    let (mean, min, max) = st.spp_summary();
    json!({
        "scene": scene.name,
        "triangles": scene.mesh.triangle_count(),
        "spheres": scene.spheres.len(),
        "mesh_bytes": scene.mesh.bytes(),
        "lights": scene.lights.len(),
        "width": s.image.width,
        "height": s.image.height,
        "spp": s.sampling.spp,
        "sampler": s.sampling.sampler.name(),
        "integrator": effects.integrator,
        "roulette": roulette_json(&s.paths.roulette),
        "dialect": scene.source.dialect.name(),
        "reader": scene.source.reader,
        "threads": if s.execution.threads == 0 { rayon::current_num_threads() } else { s.execution.threads },
        "effects": effects.names(),
        "effect_reasons": effects.on,
        "bvh": build,
        "rays": {
            "camera": st.camera_rays,
            "extension": st.extension_rays,
            "shadow": st.shadow_rays,
            "light": st.light_rays,
            "total": st.total_rays(),
        },
        "render_s": st.render_s,
        "mrays_per_s": st.mrays_per_s(),
        "intersection_tests_per_ray": st.tests_per_ray(),
        "nodes_visited_per_ray": st.nodes_per_ray(),
        "stages": st.stages,
        "ns_per_vertex": st.ns_per_vertex().map(|(camera, light)| json!({ "camera": camera, "light": light })),
        "samples_per_pixel": { "mean": mean, "min": min, "max": max },
        "invalid_samples": st.invalid_samples,
    })
}

/// The roulette a render used, as the stats and `wavepath info` report it.
pub fn roulette_json(r: &Roulette) -> Value {
    json!({ "kind": r.kind.name(), "continue_prob": r.continue_prob, "start_depth": r.start_depth })
}
