#!/usr/bin/env python3
"""Ray casting from Python: wavepath's package beside embreex, Open3D and Mitsuba 3.

    tools/python_bench.py [--python PATH] [--bin PATH] [--meshes lucy_100k,...] [--rounds R] [--reps K] [--quick]

A Python user hands numpy arrays to a library and wants numpy arrays back, so every figure is
the whole call: from origins and directions ((n,3) float32) and per-ray tmin/tmax to the
library's own result arrays of distances and triangle indices, conversions included. The
libraries, each called the way its users call it:

  wavepath  `Scene.from_arrays(vertices, faces)`, `scene.intersect(o, d, tmin=, tmax=, threads=N)`
  embreex   the Embree 2/3 binding trimesh uses (trimesh/ray/ray_pyembree.py): an EmbreeScene with
            one TriangleMesh, `scene.run(o, d, dists=tmax, output=1)`; single-threaded, so its
            one-thread figure stands in every thread row
  open3d    `o3d.t.geometry.RaycastingScene().add_triangles(...)`, `cast_rays(rays, nthreads=N)`
            with the rays as one (n,6) float32 tensor; it takes neither tmin nor tmax
  mitsuba   `llvm_ad_rgb`, an `mi.Mesh` from the arrays in a scene of `mi.load_dict`,
            `scene.ray_intersect(mi.Ray3f(o, d) with maxt)`, `dr.eval(si.t, si.prim_index)`, then
            `.numpy()` of both; threads by `dr.set_thread_count(N)`; its first call compiles a
            kernel (or finds it in Dr.Jit's disk cache), so it is reported on its own

All four get the same triangles in the same order: the mesh is written once as binary PLY by
`wavepath subdivide -n LEVEL` and read here into the same numpy arrays for every library, so a
triangle index means the same triangle everywhere and the hits can be compared ray by ray
against wavepath's (hit or miss; t within a relative 1e-4). The rays are the peers harness's
own sets, made by its `raygen` (built from ../shared/peers/rust) from that mesh as OBJ.

Every measurement is a fresh Python process (`--one LIB MESH RAYS THREADS`: import, read,
build, one untimed first call, K timed calls, one JSON line), the libraries taking turns in
each round; a table cell is the median over rounds of each process's best call. Scene
construction (with the BVH build it triggers) is timed apart from the calls.

Top level: standard library and numpy only; the libraries are imported in the process that
measures them, so a missing one is reported as such and the others still run.
"""
import argparse
import datetime
import json
import os
import platform
import resource
import shlex
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LIBS = ["wavepath", "embreex", "open3d", "mitsuba"]
LABELS = {"wavepath": "wavepath", "embreex": "embreex", "open3d": "Open3D", "mitsuba": "Mitsuba 3"}
IMPORT = {"wavepath": "wavepath", "embreex": "embreex", "open3d": "open3d", "mitsuba": "mitsuba"}
# Libraries that run on one thread whatever they are asked: measured once, shown in every row.
SINGLE_THREADED = {"embreex"}
# name: (source file under the scenes folder, subdivision levels)
MESHES = {
    "lucy_100k": ("meshes/lucy_100k.obj", 0),
    "dragon_100k": ("meshes/dragon_100k.ply", 0),
    "lucy_1.6M": ("meshes/lucy_100k.obj", 2),
    "dragon_1.6M": ("meshes/dragon_100k.ply", 2),
}
SETS = ["primary", "diffuse"]
QUICK_RES = ("400", "300")
T_REL = 1e-4
TICK = os.sysconf("SC_CLK_TCK")
NCPU = os.cpu_count() or 1


def log(msg):
    print(f"[python_bench] {msg}", file=sys.stderr, flush=True)


