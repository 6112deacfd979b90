//! Renderer benchmark (`cargo bench --bench render`): the Cornell box rendered with only the
//! effects it needs against every effect forced on (`--all-effects`), and the wavefront
//! integrator against the recursive reference. Runs alternate, best of `REPS`, on a pool of
//! 2 threads; prints one line per case. Scene: `$WAVEPATH_SCENES/cs184/sky/CBspheres_lambertian.dae`
//! when present, else the embedded default Cornell box.

use std::time::Instant;
use wavepath::Intersector;
use wavepath::Scene;
use wavepath::{IntegratorKind, Settings, Shading};

const REPS: usize = 3;

fn scene() -> Scene {
    let dir = std::env::var_os("WAVEPATH_SCENES")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/scenes"));
    let path = dir.join("cs184/sky/CBspheres_lambertian.dae");
    let mut scene = if path.is_file() {
        wavepath::load(&path, &Default::default()).expect("scene loads")
    } else {
        wavepath::default_scene()
    };
    scene.camera.fit_aspect(4.0 / 3.0);
    scene
}

/// Seconds and Mrays/s of the fastest of `REPS` renders of each settings, alternating.
fn best(scene: &Scene, bvh: &dyn Intersector, cases: &[&Settings]) -> Vec<(f64, f64)> {
    let mut out = vec![(f64::INFINITY, 0.0); cases.len()];
    for _ in 0..REPS {
        for (i, s) in cases.iter().enumerate() {
            let start = Instant::now();
            let (_, st) = wavepath::render(scene, bvh, s).expect("renders");
            let secs = start.elapsed().as_secs_f64();
            if secs < out[i].0 {
                out[i] = (secs, st.total_rays() as f64 / secs / 1e6);
            }
        }
    }
    out
}

fn main() {
    let scene = scene();
    let (bvh, _) = wavepath::build_accel(&scene, &Default::default());
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().expect("thread pool");
    pool.install(|| {
        let mut base = Settings::default();
        base.image.width = 240;
        base.image.height = 180;
        base.sampling.spp = 16;
        base.sampling.light_samples = 4;
        base.execution.threads = 2;
        for (name, depth, shading) in [("direct -m 1", 1, Shading::Direct), ("global -m 5", 5, Shading::Global)] {
            let mut needed = base.clone();
            needed.paths.max_depth = depth;
            needed.paths.shading = shading;
            let mut forced = needed.clone();
            forced.execution.all_effects = true;
            let mut recursive = needed.clone();
            recursive.execution.integrator = IntegratorKind::Recursive;
            let r = best(&scene, bvh.as_ref(), &[&needed, &forced, &recursive]);
            println!(
                "{} {name} 240x180 -s 16 -l 4, 2 threads: needed {:.3} s ({:.2} Mrays/s), all effects {:.3} s \
                 ({:.2} Mrays/s), forced/needed {:.3}; recursive {:.3} s, recursive/wavefront {:.3}",
                scene.name,
                r[0].0,
                r[0].1,
                r[1].0,
                r[1].1,
                r[1].0 / r[0].0,
                r[2].0,
                r[2].0 / r[0].0
            );
        }
    });
}
