//! The ray queues, structure of arrays. Each queue is declared once, field by field, and
//! the macro makes the struct, its growth (only ever up, so queues are reused from wave to
//! wave and frame to frame) and its splitting into disjoint chunks for rayon.

/// Declares an SoA queue: `Vec<T>` per field (T: `bytemuck::Pod`), plus a chunk type that
/// borrows the same range of every field mutably.
macro_rules! soa_queue {
    ($(#[$m:meta])* $name:ident / $chunk:ident { $($(#[$fm:meta])* $f:ident : $t:ty),* $(,)? }) => {
        $(#[$m])*
        #[derive(Clone, Debug, Default)]
        pub struct $name {
            /// Entries in use (every field holds at least this many).
            pub len: usize,
            $($(#[$fm])* pub $f: Vec<$t>,)*
        }

        /// The same range of every field of the queue, borrowed mutably.
        pub struct $chunk<'a> {
            /// Index of the chunk's first entry in the queue.
            pub start: usize,
            $(pub $f: &'a mut [$t],)*
        }

        impl $name {
            /// Makes room for `n` entries; never shrinks, so a reused queue does not allocate.
            pub fn ensure(&mut self, n: usize) {
                $(
                    if self.$f.len() < n {
                        self.$f.resize(n, <$t as bytemuck::Zeroable>::zeroed());
                    }
                )*
            }

            /// Splits the queue's first `sizes.iter().sum()` entries into consecutive pieces.
            pub fn split_sizes(&mut self, sizes: &[usize]) -> Vec<$chunk<'_>> {
                $(
                    let mut $f = {
                        let mut pieces = Vec::with_capacity(sizes.len());
                        let mut rest = &mut self.$f[..];
                        for &n in sizes {
                            let (head, tail) = rest.split_at_mut(n);
                            pieces.push(head);
                            rest = tail;
                        }
                        pieces.into_iter()
                    };
                )*
                let mut out = Vec::with_capacity(sizes.len());
                let mut start = 0;
                for &n in sizes {
                    out.push($chunk { start, $($f: $f.next().expect("one piece per size"),)* });
                    start += n;
                }
                out
            }

            /// Splits entries `0..len` into chunks of `size` (the last may be shorter).
            pub fn chunks(&mut self, len: usize, size: usize) -> Vec<$chunk<'_>> {
                let sizes: Vec<usize> = (0..len.div_ceil(size)).map(|c| size.min(len - c * size)).collect();
                self.split_sizes(&sizes)
            }
        }
    };
}

soa_queue! {
    /// Paths in flight: the ray to trace next and the path's state.
    PathQueue / PathChunk {
        ox: f32, oy: f32, oz: f32,
        dx: f32, dy: f32, dz: f32,
        tmin: f32, tmax: f32,
        /// The path's sample slot in the wave: pixel = wave pixel slot / batch, sample = base + slot % batch.
        slot: u32,
        /// Throughput (product of BSDF weights so far).
        tr: f32, tg: f32, tb: f32,
        /// Radiance gathered so far.
        lr: f32, lg: f32, lb: f32,
        /// Depth of the vertex this ray will hit (0: camera ray). The random stream of that
        /// vertex is (seed, pixel, sample, depth): this is the path's whole RNG state.
        depth: u32,
        /// Set by shade: the path has a continuation ray (before Russian roulette).
        alive: u32,
    }
}

soa_queue! {
    /// Closest hits of the path queue, entry for entry; `prim == u32::MAX` is a miss.
    HitQueue / HitChunk { t: f32, prim: u32, u: f32, v: f32 }
}

soa_queue! {
    /// Shadow rays (or hemisphere probes): a fixed block of `direct_per_vertex` entries per
    /// path; unused entries have `tmax < 0`. `w` is the contribution if unoccluded
    /// (throughput applied); the shadow stage zeroes it when occluded.
    ShadowQueue / ShadowChunk {
        ox: f32, oy: f32, oz: f32,
        dx: f32, dy: f32, dz: f32,
        tmax: f32,
        wr: f32, wg: f32, wb: f32,
    }
}
