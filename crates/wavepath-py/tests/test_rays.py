"""Ray queries from numpy: the command line's hits, watertight, any layout of input."""

import numpy as np
import pytest

import wavepath
from conftest import read_hit_file, read_ray_file, write_ray_file


@pytest.mark.parametrize("kind", ["primary", "diffuse"])
def test_hits_identical_to_rays_trace(cli, tmp_path, scenes, kind):
    mesh = scenes / "meshes" / "bunny_69k.ply"
    rays_file, hits_file = tmp_path / "r.bin", tmp_path / "h.bin"
    cli("rays", "dump", mesh, "--out", rays_file, "--kind", kind, "-r", 160, 120)
    cli("rays", "trace", mesh, rays_file, "-t", 1, "-r", 1, "-o", hits_file)
    o, d, lo, hi = read_ray_file(rays_file)
    t, prim = read_hit_file(hits_file)
    hits = wavepath.load(mesh).intersect(o, d, lo, hi)
    assert np.array_equal(hits["prim"], prim)
    assert np.array_equal(hits["t"], t)
    assert (prim != wavepath.MISS).sum() > 200  # the rays do see the mesh


def test_ray_sets_match_rays_dump(cli, tmp_path, scenes):
    mesh = scenes / "meshes" / "bunny_69k.ply"
    scene = wavepath.load(mesh)
    for kind, rays in (("primary", scene.primary_rays(40, 30)), ("diffuse", scene.diffuse_rays(40, 30, seed=5))):
        f = tmp_path / f"{kind}.bin"
        cli("rays", "dump", mesh, "--out", f, "--kind", kind, "-r", 40, 30, "--seed", 5)
        o, d, lo, hi = read_ray_file(f)
        assert np.array_equal(rays["origins"], o) and np.array_equal(rays["directions"], d)
        assert np.array_equal(rays["tmin"], lo) and np.array_equal(rays["tmax"], hi)


def two_triangle_square():
    """The unit square in z = 0 as two triangles sharing the diagonal (0,0)-(1,1)."""
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], np.float64)
    f = np.array([[0, 1, 2], [0, 2, 3]])
    return wavepath.Scene.from_arrays(v, f)


def test_shared_edge_and_vertices_do_not_leak():
    scene = two_triangle_square()
    # Rays straight down through points of the shared diagonal, its end vertices, and the
    # outer edges: each must hit exactly one of the two triangles.
    s = np.linspace(0.0, 1.0, 1001)
    pts = np.concatenate([np.stack([s, s], 1), np.stack([s, np.zeros_like(s)], 1), np.stack([np.zeros_like(s), s], 1)])
    o = np.column_stack([pts, np.full(len(pts), 2.0)])
    d = np.tile([0.0, 0.0, -1.0], (len(pts), 1))
    hits = scene.intersect(o, d)
    assert (hits["prim"] != wavepath.MISS).all(), "a ray through a shared edge or vertex leaked"
    assert np.allclose(hits["t"], 2.0)


def test_grazing_and_tilted_rays_through_the_diagonal():
    scene = two_triangle_square()
    rng = np.random.default_rng(1)
    n = 20000
    s = rng.uniform(0.001, 0.999, n)
    target = np.column_stack([s, s, np.zeros(n)])
    # Directions from steep to 1e-3 rad above the plane, any azimuth.
    elev = rng.uniform(1e-3, np.pi / 2, n)
    az = rng.uniform(0, 2 * np.pi, n)
    d = np.column_stack([np.cos(elev) * np.cos(az), np.cos(elev) * np.sin(az), -np.sin(elev)])
    o = target - 0.5 * d
    hits = scene.intersect(o, d)
    assert (hits["prim"] != wavepath.MISS).all()
    assert np.allclose(hits["t"], 0.5, rtol=1e-4)


