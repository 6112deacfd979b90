//! Stage 2: the closest hit of every ray in the path queue.

use super::queues::PathQueue;
use crate::accel::{Intersector, TraceCounters};

/// Traces the whole path queue through the intersector's batch interface.
pub fn traverse(accel: &dyn Intersector, paths: &mut PathQueue, c: &mut TraceCounters) {
    // `hit` is not cleared first: the intersector writes every entry.
    accel.closest_hits(&paths.ray, &mut paths.hit, c);
}