# ------------------------------------------------------------------ files ----
def read_ply(path):
    """The binary PLY `wavepath subdivide` writes (float x y z; uchar-int lists of 3): vertices
    (n,3) float32 and faces (m,3) int32 in file order."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    head = data[:end].decode().split("\n")
    if "format binary_little_endian 1.0" not in head:
        raise SystemExit(f"{path}: not a binary little-endian PLY")
    nv = int(next(l for l in head if l.startswith("element vertex")).split()[2])
    nf = int(next(l for l in head if l.startswith("element face")).split()[2])
    v = np.frombuffer(data, np.float32, 3 * nv, end).reshape(nv, 3).copy()
    rec = np.frombuffer(data, np.dtype([("n", "u1"), ("i", "<i4", (3,))]), nf, end + 12 * nv)
    if not (rec["n"] == 3).all():
        raise SystemExit(f"{path}: faces other than triangles")
    return v, np.ascontiguousarray(rec["i"])


def read_rays(path):
    """The peers' ray file (`RAYS`, u32 version 1, u64 count, then ox oy oz tmin dx dy dz tmax
    as f32): origins, directions (n,3) float32 contiguous, tmin, tmax (n,) float32."""
    head = np.fromfile(path, np.uint8, 16)
    if head[:4].tobytes() != b"RAYS" or head[4:8].view("<u4")[0] != 1:
        raise SystemExit(f"{path}: not a version-1 ray file")
    n = int(head[8:16].view("<u8")[0])
    r = np.fromfile(path, np.float32, 8 * n, offset=16).reshape(n, 8)
    return (np.ascontiguousarray(r[:, 0:3]), np.ascontiguousarray(r[:, 4:7]),
            np.ascontiguousarray(r[:, 3]), np.ascontiguousarray(r[:, 7]))


# ------------------------------------------------------------- libraries ----
# Each adapter: build(v, f, threads) makes the scene and forces its acceleration structure;
# call(o, d, tmin, tmax, threads) is the timed call, numpy in, the library's arrays out, with
# `self.marks` noting when conversion stops and starts; hits(out) is (t with inf on a miss,
# prim with -1 on a miss) for the comparison, outside the timing.
class Wavepath:
    def __init__(self, threads, coherent):
        import wavepath
        self.wp = wavepath
        self.version = getattr(wavepath, "__version__", "?")

    def build(self, v, f, threads):
        self.scene = self.wp.Scene.from_arrays(v, f)
        if hasattr(self.scene, "build"):
            try:
                self.info = self.scene.build(threads=threads)
            except TypeError:
                self.info = self.scene.build()
        else:  # the first intersect builds the BVH
            self.scene.intersect(np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32), threads=threads)

    def call(self, o, d, tmin, tmax, threads):
        h = self.scene.intersect(o, d, tmin=tmin, tmax=tmax, threads=threads)
        return h["t"], h["prim"]

    def hits(self, out):
        t, prim = out
        miss = prim == getattr(self.wp, "MISS", 0xFFFFFFFF)
        return np.where(miss, np.inf, t).astype(np.float32), np.where(miss, -1, prim.astype(np.int64))


class Embreex:
    def __init__(self, threads, coherent):
        import embreex
        from embreex import rtcore_scene
        from embreex.mesh_construction import TriangleMesh
        self.rtcore_scene, self.TriangleMesh = rtcore_scene, TriangleMesh
        self.version = getattr(embreex, "__version__", None) or _dist_version("embreex")

    def build(self, v, f, threads):
        # As trimesh's _EmbreeWrap: float32 vertices, int32 indices, one mesh in a default scene.
        # (trimesh also shifts and scales the mesh to a 100-unit box and converts the rays to
        # float64 and back on every call; the bare binding is measured here, the faster path.)
        self.scene = self.rtcore_scene.EmbreeScene()
        self.mesh = self.TriangleMesh(scene=self.scene, vertices=v.astype(np.float32), indices=f.astype(np.int32))
        # Embree commits (builds its BVH) on the first query.
        self.scene.run(np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32))

    def call(self, o, d, tmin, tmax, threads):
        # `dists` is the rays' tfar and is overwritten with the hit distances: a copy per call.
        r = self.scene.run(o, d, dists=tmax.copy(), output=1)
        return r["tfar"], r["primID"]

    def hits(self, out):
        t, prim = out
        miss = prim < 0
        return np.where(miss, np.inf, t).astype(np.float32), np.where(miss, -1, prim.astype(np.int64))


class Open3D:
    def __init__(self, threads, coherent):
        import open3d as o3d
        self.o3d = o3d
        self.version = o3d.__version__

    def build(self, v, f, threads):
        T = self.o3d.core.Tensor
        self.scene = self.o3d.t.geometry.RaycastingScene(nthreads=threads)
        self.scene.add_triangles(T.from_numpy(np.ascontiguousarray(v, np.float32)),
                                 T.from_numpy(np.ascontiguousarray(f, np.uint32)))
        # The Embree scene inside is committed on the first cast.
        self.scene.cast_rays(T.from_numpy(np.array([[0, 0, 0, 1, 1, 1]], np.float32)), nthreads=threads)

    def call(self, o, d, tmin, tmax, threads):
        # No tmin or tmax: the rays are only origin and direction.
        rays = self.o3d.core.Tensor.from_numpy(np.concatenate([o, d], axis=1))
        self.marks.append(time.perf_counter())
        r = self.scene.cast_rays(rays, nthreads=threads)
        self.marks.append(time.perf_counter())
        return r["t_hit"].numpy(), r["primitive_ids"].numpy()

    def hits(self, out):
        t, prim = out
        miss = ~np.isfinite(t)
        return np.where(miss, np.inf, t).astype(np.float32), np.where(miss, -1, prim.astype(np.int64))


class Mitsuba:
    def __init__(self, threads, coherent):
        import drjit as dr
        import mitsuba as mi
        mi.set_variant("llvm_ad_rgb")
        if hasattr(dr, "set_thread_count"):
            dr.set_thread_count(threads)
        self.mi, self.dr, self.coherent = mi, dr, coherent
        self.version = f"{mi.__version__} (Dr.Jit {dr.__version__})"

    def build(self, v, f, threads):
        mi = self.mi
        mesh = mi.Mesh("mesh", vertex_count=len(v), face_count=len(f), has_vertex_normals=False,
                       has_vertex_texcoords=False)
        p = mi.traverse(mesh)
        p["vertex_positions"] = mi.Float(np.ascontiguousarray(v, np.float32).ravel())
        p["faces"] = mi.UInt32(np.ascontiguousarray(f, np.uint32).ravel())
        p.update()
        # The scene's constructor builds the acceleration structure (Embree in this variant).
        self.scene = mi.load_dict({"type": "scene", "mesh": mesh})

    def call(self, o, d, tmin, tmax, threads):
        mi, dr = self.mi, self.dr
        # No tmin: Mitsuba 3's rays have only maxt (its renders offset origins instead).
        ray = mi.Ray3f(mi.Point3f(np.ascontiguousarray(o.T)), mi.Vector3f(np.ascontiguousarray(d.T)))
        ray.maxt = mi.Float(tmax)
        self.marks.append(time.perf_counter())
        si = self.scene.ray_intersect(ray, mi.RayFlags.All, self.coherent)
        # One kernel for both outputs: `.numpy()` of each alone would trace the rays twice.
        dr.eval(si.t, si.prim_index)
        # With more than one thread the launch returns at once; wait here so that the phases
        # split where the work is (the results would wait for it anyway).
        dr.sync_thread()
        self.marks.append(time.perf_counter())
        return si.t.numpy(), si.prim_index.numpy()

    def hits(self, out):
        t, prim = out
        miss = ~np.isfinite(t)
        return np.where(miss, np.inf, t).astype(np.float32), np.where(miss, -1, prim.astype(np.int64))


ADAPTERS = {"wavepath": Wavepath, "embreex": Embreex, "open3d": Open3D, "mitsuba": Mitsuba}


def _dist_version(name):
    try:
        from importlib.metadata import version
        return version(name)
    except Exception:
        return "?"


def one(lib, mesh, rays, threads, reps, coherent, hits_out):
    """One measurement in this process; prints one JSON line."""
    rec = {"lib": lib, "mesh": mesh, "rays": rays, "threads": threads, "reps": reps}
    t0 = time.perf_counter()
    a = ADAPTERS[lib](threads, coherent)
    rec["import_s"] = time.perf_counter() - t0
    rec["version"] = a.version
    t0 = time.perf_counter()
    v, f = read_ply(mesh)
    o, d, tmin, tmax = read_rays(rays)
    rec["read_s"] = time.perf_counter() - t0
    rec["triangles"], rec["n"] = len(f), len(o)
    t0 = time.perf_counter()
    a.build(v, f, threads)
    rec["build_s"] = time.perf_counter() - t0
    if getattr(a, "info", None) is not None:
        rec["build_info"] = a.info
    a.marks = []
    t0 = time.perf_counter()
    out = a.call(o, d, tmin, tmax, threads)
    rec["first_s"] = time.perf_counter() - t0
    times, cpu, phases = [], [], []
    for _ in range(reps):
        a.marks = []
        c0 = time.process_time()
        t0 = time.perf_counter()
        out = a.call(o, d, tmin, tmax, threads)
        t1 = time.perf_counter()
        cpu.append(time.process_time() - c0)
        times.append(t1 - t0)
        # Where conversion is separable: [into the library, the query, out of it].
        phases.append([a.marks[0] - t0, a.marks[1] - a.marks[0], t1 - a.marks[1]] if len(a.marks) == 2 else None)
    best = min(range(reps), key=times.__getitem__)
    rec.update(times=times, best_s=times[best], cpu_s=cpu[best], phases=phases[best],
               mrays_per_s=len(o) / times[best] / 1e6)
    t, prim = a.hits(out)
    rec["hit_count"] = int((prim >= 0).sum())
    if hits_out:
        np.savez(hits_out, t=t, prim=prim)
    print(json.dumps(rec), flush=True)


# ------------------------------------------------------------ the machine ----
def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            info = f.read().splitlines()
    except OSError:
        return platform.processor() or "unknown CPU", False
    model = next((l.split(":", 1)[1].strip() for l in info if l.startswith("model name")), "unknown CPU")
    flags = next((l.split(":", 1)[1].split() for l in info if l.startswith("flags")), [])
    return model, "avx512f" in flags


def busy_ticks():
    with open("/proc/stat") as f:
        v = [int(x) for x in f.readline().split()[1:]]
    return v[0] + v[1] + v[2] + v[5] + v[6] + (v[7] if len(v) > 7 else 0)


def wait_quiet(limit):
    """Up to `limit` seconds for a second in which the CPUs are < 10% busy: the machine is shared."""
    start = time.monotonic()
    while time.monotonic() - start < limit:
        b0, t0 = busy_ticks(), time.monotonic()
        time.sleep(1.0)
        if (busy_ticks() - b0) / TICK / ((time.monotonic() - t0) * NCPU) < 0.10:
            break
    return time.monotonic() - start


# ------------------------------------------------------------ preparation ----
def peer_tools(args):
    """The peers harness's own `raygen` and `ply2obj` (../shared/peers/rust), built once into the
    cache: the ray sets are the harness's, so these figures sit beside its tables."""
    target = os.path.join(args.cache, "peers-target")
    manifest = os.path.join(args.peers, "rust", "Cargo.toml")
    if not os.path.exists(manifest):
        raise SystemExit(f"{manifest} missing: --peers must name the peers harness folder")
    bins = {b: os.path.join(target, "release", b) for b in ("raygen", "ply2obj")}
    if not all(os.path.exists(b) for b in bins.values()):
        run(["cargo", "build", "-q", "--release", "--manifest-path", manifest, "-p", "peers-tools",
             "--bin", "raygen", "--bin", "ply2obj", "--target-dir", target])
    return bins