def test_barycentrics_normals_and_bounds():
    scene = two_triangle_square()
    o = np.array([[0.75, 0.25, 1.0], [0.25, 0.75, -3.0], [0.5, 0.2, 1.0], [2.0, 2.0, 1.0]], np.float32)
    d = np.array([[0, 0, -1], [0, 0, 2], [0, 0, -1], [0, 0, -1]], np.float32)
    hits = scene.intersect(o, d, normals=True)
    assert list(hits["prim"]) == [0, 1, 0, wavepath.MISS]
    # t is in units of the direction (the second ray's direction has length 2).
    assert np.allclose(hits["t"][:3], [1.0, 1.5, 1.0]) and np.isinf(hits["t"][3])
    # Point = (1-u-v) a + u b + v c on triangle (0,0),(1,0),(1,1): (0.75, 0.25) -> u=0.5, v=0.25.
    assert np.allclose(hits["uv"][0], [0.5, 0.25])
    assert np.allclose(hits["normal"][:3], [[0, 0, 1]] * 3)
    # tmax shorter than the hit, per ray; tmin past it.
    short = scene.intersect(o[:1], d[:1], tmax=np.array([0.5]))
    past = scene.intersect(o[:1], d[:1], tmin=1.5)
    assert short["prim"][0] == wavepath.MISS and past["prim"][0] == wavepath.MISS


def test_layouts_and_dtypes_give_the_same_hits(scenes):
    scene = wavepath.load(scenes / "meshes" / "bunny_69k.ply")
    rays = scene.diffuse_rays(64, 48)
    o, d = rays["origins"], rays["directions"]
    base = scene.intersect(o, d)
    for oo, dd in (
        (o.astype(np.float64), d.astype(np.float64)),
        (np.asfortranarray(o), np.asfortranarray(d)),
        # Columns of a wider array: strided rows.
        (np.hstack([o, d])[:, :3], np.hstack([o, d])[:, 3:]),
    ):
        h = scene.intersect(oo, dd)
        assert np.array_equal(h["prim"], base["prim"]) and np.array_equal(h["t"], base["t"])
    # A strided view (every other row) gives the hits of those rows.
    h = scene.intersect(o[::2], d[::2])
    assert np.array_equal(h["prim"], base["prim"][::2])
    # One thread or all: the same hits.
    h = scene.intersect(o, d, threads=1)
    assert np.array_equal(h["prim"], base["prim"])


def test_occluded_agrees_with_intersect(scenes):
    scene = wavepath.load(scenes / "meshes" / "bunny_69k.ply")
    rays = scene.diffuse_rays(64, 48, seed=2)
    o, d = rays["origins"], rays["directions"]
    hits = scene.intersect(o, d)
    assert np.array_equal(scene.occluded(o, d), hits["prim"] != wavepath.MISS)
    # Bounded just short of each hit: nothing in the way (the closest hit is the first).
    hit = hits["prim"] != wavepath.MISS
    tmax = np.where(hit, hits["t"] * 0.999, np.inf).astype(np.float32)
    assert not scene.occluded(o[hit], d[hit], tmax=tmax[hit]).any()


def test_spheres_and_their_normals():
    v = np.array([[-5, -5, -1], [5, -5, -1], [0, 5, -1]], np.float32)
    scene = wavepath.Scene.from_arrays(v, [[0, 1, 2]], spheres=[{"center": (0, 0, 2), "radius": 0.5, "material": 0}])
    hits = scene.intersect([[0, 0, 5], [0, 0, 0.5]], [[0, 0, -1], [0, 0, -1]], normals=True)
    # Primitive ids: triangles first, then spheres.
    assert list(hits["prim"]) == [1, 0]
    assert np.allclose(hits["t"], [2.5, 1.5]) and np.allclose(hits["normal"][0], [0, 0, 1])


def test_huge_and_tiny_scales_stay_watertight():
    for scale in (1e-4, 1e4):
        v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], np.float64) * scale + np.array([1e3, -2e3, 5e2]) * scale
        scene = wavepath.Scene.from_arrays(v, [[0, 1, 2], [0, 2, 3]])
        s = np.linspace(0, 1, 501)
        pts = v[0, :2] + np.stack([s, s], 1) * scale
        o = np.column_stack([pts, np.full(len(s), v[0, 2] + scale)])
        hits = scene.intersect(o, np.tile([0, 0, -1.0], (len(s), 1)))
        assert (hits["prim"] != wavepath.MISS).all(), f"leak at scale {scale}"
