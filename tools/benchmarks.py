#!/usr/bin/env python3
"""Regenerate BENCHMARKS.md: current results of wavepath on this machine.

    tools/benchmarks.sh [--bin PATH] [--parts renders,peers,e2e,split,viewer,large,python,denoise] [--quick] [options]

The page is one section per part, each between `<!-- part:NAME -->` and `<!-- /part:NAME -->`
and each with the date, machine, binary and command it was measured with. A run replaces the
sections of the parts it ran and keeps the others as they are (`merge_page`; tested by
`python3 tools/test_benchmarks.py`).

Parts (default: renders,peers; e2e is opt-in, it takes 15-25 minutes):
  renders  a few fixed renders, each run as wavefront and as `--integrator recursive`,
           alternating fresh processes round by round; tabulated from `--stats` JSON
  peers    ray throughput beside Embree, tinybvh and obvhs in ../shared/peers/run.sh, with
           wavepath as an EXTRA_PEER (`wavepath rays trace`); several passes, ratios per pass
  e2e      whole renders against Mitsuba 3 at equal error (../shared/peers/e2e/run.sh)
  split    where a sample's time goes: wavepath's stages beside Mitsuba's Embree traversal and
           compiled kernels (`perf`), one thread, the e2e scenes (run after e2e)
  large    meshes at the size users have: Lucy subdivided (`wavepath subdivide`) to 1.6M and
           6.4M triangles (100k converted and 25.6M with --large-levels 0,2,3,4): load, BVH build and peak memory
           beside Embree's build (medium and high quality) on the same triangles, alternating
           fresh processes
  viewer   `wavepath view` timed by tools/view_timing.py (a client on the frame stream posting
           moves) against offline renders of the same settings
  python   ray casting from numpy through the Python package beside embreex, Open3D and Mitsuba 3
           (tools/python_bench.py, run by the interpreter `--python` names: one with numpy, the
           package and the peers installed)
  denoise  how many samples Open Image Denoise saves at the raw image's error at 64 and 256
           spp on the harness scenes and the environment-lit scan, and what denoising costs
           (tools/denoise_figures.py, in a virtual environment it makes with numpy, OpenEXR
           and pyoidn)

The peers folder is copied to a scratch folder (--work) first: its scripts write build
products beside themselves, and the shared copy must stay untouched.
Every table records its command, the machine, the load average before and after, and the
share of the CPUs other processes used during each run (`other_busy`, as the peers harness
measures it). Python 3 standard library only.
"""
import argparse
import datetime
import hashlib
import json
import os
import platform
import re
import resource
import shlex
import shutil
import statistics
import subprocess
import sys
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TICK = os.sysconf("SC_CLK_TCK")
NCPU = os.cpu_count() or 1

# name, scene file (relative to the scenes folder; None = the embedded default), flags, quick flags
RENDERS = [
    ("default", None, "-s 16 -l 4 -m 5", "-s 4 -l 4 -m 5"),
    ("CBspheres_lambertian", "cs184/sky/CBspheres_lambertian.dae", "-s 64 -l 4 -m 5 -r 480 360",
     "-s 16 -l 4 -m 5 -r 480 360"),
    ("CBbunny", "cs184/sky/CBbunny.dae", "-s 64 -l 4 -m 5 -r 480 360", "-s 16 -l 4 -m 5 -r 480 360"),
    ("CBlucy", "cs184/reconstructed/sky/CBlucy.dae", "-s 16 -l 4 -m 5 -r 480 360",
     "-s 4 -l 4 -m 5 -r 480 360"),
    # glTF files: metallic-roughness materials under emissive triangles or a sky light.
    ("CornellBox-gltf", "gltf/CornellBox-Original/CornellBox-Original.gltf", "-s 16 -l 4 -m 5 -r 480 360",
     "-s 4 -l 4 -m 5 -r 480 360"),
    ("BoxTextured", "gltf/BoxTextured.glb", "-s 16 -l 4 -m 5 -r 480 360", "-s 4 -l 4 -m 5 -r 480 360"),
    ("dragon_100k-gltf", "gltf/dragon_100k.glb", "-s 16 -l 4 -m 5 -r 480 360", "-s 4 -l 4 -m 5 -r 480 360"),
    ("BrainStem", "gltf/BrainStem.glb", "-s 16 -l 4 -m 5 -r 480 360", "-s 4 -l 4 -m 5 -r 480 360"),
    ("Box-gltf", "gltf/Box/Box.gltf", "-s 16 -l 4 -m 5 -r 480 360", "-s 4 -l 4 -m 5 -r 480 360"),
]
PEER_MESHES = ["meshes/lucy_100k.obj", "meshes/dragon_100k.obj"]
PEERS = ["embree:robust", "embree:single", "embree:packet16", "tinybvh:bvh8", "obvhs:cwbvh"]
# The Cornell box around the largest subdivided Lucy, rendered as the issue of large meshes asks.
LARGE_RENDER = ("cs184/reconstructed/sky/CBlucy.dae", "-s 16 -l 4 -m 5 -r 800 600")
STAGES = ["generate", "traverse", "shade", "shadow", "compact"]
LARGE_SOURCE = "meshes/lucy_100k.obj"
E2E_QUICK = "--scenes box -r 160 120 --ladder 1,4,16,64 --ref-spp 1024"
# The harness's front views (its own default leaves spheres-box out).
E2E_FRONT = "--scenes box,dragon-box,spheres-box"
# The harness's older scenes were made when wavepath's emitters were two-sided (their Mitsuba
# versions carry a back copy of each emitter): they compare like with like only so.
E2E_OLDER = "--scenes cornell,cornell-flush,cornell-dragon --wavepath-args=--two-sided-emission"
# The project's own harness scenes (tools/e2e_scenes.py, through the harness's E2E_EXTRA_SCENES):
# a scan under an environment map, how scans are usually shown.
E2E_OWN = "--scenes dragon-env"
E2E_OWN_FILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "e2e_scenes.py")
# Effects every global-illumination render of a lit scene has; the table lists the others.
COMMON_EFFECTS = {"emission", "area-lights", "direct-light", "indirect", "russian-roulette"}


def log(msg):
    print(f"[benchmarks] {msg}", file=sys.stderr, flush=True)


# ------------------------------------------------------------------ machine / noise ----
def busy_ticks():
    with open("/proc/stat") as f:
        v = [int(x) for x in f.readline().split()[1:]]
    return v[0] + v[1] + v[2] + v[5] + v[6] + (v[7] if len(v) > 7 else 0)


def busy_share(seconds):
    b0, t0 = busy_ticks(), time.monotonic()
    time.sleep(seconds)
    return (busy_ticks() - b0) / TICK / ((time.monotonic() - t0) * NCPU)


def wait_quiet(limit):
    """Wait up to `limit` seconds for a 1-second window in which the CPUs are < 10% busy."""
    start = time.monotonic()
    while limit > 0 and time.monotonic() - start < limit and busy_share(1.0) >= 0.10:
        pass
    return time.monotonic() - start


def loadavg():
    return os.getloadavg()[0]


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            info = f.read()
    except OSError:
        return platform.processor() or "unknown CPU", []
    model = next((l.split(":", 1)[1].strip() for l in info.splitlines() if l.startswith("model name")), "unknown CPU")
    flags = next((l.split(":", 1)[1].split() for l in info.splitlines() if l.startswith("flags")), [])
    return model, [f for f in ("avx2", "fma", "avx512f") if f in flags]


def mem_gib():
    try:
        with open("/proc/meminfo") as f:
            kb = int(f.readline().split()[1])
        return f"{kb / 2**20:.0f} GiB"
    except (OSError, ValueError, IndexError):
        return "?"


def sh(cmd, **kw):
    try:
        return subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                              check=True, **kw).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return ""


def now_utc():
    return datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")


def stamp(part):
    """One line naming the machine, the load before/after and the date of a part."""
    return (f"Machine: {MACHINE['cpu']}, {NCPU} cores; load average {part['load_before']:.2f} before, "
            f"{part['load_after']:.2f} after; {part['date']}; other processes used "
            f"{100 * part['busy_mean']:.0f}% of the CPUs on average during the runs "
            f"(max {100 * part['busy_max']:.0f}%).")


# -------------------------------------------------------------------- large ----
def peak_rss(cmd):
    """Runs cmd under wait4: (stdout, peak resident bytes)."""
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
    out = p.stdout.read()
    _, status, ru = os.wait4(p.pid, 0)
    p.returncode = os.waitstatus_to_exitcode(status)
    if p.returncode != 0:
        raise SystemExit(f"failed: {shlex.join(cmd)}")
    return out.decode(), ru.ru_maxrss * 1024


