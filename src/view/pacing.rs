//! How often the viewer publishes a frame that only refines the one it published before.
//!
//! Every frame costs the render thread a copy of the image and its figures, and the frame
//! streams an encoding (a PNG of the whole image) on their threads, beside the render's
//! workers: on a 2-core machine, a frame after every band of about 55 ms took close to a
//! tenth of a core from the render. While a view refines, a frame is therefore published at
//! most every [`REFINE_GAP`] (the bands between add their rows to the next one); the first
//! image of a new view (a camera move, a settings change) and the final image go out at once.

use std::time::{Duration, Instant};

/// The shortest time between two frames of one view while it refines.
pub const REFINE_GAP: Duration = Duration::from_millis(250);

/// How long a frame of `generation` (`converged`: the final image) waits at `now` when the
/// last one published showed generation `published.0` at `published.1`: zero when it may go.
pub fn hold(published: Option<(u64, Instant)>, generation: u64, converged: bool, now: Instant) -> Duration {
    match published {
        Some((g, at)) if g == generation && !converged => (at + REFINE_GAP).saturating_duration_since(now),
        _ => Duration::ZERO,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refining_frames_wait_out_the_gap_and_new_views_and_final_images_do_not() {
        let t0 = Instant::now();
        let ms = Duration::from_millis;
        // Nothing sent yet: the first frame goes at once.
        assert_eq!(hold(None, 3, false, t0), Duration::ZERO);
        // A refinement of the view just sent waits for the rest of the gap.
        assert_eq!(hold(Some((3, t0)), 3, false, t0 + ms(100)), REFINE_GAP - ms(100));
        assert_eq!(hold(Some((3, t0)), 3, false, t0), REFINE_GAP);
        // Once the gap has passed it goes.
        assert_eq!(hold(Some((3, t0)), 3, false, t0 + REFINE_GAP), Duration::ZERO);
        assert_eq!(hold(Some((3, t0)), 3, false, t0 + REFINE_GAP * 3), Duration::ZERO);
        // A new view's first image and the final image never wait.
        assert_eq!(hold(Some((3, t0)), 4, false, t0 + ms(1)), Duration::ZERO);
        assert_eq!(hold(Some((3, t0)), 3, true, t0 + ms(1)), Duration::ZERO);
    }
}
