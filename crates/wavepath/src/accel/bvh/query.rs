//! The [`Intersector`] queries of a [`Bvh`]: each dispatched once to the kernels of the
//! tree's instruction set, with the loop its rays take.
use super::Bvh;
use super::traverse::{AnyHit, AnyHits, ClosestBatch, ClosestHit, ShadowPackets};
use crate::accel::{Intersector, TraceCounters};
use crate::geometry::{Hit, Ray};

impl Intersector for Bvh {
    fn closest_hit(&self, ray: &Ray, counters: &mut TraceCounters) -> Option<Hit> {
        if self.nodes.is_empty() {
            counters.rays += 1;
            return None;
        }
        self.tokens.dispatch_cut(self.cutouts.as_deref(), ClosestHit { bvh: self, ray, counters })
    }

    fn any_hit(&self, ray: &Ray, counters: &mut TraceCounters) -> bool {
        if self.nodes.is_empty() {
            counters.rays += 1;
            return false;
        }
        self.tokens.dispatch_cut(self.cutouts.as_deref(), AnyHit { bvh: self, ray, counters })
    }

    fn name(&self) -> String {
        format!("bvh8 {}, {} build", self.isa.name(), self.info.method)
    }

    fn closest_hits(&self, rays: &[Ray], hits: &mut [Option<Hit>], counters: &mut TraceCounters) {
        if self.nodes.is_empty() {
            counters.rays += rays.len() as u64;
            hits.iter_mut().for_each(|h| *h = None);
            return;
        }
        self.tokens.dispatch_cut(self.cutouts.as_deref(), ClosestBatch { bvh: self, rays, hits, counters })
    }

    fn any_hits_packets(&self, rays: &[Ray], occluded: &mut [bool], counters: &mut TraceCounters) {
        if self.nodes.is_empty() {
            return self.any_hits(rays, occluded, counters);
        }
        self.tokens.dispatch_cut(self.cutouts.as_deref(), ShadowPackets { bvh: self, rays, occluded, counters })
    }

    fn any_hits(&self, rays: &[Ray], occluded: &mut [bool], counters: &mut TraceCounters) {
        if self.nodes.is_empty() {
            counters.rays += rays.len() as u64;
            occluded.iter_mut().for_each(|o| *o = false);
            return;
        }
        self.tokens.dispatch_cut(self.cutouts.as_deref(), AnyHits { bvh: self, rays, occluded, counters })
    }
}