def prepare(args):
    """The meshes as binary PLY and their ray sets (the peers harness's raygen, on the same
    triangles as OBJ), made once in the cache folder."""
    os.makedirs(args.cache, exist_ok=True)
    tools = peer_tools(args)
    todo = []
    res = QUICK_RES if args.quick else None
    for name in args.meshes:
        src, level = MESHES[name]
        source = os.path.join(args.scenes, src)
        if not os.path.exists(source):
            log(f"skip {name}: no {source}")
            continue
        ply = os.path.join(args.cache, f"{name}.ply")
        if not os.path.exists(ply):
            run([args.bin, "subdivide", "-n", str(level), source, ply])
        obj = os.path.join(args.cache, f"{name}.obj")
        if not os.path.exists(obj):
            run([tools["ply2obj"], ply, obj])
        raydir = os.path.join(args.cache, f"{name}.rays-{res[0]}x{res[1]}" if res else f"{name}.rays")
        if not os.path.exists(os.path.join(raydir, "rays_diffuse.bin")):
            run([tools["raygen"], obj, raydir] + (["--width", res[0], "--height", res[1]] if res else []))
        sets = {kind: os.path.join(raydir, f"rays_{kind}.bin") for kind in args.sets}
        todo.append({"name": name, "source": src, "level": level, "ply": ply, "sets": sets})
    return todo


