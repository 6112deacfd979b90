//! Waves handed to worker threads one at a time from a shared counter, each thread working
//! on state of its own that lives as long as the render.
//!
//! rayon's splitting of a parallel iterator leaves runs of waves (a quarter of a frame with
//! two threads) that one thread works through alone and the other cannot steal from: the
//! thread that finished first waited, up to a tenth of the threads' time (docs/decisions.md,
//! "Two threads"). A counter lets a thread take the next wave whenever it is free, so the
//! threads end a frame at most one wave apart; and a thread's queues are allocated once per
//! render instead of once per rayon job.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, PoisonError};

/// One state per worker thread of the pool the render runs on (queues, scratch), kept from
/// frame to frame.
pub struct Workers<S> {
    states: Vec<Mutex<S>>,
}

impl<S: Default + Send> Workers<S> {
    /// One state per thread of the current rayon pool (allocated lazily by `S::default`,
    /// which for queues allocates nothing until the first wave).
    pub fn for_current_pool() -> Self {
        Workers { states: (0..rayon::current_num_threads().max(1)).map(|_| Mutex::default()).collect() }
    }

    /// Runs `work(state, item)` for every item, items taken in order from a shared counter
    /// by one task per worker state, and gives the `sum` of the results. Which thread runs
    /// which item varies from run to run: `work` must write nothing that depends on it
    /// (each item owns its output), and `sum` must not matter in order for what the caller
    /// keeps exact.
    pub fn run<I, R>(
        &self,
        items: impl IntoIterator<Item = I>,
        zero: impl Fn() -> R + Sync + Send,
        sum: impl Fn(R, R) -> R + Sync + Send,
        work: impl Fn(&mut S, I) -> R + Sync,
    ) -> R
    where
        I: Send,
        R: Send,
    {
        use rayon::prelude::*;
        let items: Vec<Mutex<Option<I>>> = items.into_iter().map(|i| Mutex::new(Some(i))).collect();
        let next = AtomicUsize::new(0);
        let tasks = self.states.len().min(items.len());
        (0..tasks)
            .into_par_iter()
            .with_max_len(1)
            .map(|k| {
                // Task k alone locks state k: the lock is never contended, it only proves to
                // the compiler that no two tasks share a state.
                let mut state = self.states[k].lock().unwrap_or_else(PoisonError::into_inner);
                let mut acc = zero();
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(slot) = items.get(i) else { break };
                    // Each index is handed out once, so the item is always there.
                    let Some(item) = slot.lock().unwrap_or_else(PoisonError::into_inner).take() else { continue };
                    acc = sum(acc, work(&mut state, item));
                }
                acc
            })
            .reduce(&zero, &sum)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every item is worked on exactly once, whatever the thread count, and a state is
    /// reused across runs (its count of items seen grows over both runs).
    #[test]
    fn every_item_once_and_states_kept() {
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let workers = Workers::<u64>::for_current_pool();
                let mut out = vec![0u32; 1000];
                for run in 1..=2u32 {
                    let total = workers.run(
                        out.chunks_mut(7).enumerate(),
                        || 0u64,
                        |a, b| a + b,
                        |seen, (i, chunk)| {
                            *seen += 1;
                            for (j, o) in chunk.iter_mut().enumerate() {
                                *o += (i * 7 + j) as u32 + 1;
                            }
                            chunk.len() as u64
                        },
                    );
                    assert_eq!(total, 1000);
                    for (j, &o) in out.iter().enumerate() {
                        assert_eq!(o, run * (j as u32 + 1), "threads {threads}, run {run}, item {j}");
                    }
                }
                let seen: u64 = workers.states.iter().map(|s| *s.lock().unwrap()).sum();
                assert_eq!(seen, 2 * 1000u64.div_ceil(7));
            });
        }
    }
}
