//! The partition of a set around its chosen cut, on one thread or (large sets) several.
use super::bins::{BINS, Box3};
use super::sampled::Largest;
use super::{PrimRef, SPLIT_PAR_MIN};
use glam::{Vec3, Vec3A};

/// `refs.swap(i, k)` field by field: the compiler copies a whole 28-byte reference through a
/// stack slot with overlapping 16-byte moves, and reading back such a slot waits for both
/// stores to retire (the wait was 5% of the build).
#[inline(always)]
fn swap_refs(refs: &mut [PrimRef], i: usize, k: usize) {
    let (a, b) = (&refs[i], &refs[k]);
    let (alo, ahi, akey) = (a.lo, a.hi, a.key);
    let (blo, bhi, bkey) = (b.lo, b.hi, b.key);
    refs[i].lo = blo;
    refs[i].hi = bhi;
    refs[i].key = bkey;
    refs[k].lo = alo;
    refs[k].hi = ahi;
    refs[k].key = akey;
}

/// A side of a partition: the box of its primitives and the box of their centroids.
pub(super) type Sides = (Box3, Box3);

/// Where a set is split: below or above bin boundary `bin` on axis `ax` of the binning frame
/// (centroid lower corner `clo`, bins per unit `scale`).
#[derive(Clone, Copy)]
pub(super) struct Cut {
    pub(super) ax: usize,
    pub(super) bin: usize,
    pub(super) clo: Vec3,
    pub(super) scale: Vec3,
}

/// Moves the primitives whose centroid falls in a bin below the cut to the front (Hoare's
/// scheme: only misplaced pairs are swapped); returns how many they are and both sides'
/// [`Sides`]: the centroid boxes always, the primitives' boxes and [`Largest`] references when
/// `BOXES` (else empty: the bins of all the primitives already have them, and only a sampled
/// set needs its largest).
pub(super) fn partition<const BOXES: bool>(refs: &mut [PrimRef], cut: Cut) -> (usize, Sides, Sides, [Largest; 2]) {
    let Cut { ax, bin, clo, scale } = cut;
    // `bins_of(c)[ax] < bin` on the split's one axis, by one compare instead of a clamp and a
    // conversion of all three: the bin truncates `x = (c - clo) * scale` clamped to
    // [0, BINS - 1] (a NaN to 0), and for a whole `bin` in 1..BINS that is below `bin`
    // exactly when `x` is below `bin` or NaN (x below 0 or NaN: bin 0; x at BINS - 1 or
    // above: the last bin). A NaN does occur: an extent so small that `scale` is infinite.
    let (c0, s0, edge) = (clo[ax], scale[ax], bin as f32);
    debug_assert!((1..BINS).contains(&bin));
    let left = |c: Vec3A| {
        let x = (c[ax] - c0) * s0;
        x < edge || x.is_nan()
    };
    let (mut lc, mut rc) = (Box3::EMPTY, Box3::EMPTY);
    let (mut lb, mut rb) = (Box3::EMPTY, Box3::EMPTY);
    let (mut lbig, mut rbig) = (Largest::default(), Largest::default());
    let grow = |b: &mut Box3, big: &mut Largest, r: &PrimRef| {
        if BOXES {
            b.grow(r.lo.into(), r.hi.into());
            big.offer(r);
        }
    };
    let (mut i, mut j) = (0, refs.len());
    loop {
        // The centroids that stopped each scan are kept for after the swap: read back from
        // the references just swapped, they waited on the swap's stores.
        let mut cr = Vec3A::ZERO;
        while i < j {
            cr = refs[i].centroid_a();
            if !left(cr) {
                break;
            }
            lc.grow(cr, cr);
            grow(&mut lb, &mut lbig, &refs[i]);
            i += 1;
        }
        let mut cl = Vec3A::ZERO;
        while i < j {
            cl = refs[j - 1].centroid_a();
            if left(cl) {
                break;
            }
            rc.grow(cl, cl);
            grow(&mut rb, &mut rbig, &refs[j - 1]);
            j -= 1;
        }
        if i == j {
            return (i, (lb, lc), (rb, rc), [lbig, rbig]);
        }
        // refs[i] (centroid cr) belongs right and refs[j - 1] (centroid cl) left.
        grow(&mut rb, &mut rbig, &refs[i]);
        grow(&mut lb, &mut lbig, &refs[j - 1]);
        swap_refs(refs, i, j - 1);
        lc.grow(cl, cl);
        rc.grow(cr, cr);
        i += 1;
        j -= 1;
    }
}

/// [`partition`] of halves in parallel, then the misplaced middle swapped into place: the
/// shorter of the first half's right part and the second half's left part trades places
/// with the far end of the other (the order within a side does not matter). The sides are
/// the same sets as one pass would give.
pub(super) fn partition_par<const BOXES: bool>(refs: &mut [PrimRef], cut: Cut) -> (usize, Sides, Sides, [Largest; 2]) {
    let n = refs.len();
    if n < SPLIT_PAR_MIN {
        return partition::<BOXES>(refs, cut);
    }
    let half = n / 2;
    let (a, b) = refs.split_at_mut(half);
    let ((ma, la, ra, [lbig, rbig]), (mb, lb, rb, [lbig_b, rbig_b])) =
        rayon::join(|| partition_par::<BOXES>(a, cut), || partition_par::<BOXES>(b, cut));
    // refs: [left of a: ma | right of a: half - ma | left of b: mb | right of b].
    let moved = (half - ma).min(mb);
    let (a, b) = refs.split_at_mut(half);
    if half - ma <= mb {
        a[ma..].swap_with_slice(&mut b[mb - moved..mb]);
    } else {
        a[ma..ma + moved].swap_with_slice(&mut b[..mb]);
    }
    let join = |a: Sides, b: Sides| (a.0.union(b.0), a.1.union(b.1));
    (ma + mb, join(la, lb), join(ra, rb), [lbig.merge(lbig_b), rbig.merge(rbig_b)])
}