def run(cmd):
    r = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if r.returncode != 0:
        raise SystemExit(f"failed: {shlex.join(cmd)}\n{r.stderr[-2000:]}")


def available(python, libs):
    """The libraries the interpreter can import, and why the others are missing."""
    ok, missing = [], {}
    for lib in libs:
        r = subprocess.run([python, "-c", f"import {IMPORT[lib]}"], stdout=subprocess.DEVNULL,
                           stderr=subprocess.PIPE, text=True)
        if r.returncode == 0:
            ok.append(lib)
        else:
            missing[lib] = (r.stderr.strip().splitlines() or ["?"])[-1]
            log(f"{lib}: not importable by {python}: {missing[lib]}")
    return ok, missing


def measure(args, libs, todo, jsonl):
    """All rounds; every measurement a fresh process, the libraries taking turns."""
    rows = []
    for rnd in range(args.rounds):
        for m in todo:
            for kind, rays in m["sets"].items():
                for thr in args.threads:
                    order = libs[rnd % len(libs):] + libs[:rnd % len(libs)]
                    for lib in order:
                        if lib in SINGLE_THREADED and thr != args.threads[0]:
                            continue
                        hits = None
                        if rnd == 0 and thr == args.threads[0]:
                            hits = os.path.join(args.cache, "hits", f"{m['name']}.{kind}.{lib}.npz")
                            os.makedirs(os.path.dirname(hits), exist_ok=True)
                        cmd = [args.python, os.path.abspath(__file__), "--one", lib, m["ply"], rays, str(thr),
                               "--reps", str(args.reps)] + (["--coherent"] if kind == "primary" else []) + \
                              (["--hits", hits] if hits else [])
                        waited = wait_quiet(args.wait_quiet)
                        ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
                        b0, t0 = busy_ticks(), time.monotonic()
                        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                           timeout=args.timeout)
                        wall = time.monotonic() - t0
                        busy = (busy_ticks() - b0) / TICK
                        ru1 = resource.getrusage(resource.RUSAGE_CHILDREN)
                        own = (ru1.ru_utime - ru0.ru_utime) + (ru1.ru_stime - ru0.ru_stime)
                        if p.returncode != 0:
                            log(f"{lib} {m['name']} {kind} {thr}T failed (exit {p.returncode}): "
                                f"{p.stderr.strip()[-1500:]}")
                            rec = {"lib": lib, "failed": p.stderr.strip()[-500:]}
                        else:
                            rec = json.loads(p.stdout.strip().splitlines()[-1])
                            log(f"round {rnd + 1}/{args.rounds} {m['name']:12s} {kind:7s} {thr}T {lib:8s} "
                                f"{rec['mrays_per_s']:7.2f} Mrays/s (best {1e3 * rec['best_s']:.1f} ms, first "
                                f"{1e3 * rec['first_s']:.0f} ms, build {rec['build_s']:.3f} s)")
                        rec.update(round=rnd, mesh_name=m["name"], set=kind, threads=thr, wall_s=wall,
                                   waited_s=waited, other_busy=max(0.0, busy - own) / (wall * NCPU), hits_file=hits)
                        rows.append(rec)
                        jsonl.write(json.dumps(rec) + "\n")
                        jsonl.flush()
    return rows


# ------------------------------------------------------------- comparison ----
def agreement(ref_file, peer_file):
    """Share of rays on which a peer agrees with the reference: hit or miss; t within a
    relative T_REL where both hit; the same triangle where both hit."""
    a, b = np.load(ref_file), np.load(peer_file)
    ha, hb = a["prim"] >= 0, b["prim"] >= 0
    both = ha & hb
    ta, tb = a["t"][both].astype(np.float64), b["t"][both].astype(np.float64)
    t_ok = np.abs(ta - tb) <= T_REL * np.maximum(np.abs(ta), 1e-30)
    return {"rays": int(len(ha)), "hit_agree": float((ha == hb).mean()) if len(ha) else 1.0,
            "t_agree": float(t_ok.mean()) if both.any() else 1.0,
            "prim_agree": float((a["prim"][both] == b["prim"][both]).mean()) if both.any() else 1.0,
            "ref_only": int((ha & ~hb).sum()), "peer_only": int((hb & ~ha).sum())}


