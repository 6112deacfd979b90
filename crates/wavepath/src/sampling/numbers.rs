//! Where a vertex's random numbers come from: its own stream ([`Sampler`]), or numbers drawn
//! ahead for it by a kernel that draws many streams at once ([`Drawn`]). Shading code is
//! written once, generic over [`Numbers`]: a lane kernel draws a group's numbers eight or
//! sixteen streams at a time (Sobol's scrambling is most of the cost) and then runs the same
//! per-vertex code as the one-path kernel, which therefore sees the same numbers, bit for bit.

use super::Sampler;

/// A vertex's stream of uniform numbers, by dimension.
pub trait Numbers: Copy {
    /// This stream at dimension `dim`.
    fn at(self, dim: u32) -> Self;
    /// The 2-d sample of the current dimension; the stream moves on one dimension.
    fn next_2d(&mut self) -> (f32, f32);
    /// The 1-d sample of the current dimension; the stream moves on one dimension.
    fn next_f32(&mut self) -> f32;
}

impl Numbers for Sampler {
    #[inline(always)]
    fn at(self, dim: u32) -> Self {
        Sampler::at(self, dim)
    }

    #[inline(always)]
    fn next_2d(&mut self) -> (f32, f32) {
        Sampler::next_2d(self)
    }

    #[inline(always)]
    fn next_f32(&mut self) -> f32 {
        Sampler::next_f32(self)
    }
}

/// Which dimensions of a vertex stream a kernel draws ahead, and as what: a dimension read as
/// a 2-d sample and one read as a 1-d sample differ for the patterned samplers (stratified,
/// Sobol), so the kernel must know which one the shading code will ask for.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Layout {
    /// `one_d[d]`: dimension `d` is read by `next_f32` (else by `next_2d`).
    pub one_d: Vec<bool>,
    /// Every dimension the shading code reads is in `one_d` (none was cut off): a kernel may
    /// read the table alone.
    pub complete: bool,
}

impl Layout {
    /// Dimensions drawn ahead.
    #[inline(always)]
    pub fn len(&self) -> usize {
        self.one_d.len()
    }

    #[inline(always)]
    pub fn is_empty(&self) -> bool {
        self.one_d.is_empty()
    }
}

/// One vertex's numbers drawn ahead (`table[d]`: the sample of dimension `d` as [`Layout`]
/// says it is read, a 1-d one in the first component), backed by the vertex's own stream for
/// any dimension the table does not hold or holds as the other kind: the numbers are always
/// the stream's, the table only saves drawing them one at a time.
#[derive(Clone, Copy, Debug)]
pub struct Drawn<'a> {
    pub stream: Sampler,
    pub table: &'a [[f32; 2]],
    pub one_d: &'a [bool],
    pub dim: u32,
}

impl Numbers for Drawn<'_> {
    #[inline(always)]
    fn at(mut self, dim: u32) -> Self {
        self.dim = dim;
        self
    }

    #[inline(always)]
    fn next_2d(&mut self) -> (f32, f32) {
        let d = self.dim as usize;
        self.dim = self.dim.wrapping_add(1);
        match (self.table.get(d), self.one_d.get(d)) {
            (Some(&[a, b]), Some(false)) => (a, b),
            _ => self.stream.at(d as u32).next_2d(),
        }
    }

    #[inline(always)]
    fn next_f32(&mut self) -> f32 {
        let d = self.dim as usize;
        self.dim = self.dim.wrapping_add(1);
        match (self.table.get(d), self.one_d.get(d)) {
            (Some(&[a, _]), Some(true)) => a,
            _ => self.stream.at(d as u32).next_f32(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Pattern, SamplerKind};

    /// A table drawn as the layout says gives the stream's numbers; dimensions past the table
    /// or read as the other kind fall back to the stream.
    #[test]
    fn drawn_numbers_are_the_streams() {
        for kind in [SamplerKind::Independent, SamplerKind::Stratified, SamplerKind::Sobol] {
            let s = Pattern::new(kind, 16).vertex(0x1234_5678_9abc, 2);
            let one_d = vec![false, true, true, false, true];
            let table: Vec<[f32; 2]> = one_d
                .iter()
                .enumerate()
                .map(|(d, &one)| {
                    let mut r = s.at(d as u32);
                    if one {
                        [r.next_f32(), 0.0]
                    } else {
                        let (a, b) = r.next_2d();
                        [a, b]
                    }
                })
                .collect();
            let drawn = Drawn { stream: s, table: &table, one_d: &one_d, dim: 0 };
            for d in 0..8u32 {
                assert_eq!(Numbers::next_2d(&mut drawn.at(d)), s.at(d).next_2d(), "{kind:?} 2-d, dimension {d}");
                assert_eq!(Numbers::next_f32(&mut drawn.at(d)), s.at(d).next_f32(), "{kind:?} 1-d, dimension {d}");
            }
            // Moving on: a run of reads gives the stream's run.
            let (mut a, mut b) = (drawn.at(3), s.at(3));
            for _ in 0..4 {
                assert_eq!(Numbers::next_2d(&mut a), b.next_2d());
                assert_eq!(Numbers::next_f32(&mut a), b.next_f32());
            }
        }
    }
}
