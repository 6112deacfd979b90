//! The order in which a batch traces its rays. A wave's extension and shadow rays start all
//! over the scene and point every way; traced in queue order, consecutive rays walk unrelated
//! parts of a tree that does not fit in the core's cache. Sorted by direction octant, then by
//! the cell of their origin on a 16^3 grid (Morton order), consecutive rays mostly visit the
//! same nodes and leaves. The order changes nothing a ray returns (each ray is traced alone),
//! only which memory is warm.
use crate::ray::Ray;
use glam::Vec3;

/// Batches smaller than this are traced in queue order (sorting would not pay).
pub const MIN_RAYS: usize = 256;

/// Grid cells per axis for the origin key (4 bits each, 12 in all).
const CELLS: f32 = 16.0;

/// Bit `i` of a 4-bit value moved to bit `3 i`.
const SPREAD: [u16; 16] = {
    let mut t = [0u16; 16];
    let mut v = 0;
    while v < 16 {
        let mut b = 0;
        while b < 4 {
            t[v] |= (((v >> b) & 1) as u16) << (3 * b);
            b += 1;
        }
        v += 1;
    }
    t
};

/// The 15-bit sort key: octant (3 bits, high), then the Morton code of the origin's cell in
/// the box `lo..hi` (origins outside are clamped to the border cells; NaN goes to cell 0).
#[inline]
pub fn key(ray: &Ray, lo: Vec3, scale: Vec3) -> u16 {
    let q = ((ray.origin - lo) * scale).to_array().map(|x| x.clamp(0.0, CELLS - 1.0) as usize);
    let d = ray.dir;
    let octant =
        d.x.is_sign_negative() as u16 | (d.y.is_sign_negative() as u16) << 1 | (d.z.is_sign_negative() as u16) << 2;
    octant << 12 | SPREAD[q[0] & 15] | SPREAD[q[1] & 15] << 1 | SPREAD[q[2] & 15] << 2
}

/// Indices of `rays` sorted by [`key`] (stable: equal keys keep queue order), by a two-pass
/// radix sort over the key's bytes.
pub fn coherent(rays: &[Ray], lo: Vec3, hi: Vec3) -> Vec<u32> {
    let extent = (hi - lo).max(Vec3::splat(f32::MIN_POSITIVE));
    let scale = Vec3::splat(CELLS) / extent;
    let scale = Vec3::select(scale.cmplt(Vec3::splat(f32::INFINITY)), scale, Vec3::ZERO);
    let keys: Vec<u16> = rays.iter().map(|r| key(r, lo, scale)).collect();
    let mut a: Vec<u32> = (0..rays.len() as u32).collect();
    let mut b = vec![0u32; rays.len()];
    for shift in [0u32, 8] {
        let mut start = [0usize; 257];
        for &i in &a {
            start[((keys[i as usize] >> shift) & 0xff) as usize + 1] += 1;
        }
        for k in 1..257 {
            start[k] += start[k - 1];
        }
        for &i in &a {
            let k = ((keys[i as usize] >> shift) & 0xff) as usize;
            b[start[k]] = i;
            start[k] += 1;
        }
        std::mem::swap(&mut a, &mut b);
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn order_is_a_permutation_sorted_by_key() {
        let mut rays = Vec::new();
        for i in 0..1000u32 {
            let f = |k: u32| ((i.wrapping_mul(2654435761).rotate_left(k) % 2001) as f32 - 1000.0) / 100.0;
            rays.push(Ray::new(Vec3::new(f(0), f(7), f(13)), Vec3::new(f(3), f(19), f(23))));
        }
        rays.push(Ray::new(Vec3::splat(f32::NAN), Vec3::X));
        let (lo, hi) = (Vec3::splat(-5.0), Vec3::splat(5.0));
        let order = coherent(&rays, lo, hi);
        let mut seen = vec![false; rays.len()];
        for &i in &order {
            assert!(!seen[i as usize]);
            seen[i as usize] = true;
        }
        assert!(seen.iter().all(|&s| s));
        let scale = Vec3::splat(CELLS) / (hi - lo);
        for w in order.windows(2) {
            let (a, b) = (key(&rays[w[0] as usize], lo, scale), key(&rays[w[1] as usize], lo, scale));
            assert!(a < b || (a == b && w[0] < w[1]), "not stable-sorted at {w:?}");
        }
    }

    #[test]
    fn key_separates_octants_and_cells() {
        let (lo, scale) = (Vec3::ZERO, Vec3::splat(1.0));
        let k = |o: [f32; 3], d: [f32; 3]| key(&Ray::new(Vec3::from(o), Vec3::from(d)), lo, scale);
        assert_eq!(k([0.5, 0.5, 0.5], [1.0, 1.0, 1.0]), 0);
        assert_eq!(k([1.5, 0.5, 0.5], [1.0, 1.0, 1.0]), 1);
        assert_eq!(k([0.5, 1.5, 0.5], [1.0, 1.0, 1.0]), 2);
        assert_eq!(k([0.5, 0.5, 1.5], [1.0, 1.0, 1.0]), 4);
        assert_eq!(k([0.5, 0.5, 0.5], [-0.0, 1.0, 1.0]), 1 << 12);
        assert_eq!(k([0.5, 0.5, 0.5], [1.0, 1.0, -1.0]), 4 << 12);
        assert_eq!(k([99.0, -5.0, 0.5], [1.0, 1.0, 1.0]), SPREAD[15]);
    }
}