# ---------------------------------------------------------------- tables ----
def summarise(rows, libs, todo, threads, ref):
    """{(mesh, set, threads): {lib: median Mrays/s, ...}} and the agreements."""
    ok = [r for r in rows if not r.get("failed")]
    med = statistics.median
    cells, builds, agree = {}, {}, {}
    for m in todo:
        for kind in m["sets"]:
            for thr in threads:
                row = {}
                for lib in libs:
                    src = threads[0] if lib in SINGLE_THREADED else thr
                    sel = [r for r in ok if (r["mesh_name"], r["set"], r["threads"], r["lib"]) == (m["name"], kind, src, lib)]
                    if sel:
                        row[lib] = {"mrays": med([r["n"] / r["best_s"] / 1e6 for r in sel]),
                                    "first_s": med([r["first_s"] for r in sel]),
                                    "first_max_s": max(r["first_s"] for r in sel),
                                    "busy": max(r["other_busy"] for r in sel),
                                    "cpu_share": med([r["cpu_s"] / r["best_s"] for r in sel]),
                                    "conv": med([(p[0] + p[2]) / r["best_s"] for r in sel for p in [r["phases"]] if p])
                                    if any(r["phases"] for r in sel) else None,
                                    "n": sel[0]["n"], "rounds": len(sel)}
                cells[(m["name"], kind, thr)] = row
            for lib in libs:
                if ref and lib != ref:
                    rf = next((r["hits_file"] for r in ok if r["hits_file"] and r["lib"] == ref and
                               (r["mesh_name"], r["set"]) == (m["name"], kind)), None)
                    pf = next((r["hits_file"] for r in ok if r["hits_file"] and r["lib"] == lib and
                               (r["mesh_name"], r["set"]) == (m["name"], kind)), None)
                    if rf and pf and os.path.exists(rf) and os.path.exists(pf):
                        agree[(m["name"], kind, lib)] = agreement(rf, pf)
        for lib in libs:
            sel = [r for r in ok if (r["mesh_name"], r["lib"], r["threads"]) == (m["name"], lib, threads[0])]
            if sel:
                builds[(m["name"], lib)] = {k: med([r[k] for r in sel]) for k in ("build_s", "import_s", "read_s")}
                builds[(m["name"], lib)]["triangles"] = sel[0]["triangles"]
    return cells, builds, agree


