"""How many samples denoising saves, and what it costs: the figures of BENCHMARKS.md's
"Denoising" part (`tools/benchmarks.sh --parts denoise` runs this in a virtual environment
with numpy, OpenEXR and pyoidn).

For each scene (the e2e harness's, built by its `scenes.py`, and the project's own from
`tools/e2e_scenes.py`), the binary renders a converged reference and a ladder of sample
counts with `--denoise` (one render gives both pictures: the denoised one and, as the `noisy`
layer of its EXR, the raw one). Errors are mean squared errors against the reference over all
pixels and channels as relative MSE, (x - ref)^2 / (ref^2 + 0.01) (Rousselle et al. 2011's
metric: an emitter's bright edge does not outweigh the rest of the image), less the
reference's own noise (its `variance` output variable, weighted alike). The denoised error is biased (it is measured against the converged
raw reference). For the raw image's error at 64 and 256 samples, the samples the denoised
image needs for the same error come from log-log interpolation on its ladder.
"""

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import time

import numpy as np
import OpenEXR

HERE = os.path.dirname(os.path.abspath(__file__))


def read_layers(path):
    """{layer: (h, w, c) float64} of an EXR the binary wrote ("" for the picture)."""
    with OpenEXR.File(path, separate_channels=True) as f:
        ch = {k: v.pixels for k, v in f.channels().items()}
    layers = {}
    for name in sorted(ch):
        layer, _, c = name.rpartition(".")
        layers.setdefault(layer, []).append((c, ch[name]))
    order = {"R": 0, "G": 1, "B": 2, "X": 0, "Y": 1, "Z": 2}
    return {k: np.stack([p for _, p in sorted(v, key=lambda cp: order.get(cp[0], 9))], axis=2).astype(np.float64)
            for k, v in layers.items()}


def run(cmd):
    t = time.time()
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed:\n{p.stderr}")
    return time.time() - t, p.stderr


REL_EPS = 0.01


def rel_mse(img, ref, ref_var):
    """Relative MSE of `img` against `ref`, less the reference's own share (`ref_var`: its
    variance of the mean per pixel and channel)."""
    w = 1.0 / (ref * ref + REL_EPS)
    return max(float(np.mean((img - ref) ** 2 * w)) - float(np.mean(ref_var * w)), 0.0)


