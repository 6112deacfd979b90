//! Closest hits of a batch's rays three in flight at once: in a tree beyond the caches a
//! ray's step waits on a node load from memory that the other rays' steps overlap, where one
//! ray alone leaves the core idle on each. Each ray takes the steps it would take alone, so
//! its hit and counts are the same.
use super::closest::Flight;
use super::{Stack, Walker};
use crate::accel::TraceCounters;
use crate::accel::bvh::simd::{BoxRay, PACKET, PacketShear, PacketTest};
use crate::geometry::{Hit, Ray};

impl<K: PacketTest, const N: usize, X: Copy + Default> Walker<'_, K, [&mut Stack<N, X>; 3]> {
    /// Closest hits of the rays `rays[i]` (box-test values `prep[i]`, leaf-test set-up lane
    /// `i % 8` of `shears[i / 8]`) for each `i` of `which`, into `hits[i]`, one stack per ray
    /// in flight.
    #[inline(always)]
    pub fn interleaved(
        &mut self,
        rays: &[Ray],
        prep: &[BoxRay],
        shears: &[PacketShear],
        which: &[u8],
        hits: &mut [Option<Hit>],
    ) {
        let t = self.t;
        debug_assert!(Stack::<N, X>::holds(t.bvh.stack_need));
        let [sa, sb, sc] = &mut self.stack;
        let counters = &mut *self.counters;
        let mut pending = Pending { rays, prep, shears, which: which.iter() };
        let mut a = pending.take(hits, counters);
        let mut b = pending.take(hits, counters);
        let mut c = pending.take(hits, counters);
        while a.is_some() || b.is_some() || c.is_some() {
            advance(&mut a, &mut Walker { t, stack: &mut **sa, counters: &mut *counters }, &mut pending, hits);
            advance(&mut b, &mut Walker { t, stack: &mut **sb, counters: &mut *counters }, &mut pending, hits);
            advance(&mut c, &mut Walker { t, stack: &mut **sc, counters: &mut *counters }, &mut pending, hits);
        }
    }
}

/// The rays of a batch not yet in flight.
struct Pending<'r, 'w> {
    rays: &'r [Ray],
    prep: &'r [BoxRay],
    shears: &'r [PacketShear],
    which: std::slice::Iter<'w, u8>,
}

impl<'r> Pending<'r, '_> {
    /// The next live ray (dead ones are misses without a traversal).
    #[inline(always)]
    fn take(&mut self, hits: &mut [Option<Hit>], counters: &mut TraceCounters) -> Option<Flight<'r>> {
        for &i in self.which.by_ref() {
            let i = i as usize;
            counters.rays += 1;
            if self.prep[i].live {
                return Some(Flight::new(&self.rays[i], &self.prep[i], &self.shears[i / PACKET], i % PACKET, i));
            }
            hits[i] = None;
        }
        None
    }
}

/// One step of a ray in flight (on its own stack, in `w`); a ray done gives its place to the
/// next.
#[inline(always)]
fn advance<'r, K: PacketTest, const N: usize, X: Copy + Default>(
    flight: &mut Option<Flight<'r>>,
    w: &mut Walker<'_, K, &mut Stack<N, X>>,
    pending: &mut Pending<'r, '_>,
    hits: &mut [Option<Hit>],
) {
    if let Some(f) = flight
        && f.step_any_form(w)
    {
        w.counters.nodes += f.visited;
        hits[f.slot] = f.best.hit();
        *flight = pending.take(hits, w.counters);
    }
}
