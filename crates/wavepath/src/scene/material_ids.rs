//! Each triangle's material, as runs of triangles that share one.
//!
//! Every loader emits a mesh's triangles material by material (an OBJ `usemtl` group, a glTF
//! primitive, a COLLADA `<triangles>` element), and subdivision keeps a triangle's four
//! children together, so a scene has a handful of runs however many triangles it has: a
//! 25.6M-triangle scan in a Cornell box held 102 MB of ids as one per triangle, and holds a
//! few bytes as runs. A lookup is a binary search over the runs.
use std::ops::Index;

#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct MaterialIds {
    /// One past the last triangle of each run (increasing; the last is the length).
    ends: Vec<u32>,
    /// The material of each run (neighbouring runs differ).
    ids: Vec<u32>,
}

impl MaterialIds {
    /// `len` triangles of material `id`.
    pub fn uniform(id: u32, len: usize) -> MaterialIds {
        let mut m = MaterialIds::default();
        m.push_run(id, len);
        m
    }

    pub fn len(&self) -> usize {
        self.ends.last().map_or(0, |&e| e as usize)
    }

    pub fn is_empty(&self) -> bool {
        self.ends.is_empty()
    }

    #[inline]
    fn run_of(&self, tri: usize) -> usize {
        debug_assert!(tri < self.len());
        self.ends.partition_point(|&e| e as usize <= tri)
    }

    pub fn push(&mut self, id: u32) {
        self.push_run(id, 1);
    }

    /// Appends `count` triangles of material `id`.
    pub fn push_run(&mut self, id: u32, count: usize) {
        if count == 0 {
            return;
        }
        let end = u32::try_from(self.len() + count).expect("a mesh holds fewer than 2^32 triangles");
        match (self.ids.last(), self.ends.last_mut()) {
            (Some(&last), Some(e)) if last == id => *e = end,
            _ => {
                self.ids.push(id);
                self.ends.push(end);
            }
        }
    }

    /// Shortens or lengthens to `len` triangles, new ones of material `id`.
    pub fn resize(&mut self, len: usize, id: u32) {
        if len >= self.len() {
            self.push_run(id, len - self.len());
            return;
        }
        if len == 0 {
            *self = MaterialIds::default();
            return;
        }
        // The run holding the last triangle kept ends the list.
        let keep = self.run_of(len - 1);
        self.ends.truncate(keep + 1);
        self.ids.truncate(keep + 1);
        self.ends[keep] = len as u32;
    }

    /// (first triangle, end, material) of each run, in order.
    pub fn runs(&self) -> impl Iterator<Item = (usize, usize, u32)> + '_ {
        let starts = std::iter::once(0).chain(self.ends.iter().map(|&e| e as usize));
        starts.zip(&self.ends).zip(&self.ids).map(|((s, &e), &id)| (s, e as usize, id))
    }

    /// Each triangle's material, in order.
    pub fn iter(&self) -> impl Iterator<Item = u32> + '_ {
        self.runs().flat_map(|(s, e, id)| std::iter::repeat_n(id, e - s))
    }

    /// Each triangle's material repeated `k` times (the ids of a mesh whose triangles were
    /// each split into `k` in place).
    pub fn repeated(&self, k: usize) -> MaterialIds {
        let mut out = MaterialIds::default();
        for (s, e, id) in self.runs() {
            out.push_run(id, (e - s) * k);
        }
        out
    }

    /// Bytes its arrays hold.
    pub fn bytes(&self) -> usize {
        std::mem::size_of_val(&self.ends[..]) + std::mem::size_of_val(&self.ids[..])
    }

    /// The run boundaries and materials as words (for hashing the scene).
    pub fn words(&self) -> impl Iterator<Item = u32> + '_ {
        self.ends.iter().chain(&self.ids).copied()
    }
}

impl Index<usize> for MaterialIds {
    type Output = u32;

    #[inline]
    fn index(&self, tri: usize) -> &u32 {
        &self.ids[self.run_of(tri)]
    }
}

impl Extend<u32> for MaterialIds {
    fn extend<I: IntoIterator<Item = u32>>(&mut self, iter: I) {
        iter.into_iter().for_each(|id| self.push(id));
    }
}

impl FromIterator<u32> for MaterialIds {
    fn from_iter<I: IntoIterator<Item = u32>>(iter: I) -> MaterialIds {
        let mut m = MaterialIds::default();
        m.extend(iter);
        m
    }
}

impl From<Vec<u32>> for MaterialIds {
    fn from(v: Vec<u32>) -> MaterialIds {
        v.into_iter().collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against a plain vector of ids: every lookup, the iteration, resizing both ways,
    /// appending, repeating; neighbouring equal ids share a run.
    #[test]
    fn runs_hold_what_a_vector_of_ids_holds() {
        let mut x = 3u64;
        let mut next = move |m: u64| {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (x >> 33) % m
        };
        for _ in 0..200 {
            let mut plain: Vec<u32> = Vec::new();
            let mut runs = MaterialIds::default();
            for _ in 0..next(6) {
                let (id, count) = (next(3) as u32, next(5) as usize);
                plain.extend(std::iter::repeat_n(id, count));
                runs.push_run(id, count);
            }
            let cut = next(plain.len() as u64 + 3) as usize;
            plain.resize(cut, 7);
            runs.resize(cut, 7);
            runs.extend([1, 1, 2]);
            plain.extend([1, 1, 2]);
            assert_eq!(runs.len(), plain.len());
            assert_eq!(runs.iter().collect::<Vec<_>>(), plain);
            assert!((0..plain.len()).all(|i| runs[i] == plain[i]));
            assert!(runs.ids.windows(2).all(|w| w[0] != w[1]), "{runs:?}");
            let four: Vec<u32> = plain.iter().flat_map(|&id| [id; 4]).collect();
            assert_eq!(runs.repeated(4).iter().collect::<Vec<_>>(), four);
            assert_eq!(MaterialIds::from(plain.clone()), runs);
        }
        assert_eq!(MaterialIds::uniform(5, 0), MaterialIds::default());
        assert_eq!(MaterialIds::uniform(5, 1 << 30).bytes(), 8);
    }
}
