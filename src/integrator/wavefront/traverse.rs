//! Stage 2: the closest hit of every ray in the path queue.

use super::queues::PathQueue;
use crate::accel::{Intersector, TraceCounters};
use crate::geometry::Hit;

/// Traces the whole path queue through the intersector's batch interface.
pub fn traverse(accel: &dyn Intersector, paths: &PathQueue, hits: &mut Vec<Option<Hit>>, c: &mut TraceCounters) {
    // Not cleared first: the intersector writes every entry.
    hits.resize(paths.len(), None);
    accel.closest_hits(&paths.ray, hits, c);
}
