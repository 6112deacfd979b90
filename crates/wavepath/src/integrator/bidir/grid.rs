//! A hash grid over one iteration's light vertices, for the range queries of vertex merging:
//! cells twice the merge radius wide, so the points within the radius of a query lie in the
//! 2x2x2 cells nearest to it. Built by a counting sort, so a cell's points keep their order
//! and a query visits them in the same order on every run.

use glam::Vec3;

pub struct HashGrid {
    lo: Vec3,
    inv_cell: f32,
    radius2: f32,
    /// `starts[h]..starts[h + 1]`: the entries of `points` hashed to `h`.
    starts: Vec<u32>,
    points: Vec<u32>,
}

impl HashGrid {
    /// The grid of `positions` for merges within `radius`.
    pub fn new(positions: &[Vec3], radius: f32) -> HashGrid {
        let lo = positions.iter().fold(Vec3::splat(f32::INFINITY), |a, &p| a.min(p));
        let inv_cell = 1.0 / (2.0 * radius);
        let size = positions.len().next_power_of_two().max(1);
        let mut grid = HashGrid { lo, inv_cell, radius2: radius * radius, starts: vec![0; size + 1], points: vec![] };
        let hashes: Vec<usize> = positions.iter().map(|&p| grid.hash(grid.cell(p))).collect();
        for &h in &hashes {
            grid.starts[h + 1] += 1;
        }
        for i in 0..size {
            grid.starts[i + 1] += grid.starts[i];
        }
        let mut next = grid.starts.clone();
        grid.points = vec![0; positions.len()];
        for (i, &h) in hashes.iter().enumerate() {
            grid.points[next[h] as usize] = i as u32;
            next[h] += 1;
        }
        grid
    }

    #[inline]
    fn cell(&self, p: Vec3) -> [i32; 3] {
        let c = ((p - self.lo) * self.inv_cell).floor();
        [c.x as i32, c.y as i32, c.z as i32]
    }

    #[inline]
    fn hash(&self, c: [i32; 3]) -> usize {
        let h = (c[0] as u32).wrapping_mul(73_856_093)
            ^ (c[1] as u32).wrapping_mul(19_349_663)
            ^ (c[2] as u32).wrapping_mul(83_492_791);
        h as usize & (self.starts.len() - 2)
    }

    /// Calls `f` with the index of every point within the radius of `q` (in a fixed order).
    pub fn query(&self, q: Vec3, positions: &[Vec3], mut f: impl FnMut(usize)) {
        if self.points.is_empty() {
            return;
        }
        let x = (q - self.lo) * self.inv_cell;
        let c = x.floor();
        // The neighbour on each axis: the side of the cell's centre `q` lies on.
        let frac = x - c;
        let step = |f: f32| if f < 0.5 { -1 } else { 1 };
        let (c, s) = ([c.x as i32, c.y as i32, c.z as i32], [step(frac.x), step(frac.y), step(frac.z)]);
        let mut seen = [usize::MAX; 8];
        for k in 0..8 {
            let cell = [c[0] + (k & 1) * s[0], c[1] + ((k >> 1) & 1) * s[1], c[2] + ((k >> 2) & 1) * s[2]];
            let h = self.hash(cell);
            // Two cells hashed to one bucket are visited once.
            if seen[..k as usize].contains(&h) {
                continue;
            }
            seen[k as usize] = h;
            for &i in &self.points[self.starts[h] as usize..self.starts[h + 1] as usize] {
                if (positions[i as usize] - q).length_squared() <= self.radius2 {
                    f(i as usize);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Sampler;

    /// Every query finds exactly the points a scan over all points finds.
    #[test]
    fn queries_find_what_a_scan_finds() {
        let mut s = Sampler::for_sample(7, 0, 0);
        let pts: Vec<Vec3> = (0..2000).map(|_| Vec3::new(s.next_f32(), s.next_f32(), s.next_f32() * 0.1)).collect();
        let r = 0.03;
        let grid = HashGrid::new(&pts, r);
        for _ in 0..300 {
            let q = Vec3::new(s.next_f32(), s.next_f32(), s.next_f32() * 0.1);
            let mut found = vec![];
            grid.query(q, &pts, |i| found.push(i));
            found.sort();
            let scan: Vec<usize> = (0..pts.len()).filter(|&i| (pts[i] - q).length_squared() <= r * r).collect();
            assert_eq!(found, scan);
        }
    }
}
