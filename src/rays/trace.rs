//! `wavepath rays trace`: the peers' benchmark protocol (../shared/peers/README.md).
use super::TraceArgs;
use super::file::{HitRecord, read_rays, write_hits};
use crate::accel::{Bvh, Intersector, TraceCounters};
use crate::geometry::{Hit, Ray};
use crate::load::{LoadOptions, load};
use anyhow::Result;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// Rays handed to a thread at a time (the peers' scheduler uses the same).
pub const CHUNK: usize = 1024;

/// Traces every ray once: chunks of [`CHUNK`] rays from an atomic counter; one thread runs
/// on the calling thread.
pub fn trace_all(accel: &dyn Intersector, rays: &[Ray], out: &mut [HitRecord], threads: usize) -> TraceCounters {
    let slots: Vec<Mutex<&mut [HitRecord]>> = out.chunks_mut(CHUNK).map(Mutex::new).collect();
    let next = AtomicUsize::new(0);
    let claim = || {
        let i = next.fetch_add(1, Ordering::Relaxed);
        // Each index is claimed once, so the lock is never contended.
        slots.get(i).map(|s| (i * CHUNK, s.lock().unwrap_or_else(|e| e.into_inner())))
    };
    let work = || {
        let mut c = TraceCounters::default();
        let mut buf: Vec<Option<Hit>> = vec![None; CHUNK];
        while let Some((start, mut dst)) = claim() {
            let rs = &rays[start..start + dst.len()];
            let hs = &mut buf[..rs.len()];
            accel.closest_hits(rs, hs, &mut c);
            for (d, h) in dst.iter_mut().zip(hs.iter()) {
                *d = HitRecord::from_hit(*h);
            }
        }
        c
    };
    if threads <= 1 {
        return work();
    }
    let mut total = TraceCounters::default();
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads).map(|_| s.spawn(work)).collect();
        for h in handles {
            if let Ok(c) = h.join() {
                total.add(&c);
            }
        }
    });
    total
}

pub fn trace(args: &TraceArgs) -> Result<()> {
    let threads = args.threads.or(args.threads_pos).unwrap_or(1).max(1);
    let reps = args.reps.or(args.reps_pos).unwrap_or(5).max(1);
    let rays = read_rays(&args.rays)?;
    let scene = load(&args.mesh, &LoadOptions::default())?;
    let bvh = Bvh::build(&scene).with_isa(args.isa);
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
    let notes = format!(
        "wavepath bvh8 (binned SAH, 16 bins x 3 axes, SoA child boxes; leaves <= 4 in SoA blocks: SSE filter, then the scalar watertight test); \
         isa={}; nodes={} depth={} sah_cost={:.2}; {:.1} nodes and {:.1} prim tests per ray",
        bvh.isa().name(),
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
