//! The split of a set too small for bins: each primitive's bin boundary tried in turn.
use super::PrimRef;
use super::bins::{Box3, bins_of, blocks};
use glam::{Vec3, Vec3A};

/// Sets of fewer primitives choose their split without bins (see [`cheapest_of_few`]).
pub(super) const FEW: usize = 5;

/// [`Bins::cheapest`] for fewer than [`FEW`] primitives, with the same result. Each
/// primitive's bin, plus one, is a candidate position; its two sides' boxes are unions of
/// the primitives' (exact in any order, so the costs are the same numbers the bins give),
/// and among equal costs the first axis and then the lowest position wins, as in the
/// sweep. Every leaf is such a set (whether a block of large spread triangles is split is
/// decided by its best split), and clearing and sweeping 3 x 16 bins cost far more than
/// its few primitives: a tenth of the whole build.
#[inline]
pub(super) fn cheapest_of_few(refs: &[PrimRef], clo: Vec3, scale: Vec3) -> (f32, usize, usize) {
    let n = refs.len();
    debug_assert!(n < FEW);
    let (clo, scale) = (Vec3A::from(clo), Vec3A::from(scale));
    let (inf, ninf) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
    let (mut lo, mut hi, mut k) = ([inf; FEW], [ninf; FEW], [[0usize; 3]; FEW]);
    for (i, r) in refs.iter().enumerate() {
        (lo[i], hi[i]) = (r.lo.into(), r.hi.into());
        k[i] = bins_of(r.centroid_a(), clo, scale);
    }
    let mut best = (f32::INFINITY, 0usize, 0usize);
    for ax in 0..3 {
        for kp in &k[..n] {
            let at = kp[ax] + 1;
            // Branch-free: both sides' boxes as plain values (a `&mut` to one side was 4%
            // of the build slower).
            let (mut l, mut h, mut rl, mut rh, mut c) = (inf, ninf, inf, ninf, 0u32);
            for ((kq, &plo), &phi) in k[..n].iter().zip(&lo).zip(&hi) {
                if kq[ax] < at {
                    (l, h, c) = (l.min(plo), h.max(phi), c + 1);
                } else {
                    (rl, rh) = (rl.min(plo), rh.max(phi));
                }
            }
            let (left, right) = (Box3 { lo: l, hi: h }, Box3 { lo: rl, hi: rh });
            if c as usize == n {
                continue;
            }
            let cost = left.area() * blocks(c) + right.area() * blocks(n as u32 - c);
            if cost < best.0 || (cost == best.0 && cost.is_finite() && (ax, at) < (best.1, best.2)) {
                best = (cost, ax, at);
            }
        }
    }
    best
}
