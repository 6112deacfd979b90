//! Tracing a ray file the way the peers' harness does (../shared/peers/README.md).
use super::file::HitRecord;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use wavepath::{Hit, Ray};
use wavepath::{Intersector, TraceCounters};

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
