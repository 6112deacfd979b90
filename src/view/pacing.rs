//! How often the viewer publishes a frame that only refines the one it published before.
//!
//! Every frame costs the render thread a copy of the image and its figures, and the frame
//! streams an encoding (a PNG of the whole image) on their threads, beside the render's
//! workers: on a 2-core machine, a frame after every band of about 55 ms took close to a
//! tenth of a core from the render. While a view refines, a frame is therefore published at
//! most every [`REFINE_GAP`] (the bands between add their rows to the next one); the first
//! image of a new view (a camera move, a settings change) and the final image go out at once.
//!
//! Denoised frames have a pace of their own ([`denoise_due`]): a denoise takes all cores for
//! a while (Open Image Denoise's own threads, beside the render's), so a refining frame is
//! denoised only when the denoiser has rested three times as long as its last run took, and
//! at least [`DENOISE_MIN_GAP`]; the final image is always denoised. Measured at 320x240 on
//! 2 cores (Intel Xeon, shared with other work), the Cornell box to 1024 spp: a denoise with
//! albedo and normal, prefiltered, takes 0.85 s alone and 1.8 s beside the render, which
//! then publishes a denoised frame every 7 s and converges in 34.5 s instead of the 29 s of
//! the same render without denoising (first-hit sums kept; 26.3 s without them). Resting once
//! the run's time instead gave a denoised frame every 3.6 s but converged in 40 s; a denoise
//! per pass (a pass of 16 spp takes about 0.4 s there) would cost more than the passes.

use std::time::{Duration, Instant};

/// The shortest time between two frames of one view while it refines.
pub const REFINE_GAP: Duration = Duration::from_millis(250);

/// The shortest time between the end of one denoise of a refining frame and the next.
pub const DENOISE_MIN_GAP: Duration = Duration::from_millis(1000);

/// The denoiser's rest after a run, in units of that run's time.
pub const DENOISE_REST: f64 = 3.0;

/// Whether a refining frame may be denoised at `now`, the last denoise having ended at
/// `last.0` after `last.1` seconds (`None`: none yet).
pub fn denoise_due(last: Option<(Instant, f64)>, now: Instant) -> bool {
    last.is_none_or(|(end, secs)| {
        let rest = Duration::from_secs_f64((secs * DENOISE_REST).clamp(0.0, 3600.0)).max(DENOISE_MIN_GAP);
        now >= end + rest
    })
}

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

    #[test]
    fn the_denoiser_rests_three_times_its_run_and_at_least_the_minimum() {
        let t0 = Instant::now();
        let ms = Duration::from_millis;
        assert!(denoise_due(None, t0));
        // A 0.1 s run: the minimum gap rules.
        assert!(!denoise_due(Some((t0, 0.1)), t0 + DENOISE_MIN_GAP - ms(1)));
        assert!(denoise_due(Some((t0, 0.1)), t0 + DENOISE_MIN_GAP));
        // A 0.8 s run: 2.4 s of rest.
        assert!(!denoise_due(Some((t0, 0.8)), t0 + ms(2300)));
        assert!(denoise_due(Some((t0, 0.8)), t0 + ms(2400)));
    }
}
