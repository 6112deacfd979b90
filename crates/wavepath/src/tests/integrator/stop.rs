//! `render_until`: a set stop flag ends a render early with the `Interrupted` error, for both
//! integrators; an unset one changes nothing.

use crate::render::{Interrupted, render_until, render_with_progress};
use crate::settings::{IntegratorKind, Settings};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

fn settings(integrator: IntegratorKind) -> Settings {
    let mut s = Settings::default();
    s.image.width = 64;
    s.image.height = 48;
    s.sampling.spp = 64;
    s.paths.max_depth = 3;
    s.execution.integrator = integrator;
    s
}

#[test]
fn a_set_flag_stops_the_render_with_the_interrupted_error() {
    let scene = crate::load::default_scene();
    for integrator in [IntegratorKind::Wavefront, IntegratorKind::Recursive] {
        let s = settings(integrator);
        let (accel, _) = crate::accel::build(&scene, &s);
        let total = (s.image.width * s.image.height) as u64 * s.sampling.spp as u64;
        // Set once the first tenth of the samples is done: the render must end well short
        // of all of them, with the error the Python package turns into KeyboardInterrupt.
        let stop = AtomicBool::new(false);
        let done = AtomicU64::new(0);
        let tick = |n: u64| {
            if done.fetch_add(n, Ordering::Relaxed) + n >= total / 10 {
                stop.store(true, Ordering::Relaxed);
            }
        };
        let err = render_until(&scene, accel.as_ref(), &s, &tick, &stop).err().expect("stopped");
        // Recognised by type, as the Python package and the viewer recognise it.
        assert!(err.is::<Interrupted>(), "{integrator:?}: {err:#}");
        assert_eq!(err.downcast_ref::<Interrupted>(), Some(&Interrupted), "{integrator:?}");
        assert!(
            done.load(Ordering::Relaxed) < total / 2,
            "{integrator:?}: {} of {total}",
            done.load(Ordering::Relaxed)
        );
    }
}

#[test]
fn an_unset_flag_changes_nothing() {
    let scene = crate::load::default_scene();
    let mut s = settings(IntegratorKind::Wavefront);
    s.sampling.spp = 4;
    let (accel, _) = crate::accel::build(&scene, &s);
    let a = render_until(&scene, accel.as_ref(), &s, &|_| {}, &AtomicBool::new(false)).expect("renders");
    let b = render_with_progress(&scene, accel.as_ref(), &s, &|_| {}).expect("renders");
    assert_eq!(a.film.pixels, b.film.pixels);
}
