//! The sampled split of a large set: bins of a sample of its references, beside its largest
//! ones.
use super::{PrimRef, SPLIT_PAR_MIN};

/// Sets of at least this many primitives choose their split from the bins of a sample of
/// [`SAMPLE`] of them, not of all: the top levels of a large mesh bin a sixteenth of their
/// references or fewer, for the same SAH cost to a tenth of a percent (docs/decisions.md,
/// "Build"). Smaller sets bin all: a sample misses the few large triangles of a scene's
/// walls, and at 16k the top split of a dragon in a Cornell box changed enough to cost 2.5%
/// more nodes per ray (or 0.6% fewer at 64k: the top split is sensitive either way), so
/// scenes of up to 128k primitives keep the trees of full binning. Larger ones bin their
/// [`Largest`] references beside the sample.
pub(super) const SAMPLED_MIN: usize = 1 << 17;
/// References a sampled split bins.
pub(super) const SAMPLE: usize = 1 << 14;
const _: () = assert!(SAMPLED_MIN >= 2 * SAMPLE && SAMPLE.is_multiple_of(2));

/// Most references a set keeps as its largest (see [`Largest`]).
pub(super) const LARGEST: usize = 32;

/// The largest references of a set by box area, up to [`LARGEST`]: a sampled split (see
/// [`SAMPLED_MIN`]) bins them beside its sample. A sample misses a scene's few large
/// primitives (the walls of a room around a scanned statue), and their boxes decide where a
/// good split is: without them the Cornell box around the 25.6M-triangle Lucy took 8.5 nodes
/// per ray instead of 6.0 (full binning: 5.9). Even a few of the largest do it: there the
/// walls are 3,072 triangles. The partition of a sampled set keeps each side's largest, so no
/// pass but the root's looks for them.
#[derive(Clone, Debug)]
pub(super) struct Largest {
    /// (half the box's area, reference), in no order.
    pub(super) refs: Vec<(f32, PrimRef)>,
    /// The smallest area kept once full (a reference must beat it), else -inf.
    pub(super) floor: f32,
}

impl Largest {
    /// The largest references of `refs`, over chunks in parallel.
    pub(super) fn of_par(refs: &[PrimRef]) -> Largest {
        use rayon::prelude::*;
        refs.par_chunks(SPLIT_PAR_MIN)
            .map(|c| {
                let mut l = Largest::default();
                c.iter().for_each(|r| l.offer(r));
                l
            })
            .reduce(Largest::default, Largest::merge)
    }

    #[inline(always)]
    pub(super) fn offer(&mut self, r: &PrimRef) {
        let d = r.hi - r.lo;
        let key = d.x * d.y + d.y * d.z + d.z * d.x;
        // A NaN area compares false: never kept.
        if key > self.floor {
            self.insert(key, r);
        }
    }

    #[cold]
    pub(super) fn insert(&mut self, key: f32, r: &PrimRef) {
        if self.refs.len() < LARGEST {
            self.refs.push((key, *r));
        } else if let Some(min) = self.refs.iter_mut().min_by(|a, b| a.0.total_cmp(&b.0)) {
            *min = (key, *r);
        }
        if self.refs.len() == LARGEST {
            self.floor = self.refs.iter().map(|e| e.0).fold(f32::INFINITY, f32::min);
        }
    }

    pub(super) fn merge(mut self, o: Largest) -> Largest {
        for (key, r) in &o.refs {
            if *key > self.floor {
                self.insert(*key, r);
            }
        }
        self
    }
}

impl Default for Largest {
    fn default() -> Largest {
        Largest { refs: Vec::new(), floor: f32::NEG_INFINITY }
    }
}
