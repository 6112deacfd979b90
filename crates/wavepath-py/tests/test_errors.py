"""Bad input raises the right exception with the command line's one-line message; the
interpreter never crashes."""

import numpy as np
import pytest

import wavepath

TRI_V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
TRI_F = np.array([[0, 1, 2]])


def test_missing_file_is_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError, match="nothere.obj: cannot open"):
        wavepath.load(tmp_path / "nothere.obj")


def test_malformed_files_are_value_errors_naming_the_file(tmp_path, cli):
    bad_obj = tmp_path / "bad.obj"
    bad_obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    bad_dae = tmp_path / "bad.dae"
    bad_dae.write_text("<COLLADA><library_geometries>")
    nan_ply = tmp_path / "nan.ply"
    nan_ply.write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                       "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n")
    for f in (bad_obj, bad_dae, nan_ply, tmp_path / "scene.xyz"):
        if not f.exists():
            f.write_text("x")
        with pytest.raises(ValueError) as e:
            wavepath.load(f)
        msg = str(e.value)
        assert str(f) in msg and "\n" not in msg
        # The command line says the same thing.
        p = cli(f, "-r", 8, 6, "-f", f.with_suffix(".png"), check=False)
        assert p.returncode != 0 and msg in p.stderr


@pytest.mark.parametrize(
    "vertices,faces,message",
    [
        (np.zeros((3, 2)), TRI_F, r"vertices must have shape \(n, 3\), got shape \(3, 2\)"),
        (np.zeros(9), TRI_F, r"vertices must have shape \(n, 3\), got shape \(9,\)"),
        (TRI_V.astype(complex), TRI_F, "vertices must be a float32 or float64 array"),
        (np.array([[0, 0, 0], [np.nan, 0, 0], [0, 1, 0]]), TRI_F, "vertex 1 has a non-finite coordinate"),
        (TRI_V, np.array([[0, 1, 3]]), "triangle 0 uses vertex 3, but there are only 3"),
        (TRI_V, np.array([[0, -1, 2]]), "faces: row 0 holds -1, not an index"),
        (TRI_V, np.array([[0.0, 1.0, 2.0]]), "faces must be an integer array"),
        (TRI_V, np.zeros((0, 3), int), "no triangles and no spheres"),
        (TRI_V, np.array([0, 1, 2]), r"faces must have shape \(m, 3\)"),
    ],
)
def test_bad_arrays_are_value_errors(vertices, faces, message):
    with pytest.raises(ValueError, match=message):
        wavepath.Scene.from_arrays(vertices, faces)


def test_bad_materials_lights_and_ids():
    with pytest.raises(ValueError, match='unknown key "colour"'):
        wavepath.Scene.from_arrays(TRI_V, TRI_F, materials=[{"type": "diffuse", "colour": (1, 0, 0)}])
    with pytest.raises(ValueError, match='unknown type "velvet"'):
        wavepath.Scene.from_arrays(TRI_V, TRI_F, materials=[{"type": "velvet"}])
    with pytest.raises(ValueError, match="uses material 1, but there are only 1"):
        wavepath.Scene.from_arrays(TRI_V, TRI_F, material_ids=[1])
    with pytest.raises(ValueError, match='needs "intensity"'):
        wavepath.Scene.from_arrays(TRI_V, TRI_F, lights=[{"type": "point", "position": (0, 0, 1)}])
    with pytest.raises(ValueError, match='"radiance" is not finite'):
        wavepath.Scene.from_arrays(TRI_V, TRI_F, lights=[{"type": "sky", "radiance": float("nan")}])


def test_bad_rays_are_value_errors():
    scene = wavepath.Scene.from_arrays(TRI_V, TRI_F)
    o = np.zeros((4, 3), np.float32)
    d = np.tile(np.float32([0, 0, -1]), (4, 1))
    with pytest.raises(ValueError, match="origins has 4 rows but directions has 3"):
        scene.intersect(o, d[:3])
    with pytest.raises(ValueError, match=r"directions must have shape \(n, 3\)"):
        scene.intersect(o, d[:, :2])
    with pytest.raises(ValueError, match=r"tmax must be a number or have shape \(4,\)"):
        scene.intersect(o, d, tmax=np.ones(3))
    bad = d.copy()
    bad[2] = np.nan
    with pytest.raises(ValueError, match="ray 2 is not a ray"):
        scene.intersect(o, bad)
    bad[2] = 0
    with pytest.raises(ValueError, match="ray 2 is not a ray"):
        scene.occluded(o, bad)


@pytest.mark.parametrize(
    "kwargs,message",
    [
        (dict(spp=0), r"spp \(samples per pixel\) must be between 1 and 1048576, got 0"),
        (dict(resolution=(0, 10)), r"resolution \(image width\) must be between 1 and 32768, got 0"),
        (dict(resolution=(32768, 32768)), "more than the limit"),
        (dict(max_depth=-1), "max_depth"),
        (dict(rr=1.5), r"rr \(continue probability\) must be in \(0, 1\], got 1.5"),
        (dict(sampler="halton"), "sampler must be"),
        (dict(adaptive=(0, 0.1)), r"adaptive \(batch size\)"),
        (dict(lens_radius=-1.0), r"lens_radius \(lens radius\) must be a non-negative number"),
        (dict(fov="wide"), "fov must be cs184 or frame, got 'wide'"),
        (dict(camera={"eye": (0, 0, 1), "target": (0, 0, 1)}), "the same point"),
        (dict(progress=3), "progress must be callable"),
    ],
)
def test_absurd_render_options_are_value_errors(kwargs, message):
    with pytest.raises(ValueError, match=message):
        wavepath.default_scene().render(**kwargs)


@pytest.mark.parametrize(
    "kwargs,flags,keyword,flag",
    [
        (dict(resolution=(0, 10)), ["-r", "0", "10"], "resolution", "-r"),
        (dict(resolution=(100000, 10)), ["-r", "100000", "10"], "resolution", "-r"),
        (dict(resolution=(20000, 20000)), ["-r", "20000", "20000"], "resolution", "-r"),
        (dict(rr=1.5), ["--rr", "1.5"], "rr", "--rr"),
        (dict(spp=0), ["-s", "0"], "spp", "-s"),
        (dict(max_depth=-1), ["-m", "-1"], "max_depth", "-m"),
        (dict(adaptive=(64, -1.0)), ["-a", "64", "-1"], "adaptive", "-a"),
        (dict(sampler="halton"), ["--sampler", "halton"], "sampler", "--sampler"),
        (dict(shading="wireframe"), ["--shading", "wireframe"], "shading", "--shading"),
    ],
)
def test_a_bad_value_gets_the_command_lines_message(cli, tmp_path, kwargs, flags, keyword, flag):
    """The engine checks both front ends' values: the same message, but for the option's name."""
    p = cli(*flags, "-f", tmp_path / "x.png", check=False)
    assert p.returncode != 0, p.stderr
    line = p.stderr.strip()
    assert "\n" not in line, line
    message = line.removeprefix("error: ").removesuffix(" (see wavepath --help)")
    with pytest.raises(ValueError) as raised:
        wavepath.default_scene().render(**kwargs)
    assert str(raised.value).replace(keyword, flag, 1) == message