def ply_to_obj(src, dst):
    """The subdivided binary PLY (float x y z; uchar int indices) as OBJ for the Embree peer,
    floats printed exactly (%.9g)."""
    import struct
    with open(src, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    head = data[:end].decode().split("\n")
    nv = int(next(l for l in head if l.startswith("element vertex")).split()[2])
    nf = int(next(l for l in head if l.startswith("element face")).split()[2])
    with open(dst, "w", buffering=1 << 22) as o:
        o.writelines("v %.9g %.9g %.9g\n" % p for p in struct.iter_unpack("<3f", data[end:end + 12 * nv]))
        fb = data[end + 12 * nv:end + 12 * nv + 13 * nf]
        o.writelines("f %d %d %d\n" % (a + 1, b + 1, c + 1) for _, a, b, c in struct.iter_unpack("<B3i", fb))


def embree_peer(args, peers_dir, work):
    """The peers harness's Embree program, compiled here (Debian's libembree-dev), or None."""
    exe = os.path.join(work, "peer_embree")
    src = os.path.join(peers_dir, "cpp", "peer_embree.cpp")
    if os.access(exe, os.X_OK):
        return exe
    if not (os.path.exists(src) and os.path.exists("/usr/include/embree3/rtcore.h") and shutil.which("g++")):
        log("large: no Embree peer (needs ../shared/peers, g++ and libembree-dev); wavepath alone")
        return None
    subprocess.run(["g++", "-O3", "-march=native", "-std=c++17", "-I", os.path.dirname(src), src, "-o", exe,
                    "-lembree3", "-lpthread"], check=True)
    return exe


def part_large(args, scenes_dir, peers_dir):
    work = os.path.join(args.work, "large")
    os.makedirs(work, exist_ok=True)
    source = os.path.join(scenes_dir, LARGE_SOURCE)
    embree = embree_peer(args, peers_dir, work)
    part = {"load_before": loadavg(), "date": now_utc(), "rows": [], "source": LARGE_SOURCE,
            "embree": bool(embree)}
    for level in args.large_levels:
        ply = os.path.join(work, f"lucy_x{4 ** level}.ply")
        if not os.path.exists(ply):
            subprocess.run([args.bin, "subdivide", source, ply, "-n", str(level)], check=True,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        rays = os.path.join(work, f"rays_x{4 ** level}.bin")
        if not os.path.exists(rays):
            subprocess.run([args.bin, "rays", "dump", "--kind", "primary", "--out", rays, "-r", "64", "48", ply],
                           check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        obj = os.path.splitext(ply)[0] + ".obj"
        if not os.path.exists(obj):
            ply_to_obj(ply, obj)
        row = {"ply": ply, "bytes": os.path.getsize(ply), "obj_bytes": os.path.getsize(obj), "runs": []}
        for rnd in range(args.rounds):
            wait_quiet(args.wait_quiet)
            info = json.loads(peak_rss([args.bin, "info", "--json", ply])[0])
            obj_info = json.loads(peak_rss([args.bin, "info", "--json", obj])[0])
            out, rss = peak_rss([args.bin, "rays", "trace", ply, rays, str(args.threads), "1"])
            fast, fast_rss = peak_rss([args.bin, "rays", "trace", ply, rays, str(args.threads), "1", "--bvh-build", "fast"])
            run = {"round": rnd, "load_s": info["load_s"], "obj_load_s": obj_info["load_s"], "triangles": info["triangles"],
                   "build_s": json.loads(out)["build_s"], "rss": rss,
                   "fast_build_s": json.loads(fast)["build_s"], "fast_rss": fast_rss}
            if embree:
                for q in ("medium", "high"):
                    eo, erss = peak_rss([embree, obj, rays, str(args.threads), "1", "--quality", q])
                    run[f"embree_{q}_s"], run[f"embree_{q}_rss"] = json.loads(eo)["build_s"], erss
            log(f"large x{4 ** level} round {rnd}: load {run['load_s']:.3f} s build {run['build_s']:.2f} s "
                f"(fast {run['fast_build_s']:.2f} s) peak {rss / 2 ** 30:.2f} GiB" + (f"; embree medium {run['embree_medium_s']:.2f} s high "
                                                     f"{run['embree_high_s']:.2f} s" if embree else ""))
            row["runs"].append(run)
        part["rows"].append(row)
    part["renders"] = large_renders(args, scenes_dir, work)
    part["load_after"] = loadavg()
    if peers_dir and os.path.isfile(os.path.join(peers_dir, "run.sh")):
        plys = [r["ply"] for r in part["rows"]]
        part["peers"] = run_harness(args, peers_dir, plys, 1, 5, "peers-large.log")
    return part


LARGE_VARIANTS = (("sah", "auto"), ("sah", "corners"), ("fast", "auto"))


def large_renders(args, scenes_dir, work):
    """The Cornell box around the largest subdivided Lucy (`--subdivide`), with the BVH's
    builds and leaf layouts of `LARGE_VARIANTS`, alternating fresh processes: seconds to the
    first pixel (load, subdivision and build: the wall time before rendering starts), total
    seconds, peak memory, Mrays/s."""
    scene, flags = LARGE_RENDER
    path = os.path.join(scenes_dir, scene)
    level = max(args.large_levels)
    if not os.path.exists(path):
        log(f"large: no {scene}; render skipped")
        return []
    runs = []
    for rnd in range(args.rounds):
        for build, layout in LARGE_VARIANTS:
            wait_quiet(args.wait_quiet)
            stats = os.path.join(work, f"render-{build}-{layout}.json")
            cmd = [args.bin, path, "--subdivide", str(level), *flags.split(), "-t", str(args.threads),
                   "--bvh-build", build, "--bvh-leaves", layout,
                   "-f", os.path.join(work, f"cblucy-{build}-{layout}.png"), "--stats", stats]
            t0 = time.monotonic()
            _, rss = peak_rss(cmd)
            wall = time.monotonic() - t0
            with open(stats) as f:
                st = json.load(f)
            run = {"round": rnd, "build": build, "layout": layout, "wall": wall, "rss": rss, "render_s": st["render_s"],
                   "first_pixel": wall - st["render_s"], "build_s": st["bvh"]["build_s"],
                   "mrays": st["mrays_per_s"], "triangles": st["triangles"], "rays": st["rays"]["total"],
                   "mesh_bytes": st["mesh_bytes"], "node_bytes": st["bvh"]["node_bytes"],
                   "leaf_bytes": st["bvh"]["leaf_bytes"]}
            log(f"large render {build} {layout} round {rnd}: first pixel {run['first_pixel']:.1f} s, total {wall:.1f} s, "
                f"peak {rss / 2 ** 30:.2f} GiB, {run['mrays']:.2f} Mrays/s")
            runs.append(run)
    return [{"scene": scene, "flags": flags, "level": level, "runs": runs}]


def tri_count(n):
    """A triangle count as a table shows it: 100k, 1.6M."""
    return f"{n / 1e3:.0f}k" if n < 1e6 else f"{n / 1e6:.1f}M"


def md_large(args, part):
    med = statistics.median
    out = ["## Large meshes\n"]
    out.append(f"`{part['source']}` subdivided by `wavepath subdivide` (midpoints, shared edges: the same "
               f"surface) into binary PLY. Load: `wavepath info --json` `load_s` (read, parse, validate, "
               f"from the page cache, on all cores), of the PLY and of the same mesh as OBJ (written by "
               f"this script, `%.9g` coordinates). Build: `wavepath rays trace MESH RAYS {args.threads} 1` `build_s` "
               f"(8-wide BVH, {args.threads} threads) and the Embree peer's `build_s` on the same triangles "
               f"(OBJ), `--quality medium` and `high`; wavepath's leaves in the default layout (corners below 16M "
               f"primitives, packed from there), its default build (binned SAH) and, beside it, `--bvh-build fast` "
               f"(Morton order). Peak: the whole process's resident memory (the Embree "
               f"peer's includes its own OBJ arrays). Medians of {args.rounds} rounds of fresh processes, run "
               f"in turn; the ratio is Embree medium's build time over wavepath's per round (> 1: wavepath "
               f"builds faster).\n")
    cols = "| triangles | PLY MB | load s | load GB/s | OBJ MB | OBJ load s | OBJ MB/s | build s | fast build s | embree medium s | embree high s | ratio vs medium (per round) | peak GiB | B/tri | fast peak GiB | embree peak GiB |"
    out += [cols, "|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|---|--:|--:|--:|--:|"]
    for row in part["rows"]:
        r = row["runs"]
        tris = r[0]["triangles"]
        load = med([x["load_s"] for x in r])
        obj_load = med([x["obj_load_s"] for x in r])
        rss = med([x["rss"] for x in r])
        em = [x.get("embree_medium_s") for x in r]
        eh = [x.get("embree_high_s") for x in r]
        ratios = [x["embree_medium_s"] / x["build_s"] for x in r if "embree_medium_s" in x]
        erss = [x["embree_medium_rss"] for x in r if "embree_medium_rss" in x]
        out.append(f"| {tri_count(tris)} | {row['bytes'] / 1e6:.0f} | {load:.3f} | {row['bytes'] / load / 1e9:.2f} | "
                   f"{row['obj_bytes'] / 1e6:.0f} | {obj_load:.3f} | {row['obj_bytes'] / obj_load / 1e6:.0f} | "
                   f"{med([x['build_s'] for x in r]):.3g} | {med([x['fast_build_s'] for x in r]):.3g} | "
                   + (f"{med(em):.3g} | {med(eh):.3g} | {', '.join(f'{x:.2f}' for x in ratios)} | " if ratios else "- | - | - | ")
                   + f"{rss / 2 ** 30:.2f} | {rss / tris:.0f} | {med([x['fast_rss'] for x in r]) / 2 ** 30:.2f} | "
                   + (f"{med(erss) / 2 ** 30:.2f} |" if erss else "- |"))
    out.append("")
    out.append(f"Command: `tools/benchmarks.sh --parts large --large-levels {','.join(map(str, args.large_levels))}`.  ")
    out.append(f"Machine: {MACHINE['cpu']}, {NCPU} cores; load average {part['load_before']:.2f} before, "
               f"{part['load_after']:.2f} after; {part['date']}.\n")
    for r in part.get("renders", []):
        runs = r["runs"]
        tris = runs[0]["triangles"]
        out.append(f"### A Cornell box around the {tris / 1e6:.1f}M-triangle Lucy\n")
        out.append(f"`wavepath {args.scenes_shown}/{r['scene']} --subdivide {r['level']} {r['flags']} -t {args.threads} "
                   f"--bvh-build BUILD --bvh-leaves LAYOUT --stats` (glass Lucy, global illumination), alternating fresh processes, "
                   f"medians of {args.rounds}. First pixel: the wall time before rendering starts (load, "
                   f"subdivision, BVH build). Resident: the mesh, the tree's nodes and its leaves as the stats "
                   f"report them; peak: the whole process.\n")
        out.append("| build | leaves | first pixel s | of it BVH build s | render s | total s | Mrays/s | peak GiB | B/tri | mesh / nodes / leaves B/tri |")
        out.append("|---|---|--:|--:|--:|--:|--:|--:|--:|---|")
        for build, layout in LARGE_VARIANTS:
            # Runs recorded before the fast build existed carry no "build": they are SAH builds.
            sel = [x for x in runs if (x.get("build", "sah"), x["layout"]) == (build, layout)]
            if not sel:
                continue
            m = lambda k: statistics.median([x[k] for x in sel])
            out.append(f"| {build} | {layout} | {m('first_pixel'):.1f} | {m('build_s'):.1f} | {m('render_s'):.1f} | {m('wall'):.1f} | "
                       f"{m('mrays'):.2f} | {m('rss') / 2 ** 30:.2f} | {m('rss') / tris:.0f} | "
                       f"{sel[0]['mesh_bytes'] / tris:.1f} / {sel[0]['node_bytes'] / tris:.1f} / {sel[0]['leaf_bytes'] / tris:.1f} |")
        out.append("")
    if part.get("peers"):
        out += md_peers(args, part["peers"], None, title="### Ray throughput on the large meshes\n")
    return out


def timed(cmd, failure=None):
    """Runs cmd: (stdout, wall seconds, other processes' share of the CPUs meanwhile, its own CPU
    seconds); exits with `failure` (or the command) and its stderr's tail if it fails."""
    ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    b0, t0 = busy_ticks(), time.monotonic()
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    wall = time.monotonic() - t0
    busy = (busy_ticks() - b0) / TICK
    ru1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    own = (ru1.ru_utime - ru0.ru_utime) + (ru1.ru_stime - ru0.ru_stime)
    if p.returncode != 0:
        raise SystemExit(f"{failure or 'failed: ' + shlex.join(cmd)}\n{p.stderr[-2000:]}")
    return p.stdout, wall, max(0.0, busy - own) / (wall * NCPU), own


# ------------------------------------------------------------------ renders ----
def run_render(args, name, scene, flags, integrator, tmp):
    st = os.path.join(tmp, f"{name}-{integrator}.json")
    img = os.path.join(tmp, f"{name}-{integrator}.pfm")
    for f in (st, img):
        if os.path.exists(f):
            os.remove(f)
    cmd = [args.bin] + ([scene] if scene else []) + flags.split() + \
        ["-t", str(args.threads), "--integrator", integrator, "-f", img, "--stats", st]
    waited = wait_quiet(args.wait_quiet)
    _, wall, other_busy, own = timed(cmd, f"render failed: {shlex.join(cmd)}")
    with open(st) as f:
        stats = json.load(f)
    rec = {"scene": name, "integrator": integrator, "wall_s": wall, "cpu_s": own, "waited_s": waited,
           "other_busy": other_busy, "stats": stats}
    log(f"{name:22s} {integrator:9s} render {stats['render_s']:.3f} s  {stats['mrays_per_s']:.2f} Mrays/s  "
        f"wall {wall:.2f} s  others {100 * rec['other_busy']:.0f}%")
    return rec


def part_renders(args, scenes_dir):
    tmp = os.path.join(args.work, "renders")
    os.makedirs(tmp, exist_ok=True)
    todo = []
    for name, rel, flags, qflags in RENDERS:
        path = os.path.join(scenes_dir, rel) if rel else None
        if path and not os.path.exists(path):
            log(f"skip {name}: {path} not found")
            continue
        todo.append((name, path, qflags if args.quick else flags))
    part = {"load_before": loadavg(), "date": now_utc(), "runs": [], "todo": todo}
    for rnd in range(args.rounds):
        for name, path, flags in todo:
            order = ("wavefront", "recursive") if rnd % 2 == 0 else ("recursive", "wavefront")
            for integ in order:
                r = run_render(args, name, path, flags, integ, tmp)
                r["round"] = rnd
                part["runs"].append(r)
    part["load_after"] = loadavg()
    busy = [r["other_busy"] for r in part["runs"]] or [0.0]
    part["busy_mean"], part["busy_max"] = statistics.mean(busy), max(busy)
    return part


def fmt(x, nd=2):
    return "-" if x is None else f"{x:.{nd}f}"


def md_renders(args, part, scenes_dir):
    out = []
    rounds = args.rounds
    out.append("## Renders\n")
    out.append(f"Wavefront integrator, {args.threads} threads, best of {rounds} round{'s' if rounds > 1 else ''} by `render_s` "
               "(rendering only: no load, no BVH build). Stage times are thread-seconds summed over the "
               "workers (of the best run); tests and nodes are per ray (all rays). Every scene is shaded "
               "in lanes, by kind (docs/decisions.md, \"Shade in lanes\").\n")
    out.append("| scene | flags | other effects | rays (M) | render s | Mrays/s | " + " | ".join(STAGES) +
               " | tests / ray | nodes / ray | BVH build s |")
    out.append("|---|---|---|--:|--:|--:|" + "--:|" * len(STAGES) + "--:|--:|--:|")
    for name, path, flags in part["todo"]:
        runs = [r for r in part["runs"] if r["scene"] == name and r["integrator"] == "wavefront"]
        if not runs:
            continue
        b = min(runs, key=lambda r: r["stats"]["render_s"])["stats"]
        stages = [fmt(b["stages"].get(s)) for s in STAGES]
        other = [e for e in b.get("effects", []) if e not in COMMON_EFFECTS]
        out.append(f"| {name} | `{flags}` | {', '.join(other) or '-'} | {b['rays']['total'] / 1e6:.1f} | {b['render_s']:.3f} | "
                   f"{b['mrays_per_s']:.1f} | " + " | ".join(stages) +
                   f" | {b['intersection_tests_per_ray']:.2f} | {b['nodes_visited_per_ray']:.2f} | "
                   f"{b['bvh']['build_s']:.3f} |")
    out.append("")
    # The run the table shows per scene (least render time), its rays per second.
    best = {}
    for name, _, _ in part["todo"]:
        runs = [r for r in part["runs"] if r["scene"] == name and r["integrator"] == "wavefront"]
        if runs:
            best[name] = min(runs, key=lambda r: r["stats"]["render_s"])["stats"]["mrays_per_s"]
    if best.get("CBbunny"):
        out.append("Rays per second against CBbunny's (the runs shown): " + ", ".join(
            f"{name} {v / best['CBbunny']:.2f}x" for name, v in best.items() if name != "CBbunny") + ".\n")
    out.append(f"Command, per scene, run and integrator: `{args.bin_shown} [$S/SCENE] FLAGS -t {args.threads} "
               f"--integrator wavefront|recursive -f x.pfm --stats x.json` with `S={args.scenes_shown}` (scene files: "
               + ", ".join(f"`{os.path.relpath(p, scenes_dir)}`" if p else "default: embedded"
                           for _, p, _ in part["todo"]) + ").  ")
    out.append(stamp(part) + "\n")

    out.append("### Wavefront vs recursive\n")
    out.append(f"The same renders with `--integrator recursive` (the single-ray reference, same BVH), "
               f"each round running the two integrators back to back as fresh processes, the order "
               f"swapped every round. Ratio = recursive / wavefront per round (> 1: the wavefront is "
               f"faster), by `render_s` and by process wall time (load + build + render + write).\n")
    out.append("| scene | wavefront render s | recursive render s | ratio per round | median ratio | "
               "median wall ratio |")
    out.append("|---|---|---|---|--:|--:|")
    for name, _, _ in part["todo"]:
        w, rr, ratios, wall = [], [], [], []
        for rnd in range(rounds):
            a = [r for r in part["runs"] if r["scene"] == name and r["round"] == rnd]
            wf = next((r for r in a if r["integrator"] == "wavefront"), None)
            rc = next((r for r in a if r["integrator"] == "recursive"), None)
            if not (wf and rc):
                continue
            w.append(wf["stats"]["render_s"])
            rr.append(rc["stats"]["render_s"])
            ratios.append(rr[-1] / w[-1])
            wall.append(rc["wall_s"] / wf["wall_s"])
        if not ratios:
            continue
        out.append(f"| {name} | {', '.join(f'{x:.2f}' for x in w)} | {', '.join(f'{x:.2f}' for x in rr)} | "
                   f"{', '.join(f'{x:.2f}' for x in ratios)} | **{statistics.median(ratios):.2f}** | "
                   f"{statistics.median(wall):.2f} |")
    out.append("")
    out.append("Command: as above, alternating `--integrator wavefront` and `--integrator recursive`.  ")
    out.append(stamp(part) + "\n")
    return out


# ------------------------------------------------------------------ peers ----
def copy_tree(src, dst):
    """Copy src's files into dst (mtimes kept, so the harness rebuilds only what changed);
    build products already in dst stay; nothing to do when dst is src (a writable checkout)."""
    if os.path.realpath(src) == os.path.realpath(dst):
        return
    os.makedirs(dst, exist_ok=True)
    subprocess.run(["cp", "-a", "--no-preserve=ownership", os.path.join(src, "."), dst], check=True)
    subprocess.run(["chmod", "-R", "u+w", dst], check=True)


def part_peers(args, scenes_dir, peers_dir):
    meshes = [os.path.join(scenes_dir, m) for m in PEER_MESHES]
    meshes = [m for m in meshes if os.path.exists(m)]
    if not meshes:
        raise SystemExit(f"no peer meshes found under {scenes_dir}")
    return run_harness(args, peers_dir, meshes, args.peer_passes, args.reps, "peers.log")


def run_harness(args, peers_dir, meshes, passes, reps, log_name):
    """The peers harness on `meshes`, `passes` times: its result lines, tagged by pass."""
    work = args.peers_work
    copy_tree(peers_dir, work)
    threads = "1" if args.threads == 1 else f"1 {args.threads}"
    env_common = {
        "PEERS": " ".join(PEERS),
        "EXTRA_PEERS": f"wavepath={os.path.abspath(args.bin)} rays trace",
        "REPS": str(reps), "WARMUP": "1", "THREADS_LIST": threads,
        "WAIT_QUIET": str(int(args.wait_quiet)), "RERUN_NOISY": "0",
        "PEERS_BUILD": os.path.join(work, "build"),
    }
    part = {"load_before": loadavg(), "date": now_utc(), "rows": [], "meshes": meshes, "env": env_common,
            "passes": passes}
    logf = os.path.join(args.work, log_name)
    for p in range(passes):
        env = dict(os.environ, **env_common)
        env["SKIP_BUILD"] = "1" if (p > 0 or args.skip_build) else "0"
        log(f"peers harness pass {p + 1}/{passes} on {len(meshes)} meshes (log: {logf})")
        with open(logf, "a") as lf:
            r = subprocess.run([os.path.join(work, "run.sh")] + meshes, env=env, stdout=lf, stderr=lf,
                               cwd=work)
        if r.returncode != 0:
            raise SystemExit(f"peers harness failed (exit {r.returncode}); see {logf}")
        for m in meshes:
            name = os.path.splitext(os.path.basename(m))[0]
            with open(os.path.join(work, "build", "results", name + ".jsonl")) as f:
                for line in f:
                    if line.strip():
                        d = json.loads(line)
                        d["pass"] = p
                        part["rows"].append(d)
    part["load_after"] = loadavg()
    busy = [r.get("other_busy", 0.0) for r in part["rows"]] or [0.0]
    part["busy_mean"], part["busy_max"] = statistics.mean(busy), max(busy)
    return part


def md_peers(args, part, scenes_dir, title="## Ray throughput against the peers\n"):
    rows = [r for r in part["rows"] if not r.get("failed")]
    cols = PEERS + ["wavepath:-"]
    passes = part.get("passes", args.peer_passes)

    def label(c):
        return "wavepath" if c == "wavepath:-" else c.replace(":", " ")

    out = [title]
    out.append(f"Closest-hit rays of `wavepath rays trace` beside the peers in `../shared/peers/run.sh`, "
               f"same meshes and ray sets (primary: 800x600 camera rays; diffuse: one cosine bounce per "
               f"primary hit). Mrays/s, best of {part['env']['REPS']} timed passes per run and best of "
               f"{passes} harness pass{'es' if passes > 1 else ''}; the ratios are wavepath over the peer within one "
               f"pass (fresh processes run back to back), their median over passes with the range in "
               f"brackets. `hits`: wavepath's verdict against Embree's watertight `robust` variant; `/ embree robust` "
               f"compares with the one peer variant that asks for a watertight triangle test, as "
               f"wavepath's is (docs/decisions.md, \"Where the gap to the fastest peers is\").\n")
    out.append("| mesh, rays, threads | " + " | ".join(label(c) for c in cols) +
               " | / embree robust | / embree single | / embree packet16 | / obvhs cwbvh | / tinybvh bvh8 | hits |")
    out.append("|---|" + "--:|" * len(cols) + "--:|--:|--:|--:|--:|---|")
    keys = []
    for r in rows:
        k = (r["mesh"], r["set"], r["threads"])
        if k not in keys:
            keys.append(k)
    for mesh, set_, thr in keys:
        sel = [r for r in rows if (r["mesh"], r["set"], r["threads"]) == (mesh, set_, thr)]

        def best(c):
            peer, var = c.split(":")
            v = [r["mrays_per_s"] for r in sel if r["peer"] == peer and r["variant"] == var]
            return max(v) if v else None

        def ratio(c):
            peer, var = c.split(":")
            rs = []
            for p in sorted({r["pass"] for r in sel}):
                a = [r["mrays_per_s"] for r in sel if r["pass"] == p and r["peer"] == "wavepath"]
                b = [r["mrays_per_s"] for r in sel if r["pass"] == p and r["peer"] == peer and r["variant"] == var]
                if a and b:
                    rs.append(a[0] / b[0])
            if not rs:
                return "-"
            m = statistics.median(rs)
            return f"{m:.2f}" if len(rs) == 1 else f"{m:.2f} ({min(rs):.2f}-{max(rs):.2f})"

        verdicts = sorted({(r.get("compare") or {}).get("verdict", "?") for r in sel if r["peer"] == "wavepath"})
        busy = max(r.get("other_busy", 0) for r in sel)
        cells = []
        for c in cols:
            b = best(c)
            cells.append("-" if b is None else (f"**{b:.2f}**" if c == "wavepath:-" else f"{b:.2f}"))
        out.append(f"| {mesh} {set_} {thr}T{' !' if busy > 0.10 else ''} | " + " | ".join(cells) +
                   f" | {ratio('embree:robust')} | {ratio('embree:single')} | {ratio('embree:packet16')} | {ratio('obvhs:cwbvh')} | {ratio('tinybvh:bvh8')} | "
                   f"{', '.join(verdicts)} |")
    out.append("")
    out.append("`!`: other processes used more than 10% of the CPUs during some run of that row "
               "(treat it as a lower bound).  ")
    e = part["env"]
    meshes = " ".join(f"{args.scenes_shown}/{os.path.relpath(m, scenes_dir)}" if scenes_dir and m.startswith(scenes_dir)
                      else os.path.basename(m) for m in part["meshes"])
    times = "once" if passes == 1 else f"{passes} times"
    out.append(f"Command ({times}, in a scratch copy of `../shared/peers`): "
               f"`PEERS=\"{e['PEERS']}\" EXTRA_PEERS=\"wavepath={args.bin_shown} rays trace\" "
               f"REPS={e['REPS']} WARMUP={e['WARMUP']} THREADS_LIST=\"{e['THREADS_LIST']}\" "
               f"WAIT_QUIET={e['WAIT_QUIET']} RERUN_NOISY=0 ./run.sh {meshes}`.  ")
    out.append(stamp(part) + "\n")
    return out


# ------------------------------------------------------------------ e2e ----
def part_e2e(args, scenes_dir, peers_dir):
    work = args.peers_work
    copy_tree(peers_dir, work)
    # e2e/scenes.py reads the scenes at ../../scenes from its own folder: link them beside the copy.
    link = os.path.join(os.path.dirname(work), "scenes")
    if os.path.islink(link) and os.path.realpath(link) != scenes_dir:
        os.remove(link)
    if not os.path.lexists(link):
        os.symlink(scenes_dir, link)
    elif os.path.realpath(link) != scenes_dir:
        raise SystemExit(f"{link} exists and is not a link to {scenes_dir}; e2e needs it (or another --peers-work)")
    part = {"load_before": loadavg(), "date": now_utc(), "cmds": [], "rows": []}
    extra = ":".join(p for p in (os.environ.get("E2E_EXTRA_SCENES", ""), E2E_OWN_FILE) if p)
    env = dict(os.environ, WAVEPATH=os.path.abspath(args.bin), E2E_BUILD=os.path.join(work, "e2e", "build"),
               E2E_EXTRA_SCENES=extra)
    logf = os.path.join(args.work, "e2e.log")
    # One harness run per --e2e-args (the older scenes need their own wavepath options).
    with open(logf, "w") as lf:
        for k, e2e_args in enumerate(args.e2e_args):
            run_name = "benchmarks-" + datetime.datetime.now().strftime("%Y%m%d-%H%M%S") + f"-{k}"
            cmd = [os.path.join(work, "e2e", "run.sh"), "--threads", str(args.threads), "--run-name", run_name,
                   "--wait-quiet", str(int(args.wait_quiet))] + shlex.split(e2e_args)
            log(f"e2e comparison with Mitsuba 3, run {k + 1} of {len(args.e2e_args)} (log: {logf})")
            lf.flush()
            r = subprocess.run(cmd, env=env, stdout=lf, stderr=lf, cwd=REPO)
            if r.returncode != 0:
                raise SystemExit(f"e2e harness failed (exit {r.returncode}); see {logf}")
            with open(os.path.join(work, "e2e", "build", "results", run_name + ".jsonl")) as f:
                part["rows"] += [json.loads(l) for l in f if l.strip()]
            part["cmds"].append(cmd[1:])
    part["load_after"] = loadavg()
    busy = [r.get("other_busy", 0.0) for r in part["rows"] if r.get("kind") == "ladder"] or [0.0]
    part["busy_mean"], part["busy_max"] = statistics.mean(busy), max(busy)
    return part


def md_e2e(args, part):
    rows = part["rows"]
    out = ["## End to end against Mitsuba 3\n"]
    common = next((r for r in rows if r.get("kind") == "summary"), {})
    out.append(f"Whole renders at equal error ({common.get('width', '?')}x{common.get('height', '?')}, "
               f"-m {common.get('m', '?')}, {common.get('threads', '?')} threads): seconds each renderer "
               f"needs to reach the same relative RMSE against its own converged reference (`~`: "
               f"extrapolated). Speedup = Mitsuba seconds / wavepath seconds (> 1: wavepath faster), by "
               f"render time and by whole-process time (Mitsuba's includes Python start and import). "
               f"The harness runs each renderer's ladder as a block, not alternating, so on a busy machine "
               f"these ratios are the least reliable on this page (`--reps R` keeps the fastest of R).\n")
    out.append("| scene | target rel. RMSE | renderer | ms / spp | render s to target | speedup (render) | "
               "speedup (wall) | refs: mean lum. diff |")
    out.append("|---|--:|---|--:|--:|--:|--:|--:|")
    for s in (r for r in rows if r.get("kind") == "summary"):
        agree = next((r for r in rows if r.get("kind") == "agreement" and r["scene"] == s["scene"]), {})
        for n, d in s["renderers"].items():
            t = d.get("render_s_to_target")
            ts = "n/a" if t is None else ("~" if d.get("render_extrapolated") else "") + f"{t:.3f}"
            out.append(f"| {s['scene']} | {s['target_rel_rmse']:.3f} | {n} | {d['ms_per_spp']:.1f} | {ts} | "
                       f"{fmt(d.get('speedup_render'))} | {fmt(d.get('speedup_wall'))} | "
                       f"{100 * agree.get('mean_rel_diff_lum_masked', float('nan')):+.1f}% |")
    out.append("")
    for cmd in part["cmds"]:
        shown = [c for i, c in enumerate(cmd) if c != "--run-name" and cmd[i - 1] != "--run-name"]
        out.append(f"Command: `WAVEPATH={args.bin_shown} ../shared/peers/e2e/run.sh {shlex.join(shown)}` "
                   f"(in a scratch copy).  ")
    out.append(stamp(part) + "\n")
    return out


# ------------------------------------------------------------------- split ----
# The harness scenes, each with the wavepath options its comparison needs (as E2E_OLDER says).
SPLIT_SCENES = [("box", ""), ("dragon-box", ""), ("spheres-box", ""), ("cornell", "--two-sided-emission"),
                ("cornell-flush", "--two-sided-emission"), ("cornell-dragon", "--two-sided-emission"),
                ("dragon-env", "")]
SPLIT_FLAGS = "-s 64 -m 5 -r 320 240 -t 1"
PERF_HZ = 4000


def perf_split(report):
    """Seconds of Embree's closest-hit and any-hit traversal and of Dr.Jit's compiled kernels in a
    `perf report --sort dso,symbol -n` of a Mitsuba process (samples at PERF_HZ)."""
    out = {"intersect": 0, "occluded": 0, "jit": 0}
    for line in report.splitlines():
        m = re.match(r"\s*[\d.]+%\s+(\d+)\s+(.*)", line)
        if not m:
            continue
        n, rest = int(m.group(1)), m.group(2)
        if "embree" in rest and "::intersect" in rest:
            out["intersect"] += n
        elif "embree" in rest and "::occluded" in rest:
            out["occluded"] += n
        elif "[JIT]" in rest:
            out["jit"] += n
    return {k: v / PERF_HZ for k, v in out.items()}


def part_split(args, scenes_dir, peers_dir):
    """Where a sample's time goes, wavepath's stages beside Mitsuba's (`llvm_ad_rgb`): one thread,
    the e2e harness's scenes; Mitsuba's share in Embree and in its compiled kernels from `perf`."""
    build = os.path.join(args.peers_work, "e2e", "build")
    scenes, py = os.path.join(build, "scenes"), os.path.join(build, "venv", "bin", "python")
    render_py = os.path.join(args.peers_work, "e2e", "mitsuba_render.py")
    if not (os.path.isdir(scenes) and os.access(py, os.X_OK) and os.path.exists(render_py)):
        raise SystemExit(f"split: no e2e scenes or Mitsuba under {build}: run --parts e2e first (same --peers-work)")
    perf = shutil.which("perf")
    if not perf:
        raise SystemExit("split: needs `perf` (Debian: linux-perf) to see where Mitsuba's time goes")
    tmp = os.path.join(args.work, "split")
    os.makedirs(tmp, exist_ok=True)
    part = {"load_before": loadavg(), "date": now_utc(), "runs": []}
    for rnd in range(args.rounds):
        for name, extra in SPLIT_SCENES:
            d = os.path.join(scenes, name)
            if not os.path.exists(os.path.join(d, "spec.json")):
                log(f"split: skip {name}: not built")
                continue
            with open(os.path.join(d, "spec.json")) as f:
                spec = json.load(f)
            cam = os.path.join(d, "camera.txt")
            stats = os.path.join(tmp, "wavepath.json")
            envmap = spec.get("envmap", {}).get("file")
            wp = ([args.bin] + (["-c", cam] if os.path.exists(cam) else []) +
                  (["-e", os.path.normpath(os.path.join(d, envmap))] if envmap else []) +
                  [os.path.normpath(os.path.join(d, spec["wavepath_scene"]))] + SPLIT_FLAGS.split() +
                  extra.split() + ["-f", os.path.join(tmp, "wavepath.pfm"), "--stats", stats])
            mi = [py, render_py, "--spec", os.path.join(d, "spec.json"), "--variant", "llvm_ad_rgb", "-r", "320",
                  "240", "-m", "5", "--spp", "64", "--threads", "1", "--seed", "0", "--out",
                  os.path.join(tmp, "mitsuba.npy")]
            data = os.path.join(tmp, "perf.data")
            perf_mi = [perf, "record", "-q", "-F", str(PERF_HZ), "-e", "cpu-clock", "-o", data] + mi
            rec = {"scene": name, "round": rnd, "busy": []}
            for which in (("wp", "mi", "perf") if rnd % 2 == 0 else ("mi", "perf", "wp")):
                wait_quiet(args.wait_quiet)
                if which == "wp":
                    _, _, busy, _ = timed(wp)
                    with open(stats) as f:
                        st = json.load(f)
                    rec["wp"] = {"render_s": st["render_s"], **{k: st["stages"].get(k, 0.0) for k in STAGES}}
                elif which == "mi":
                    out, _, busy, _ = timed(mi)
                    rec["mi_render_s"] = json.loads(out.strip().splitlines()[-1])["render_s"]
                else:
                    out, _, busy, _ = timed(perf_mi)
                    rec["mi_perf_render_s"] = json.loads(out.strip().splitlines()[-1])["render_s"]
                    rep = sh([perf, "report", "-i", data, "--no-children", "--sort", "dso,symbol", "-n"])
                    rec["mi_split"] = perf_split(rep)
                rec["busy"].append(busy)
            log(f"split {name:15s} wavepath {rec['wp']['render_s']:.3f} s, Mitsuba {rec['mi_render_s']:.3f} s "
                f"(under perf {rec['mi_perf_render_s']:.3f}: {rec['mi_split']})")
            part["runs"].append(rec)
    part["load_after"] = loadavg()
    busy = [b for r in part["runs"] for b in r["busy"]] or [0.0]
    part["busy_mean"], part["busy_max"] = statistics.mean(busy), max(busy)
    return part


def md_split(args, part):
    def med(xs):
        return statistics.median(xs) if xs else float("nan")

    out = ["## Where a sample's time goes against Mitsuba 3\n"]
    out.append(f"The e2e harness's scenes rendered by both renderers at `{SPLIT_FLAGS}` (one thread: thread-seconds "
               "are seconds), seconds per render, medians over rounds of fresh processes alternating. wavepath's "
               "stages from `--stats` (shading: shade + compact + generate). Mitsuba `llvm_ad_rgb`'s parts from "
               f"`perf record -F {PERF_HZ}` of a separate run (Embree's closest-hit and any-hit traversal, the "
               "compiled kernels Dr.Jit runs for everything else), scaled to its render time without perf; they "
               "include its untimed 1-spp warm-up render (1/65 of the rays). Ratios wavepath / Mitsuba (> 1: "
               "wavepath slower).\n")
    out.append("| scene | wavepath s | Mitsuba s | ratio | closest hits wp / mi | any hits wp / mi | "
               "shading wp / mi |")
    out.append("|---|--:|--:|--:|--:|--:|--:|")
    for name, _ in SPLIT_SCENES:
        runs = [r for r in part["runs"] if r["scene"] == name]
        if not runs:
            continue
        wp = med([r["wp"]["render_s"] for r in runs])
        mi = med([r["mi_render_s"] for r in runs])
        scale = [r["mi_render_s"] / r["mi_perf_render_s"] for r in runs]
        mi_part = {k: med([r["mi_split"][k] * f for r, f in zip(runs, scale)]) for k in ("intersect", "occluded", "jit")}
        trav = med([r["wp"]["traverse"] for r in runs])
        shadow = med([r["wp"]["shadow"] for r in runs])
        shading = med([r["wp"]["shade"] + r["wp"]["compact"] + r["wp"]["generate"] for r in runs])
        out.append(f"| {name} | {wp:.3f} | {mi:.3f} | **{wp / mi:.2f}** | {trav:.3f} / {mi_part['intersect']:.3f} "
                   f"({trav / mi_part['intersect']:.2f}) | {shadow:.3f} / {mi_part['occluded']:.3f} "
                   f"({shadow / mi_part['occluded']:.2f}) | {shading:.3f} / {mi_part['jit']:.3f} "
                   f"({shading / mi_part['jit']:.2f}) |")
    out.append("")
    out.append(f"Command: `tools/benchmarks.sh --parts split` (after `--parts e2e`, which builds the scenes and "
               f"Mitsuba), {args.rounds} rounds.  ")
    out.append(stamp(part) + "\n")
    return out


# ------------------------------------------------------------------ viewer ----
VIEWER = ("cs184/sky/CBbunny.dae", "-r 640 480 -m 5 -s 64")


def part_viewer(args, scenes_dir):
    """`wavepath view` timed by tools/view_timing.py against offline renders of the same settings."""
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    sys.dont_write_bytecode = True
    import view_timing
    scene, flags = VIEWER
    path = os.path.join(scenes_dir, scene)
    if not os.path.exists(path):
        raise SystemExit(f"viewer: no {path}")
    part = {"load_before": loadavg(), "date": now_utc(), "scene": scene, "flags": flags}
    res = view_timing.measure(args.bin, path, flags.split() + ["-t", str(args.threads)],
                              moves=3 if args.quick else 5, offline_runs=args.rounds, log=log)
    part.update(res)
    part["load_after"] = loadavg()
    busy = [m.get("other_busy", 0.0) for m in res["moves"]] + [r.get("other_busy", 0.0) for r in res["offline"]]
    part["busy_mean"], part["busy_max"] = statistics.mean(busy or [0.0]), max(busy or [0.0])
    return part


def md_viewer(args, part):
    def rng(xs, f):
        return "-" if not xs else (f.format(min(xs)) if min(xs) == max(xs) else f.format(min(xs)) + "-" + f.format(max(xs)))

    mv, off = part["moves"], part["offline"]
    out = ["## Interactive viewer\n"]
    out.append(f"`wavepath view {args.scenes_shown}/{part['scene']} {part['flags']} -t {args.threads}` timed by "
               f"`tools/view_timing.py`: a client on the frame stream (`/events`) that posts {len(mv)} moves to "
               f"`/control` (alternately `m=5`, a new generation of the same view, and `reset=1`), each once the "
               f"previous one has converged, and times the frames; against {len(off)} offline renders of the same "
               f"settings (`wavepath SCENE {part['flags']} -t {args.threads} --stats`). Ranges over the moves and "
               f"the offline runs.\n")
    out.append("| figure | viewer | offline |")
    out.append("|---|--:|--:|")
    out.append(f"| page (`/`) served in | {rng([1e3 * part['page_s']], '{:.1f}')} ms | - |")
    out.append(f"| first image after a move | {rng([1e3 * m['first_s'] for m in mv], '{:.1f}')} ms | - |")
    out.append(f"| updates per second while converging | {rng([m['updates_per_s'] for m in mv], '{:.1f}')} | - |")
    out.append(f"| Mrays/s in render calls | {rng([m['mrays_per_s'] for m in mv], '{:.1f}')} | "
               f"{rng([r['mrays_per_s'] for r in off], '{:.1f}')} |")
    out.append(f"| seconds to {mv[0]['spp'] if mv else '?'} spp | {rng([m['converge_s'] for m in mv], '{:.2f}')} | "
               f"{rng([r['render_s'] for r in off], '{:.2f}')} |")
    out.append("")
    out.append(f"Command: `tools/view_timing.py --bin {args.bin_shown} {args.scenes_shown}/{part['scene']} "
               f"{part['flags']} -t {args.threads}` (what `tools/benchmarks.sh --parts viewer` runs).  ")
    out.append(stamp(part) + "\n")
    return out


# ------------------------------------------------------------------ python ----
PYTHON_VENV = ("python3 -m venv VENV && VENV/bin/pip install ./crates/wavepath-py numpy embreex open3d "
               "mitsuba trimesh")


def part_python(args, scenes_dir, peers_dir):
    """tools/python_bench.py under the interpreter that has the libraries: the standard
    library's python3 here need not have numpy, so the whole script runs under `--python`."""
    work = os.path.join(args.work, "python")
    os.makedirs(work, exist_ok=True)
    md, jsonl = os.path.join(work, "python.md"), os.path.join(work, "results.jsonl")
    threads = "1" if args.threads == 1 else f"1,{args.threads}"
    opts = ["--bin", os.path.abspath(args.bin), "--scenes", scenes_dir, "--peers", peers_dir, "--cache", work,
            "--threads", threads, "--rounds", str(args.rounds), "--reps", str(min(args.reps, 5) if not args.quick else args.reps),
            "--wait-quiet", str(args.wait_quiet)] + (["--quick"] if args.quick else []) + shlex.split(args.python_args)
    cmd = [args.python, os.path.join(REPO, "tools", "python_bench.py")] + opts + ["--md", md, "--jsonl", jsonl]
    part = {"load_before": loadavg(), "date": now_utc(), "opts": opts}
    log(f"python: {shlex.join(cmd)}")
    r = subprocess.run(cmd, cwd=REPO)
    if r.returncode != 0:
        raise SystemExit(f"python part failed (exit {r.returncode}); is {args.python} an interpreter with numpy "
                         f"and the libraries? ({PYTHON_VENV})")
    with open(md) as f:
        part["md"] = f.read()
    with open(jsonl) as f:
        part["rows"] = [json.loads(l) for l in f if l.strip()]
    part["load_after"] = loadavg()
    busy = [r.get("other_busy", 0.0) for r in part["rows"] if "other_busy" in r] or [0.0]
    part["busy_mean"], part["busy_max"] = statistics.mean(busy), max(busy)
    return part


def md_python(args, part):
    shown = list(part["opts"])
    for flag, value in (("--bin", args.bin_shown), ("--scenes", args.scenes_shown), ("--cache", "CACHE")):
        shown[shown.index(flag) + 1] = value
    out = ["## Ray casting from Python\n"]
    out.append(f"`wavepath` from Python (the package in `crates/wavepath-py`) beside the Python ray casters "
               f"its users would otherwise reach for, measured by `tools/python_bench.py`. The interpreter "
               f"needs numpy, the package and the peers: `{PYTHON_VENV}`, then "
               f"`tools/benchmarks.sh --parts python --python VENV/bin/python`.\n")
    out.append(part["md"].rstrip() + "\n")
    out.append(f"Command: `VENV/bin/python tools/python_bench.py {shlex.join(shown)}` (what "
               f"`tools/benchmarks.sh --parts python` runs; raw results, one JSON line per process, in "
               f"`{os.path.join(args.work, 'python', 'results.jsonl')}`).  ")
    out.append(stamp(part) + "\n")
    return out


# ----------------------------------------------------------------- denoise ----
DENOISE_SCENES = "box,dragon-box,spheres-box,dragon-env"


def part_denoise(args, scenes_dir, peers_dir):
    """tools/denoise_figures.py in a virtual environment of its own (numpy, OpenEXR, pyoidn)."""
    venv = os.path.join(args.work, "denoise-venv")
    py = os.path.join(venv, "bin", "python")
    if not os.access(py, os.X_OK):
        log(f"denoise: making {venv} (numpy, OpenEXR, pyoidn)")
        sh([sys.executable, "-m", "venv", venv])
        sh([os.path.join(venv, "bin", "pip"), "install", "-q", "numpy", "OpenEXR", "pyoidn"])
    oidn = sh([py, "-c", "import os, pyoidn; print(os.path.dirname(pyoidn.__file__))"]).strip()
    out = os.path.join(args.work, "denoise.json")
    part = {"load_before": loadavg(), "date": now_utc(), "busy_mean": 0.0, "busy_max": 0.0}
    cmd = [py, os.path.join(REPO, "tools", "denoise_figures.py"), "--bin", os.path.abspath(args.bin), "--oidn", oidn,
           "--e2e", os.path.join(peers_dir, "e2e"), "--scenes-dir", scenes_dir, "--work",
           os.path.join(args.work, "denoise"), "--scenes", DENOISE_SCENES, "--threads", str(args.threads),
           "--out", out]
    if args.quick:
        cmd += ["--scenes", "box", "--ref-spp", "512", "--ladder", "1,4,16,64", "--big", "640", "360"]
    log("denoise: tools/denoise_figures.py")
    # Other processes' share of the CPUs: all busy time less this run's own (its children's).
    b0, t0, own0 = busy_ticks(), time.monotonic(), resource.getrusage(resource.RUSAGE_CHILDREN)
    r = subprocess.run(cmd)
    if r.returncode != 0:
        raise SystemExit(f"denoise: tools/denoise_figures.py failed (exit {r.returncode})")
    own1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    own = (own1.ru_utime + own1.ru_stime) - (own0.ru_utime + own0.ru_stime)
    other = (busy_ticks() - b0) / TICK - own
    part["busy_mean"] = part["busy_max"] = max(other, 0.0) / ((time.monotonic() - t0) * NCPU)
    with open(out) as f:
        part["result"] = json.load(f)
    part["cmd"] = cmd[1:]
    part["load_after"] = loadavg()
    return part


def md_denoise(args, part):
    d = part["result"]
    out = ["## Denoising\n"]
    out.append(f"What Intel Open Image Denoise (`--denoise`: its `RT` filter, HDR, fed the render's albedo and normal, "
               f"prefiltered) buys at {d['width']}x{d['height']}, `-m {d['m']}`, {d['threads']} threads. Error: relative "
               f"MSE, (x - ref)^2 / (ref^2 + 0.01) averaged over pixels and channels, against wavepath's own "
               f"{d['ref_spp']}-spp reference, less the reference's own noise (from its `variance` output variable). "
               f"**The denoised error is biased**: it is measured against the converged raw reference, and a denoiser "
               f"trades noise for blur, so its curve flattens where the raw one keeps falling. 'Samples' is the "
               f"sample count at which the denoised image reaches the raw image's error at 64 and 256 spp "
               f"(log-log interpolation on the ladder {','.join(map(str, d['ladder']))}; `<=1`: already at one "
               f"sample; `never`: not on the ladder); 'fewer' is the raw count over it.\n")
    out.append("| scene | raw relMSE at 64 spp | denoised: samples for it | fewer | raw relMSE at 256 spp | "
               "denoised: samples for it | fewer | denoised relMSE at 16 spp | reference's own |")
    out.append("|---|--:|--:|--:|--:|--:|--:|--:|--:|")
    for s in d["scenes"]:
        cells = []
        for at in (64, 256):
            t = next((t for t in s["targets"] if t["raw_spp"] == at), None)
            if t is None:
                cells += ["n/a", "n/a", "n/a"]
                continue
            n = t["denoised_spp"]
            need = "never" if n is None else (f"<={n:.0f}" if t["how"] == "<=" else f"{n:.1f}")
            fewer = "n/a" if n is None else (f">={at / n:.0f}x" if t["how"] == "<=" else f"{at / n:.1f}x")
            cells += [f"{t['raw_error']:.2e}", need, fewer]
        d16 = next((r["denoised"] for r in s["rows"] if r["spp"] == 16), float("nan"))
        out.append(f"| {s['scene']} | " + " | ".join(cells) + f" | {d16:.2e} | {s['ref_rel_mse']:.1e} |")
    c = d["cost"]
    sizes = [k for k in c if k != "scene"]
    out.append("")
    out.append("Denoising costs (`denoise_s` of `--stats`, median of 3 fresh processes, the "
               f"{c['scene']} scene at 1 spp; prefiltering runs three filters): "
               + ", ".join(f"{k}: {c[k]['median_s']:.2f} s" for k in sizes) + ".  ")
    out.append(f"Command: `tools/benchmarks.sh --parts denoise` (`tools/denoise_figures.py {shlex.join(part['cmd'][1:3])} "
               f"... --scenes {DENOISE_SCENES}`).  ")
    out.append(stamp(part) + "\n")
    return out


# ------------------------------------------------------------------ page ----
# The page's parts in order, with the title a part has before it was ever run.
PART_ORDER = ["renders", "peers", "e2e", "split", "viewer", "large", "python", "denoise"]
PART_TITLES = {"renders": "Renders", "peers": "Ray throughput against the peers",
               "e2e": "End to end against Mitsuba 3", "split": "Where a sample's time goes against Mitsuba 3",
               "viewer": "Interactive viewer",
               "large": "Large meshes", "python": "Ray casting from Python", "denoise": "Denoising"}
NOT_RUN = {
    "e2e": "`tools/benchmarks.sh --parts e2e` adds whole renders against Mitsuba 3 at equal error "
           "(`../shared/peers/e2e/run.sh`, 15-25 min; with `--e2e-args '" + E2E_QUICK + "'` under a minute).",
    "split": "`tools/benchmarks.sh --parts split` (after `--parts e2e`; needs `perf`) times each harness scene's "
             "stages beside Mitsuba's Embree calls and compiled kernels, a few minutes.",
    "viewer": "`tools/benchmarks.sh --parts viewer` times `wavepath view` (tools/view_timing.py), about a minute.",
    "python": "`tools/benchmarks.sh --parts python --python VENV/bin/python` casts rays from numpy through the "
              "Python package beside embreex, Open3D and Mitsuba 3 (tools/python_bench.py, about 15 min; "
              "`--quick` about one), with an interpreter made by `" + PYTHON_VENV + "`.",
    "denoise": "`tools/benchmarks.sh --parts denoise` measures how many samples Open Image Denoise saves and what "
               "it costs (tools/denoise_figures.py, about 15 min).",
}
SECTION = re.compile(r"^<!-- part:([a-z0-9_-]+) -->\n(.*?)^<!-- /part:\1 -->[ \t]*\n?", re.S | re.M)
PAGE_HEAD = """# Benchmarks

Generated by `tools/benchmarks.sh`; rerun it rather than editing this page. Each section is one
part (`--parts renders,peers,e2e,split,viewer,large,python,denoise`) and says when, on what machine, with
which binary and command it was measured: a run replaces the sections of the parts it ran and
keeps the others as they were, with their dates, so sections of one page may come from
different days and builds. Why the code is as it is, with the figures of past experiments:
[docs/decisions.md](docs/decisions.md). Ratios come from fresh processes run side by side;
absolute times move with the machine's load.
"""


def section(name, body):
    """A part's section: its Markdown between the markers `merge_page` finds again."""
    return f"<!-- part:{name} -->\n{body.strip()}\n<!-- /part:{name} -->\n"


def split_sections(text):
    """The sections of a page: {name: section text with its markers}, in page order."""
    return {m.group(1): m.group(0) if m.group(0).endswith("\n") else m.group(0) + "\n"
            for m in SECTION.finditer(text)}


def merge_page(old, new):
    """The page after a run: `new` ({part: Markdown}) replaces those parts' sections, every other
    section of `old` stays verbatim (parts this script no longer knows at the end, so nothing is
    lost), and a part never run gets a note saying how to run it."""
    kept = split_sections(old or "")
    out = [PAGE_HEAD]
    for name in PART_ORDER + [n for n in kept if n not in PART_ORDER]:
        if name in new:
            out.append(section(name, new[name]))
        elif name in kept:
            out.append(kept[name])
        else:
            out.append(f"## {PART_TITLES[name]}\n\nNot run yet: " +
                       NOT_RUN.get(name, f"`tools/benchmarks.sh --parts {name}`.") + "\n")
    return "\n".join(out)


def measured_line(run, part):
    """The line under a section's title: when, where, with what and how it was measured."""
    load0, load1 = part.get("load_before", 0.0), part.get("load_after", 0.0)
    busy_mean, busy_max = part.get("busy_mean", 0.0), part.get("busy_max", 0.0)
    noisy = busy_mean > 0.10 or load0 > 0.5 * NCPU
    if "busy_mean" not in part:  # the part does not measure other processes' share
        note = ("**noisy machine** (the load was high at the start): absolute figures are lower bounds"
                if noisy else "other processes' share of the CPUs not measured")
    elif noisy:
        how = ("ratios can be off by tens of percent, and two-thread figures mean little (no free second core)"
               if busy_mean > 0.3 else "ratios carry several percent of noise")
        note = (f"**noisy machine** (other processes used {100 * busy_mean:.0f}% of the CPUs on average, max "
                f"{100 * busy_max:.0f}%, or the load was high at the start): absolute figures are lower bounds, {how}")
    else:
        note = (f"quiet machine (other processes used {100 * busy_mean:.0f}% of the CPUs on average, "
                f"max {100 * busy_max:.0f}%)")
    return (f"Measured on {part['date']} by `{run['cmdline']}` on {run['machine']}; wavepath `{run['bin']}` "
            f"(sha256 {run['digest']}, built {run['built']}), repository at {run['head']}, {run['rustc']}. "
            f"Load average {load0:.2f} at the start, {load1:.2f} at the end; {note}.\n")


def with_measured(lines, run, part):
    """A part's Markdown lines with the measured line under its title."""
    return "\n".join(lines[:1] + [measured_line(run, part)] + lines[1:])


# ------------------------------------------------------------------ main ----
MACHINE = {}


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[1],
                                 formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    ap.add_argument("--bin", default=os.environ.get("WAVEPATH", "target/release/wavepath"),
                    help="wavepath binary (default: $WAVEPATH or target/release/wavepath)")
    ap.add_argument("--parts", default="renders,peers", help="comma list of " + ", ".join(PART_ORDER))
    ap.add_argument("--large-levels", default="2,3", help="large: subdivision levels of Lucy 100k (0: converted as it is; 4: 25.6M)")
    ap.add_argument("--e2e", action="store_true", help="also run the e2e part (same as adding it to --parts)")
    ap.add_argument("--quick", action="store_true",
                    help="a quick look (~3 min): fewer samples, 1 round, 1 peers pass, 3 reps")
    ap.add_argument("--scenes", dest="scenes_arg", default=None,
                    help="scenes folder (default: $WAVEPATH_SCENES or ../shared/scenes)")
    ap.add_argument("--peers", default=None, help="peers harness folder (default: SCENES/../peers)")
    ap.add_argument("--work", default=os.path.join(os.environ.get("TMPDIR", "/tmp"), "wavepath-benchmarks"),
                    help="scratch folder (peers copy and builds, images; default /tmp/wavepath-benchmarks)")
    ap.add_argument("--peers-work", default=None,
                    help="where the peers harness is copied and built (default WORK/peers; kept between runs)")
    ap.add_argument("--out", default=os.path.join(REPO, "BENCHMARKS.md"), help="page to write")
    ap.add_argument("--threads", type=int, default=NCPU, help=f"render threads / 2nd thread count (default {NCPU})")
    ap.add_argument("--rounds", type=int, default=None, help="alternating render rounds (default 3; quick 1)")
    ap.add_argument("--peer-passes", type=int, default=None, help="peers harness passes (default 3; quick 1)")
    ap.add_argument("--reps", type=int, default=None, help="timed passes per peer run (default 10; quick 3)")
    ap.add_argument("--wait-quiet", type=float, default=None,
                    help="before each run wait up to S s for a quiet second (default 2; quick 0)")
    ap.add_argument("--e2e-args", action="append", default=None,
                    help="extra options for one e2e/run.sh run; repeat for several runs in one table "
                         "(default: the front views, " + repr(E2E_FRONT) + ", then the older cornell scenes with "
                         + repr(E2E_OLDER) + ", then the project's own with " + repr(E2E_OWN) + "; quick: " + repr(E2E_QUICK) + ", under a minute)")
    ap.add_argument("--skip-build", action="store_true", help="peers: use what is already built")
    ap.add_argument("--python", default="python3",
                    help="python: the interpreter with numpy, the wavepath package, embreex, open3d and mitsuba "
                         "(default python3; make one with: " + PYTHON_VENV + ")")
    ap.add_argument("--python-args", default="",
                    help="python: extra options for tools/python_bench.py, e.g. '--meshes lucy_100k'")
    args = ap.parse_args(argv)
    q = args.quick
    args.rounds = args.rounds or (1 if q else 3)
    args.peer_passes = args.peer_passes or (1 if q else 3)
    args.reps = args.reps or (3 if q else 10)
    args.large_levels = [int(x) for x in args.large_levels.split(",") if x]
    args.e2e_args = args.e2e_args if args.e2e_args is not None else ([E2E_QUICK] if q else [E2E_FRONT, E2E_OLDER, E2E_OWN])
    args.wait_quiet = args.wait_quiet if args.wait_quiet is not None else (0 if q else 2)
    parts = [p for p in args.parts.split(",") if p] + (["e2e"] if args.e2e and "e2e" not in args.parts else [])
    for p in parts:
        if p not in PART_ORDER:
            ap.error(f"unknown part {p}")

    os.chdir(REPO)
    args.bin_shown = args.bin
    if not os.access(args.bin, os.X_OK):
        ap.error(f"no wavepath binary at {args.bin} (cargo build --release, or --bin PATH)")
    args.scenes_shown = args.scenes_arg or os.environ.get("WAVEPATH_SCENES") or "../shared/scenes"
    scenes_dir = os.path.abspath(args.scenes_shown)
    if not os.path.isdir(scenes_dir):
        ap.error(f"no scenes folder at {scenes_dir} (--scenes or WAVEPATH_SCENES)")
    peers_dir = os.path.abspath(args.peers or os.path.join(os.path.dirname(scenes_dir), "peers"))
    if ("peers" in parts or "e2e" in parts or "split" in parts or "denoise" in parts) and not os.path.isfile(os.path.join(peers_dir, "run.sh")):
        ap.error(f"no peers harness at {peers_dir} (--peers)")
    os.makedirs(args.work, exist_ok=True)
    args.peers_work = os.path.abspath(args.peers_work or os.path.join(args.work, "peers"))

    model, flags = cpu_model()
    with open(args.bin, "rb") as f:
        digest = hashlib.sha256(f.read()).hexdigest()[:12]
    MACHINE.update(cpu=model, flags=flags)
    # The commit of the checkout the binary was built in (its target/ folder's parent), else this one's.
    src = os.path.dirname(os.path.abspath(args.bin))
    while src != os.path.dirname(src) and not os.path.exists(os.path.join(src, ".git")):
        src = os.path.dirname(src)
    head = sh(["git", "-C", src if os.path.exists(os.path.join(src, ".git")) else REPO, "rev-parse", "--short", "HEAD"])
    built = datetime.datetime.fromtimestamp(os.path.getmtime(args.bin), datetime.timezone.utc)
    t0 = time.monotonic()
    start = {"load": os.getloadavg(), "date": now_utc()}
    log(f"parts {parts}; binary {args.bin} ({digest}); load {start['load'][0]:.2f}")

    results = {}
    if "renders" in parts:
        results["renders"] = part_renders(args, scenes_dir)
    if "peers" in parts:
        results["peers"] = part_peers(args, scenes_dir, peers_dir)
    if "e2e" in parts:
        results["e2e"] = part_e2e(args, scenes_dir, peers_dir)
    if "split" in parts:
        results["split"] = part_split(args, scenes_dir, peers_dir)
    if "viewer" in parts:
        results["viewer"] = part_viewer(args, scenes_dir)
    if "large" in parts:
        results["large"] = part_large(args, scenes_dir, peers_dir)
    if "python" in parts:
        results["python"] = part_python(args, scenes_dir, peers_dir)
    if "denoise" in parts:
        results["denoise"] = part_denoise(args, scenes_dir, peers_dir)
    took = time.monotonic() - t0
    with open(os.path.join(args.work, "results.json"), "w") as f:
        json.dump({"args": {k: v for k, v in vars(args).items()}, "results": results}, f, indent=1, default=str)

    run = {"cmdline": "tools/benchmarks.sh " + shlex.join(argv) if argv else "tools/benchmarks.sh",
           "machine": f"{model} ({', '.join(flags) or 'no AVX2'}), {NCPU} cores, {mem_gib()}, Linux {platform.release()}",
           "bin": args.bin_shown, "digest": digest, "built": built.strftime("%Y-%m-%d %H:%M UTC"),
           "head": head or "?", "rustc": sh(["rustc", "-V"]) or "rustc ?"}
    md = {}
    if "renders" in results:
        md["renders"] = with_measured(md_renders(args, results["renders"], scenes_dir), run, results["renders"])
    if "peers" in results:
        md["peers"] = with_measured(md_peers(args, results["peers"], scenes_dir), run, results["peers"])
    if "e2e" in results:
        md["e2e"] = with_measured(md_e2e(args, results["e2e"]), run, results["e2e"])
    if "split" in results:
        md["split"] = with_measured(md_split(args, results["split"]), run, results["split"])
    if "viewer" in results:
        md["viewer"] = with_measured(md_viewer(args, results["viewer"]), run, results["viewer"])
    if "large" in results:
        md["large"] = with_measured(md_large(args, results["large"]), run, results["large"])
    if "python" in results:
        md["python"] = with_measured(md_python(args, results["python"]), run, results["python"])
    if "denoise" in results:
        md["denoise"] = with_measured(md_denoise(args, results["denoise"]), run, results["denoise"])
    old = ""
    if os.path.exists(args.out):
        with open(args.out) as f:
            old = f.read()
    with open(args.out, "w") as f:
        f.write(merge_page(old, md).rstrip() + "\n")
    log(f"wrote {args.out} ({took / 60:.1f} min)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
