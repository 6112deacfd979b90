//! BVH build and closest-hit / any-hit traversal of primary and diffuse rays, on the dragon
//! and Lucy from WAVEPATH_SCENES (a generated bumpy sphere when that folder is absent).
use criterion::{Criterion, criterion_group, criterion_main};
use glam::Vec3;
use std::hint::black_box;
use std::path::PathBuf;
use std::time::Duration;
use wavepath::Ray;
use wavepath::{Bvh, Intersector, TraceCounters};
use wavepath::{Mesh, Scene};
use wavepath::{diffuse_rays, primary_rays};

fn scenes() -> Vec<(String, Scene)> {
    let dir =
        std::env::var_os("WAVEPATH_SCENES").map(PathBuf::from).unwrap_or_else(|| PathBuf::from("../shared/scenes"));
    let mut out = Vec::new();
    for name in ["dragon_100k", "lucy_100k"] {
        let p = dir.join("meshes").join(format!("{name}.obj"));
        if let Ok(s) = wavepath::load(&p, &Default::default()) {
            out.push((name.to_string(), s));
        }
    }
    if out.is_empty() {
        out.push(("uv_sphere_100k".to_string(), generated()));
    }
    out
}

/// A UV sphere with a wavy radius (about 100k triangles), framed by the default camera.
fn generated() -> Scene {
    let (nu, nv) = (317usize, 158usize);
    let mut positions = Vec::new();
    for j in 0..=nv {
        let th = std::f32::consts::PI * j as f32 / nv as f32;
        for i in 0..nu {
            let ph = std::f32::consts::TAU * i as f32 / nu as f32;
            let r = 1.0 + 0.05 * (7.0 * ph).sin() * (5.0 * th).cos();
            positions.push(r * Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()));
        }
    }
    let mut triangles = Vec::new();
    for j in 0..nv as u32 {
        for i in 0..nu as u32 {
            let (a, b) = (j * nu as u32 + i, j * nu as u32 + (i + 1) % nu as u32);
            let (c, d) = (a + nu as u32, b + nu as u32);
            triangles.push([a, c, b]);
            triangles.push([b, c, d]);
        }
    }
    let material_ids = vec![0; triangles.len()];
    let mut s = wavepath::default_scene();
    s.mesh = Mesh { positions, triangles, material_ids: material_ids.into(), ..Mesh::default() };
    s.spheres.clear();
    s.camera = wavepath::Camera::look_at(Vec3::new(0.0, 0.5, 3.5), Vec3::ZERO, Vec3::Y, 45.0, 4.0 / 3.0);
    s
}

/// Rays per batch in the wave benches (the wavefront's wave size).
const WAVE: usize = 4096;

fn bench(c: &mut Criterion) {
    for (name, scene) in scenes() {
        let mut g = c.benchmark_group(format!("bvh/{name}"));
        g.sample_size(10).measurement_time(Duration::from_secs(3)).warm_up_time(Duration::from_secs(1));
        g.bench_function("build", |b| b.iter(|| black_box(Bvh::build(&scene))));
        let bvh = Bvh::build(&scene);
        let primary = primary_rays(&scene, 400, 300);
        let diffuse = diffuse_rays(&scene, &bvh, &primary, 1);
        for (set, rays) in [("primary", &primary), ("diffuse", &diffuse)] {
            let mut hits = vec![None; rays.len()];
            g.bench_function(format!("closest/{set}"), |b| {
                b.iter(|| {
                    let mut tc = TraceCounters::default();
                    bvh.closest_hits(rays, &mut hits, &mut tc);
                    black_box(&hits);
                })
            });
            g.bench_function(format!("any/{set}"), |b| {
                b.iter(|| {
                    let mut tc = TraceCounters::default();
                    black_box(rays.iter().filter(|r: &&Ray| bvh.any_hit(r, &mut tc)).count())
                })
            });
            // The wavefront's use: batches of one wave (4096 rays), in queue order.
            let mut occluded = vec![false; rays.len()];
            g.bench_function(format!("any_hits/{set}"), |b| {
                b.iter(|| {
                    let mut tc = TraceCounters::default();
                    for (r, o) in rays.chunks(WAVE).zip(occluded.chunks_mut(WAVE)) {
                        bvh.any_hits(r, o, &mut tc);
                    }
                    black_box(&occluded);
                })
            });
            g.bench_function(format!("closest_hits/{set}"), |b| {
                b.iter(|| {
                    let mut tc = TraceCounters::default();
                    for (r, h) in rays.chunks(WAVE).zip(hits.chunks_mut(WAVE)) {
                        bvh.closest_hits(r, h, &mut tc);
                    }
                    black_box(&hits);
                })
            });
        }
        g.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
