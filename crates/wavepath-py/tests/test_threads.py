"""A render leaves the interpreter alive: other threads run, Ctrl-C stops it, progress is told."""

import _thread
import os
import signal
import threading
import time

import numpy as np
import pytest

import wavepath

# Long enough (a few seconds on 2 cores) that the checks below have time to act.
SLOW = dict(resolution=(320, 240), spp=256, max_depth=6)


def spin_during(call):
    """Runs `call` while another Python thread counts as fast as it can; returns how far it
    counted during the call and the call's seconds."""
    count = 0
    running = True

    def spin():
        nonlocal count
        while running:
            count += 1

    t = threading.Thread(target=spin)
    t.start()
    time.sleep(0.05)
    start = count
    t0 = time.perf_counter()
    call()
    elapsed = time.perf_counter() - t0
    during = count - start
    running = False
    t.join()
    return during, elapsed


def test_other_python_threads_run_during_a_render():
    during, elapsed = spin_during(
        lambda: wavepath.default_scene().render(resolution=(160, 120), spp=64, max_depth=4)
    )
    # Holding the GIL for the render would let the spinning thread count only in the
    # moments between calls; released, it counts all along (millions per second).
    assert elapsed > 0.2, "the render was too quick to tell"
    assert during > 50_000 * elapsed, f"only {during} increments in {elapsed:.2f} s"


@pytest.fixture
def ctrl_c_handled():
    """Python's own Ctrl-C handler for the test's duration. A shell without job control
    starts background commands with SIGINT ignored, and a Python started so installs no
    handler: Ctrl-C would never reach it, whatever the render does."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


@pytest.mark.parametrize("how", ["interrupt_main", "SIGINT"])
def test_ctrl_c_interrupts_a_render_within_a_second(how, ctrl_c_handled):
    fired = {}

    def interrupt():
        fired["at"] = time.perf_counter()
        if how == "SIGINT":
            # What a terminal's Ctrl-C sends: the signal itself, to this process.
            os.kill(os.getpid(), signal.SIGINT)
        else:
            _thread.interrupt_main()

    timer = threading.Timer(0.5, interrupt)
    t0 = time.perf_counter()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        wavepath.default_scene().render(**SLOW)
    end = time.perf_counter()
    timer.join()
    assert "at" in fired
    assert end - fired["at"] < 1.0, f"the render went on for {end - fired['at']:.2f} s after Ctrl-C"
    # The scene is still usable afterwards, camera and all.
    image, _ = wavepath.default_scene().render(resolution=(8, 6))
    assert np.isfinite(image).all()


def test_progress_is_reported_and_its_exception_stops_the_render():
    seen = []
    wavepath.default_scene().render(resolution=(160, 120), spp=32, max_depth=4, progress=lambda d, t: seen.append((d, t)))
    total = 160 * 120 * 32
    assert seen and all(t == total for _, t in seen)
    assert [d for d, _ in seen] == sorted(d for d, _ in seen)
    assert seen[-1][0] == total

    class Stop(Exception):
        pass

    def stop(done, total):
        raise Stop()

    t0 = time.perf_counter()
    with pytest.raises(Stop):
        wavepath.default_scene().render(**SLOW, progress=stop)
    assert time.perf_counter() - t0 < 1.5


def test_ray_queries_release_the_gil_too():
    scene = wavepath.default_scene()
    rays = scene.primary_rays(800, 600)
    o = np.repeat(rays["origins"], 8, axis=0)
    d = np.repeat(rays["directions"], 8, axis=0)
    during, elapsed = spin_during(lambda: scene.intersect(o, d, threads=1))
    assert during > 50_000 * elapsed, f"only {during} increments in {elapsed:.2f} s"


def test_queries_from_other_threads_during_a_render_wait_and_agree():
    # One scene, a render on this thread and ray queries on others: the queries wait for the
    # render's camera to be put back (no deadlock on the GIL) and see the scene unchanged.
    scene = wavepath.default_scene()
    rays = scene.primary_rays(64, 48)
    expected = scene.intersect(rays["origins"], rays["directions"])["prim"]
    results, errors = [], []

    def query():
        try:
            for _ in range(20):
                results.append(scene.intersect(rays["origins"], rays["directions"])["prim"])
                scene.primary_rays(8, 6)
        except Exception as e:  # pragma: no cover - reported below
            errors.append(e)

    threads = [threading.Thread(target=query) for _ in range(2)]
    for t in threads:
        t.start()
    image, _ = scene.render(resolution=(96, 72), spp=16, max_depth=3, progress=lambda d, t: None)
    for t in threads:
        t.join(timeout=30)
    assert not any(t.is_alive() for t in threads), "a query thread hung"
    assert not errors and len(results) == 40
    assert all(np.array_equal(r, expected) for r in results)
    assert np.isfinite(image).all()


def test_a_query_from_the_renders_own_callback_is_refused():
    scene = wavepath.default_scene()
    rays = scene.primary_rays(4, 3)

    def cb(done, total):
        scene.intersect(rays["origins"], rays["directions"])

    with pytest.raises(RuntimeError, match="being rendered"):
        scene.render(**SLOW, progress=cb)
    # And the scene works again once the render has ended.
    assert scene.intersect(rays["origins"], rays["directions"])["t"].shape == (12,)
