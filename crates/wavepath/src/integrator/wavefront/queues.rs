//! The queues of one wave, structure of arrays: one `Vec` per field, grown once and then
//! reused by every wave a worker thread runs (cleared, never freed), so the steady state
//! allocates nothing. Rays are kept whole (`Ray`) because that is what the intersector's
//! batch interface consumes.
//!
//! Each queue is declared once, one line per field, by [`soa_queue!`]: a field added there
//! is stored, pushed, truncated, compacted and started with the others, with no second list
//! to keep in step.

use crate::geometry::{Hit, Ray};
use crate::integrator::Bounce;
use glam::Vec3;

/// A structure-of-arrays queue from one declaration: the queue (one `Vec` per field), for the
/// open form an entry struct (one value per field), and the queue's operations, each a loop over the
/// fields unrolled at compile time.
///
/// Two forms:
///
/// - `struct Q { field: T = kind, .. }`: every array has the queue's length. `kind`
///   says what [`PathQueue::start_camera_paths`] does with the field and whether compaction
///   carries it:
///   - `given`: pushed by the caller before the start (checked in debug builds);
///   - `index`: the entry's index (`0..n`);
///   - `start(x)`: `x`;
///   - `scratch(x)`: `x`, and [`PathQueue::move_entry`] leaves it behind (a stage writes it
///     for every entry before any stage reads it, so carrying it would be wasted copying).
/// - `struct Q of E, open S { field: T = grow(x), .. }`: the arrays keep the largest length
///   ever needed (entries past `len` are stale; `x` fills new room and is never read), and a
///   writer gets room with `open`, which hands out `S`, one slice per field.
macro_rules! soa_queue {
    // The first field's length (every array has it in both forms).
    (@cap $q:expr; $first:ident $(, $rest:ident)*) => {
        $q.$first.len()
    };
    (@start $v:expr, $n:ident, $ty:ty, given) => {
        debug_assert_eq!($v.len(), $n)
    };
    (@start $v:expr, $n:ident, $ty:ty, index) => {{
        $v.clear();
        $v.extend(0..$n as $ty);
    }};
    (@start $v:expr, $n:ident, $ty:ty, start $x:expr) => {{
        $v.clear();
        $v.resize($n, $x);
    }};
    (@start $v:expr, $n:ident, $ty:ty, scratch $x:expr) => {
        soa_queue!(@start $v, $n, $ty, start $x)
    };
    (@move $v:expr, $from:ident, $to:ident, scratch) => {};
    (@move $v:expr, $from:ident, $to:ident, $kind:ident) => {
        $v[$to] = $v[$from]
    };

    (
        $(#[$attr:meta])*
        $vis:vis struct $name:ident {
            $(
                $(#[$fattr:meta])*
                $fvis:vis $field:ident: $ty:ty = $kind:ident $(($x:expr))?
            ),+ $(,)?
        }
    ) => {
        $(#[$attr])*
        $vis struct $name {
            $($(#[$fattr])* $fvis $field: Vec<$ty>,)+
        }

        impl $name {
            pub fn len(&self) -> usize {
                soa_queue!(@cap self; $($field),+)
            }

            pub fn is_empty(&self) -> bool {
                self.len() == 0
            }

            pub fn clear(&mut self) {
                self.truncate(0);
            }

            pub fn truncate(&mut self, n: usize) {
                $(self.$field.truncate(n);)+
            }

            /// Gives the `n` camera paths whose `given` fields are already pushed a fresh
            /// path state (filled field by field: the same for every camera path).
            pub fn start_camera_paths(&mut self, n: usize) {
                $(soa_queue!(@start self.$field, n, $ty, $kind $($x)?);)+
            }

            /// Copies entry `from` over entry `to` (compaction, `to < from`).
            #[inline]
            pub fn move_entry(&mut self, from: usize, to: usize) {
                $(soa_queue!(@move self.$field, from, to, $kind);)+
            }
        }
    };

    (
        $(#[$attr:meta])*
        $vis:vis struct $name:ident of $entry:ident, open $slots:ident {
            $(
                $(#[$fattr:meta])*
                $fvis:vis $field:ident: $ty:ty = grow($fill:expr)
            ),+ $(,)?
        }
    ) => {
        $(#[$attr])*
        $vis struct $name {
            $($(#[$fattr])* $field: Vec<$ty>,)+
            len: usize,
        }

        #[doc = concat!("One entry of a [`", stringify!($name), "`].")]
        // An entry and `push` write one at a time (tests, the path queue's camera rays); a
        // queue the kernels fill in batches may have no other writer.
        #[allow(dead_code)]
        #[derive(Clone, Copy, Debug)]
        $vis struct $entry {
            $($(#[$fattr])* $fvis $field: $ty,)+
        }

        #[doc = concat!("Room opened in a [`", stringify!($name), "`], one slice per field.")]
        $vis struct $slots<'a> {
            $($(#[$fattr])* $fvis $field: &'a mut [$ty],)+
        }

        impl $name {
            pub fn len(&self) -> usize {
                self.len
            }

            pub fn clear(&mut self) {
                self.len = 0;
            }

            $(
                $(#[$fattr])*
                $fvis fn $field(&self) -> &[$ty] {
                    &self.$field[..self.len]
                }
            )+

            #[allow(dead_code)]
            #[inline]
            pub fn push(&mut self, e: $entry) {
                let s = self.open(1);
                $(s.$field[0] = e.$field;)+
                self.commit(1);
            }

            /// Room for `extra` entries after the current ones (stale contents), for a
            /// writer that fills them in order and then [`commit`](Self::commit)s how many
            /// it wrote: it can store every candidate and move on past the valid ones only,
            /// with no branch per ray.
            #[inline]
            pub fn open(&mut self, extra: usize) -> $slots<'_> {
                let (start, end) = (self.len, self.len + extra);
                if soa_queue!(@cap self; $($field),+) < end {
                    self.grow(end);
                }
                $slots { $($field: &mut self.$field[start..end],)+ }
            }

            /// The first `n` entries after the current ones (written after
            /// [`open`](Self::open)) join the queue.
            #[inline]
            pub fn commit(&mut self, n: usize) {
                self.len += n;
                debug_assert!(self.len <= soa_queue!(@cap self; $($field),+));
            }

            #[cold]
            fn grow(&mut self, end: usize) {
                // At least doubled, so a queue filled by single pushes grows in amortised
                // O(1).
                let end = end.max(2 * soa_queue!(@cap self; $($field),+));
                $(self.$field.resize(end, $fill);)+
            }
        }
    };
}

soa_queue! {
    /// Paths in flight: the ray each traces next, what it hit and the path's state.
    #[derive(Clone, Debug, Default)]
    pub struct PathQueue {
        pub ray: Ray = given,
        /// `ray`'s closest hit: traverse writes it for every path before shade reads it.
        pub hit: Option<Hit> = scratch(None),
        /// Key of the path's random streams ([`crate::sampling::Sampler::path_key`]): with
        /// `depth` this is the path's whole RNG state.
        pub key: u64 = given,
        /// The path's sample slot in the wave (pixel = wave pixel `slot / batch`).
        pub slot: u32 = index,
        /// Product of BSDF weights so far.
        pub throughput: Vec3 = start(Vec3::ONE),
        /// Radiance gathered so far.
        pub radiance: Vec3 = start(Vec3::ZERO),
        /// Depth of the vertex this ray will hit (0: camera ray).
        pub depth: u32 = start(0),
        /// Set by shade for every path: the path has a continuation ray (before Russian
        /// roulette).
        pub alive: bool = scratch(false),
        /// What the vertex that sampled `ray` means for the light the ray finds (read only by
        /// kernels with non-diffuse materials).
        pub bounce: Bounce = start(Bounce::DELTA),
        /// path+light: light tracing's density of the path so far over the camera's, squared
        /// ([`CausticTerms`](crate::integrator::bidir::caustics::CausticTerms)); 0 otherwise.
        pub pl: f32 = start(0.0),
    }
}

soa_queue! {
    /// Shadow rays (or hemisphere probes) of one bounce, in the order shading wrote them.
    ///
    /// The arrays keep the largest length any bounce needed: a writer gets room with
    /// [`open`](Self::open) without filling it first, and one capacity check per batch
    /// instead of one per ray and field.
    #[derive(Clone, Debug, Default)]
    pub struct ShadowQueue of ShadowEntry, open ShadowSlots {
        pub ray: Ray = grow(Ray { origin: Vec3::ZERO, dir: Vec3::ZERO, tmin: 0.0, tmax: 0.0 }),
        /// Contribution if unoccluded (throughput applied); a probe's is multiplied by the
        /// emission it sees.
        pub weight: Vec3 = grow(Vec3::ZERO),
        /// Index of the path (in the path queue) the contribution goes to.
        pub owner: u32 = grow(0),
    }
}
