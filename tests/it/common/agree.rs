//! Two independent renders of the same image compared region by region.

use wavepath::film::Accumulator;

/// Compares 8x8-pixel region means channel by channel: |a - b| <= 5 sigma of the
/// difference, sigma from the per-pixel variances of the means. Returns the largest |z|.
pub fn assert_agree(a: &Accumulator, b: &Accumulator, what: &str) -> f64 {
    const R: usize = 8;
    let mut worst: f64 = 0.0;
    let mut nonzero = 0;
    for ry in 0..a.height / R {
        for rx in 0..a.width / R {
            let (mut ma, mut mb, mut va, mut vb) =
                (glam::DVec3::ZERO, glam::DVec3::ZERO, glam::DVec3::ZERO, glam::DVec3::ZERO);
            for y in ry * R..(ry + 1) * R {
                for x in rx * R..(rx + 1) * R {
                    let (pa, pb) = (&a.pixels[y * a.width + x], &b.pixels[y * b.width + x]);
                    ma += pa.mean().as_dvec3();
                    mb += pb.mean().as_dvec3();
                    va += pa.variance_of_mean();
                    vb += pb.variance_of_mean();
                }
            }
            for c in 0..3 {
                let d = (ma[c] - mb[c]).abs();
                let sd = (va[c] + vb[c]).sqrt();
                if sd == 0.0 {
                    assert!(
                        d <= 1e-6 * ma[c].abs().max(1.0),
                        "{what}: region ({rx},{ry}) channel {c}: {} vs {} with zero variance",
                        ma[c],
                        mb[c]
                    );
                    continue;
                }
                nonzero += 1;
                let z = d / sd;
                worst = worst.max(z);
                assert!(
                    z < 5.0,
                    "{what}: region ({rx},{ry}) channel {c}: {} vs {} (z = {z:.2})",
                    ma[c] / 64.0,
                    mb[c] / 64.0
                );
            }
        }
    }
    assert!(nonzero > 0, "{what}: nothing to compare");
    worst
}