def markdown(args, rows, libs, missing, todo, ref):
    cells, builds, agree = summarise(rows, libs, todo, args.threads, ref)
    peers = [l for l in libs if l != "wavepath"]
    versions = {}
    for r in rows:
        if not r.get("failed"):
            versions.setdefault(r["lib"], r["version"])
    out = []
    thr_note = ", ".join(f"{t}" for t in args.threads)
    out.append(f"Closest hits of the same rays on the same triangles from numpy, through each library's "
               f"Python API: Mrays/s of the whole call, from numpy arrays (origins and directions (n,3) "
               f"float32, tmin and tmax (n,)) to the library's result arrays of distances and triangle "
               f"indices, conversions included; {thr_note} threads. Median over {args.rounds} round"
               f"{'s' if args.rounds > 1 else ''} of fresh processes (the libraries taking turns) of each "
               f"process's best of {args.reps} calls after one untimed first call. Rays: the peers "
               f"harness's own sets (its `raygen`: primary, "
               f"{'x'.join(QUICK_RES) if args.quick else '800x600'} camera rays framing the mesh, in 4x4 pixel "
               f"blocks; diffuse, one cosine bounce per primary hit). `/ fastest peer`: wavepath over the fastest other "
               f"library of the row (> 1: wavepath faster). Agreement with "
               f"{LABELS.get(ref, ref)}'s hits, ray by ray: the % of rays with the same verdict (hit or "
               f"miss) / the % of the rays both hit with t within a relative {T_REL:g} of the reference's.\n")
    out.append("Versions: " + "; ".join(f"{LABELS[l]} {versions.get(l, '?')}" for l in libs) +
               (". Not importable, so not measured: " + "; ".join(f"{LABELS[l]} ({e})" for l, e in missing.items())
                if missing else "") + ".\n")
    for m in todo:
        tris = next((b["triangles"] for (mn, _), b in builds.items() if mn == m["name"]), None)
        how = f"`{m['source']}`" + (f" subdivided {m['level']} times (`wavepath subdivide -n {m['level']}`)"
                                    if m["level"] else " (as binary PLY)")
        out.append(f"### {m['name']}: {tris:,} triangles\n" if tris else f"### {m['name']}\n")
        out.append(f"{how}.\n")
        out.append("| rays | threads | " + " | ".join(LABELS[l] for l in libs) + " | / fastest peer | " +
                   " | ".join(f"agreement {LABELS[l]}" for l in peers if l != ref) + " |")
        out.append("|---|--:|" + "--:|" * len(libs) + "--:|" + "--:|" * len([l for l in peers if l != ref]))
        for kind in m["sets"]:
            for thr in args.threads:
                row = cells.get((m["name"], kind, thr), {})
                cs = []
                for lib in libs:
                    c = row.get(lib)
                    if not c:
                        cs.append("-")
                        continue
                    s = f"{c['mrays']:.2f}"
                    if lib == "wavepath":
                        s = f"**{s}**"
                    if lib in SINGLE_THREADED and thr != args.threads[0]:
                        s += " (1T)"
                    if c["busy"] > 0.10:
                        s += " !"
                    cs.append(s)
                pv = [(row[l]["mrays"], l) for l in peers if l in row]
                ratio = f"{row['wavepath']['mrays'] / max(pv)[0]:.2f} ({LABELS[max(pv)[1]]})" \
                    if "wavepath" in row and pv else "-"
                ag = []
                for l in peers:
                    if l == ref:
                        continue
                    a = agree.get((m["name"], kind, l))
                    ag.append(f"{100 * a['hit_agree']:.2f} / {100 * a['t_agree']:.2f}" if a else "-")
                n = next(iter(row.values()))["n"] if row else 0
                out.append(f"| {kind} ({n:,}) | {thr} | " + " | ".join(cs) + f" | {ratio} | " + " | ".join(ag) + " |")
        out.append("")
    # Build, first call, conversion.
    out.append("### Scene construction, first call, conversion\n")
    out.append("Build: seconds from the numpy arrays to a scene ready to trace (the library's scene "
               "object, its BVH build included: wavepath `Scene.from_arrays` + `build(threads=N)`; "
               "embreex and Open3D build on their first query, forced here by a one-ray query; Mitsuba "
               "builds in `load_dict`), on the process's N threads where the library takes a count "
               "(wavepath, Open3D's `RaycastingScene(nthreads=N)`, Mitsuba's Dr.Jit pool; embreex's "
               "Embree device uses every core), median over the processes of the mesh at "
               f"{args.threads[0]} thread{'s' if args.threads[0] > 1 else ''}. First call: the first full "
               "call of a process (the first ray set, same processes), median, with the slowest in "
               "brackets. Conversion: "
               "the share of the best call spent outside the library's query function (building "
               "the input tensors or arrays before it, reading the results after it), where the API "
               "separates them.\n")
    heads = []
    for m in todo:
        heads += [f"{m['name']} build s", f"{m['name']} first call ms"]
    out.append("| library | import s | " + " | ".join(heads) + " | conversion share |")
    out.append("|---|--:|" + "--:|" * len(heads) + "--:|")
    for lib in libs:
        cs = []
        imp = [b["import_s"] for (mn, l), b in builds.items() if l == lib]
        for m in todo:
            b = builds.get((m["name"], lib))
            c = cells.get((m["name"], next(iter(m["sets"])), args.threads[0]), {}).get(lib)
            cs.append(f"{b['build_s']:.3f}" if b else "-")
            cs.append(f"{1e3 * c['first_s']:.0f} ({1e3 * c['first_max_s']:.0f})" if c else "-")
        conv = [c[lib]["conv"] for c in cells.values() if lib in c and c[lib]["conv"] is not None]
        out.append(f"| {LABELS[lib]} | {statistics.median(imp):.2f} | " + " | ".join(cs) + " | " +
                   (f"{100 * min(conv):.0f}-{100 * max(conv):.0f}%" if conv else "-") + " |"
                   if imp else f"| {LABELS[lib]} | - | " + " | ".join("-" for _ in heads) + " | - |")
    out.append("")
    notes = {}
    notes["embreex"] = ("- embreex is single-threaded (one `rtcIntersect1` after another): its one-thread figure "
               "stands in the two-thread rows, marked (1T). It is called as trimesh calls it, float32 "
               "arrays straight into `EmbreeScene.run(o, d, dists=tmax, output=1)`, but without "
               "trimesh's own wrapper, which also moves and scales the mesh to a 100-unit box and "
               "converts every batch of rays to float64 and back. It has no tmin (tnear is 0), and it "
               "writes the hit distances into `dists`, so each call passes a copy of tmax.")
    notes["open3d"] = ("- Open3D's `cast_rays` takes no tmin and no tmax (rays are origin and direction only): "
               "it finds the closest hit along the whole line from the origin. It computes and returns "
               "all its outputs (distance, geometry and triangle ids, barycentrics, normals) every call.")
    notes["mitsuba"] = ("- Mitsuba 3 (`llvm_ad_rgb`, Embree inside) has maxt but no tmin. Its calls are lazy: "
               "`.numpy()` of `si.t` and then of `si.prim_index` without `dr.eval(si.t, si.prim_index)` "
               "first compiles and runs two kernels, tracing every ray twice; the benchmark evaluates "
               "both in one. The first call of a process compiles that kernel (or loads it from Dr.Jit's "
               "disk cache, `~/.drjit`): hence its first-call column. Threads: `dr.set_thread_count(N)`. "
               "Primary rays are traced with `coherent=True`, as Mitsuba's own integrators do for "
               "camera rays.")
    out.append("Notes:\n")
    out += [notes[l] for l in libs if l in notes]
    out.append("- The primary rays carry the camera's near and far distances as tmin and tmax; the "
               "libraries that ignore tmin still agree where nothing lies between the camera and tmin.")
    out.append("- `!`: other processes used more than 10% of the CPUs during some run of that cell.")
    model, avx512 = cpu_model()
    out.append("")
    out.append(f"CPU: {model}, {NCPU} cores, AVX-512 {'yes' if avx512 else 'no'} (`avx512f` "
               f"{'in' if avx512 else 'not in'} /proc/cpuinfo's flags).")
    return "\n".join(out) + "\n"


