"""Scenes from arrays render what their values say (closed forms), and load as the command line."""

import types

import numpy as np

import wavepath


def quad(y=0.0, size=50.0, up=True):
    v = np.array([[-size, y, -size], [size, y, -size], [size, y, size], [-size, y, size]], np.float32)
    f = np.array([[0, 2, 1], [0, 3, 2]]) if up else np.array([[0, 1, 2], [0, 2, 3]])
    return v, f


def test_diffuse_plane_under_the_sky_shows_its_albedo():
    # A Lambertian plane of albedo a under unit radiance from the upper hemisphere reflects
    # L = a/pi * integral(cos) = a, whatever the sampling (direct light only, depth 1).
    v, f = quad()
    albedo = np.array([0.7, 0.4, 0.2])
    scene = wavepath.Scene.from_arrays(
        v, f,
        materials=[{"type": "diffuse", "color": tuple(albedo)}],
        lights=[{"type": "sky", "radiance": 1.0}],
        camera={"eye": (0, 2, 0.01), "target": (0, 0, 0), "fov": 30},
    )
    image, stats = scene.render(resolution=(16, 16), spp=256, max_depth=1)
    mean = image.reshape(-1, 3).mean(0)
    # 65,536 samples: the standard error of the mean is well under 1%.
    assert np.allclose(mean, albedo, rtol=0.02), mean
    assert stats["invalid_samples"] == 0


def test_emitter_seen_directly_is_its_radiance_and_one_sided_by_default():
    v, f = quad()
    radiance = (2.0, 3.0, 4.0)
    cam_above = {"eye": (0, 2, 0.01), "target": (0, 0, 0), "fov": 20}
    cam_below = {"eye": (0, -2, 0.01), "target": (0, 0, 0), "fov": 20}
    scene = wavepath.Scene.from_arrays(v, f, materials=[{"type": "emitter", "radiance": radiance}], camera=cam_above)
    image, _ = scene.render(resolution=(8, 8), spp=1, max_depth=0)
    assert np.allclose(image, radiance)
    back, _ = scene.render(resolution=(8, 8), spp=1, max_depth=0, camera=cam_below)
    assert np.allclose(back, 0.0)
    two = wavepath.Scene.from_arrays(v, f, materials=[{"type": "emitter", "radiance": radiance, "two_sided": True}])
    both, _ = two.render(resolution=(8, 8), spp=1, max_depth=0, camera=cam_below)
    assert np.allclose(both, radiance)


def test_material_ids_pick_materials():
    v, f = quad()
    scene = wavepath.Scene.from_arrays(
        v, f, material_ids=np.array([0, 1], np.int32),
        materials=[{"type": "emitter", "radiance": 1.0}, {"type": "emitter", "radiance": 5.0}],
        camera={"eye": (0, 2, 0.0), "target": (0, 0, 0), "up": (0, 0, 1), "fov": 10},
    )
    rays = scene.primary_rays(8, 8)
    hits = scene.intersect(rays["origins"], rays["directions"])
    image, _ = scene.render(resolution=(8, 8), spp=1, max_depth=0)
    flat = np.flipud(image).reshape(-1, 3)[:, 0]  # rows bottom-up, as the rays
    assert set(np.unique(hits["prim"])) == {0, 1}
    assert np.allclose(flat, np.where(hits["prim"] == 0, 1.0, 5.0))


def test_trimesh_like_objects_and_round_trips(scenes):
    scene = wavepath.load(scenes / "meshes" / "bunny_69k.ply")
    mesh = types.SimpleNamespace(vertices=scene.vertices.astype(np.float64), faces=scene.faces.astype(np.int64))
    again = wavepath.Scene.from_arrays(mesh)
    assert again.triangle_count == scene.triangle_count > 60000
    rays = scene.diffuse_rays(48, 36)
    a = scene.intersect(rays["origins"], rays["directions"])
    b = again.intersect(rays["origins"], rays["directions"])
    assert np.array_equal(a["prim"], b["prim"]) and np.array_equal(a["t"], b["t"])


def test_load_options_and_scene_facts(scenes):
    path = scenes / "cs184" / "sky" / "CBspheres_lambertian.dae"
    scene = wavepath.load(path)
    assert scene.dialect == "cs184" and scene.sphere_count == 2 and scene.lights == ["area"]
    lo, hi = scene.bounds
    assert all(a < b for a, b in zip(lo, hi))
    both = wavepath.load(path, two_sided_emission=True, camera="file")
    assert "Scene(" in repr(both)
    sub = wavepath.load(scenes / "meshes" / "suzanne.obj", subdivide=1)
    assert sub.triangle_count == 4 * wavepath.load(scenes / "meshes" / "suzanne.obj").triangle_count
    info = scene.build()
    assert info["nodes"] > 0 and info["build_s"] >= 0
