"""Renders from Python are the command line's renders: same settings, same bits."""

import numpy as np
import pytest

import wavepath
from conftest import read_pfm


def cli_render(cli, tmp_path, scene_args, flags):
    out = tmp_path / "cli.pfm"
    cli(*scene_args, *flags, "-f", out)
    return read_pfm(out)


def test_default_scene_matches_command_line_bit_for_bit(cli, tmp_path):
    image, stats = wavepath.default_scene().render(resolution=(48, 36), spp=4, max_depth=3, seed=7)
    expected = cli_render(cli, tmp_path, [], ["-r", 48, 36, "-s", 4, "-m", 3, "--seed", 7])
    assert image.shape == (36, 48, 3) and image.dtype == np.float32
    assert np.array_equal(image, expected)
    assert stats["spp"] == 4 and stats["width"] == 48 and stats["height"] == 36
    assert stats["rays"]["camera"] == 48 * 36 * 4 and stats["rays"]["total"] > stats["rays"]["camera"]


def test_defaults_are_the_command_lines(cli, tmp_path):
    # Nothing given but the size: the command line's defaults for the scene's dialect.
    image, _ = wavepath.default_scene().render(resolution=(32, 24))
    assert np.array_equal(image, cli_render(cli, tmp_path, [], ["-r", 32, 24]))


@pytest.mark.parametrize(
    "kwargs,flags",
    [
        (dict(sampler="sobol", light_samples=2, max_depth=4), ["--sampler", "sobol", "-l", 2, "-m", 4]),
        (dict(roulette="throughput", max_depth=6, rr_depth=2), ["--roulette", "throughput", "-m", 6, "--rr-depth", 2]),
        (dict(hemisphere=True, mis=False, max_depth=1), ["-H", "--no-mis", "-m", 1]),
        (dict(integrator="recursive", max_depth=3), ["--integrator", "recursive", "-m", 3]),
        (dict(integrator="bdpt", max_depth=3), ["--integrator", "bdpt", "-m", 3]),
        (dict(integrator="vcm", max_depth=3), ["--integrator", "vcm", "-m", 3]),
        (dict(integrator="path+light", light_paths=0.5, max_depth=3), ["--integrator", "path+light", "--light-paths", 0.5, "-m", 3]),
        (dict(adaptive=(4, 0.05), spp=16, max_depth=2), ["-a", 4, 0.05, "-s", 16, "-m", 2]),
        (dict(shading="normals"), ["--shading", "normals"]),
        (dict(isa="scalar", max_depth=2), ["--isa", "scalar", "-m", 2]),
        (dict(fov="frame", max_depth=2), ["--fov", "frame", "-m", 2]),
        (dict(accumulate=False, max_depth=3), ["-o", 0, "-m", 3]),
    ],
)
def test_options_match_their_flags(cli, tmp_path, scenes, kwargs, flags):
    path = scenes / "cs184" / "sky" / "CBspheres_lambertian.dae"
    image, _ = wavepath.load(path).render(resolution=(40, 30), spp=kwargs.pop("spp", 2), seed=3, **kwargs)
    spp = flags[flags.index("-s") + 1] if "-s" in flags else 2
    rest = [f for i, f in enumerate(flags) if not (f == "-s" or (i > 0 and flags[i - 1] == "-s"))]
    expected = cli_render(cli, tmp_path, [path], ["-r", 40, 30, "-s", spp, "--seed", 3, *rest])
    assert np.array_equal(image, expected)


def test_auto_chooses_path_light_for_caustics(cli, tmp_path, scenes):
    # Mirror and glass spheres under emissive triangles: the default (auto) traces light paths
    # for the caustics, as the command line does, and says so in the stats.
    path = scenes / "obj" / "CornellBox" / "CornellBox-Sphere.obj"
    image, stats = wavepath.load(path).render(resolution=(40, 30), spp=2, max_depth=5, seed=3)
    assert stats["integrator"]["name"] == "path+light"
    assert "light_paths" in stats["stages"]
    expected = cli_render(cli, tmp_path, [path], ["-r", 40, 30, "-s", 2, "-m", 5, "--seed", 3])
    assert np.array_equal(image, expected)


def test_mesh_file_matches_command_line(cli, tmp_path, scenes):
    # A standard-dialect file (OBJ: Sobol, throughput roulette) lit by the default sky.
    path = scenes / "meshes" / "suzanne.obj"
    image, stats = wavepath.load(path).render(resolution=(40, 30), spp=3, max_depth=3)
    assert stats["dialect"] == "standard"
    assert np.array_equal(image, cli_render(cli, tmp_path, [path], ["-r", 40, 30, "-s", 3, "-m", 3]))


def test_threads_do_not_change_the_image():
    scene = wavepath.default_scene()
    one, _ = scene.render(resolution=(40, 30), spp=4, max_depth=3, threads=1)
    two, _ = scene.render(resolution=(40, 30), spp=4, max_depth=3, threads=2)
    assert np.array_equal(one, two)


def test_camera_override_is_for_one_render_only():
    scene = wavepath.default_scene()
    before, _ = scene.render(resolution=(24, 18), spp=1)
    moved, _ = scene.render(resolution=(24, 18), spp=1, camera={"eye": (0, 0.75, 3), "target": (0, 0.75, 0), "fov": 60})
    after, _ = scene.render(resolution=(24, 18), spp=1)
    assert not np.array_equal(before, moved)
    assert np.array_equal(before, after)


def test_stats_are_the_command_lines(cli, tmp_path):
    stats_file = tmp_path / "stats.json"
    _, stats = wavepath.default_scene().render(resolution=(32, 24), spp=2, max_depth=3)
    cli("-r", 32, 24, "-s", 2, "-m", 3, "-f", tmp_path / "x.pfm", "--stats", stats_file)
    import json

    expected = json.loads(stats_file.read_text())
    # Timings differ run to run; the counts and choices must not.
    for key in ("rays", "effects", "samples_per_pixel", "sampler", "roulette", "invalid_samples"):
        assert stats[key] == expected[key], key
    assert stats["mrays_per_s"] > 0
    assert any("rays" in line.lower() for line in stats["log"])
    assert set(stats["stages"]) == set(expected["stages"])


def test_no_nan_or_inf_in_images(scenes):
    for name in ("CBspheres.dae", "CBbunny.dae"):
        image, stats = wavepath.load(scenes / "cs184" / "sky" / name).render(resolution=(32, 24), spp=2, max_depth=4)
        assert np.isfinite(image).all() and stats["invalid_samples"] == 0
