"""The project's own scenes for the end-to-end harness (`../shared/peers/e2e`), loaded through its
`E2E_EXTRA_SCENES` hook (`tools/benchmarks.sh` sets it):

    E2E_EXTRA_SCENES=tools/e2e_scenes.py ../shared/peers/e2e/run.sh --scenes dragon-env

`dragon-env` is how a scan is usually shown: the dragon standing on a large ground quad, lit only
by an HDR environment map (no emitters), seen from the front and a little above.
"""

import json
import os
import subprocess

import numpy as np

import scenes

ENVMAP = os.path.join(scenes.SCENES_DIR, "envmaps", "uffizi_1200x600.hdr")
# The ground: a square 20 units wide at y = 0 (the dragon is 1.5 long), light grey.
GROUND_HALF = 10.0


@scenes.scene("dragon-env", "dragon_100k (1.5 units long, Kd 0.8) on a 20x20 ground quad (Kd 0.3), lit only by "
              "envmaps/uffizi_1200x600.hdr; own camera in front, a little above; generated OBJ, 100,002 triangles")
def build_dragon_env(wavepath, out_dir):
    dp, dgroups, _ = scenes.parse_obj(scenes.DRAGON_OBJ)
    dt = np.concatenate([t for _, t in dgroups])
    d = dp.astype(np.float64)
    lo, hi = d.min(0), d.max(0)
    # As in dragon-box: 1.5 units long, centred, feet 1 mm above the ground.
    s = 1.5 / (hi[0] - lo[0])
    d = (d - np.array([(lo[0] + hi[0]) / 2, lo[1], (lo[2] + hi[2]) / 2])) * s
    d[:, 1] += 1e-3
    g = GROUND_HALF
    ground = np.array([[-g, 0.0, -g], [-g, 0.0, g], [g, 0.0, g], [g, 0.0, -g]], dtype=np.float32)
    # Wound to face up (+Y), split into two triangles.
    gt = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int64)
    parts = [("ground", "ground", ground, gt), ("dragon", "dragon", d.astype(np.float32), dt)]
    mats = {"ground": {"kd": [0.3, 0.3, 0.3], "ke": [0.0, 0.0, 0.0]},
            "dragon": {"kd": [0.8, 0.8, 0.8], "ke": [0.0, 0.0, 0.0]}}
    out_obj = os.path.join(out_dir, "dragon-env.obj")
    scenes.write_mtl(os.path.join(out_dir, "dragon-env.mtl"), mats)
    scenes.write_obj(out_obj, parts, "dragon-env.mtl")
    camera = scenes.look_at_camera((0.0, 0.9, 3.2), (0.0, 0.45, 0.0), 30.0)
    # wavepath lights an OBJ without emitters by a default sky unless it is given a map: the
    # harness reads the scene as wavepath renders it, with `-e`.
    info = scenes.wavepath_info
    scenes.wavepath_info = lambda wp, scene_file: info_with_map(wp, scene_file)
    try:
        return scenes.spec_from_obj(wavepath, "dragon-env", out_obj, out_dir, scenes.SCENES["dragon-env"][1],
                                    emitter_back_copy=False, camera=camera, envmap=ENVMAP)
    finally:
        scenes.wavepath_info = info


def info_with_map(wavepath, scene_file):
    out = subprocess.run([wavepath, "info", "--json", "-e", ENVMAP, scene_file], check=True,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True).stdout
    return json.loads(out[out.index("{"):])
