//! Which loop each ray of a batch takes: set up in groups (most primary rays miss the tree
//! and end there), runs of coherent rays as packets, the others one by one or, in trees
//! beyond the caches, three in flight.
use super::coherent::{COHERENT, MIN_RAYS, Rays, packet_len};
use super::{BigStack, Walker};
use crate::accel::TraceCounters;
use crate::accel::bvh::Bvh;
use crate::accel::bvh::simd::{BoxRay, Frustum, PACKET, PacketShear, PacketTest, WithKernels};
use crate::geometry::{Hit, Ray};

/// Rays set up at a time ahead of their traversal in a batch (at most 32: one bit each
/// in the mask of rays that may enter the tree).
const SETUP_GROUP: usize = 32;
const _: () = assert!(SETUP_GROUP <= 32);

/// [`crate::accel::Intersector::closest_hits`] of a non-empty tree.
///
/// One dispatch and one stack for the whole batch, so the loop runs inside the AVX2 context
/// and no stack is cleared per ray. The loop is this value's `run`, `#[inline(always)]`, on
/// purpose: a helper taking a closure compiled it outside the AVX2 context and halved
/// traversal speed (measured: CBspheres_lambertian 1.2 s -> 2.6 s, one thread). Every
/// closure given to `with_avx2` is `#[inline(always)]` for the same reason: a larger body
/// (set-up of the shear added to this loop) was left out of line by the inliner, outside the
/// AVX2 context, and ran six times slower.
pub struct ClosestBatch<'a> {
    pub bvh: &'a Bvh,
    pub rays: &'a [Ray],
    pub hits: &'a mut [Option<Hit>],
    pub counters: &'a mut TraceCounters,
}

impl WithKernels for ClosestBatch<'_> {
    type Output = ();

    #[inline(always)]
    fn run<K: PacketTest>(self, isa: K) {
        let ClosestBatch { bvh, rays, hits, counters } = self;
        // One stack for every loop (a packet's rays per entry, unused by single rays): a
        // stack of its own for the packets cost each batch its allocation.
        let mut stack = BigStack::<Rays>::boxed();
        // The stacks of the second and third ray in flight (trees beyond the caches only).
        let mut more: Option<Box<[BigStack<Rays>; 2]>> = None;
        // Filled per group (not cleared: every entry read was just written).
        let mut prep = [BoxRay::DEAD; SETUP_GROUP];
        // Per group, eight rays at a time: which may enter the tree at all (most primary
        // rays miss it) and the set-up (three divisions per ray) of the eights that have
        // one; the others are misses without further work.
        let mut slot = [0u8; SETUP_GROUP];
        let mut singles = [0u8; SETUP_GROUP];
        // The leaf-test set-up of each eight of the group with a ray traced alone, made where
        // the first such ray comes (a packet of coherent rays makes its own: made for every
        // eight, it cost camera rays 7% more instructions; made in a pass of its own after
        // the runs are known, 2% more than here).
        let mut shears = [PacketShear::EMPTY; SETUP_GROUP / PACKET];
        for (rs, hs) in rays.chunks(SETUP_GROUP).zip(hits.chunks_mut(SETUP_GROUP)) {
            let mut todo = isa.set_up(bvh.root.as_ref(), rs, &mut prep[..rs.len()]);
            let mut n = 0;
            while todo != 0 {
                slot[n] = todo.trailing_zeros() as u8;
                todo &= todo - 1;
                n += 1;
            }
            counters.rays += (rs.len() - n) as u64;
            hs.fill(None);
            let mut made = 0u32;
            // Runs of coherent rays (camera rays) as packets, the others one by one or, in
            // trees beyond the caches, three at a time.
            // After two rays in a row that start no packet, the rest of the group goes alone
            // without looking (extension rays: the look cost each ~20 instructions). Whether a
            // ray goes in a packet or alone never changes its hit, only what it costs.
            let mut k = 0;
            let mut m = 0;
            let mut alone = 0;
            while k < n {
                let (len, packet) = if alone < 2 {
                    let len = packet_len(rs, &slot[k..n], &prep);
                    (len, len >= MIN_RAYS)
                } else {
                    (n - k, false)
                };
                alone = if packet { 0 } else { alone + 1 };
                if packet {
                    let f = Frustum::of(slot[k..k + len].iter().map(|&i| &prep[i as usize]));
                    let mut w = Walker::new(bvh, isa, &mut *stack, &mut *counters);
                    let first = slot[k] as usize;
                    if slot[k + len - 1] as usize == first + len - 1 {
                        // Rays next to each other (camera rays): traced where they are.
                        w.coherent(&rs[first..first + len], &f, &mut hs[first..first + len]);
                    } else {
                        let mut rays = [rs[first]; COHERENT];
                        for (r, &i) in rays.iter_mut().zip(&slot[k..k + len]) {
                            *r = rs[i as usize];
                        }
                        let mut out = [None; COHERENT];
                        w.coherent(&rays[..len], &f, &mut out[..len]);
                        for (&i, h) in slot[k..k + len].iter().zip(out) {
                            hs[i as usize] = h;
                        }
                    }
                } else if bvh.cached {
                    let mut w = Walker::new(bvh, isa, &mut *stack, &mut *counters);
                    for &i in &slot[k..k + len] {
                        let i = i as usize;
                        shear_of(isa, rs, i, &mut shears, &mut made);
                        hs[i] = w.closest(&rs[i], &prep[i], &shears[i / PACKET], i % PACKET);
                    }
                } else {
                    for &i in &slot[k..k + len] {
                        shear_of(isa, rs, i as usize, &mut shears, &mut made);
                    }
                    singles[m..m + len].copy_from_slice(&slot[k..k + len]);
                    m += len;
                }
                k += len;
            }
            if m > 0 {
                let more = more.get_or_insert_with(|| Box::new([BigStack::new(), BigStack::new()]));
                let [b, c] = &mut **more;
                Walker::new(bvh, isa, [&mut *stack, b, c], &mut *counters).interleaved(
                    rs,
                    &prep,
                    &shears,
                    &singles[..m],
                    hs,
                );
            }
        }
    }
}

/// Makes the leaf-test set-up of the eight of `rays` that holds ray `i`, unless `made` says it
/// is there (bit `g`: eight `g`).
#[inline(always)]
fn shear_of<K: PacketTest>(isa: K, rays: &[Ray], i: usize, shears: &mut [PacketShear], made: &mut u32) {
    let g = i / PACKET;
    if *made >> g & 1 == 0 {
        let from = g * PACKET;
        shears[g] = isa.packet_shear(&rays[from..rays.len().min(from + PACKET)]);
        *made |= 1 << g;
    }
}