# ------------------------------------------------------------------ main ----
# ------------------------------------------------------------------ renders ----
# Render from Python against the command line: the same scene and settings in fresh processes
# taking turns; the figure is the render's own time (stats "render_s", loading and the BVH
# build excluded in both), and the whole `render()` call beside it.
RENDER_SCENES = ["cs184/sky/CBspheres_lambertian.dae", "meshes/dragon_100k.ply"]
RENDER_FLAGS = {"spp": 64, "light_samples": 1, "max_depth": 5, "resolution": (320, 240)}


def render_flags(threads):
    f = RENDER_FLAGS
    return ["-s", f["spp"], "-l", f["light_samples"], "-m", f["max_depth"], "-r", *f["resolution"], "-t", threads]


def render_one(scene_path, threads):
    """One render from Python in this process; prints one JSON line."""
    import wavepath
    scene = wavepath.load(scene_path)
    t0 = time.perf_counter()
    _, stats = scene.render(threads=threads, **RENDER_FLAGS)
    call = time.perf_counter() - t0
    print(json.dumps({"who": "python", "render_s": stats["render_s"], "call_s": call}))


def render_cli(args, scene_path, threads):
    with tempfile.TemporaryDirectory() as tmp:
        stats = os.path.join(tmp, "s.json")
        cmd = [args.bin, scene_path, *map(str, render_flags(threads)), "-f", os.path.join(tmp, "x.pfm"), "--stats", stats]
        t0 = time.perf_counter()
        r = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, timeout=args.timeout)
        wall = time.perf_counter() - t0
        if r.returncode != 0:
            raise SystemExit(f"failed: {shlex.join(cmd)}\n{r.stderr[-2000:]}")
        with open(stats) as f:
            return {"who": "cli", "render_s": json.load(f)["render_s"], "call_s": wall}


def measure_renders(args, jsonl):
    """Rounds of (command line, Python) fresh processes per scene and thread count."""
    rows = []
    for rnd in range(args.rounds):
        for rel in RENDER_SCENES:
            path = os.path.join(args.scenes, rel)
            if not os.path.exists(path):
                log(f"skip render of {rel}: missing")
                continue
            for threads in args.threads:
                wait_quiet(args.wait_quiet)
                a = render_cli(args, path, threads)
                wait_quiet(args.wait_quiet)
                r = subprocess.run([args.python, os.path.abspath(__file__), "--one-render", path, str(threads)],
                                   capture_output=True, text=True, timeout=args.timeout)
                if r.returncode != 0:
                    raise SystemExit(f"python render failed: {r.stderr[-2000:]}")
                b = json.loads(r.stdout.strip().splitlines()[-1])
                for x in (a, b):
                    x.update({"kind": "render", "scene": rel, "threads": threads, "round": rnd})
                    jsonl.write(json.dumps(x) + "\n")
                    rows.append(x)
                log(f"render {rel} {threads}T round {rnd + 1}: cli {a['render_s']:.3f} s, python {b['render_s']:.3f} s")
    return rows