def samples_for(target, ladder, errors):
    """Samples at which `errors` (over `ladder`) reaches `target` by log-log interpolation;
    (value, how): how is "" (interpolated), "<=" (already at the first rung) or None (never)."""
    pts = [(n, e) for n, e in zip(ladder, errors) if e > 0]
    if not pts:
        return None, None
    if pts[0][1] <= target:
        return pts[0][0], "<="
    for (n0, e0), (n1, e1) in zip(pts, pts[1:]):
        if e1 <= target:
            a = (math.log(target) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(n0) + a * (math.log(n1) - math.log(n0))), ""
    return None, None


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin", required=True)
    ap.add_argument("--oidn", required=True, help="pyoidn's folder (or the library)")
    ap.add_argument("--e2e", required=True, help="the e2e harness folder (its scenes.py)")
    ap.add_argument("--scenes-dir", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--scenes", default="box,dragon-box,spheres-box,dragon-env")
    ap.add_argument("-r", nargs=2, type=int, default=[320, 240])
    ap.add_argument("-m", type=int, default=5)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--ref-spp", type=int, default=4096)
    ap.add_argument("--ladder", default="1,2,4,8,16,32,64,128,256")
    ap.add_argument("--big", nargs=2, type=int, default=[1920, 1080], help="size of the denoise-cost render")
    ap.add_argument("--out", required=True)
    a = ap.parse_args(argv)
    os.environ["E2E_SCENES_DIR"] = a.scenes_dir
    os.environ["E2E_EXTRA_SCENES"] = os.path.join(HERE, "e2e_scenes.py")
    sys.path.insert(0, a.e2e)
    sys.dont_write_bytecode = True
    import scenes  # noqa: E402 (the harness's module, found through --e2e)

    os.makedirs(a.work, exist_ok=True)
    w, h = a.r
    ladder = [int(x) for x in a.ladder.split(",")]
    common = ["-m", str(a.m), "-r", str(w), str(h), "-t", str(a.threads)]
    result = {"width": w, "height": h, "m": a.m, "threads": a.threads, "ref_spp": a.ref_spp, "ladder": ladder,
              "scenes": []}
    for name in a.scenes.split(","):
        spec = scenes.build(name, a.bin, a.work)
        base = [a.bin] + scenes.wavepath_args(spec, w, h) + [spec["wavepath_scene_abs"]] + common
        ref_path = os.path.join(a.work, f"ref-{name}-{a.ref_spp}-{w}x{h}-m{a.m}.exr")
        if not os.path.exists(ref_path):
            print(f"[denoise] {name}: reference, {a.ref_spp} spp", file=sys.stderr, flush=True)
            run(base + ["-s", str(a.ref_spp), "--aov", "variance", "-f", ref_path])
        ref = read_layers(ref_path)
        ref_img, ref_var = ref[""], ref["variance"]
        rows = []
        for n in ladder:
            out, stats = os.path.join(a.work, f"{name}-{n}.exr"), os.path.join(a.work, f"{name}-{n}.json")
            run(base + ["-s", str(n), "--denoise", "--oidn", a.oidn, "-f", out, "--stats", stats])
            layers = read_layers(out)
            with open(stats) as f:
                st = json.load(f)
            rows.append({"spp": n, "raw": rel_mse(layers["noisy"], ref_img, ref_var),
                         "denoised": rel_mse(layers[""], ref_img, ref_var),
                         "render_s": st["render_s"], "denoise_s": st["denoise_s"]})
            print(f"[denoise] {name} {n:4d} spp: raw {rows[-1]['raw']:.3e}, denoised {rows[-1]['denoised']:.3e} "
                  f"(denoise {st['denoise_s']:.3f} s)", file=sys.stderr, flush=True)
        ref_share = float(np.mean(ref_var / (ref_img * ref_img + REL_EPS)))
        s = {"scene": name, "ref_rel_mse": ref_share, "rows": rows,
             "targets": []}
        for at in (64, 256):
            if at not in ladder:
                continue
            target = next(r["raw"] for r in rows if r["spp"] == at)
            need, how = samples_for(target, ladder, [r["denoised"] for r in rows])
            s["targets"].append({"raw_spp": at, "raw_error": target, "denoised_spp": need, "how": how})
        result["scenes"].append(s)
    # What denoising costs at two sizes (the first scene; 1 spp: the denoiser's time does not
    # depend on the samples).
    name = a.scenes.split(",")[0]
    spec = scenes.build(name, a.bin, a.work)
    cost = {}
    for (cw, ch) in ((w, h), tuple(a.big)):
        times = []
        for rep in range(3):
            stats = os.path.join(a.work, f"cost-{cw}x{ch}.json")
            cmd = ([a.bin] + scenes.wavepath_args(spec, cw, ch) + [spec["wavepath_scene_abs"], "-m", str(a.m), "-r",
                   str(cw), str(ch), "-t", str(a.threads), "-s", "1", "--denoise", "--oidn", a.oidn, "-f",
                   os.path.join(a.work, "cost.exr"), "--stats", stats])
            run(cmd)
            with open(stats) as f:
                times.append(json.load(f)["denoise_s"])
        cost[f"{cw}x{ch}"] = {"median_s": statistics.median(times), "all_s": times}
    result["cost"] = {"scene": name, **cost}
    with open(a.out, "w") as f:
        json.dump(result, f, indent=1)


if __name__ == "__main__":
    main(sys.argv[1:])
