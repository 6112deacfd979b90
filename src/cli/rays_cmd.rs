//! `wavepath rays dump` and `wavepath rays trace`: the peers' benchmark protocol
//! (../shared/peers/README.md), so wavepath runs in their harness as one more peer.
use super::args::{DumpArgs, TraceArgs};
use anyhow::{Result, bail};
use std::time::Instant;
use wavepath::LoadOptions;
use wavepath::{Bvh, BvhBuild, BvhOptions, TraceCounters};
use wavepath::{diffuse_rays, primary_rays};
use wavepath_apps::rayfile::file::{HitRecord, read_rays, write_hits, write_rays};
use wavepath_apps::rayfile::trace_all;

pub fn run_dump(args: &DumpArgs) -> Result<()> {
    let (w, h) = match args.resolution.as_deref() {
        None => (800, 600),
        Some([w, h]) if *w > 0 && *h > 0 => (*w as usize, *h as usize),
        Some(_) => bail!("{}: -r needs a width and a height above 0", args.scene.display()),
    };
    let mut scene = super::load_scene(&args.scene, &LoadOptions::default())?;
    if let Some(c) = &args.camera_file {
        scene.camera = wavepath::read_camera_file(c)?;
    }
    let primary = primary_rays(&scene, w, h);
    let rays = match args.kind.as_str() {
        "primary" => primary,
        _ => {
            let bvh = Bvh::build(&scene);
            diffuse_rays(&scene, &bvh, &primary, args.seed)
        }
    };
    write_rays(&args.out, &rays)?;
    eprintln!("{}: wrote {} {} rays", args.out.display(), rays.len(), args.kind);
    Ok(())
}

pub fn run_trace(args: &TraceArgs) -> Result<()> {
    let threads = args.threads.or(args.threads_pos).unwrap_or(1).max(1);
    let reps = args.reps.or(args.reps_pos).unwrap_or(5).max(1);
    let rays = read_rays(&args.rays)?;
    let scene = super::with_spinner("loading", || super::load_scene(&args.mesh, &LoadOptions::default()))?;
    super::check_build_memory(&scene, args.bvh_leaves, None)?;
    let bvh = super::with_spinner("building the BVH", || {
        Bvh::build_with(&scene, BvhOptions { build: args.bvh_build, leaves: args.bvh_leaves })
    })
    .with_isa(args.isa);
    let info = bvh.info();
    let mut hits = vec![HitRecord::MISS; rays.len()];
    for _ in 0..args.warmup {
        trace_all(&bvh, &rays, &mut hits, threads);
    }
    let mut times = Vec::with_capacity(reps);
    let mut counters = TraceCounters::default();
    for _ in 0..reps {
        hits.fill(HitRecord::MISS);
        let t0 = Instant::now();
        counters = trace_all(&bvh, &rays, &mut hits, threads);
        times.push(t0.elapsed().as_secs_f64());
    }
    let best = times.iter().copied().fold(f64::INFINITY, f64::min);
    let mean = times.iter().sum::<f64>() / times.len() as f64;
    let (mut nhits, mut checksum) = (0u64, 0f64);
    for h in &hits {
        if h.prim != u32::MAX {
            nhits += 1;
            checksum += h.t as f64;
        }
    }
    if let Some(path) = &args.hits {
        write_hits(path, &hits)?;
    }
    let per_ray = |x: u64| x as f64 / counters.rays.max(1) as f64;
    let tree = match args.bvh_build {
        BvhBuild::Sah => "binned SAH, 16 bins x 3 axes, sets of 128k and more binned from a sample of 16k",
        BvhBuild::Fast => "Morton order (LBVH), sets of 16 and fewer cut into leaves of four in curve order",
    };
    let notes = format!(
        "wavepath bvh8 ({tree}, SoA child boxes; leaves <= 4 in SoA blocks: SSE filter, then the scalar watertight test); \
         isa={}; leaves={}; nodes={} depth={} sah_cost={:.2}; {:.1} nodes and {:.1} prim tests per ray",
        bvh.isa().name(),
        bvh.layout(),
        info.nodes,
        info.depth,
        info.sah_cost,
        per_ray(counters.nodes),
        per_ray(counters.prim_tests)
    );
    let line = serde_json::json!({
        "peer": "wavepath",
        "variant": args.variant,
        "build_s": info.build_s,
        "tris": scene.mesh.triangle_count(),
        "mesh_bytes": scene.mesh.bytes(),
        "node_bytes": info.node_bytes,
        "leaf_bytes": info.leaf_bytes,
        "leaves": info.leaves,
        "rays": rays.len(),
        "threads": threads,
        "reps": reps,
        "seconds": best,
        "seconds_mean": mean,
        "mrays_per_s": rays.len() as f64 / best / 1e6,
        "hits": nhits,
        "checksum": checksum,
        "notes": notes,
    });
    println!("{line}");
    Ok(())
}