def render_markdown(rows, threads):
    f = RENDER_FLAGS
    out = [f"Render from Python against the command line: the same scene and settings (`-s {f['spp']} -l "
           f"{f['light_samples']} -m {f['max_depth']} -r {f['resolution'][0]} {f['resolution'][1]} -t N`, the "
           f"same image bit for bit), fresh processes taking turns. Seconds of the render itself (the "
           f"statistics' `render_s`, load and BVH build excluded in both), median over rounds; the ratio "
           f"is Python over the command line per round, its median and range (< 1.02: within 2%). "
           f"`render()` call: the whole Python call (its BVH build included).\n",
           "| scene | threads | command line s | Python s | Python / command line | `render()` call s |",
           "|---|--:|--:|--:|--:|--:|"]
    for rel in RENDER_SCENES:
        for t in threads:
            cli = [r for r in rows if r["scene"] == rel and r["threads"] == t and r["who"] == "cli"]
            py = [r for r in rows if r["scene"] == rel and r["threads"] == t and r["who"] == "python"]
            if not cli or not py:
                continue
            ratios = [p["render_s"] / c["render_s"] for c, p in zip(cli, py)]
            med = statistics.median
            out.append(f"| `{rel}` | {t} | {med(c['render_s'] for c in cli):.3f} | {med(p['render_s'] for p in py):.3f} | "
                       f"{med(ratios):.3f} ({min(ratios):.3f}-{max(ratios):.3f}) | {med(p['call_s'] for p in py):.3f} |")
    return "\n".join(out) + "\n"


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[1],
                                 formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    ap.add_argument("--one", nargs=4, metavar=("LIB", "MESH", "RAYS", "THREADS"),
                    help="measure one library in this process and print one JSON line")
    ap.add_argument("--hits", help="with --one: write the hits (t, prim) to this .npz")
    ap.add_argument("--one-render", nargs=2, metavar=("SCENE", "THREADS"),
                    help="render SCENE from Python in this process and print one JSON line")
    ap.add_argument("--parts", default="rays,render",
                    help="rays (ray casting against the peers), render (Python against the command line)")
    ap.add_argument("--coherent", action="store_true", help="with --one: the rays are coherent (camera rays)")
    ap.add_argument("--python", default=sys.executable,
                    help="interpreter that has numpy and the libraries (default: this one)")
    ap.add_argument("--bin", default=os.environ.get("WAVEPATH", os.path.join(REPO, "target/release/wavepath")),
                    help="wavepath binary, for `subdivide` (default $WAVEPATH or target/release/wavepath)")
    ap.add_argument("--scenes", default=os.environ.get("WAVEPATH_SCENES") or os.path.join(REPO, "..", "shared", "scenes"),
                    help="scenes folder (default $WAVEPATH_SCENES or ../shared/scenes)")
    ap.add_argument("--peers", default=os.path.join(REPO, "..", "shared", "peers"),
                    help="the peers harness folder, whose raygen makes the ray sets (default ../shared/peers)")
    ap.add_argument("--cache", default=os.path.join(REPO, "target", "python-bench"),
                    help="meshes, rays and hits made here (default target/python-bench)")
    ap.add_argument("--meshes", default=None, help="comma list of " + ", ".join(MESHES) + " (default all; quick lucy_100k)")
    ap.add_argument("--libs", default=",".join(LIBS), help="comma list of libraries (default all)")
    ap.add_argument("--sets", default=",".join(SETS), help="ray sets (default primary,diffuse)")
    ap.add_argument("--threads", default=None, help=f"comma list of thread counts (default 1,{NCPU})")
    ap.add_argument("--rounds", type=int, default=None, help="rounds of fresh processes (default 3; quick 1)")
    ap.add_argument("--reps", type=int, default=None, help="timed calls per process (default 5; quick 3)")
    ap.add_argument("--quick", action="store_true",
                    help=f"one mesh, {'x'.join(QUICK_RES)} primary rays, 1 round, 3 calls")
    ap.add_argument("--wait-quiet", type=float, default=None,
                    help="before each process wait up to S s for a quiet second (default 1; quick 0)")
    ap.add_argument("--timeout", type=float, default=900, help="seconds one process may take")
    ap.add_argument("--jsonl", default=None, help="raw results, one JSON line per process (default CACHE/results.jsonl)")
    ap.add_argument("--md", default=None, help="write the Markdown here (default: standard output)")
    args = ap.parse_args(argv)
    if args.one_render:
        render_one(args.one_render[0], int(args.one_render[1]))
        return 0
    if args.one:
        lib, mesh, rays, thr = args.one
        one(lib, mesh, rays, int(thr), args.reps or 5, args.coherent, args.hits)
        return 0

    q = args.quick
    args.meshes = (args.meshes or ("lucy_100k" if q else ",".join(MESHES))).split(",")
    for m in args.meshes:
        if m not in MESHES:
            ap.error(f"unknown mesh {m} (known: {', '.join(MESHES)})")
    args.sets = [s for s in args.sets.split(",") if s]
    args.threads = [int(t) for t in (args.threads or ("1" if NCPU == 1 else f"1,{NCPU}")).split(",") if t]
    args.rounds = args.rounds or (1 if q else 3)
    args.reps = args.reps or (3 if q else 5)
    args.wait_quiet = args.wait_quiet if args.wait_quiet is not None else (0 if q else 1)
    args.cache = os.path.abspath(args.cache)
    args.scenes = os.path.abspath(args.scenes)
    if not os.access(args.bin, os.X_OK):
        ap.error(f"no wavepath binary at {args.bin} (--bin)")
    asked = [l for l in args.libs.split(",") if l]
    for l in asked:
        if l not in LIBS:
            ap.error(f"unknown library {l}")
    libs = [l for l in LIBS if l in asked]
    libs, missing = available(args.python, libs)
    if not libs:
        raise SystemExit("no library importable")
    ref = "wavepath" if "wavepath" in libs else libs[0]
    todo = prepare(args)
    if not todo:
        raise SystemExit(f"no meshes found under {args.scenes}")
    jsonl_path = args.jsonl or os.path.join(args.cache, "results.jsonl")
    date = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    load0 = os.getloadavg()[0]
    log(f"{', '.join(libs)} on {', '.join(m['name'] for m in todo)}; {args.rounds} rounds; raw results: {jsonl_path}")
    with open(jsonl_path, "w") as jsonl:
        jsonl.write(json.dumps({"kind": "run", "date": date, "argv": argv, "python": args.python, "libs": libs,
                                "missing": missing, "cpu": cpu_model()[0], "avx512f": cpu_model()[1],
                                "load_before": load0}) + "\n")
        parts = args.parts.split(",")
        rows = measure(args, libs, todo, jsonl) if "rays" in parts else []
        renders = measure_renders(args, jsonl) if "render" in parts and "wavepath" in libs else []
        jsonl.write(json.dumps({"kind": "end", "load_after": os.getloadavg()[0]}) + "\n")
    md = markdown(args, rows, libs, missing, todo, ref) if rows else ""
    if renders:
        md += "\n" + render_markdown(renders, args.threads)
    if args.md:
        with open(args.md, "w") as f:
            f.write(md)
        log(f"wrote {args.md}")
    else:
        print(f"## Ray casting from Python\n\n{date}; `{shlex.join(['tools/python_bench.py'] + argv)}`\n\n{md}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
