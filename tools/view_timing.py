#!/usr/bin/env python3
"""Times `wavepath view` as a browser would see it, against offline renders of the same settings.

    tools/view_timing.py [--bin PATH] [--moves N] [--offline N] SCENE [wavepath flags ...]
    tools/view_timing.py ../shared/scenes/cs184/sky/CBbunny.dae -r 640 480 -m 5 -s 64 -t 2

Starts `wavepath view SCENE FLAGS` (a free port on 127.0.0.1), fetches the page (`/`), opens the
frame stream (`/events`, server-sent events, one JSON object per frame) and waits for the first
render to converge. Then, N times, posts a move to `/control` (alternately `m=5`, which starts a
new generation of the same view, and `reset=1`) and, from the frames of that generation, takes:
the time from the post to its first frame, the frames per second until the converged one, the
time to convergence (the `-s` cap) and the Mrays/s the viewer reports for its render calls. Then
renders the same scene offline N times (`wavepath SCENE FLAGS --stats`) for `render_s` and
Mrays/s. Prints a summary and, with `--json`, the figures as JSON. tools/benchmarks.py runs it as
its `viewer` part. Python 3 standard library only.
"""
import argparse
import json
import os
import queue
import socket
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request

TICK = os.sysconf("SC_CLK_TCK")
NCPU = os.cpu_count() or 1


def busy_ticks():
    with open("/proc/stat") as f:
        v = [int(x) for x in f.readline().split()[1:]]
    return v[0] + v[1] + v[2] + v[5] + v[6] + (v[7] if len(v) > 7 else 0)


def proc_ticks(pid):
    """CPU ticks (user + system) of a process and its reaped children."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            v = f.read().rsplit(")", 1)[1].split()
        return sum(int(x) for x in v[11:15])
    except (OSError, IndexError, ValueError):
        return 0


class Busy:
    """The share of all CPUs that processes other than `pids` (and this one) used meanwhile."""

    def __init__(self, pids):
        self.pids = pids
        self.b0, self.t0 = busy_ticks(), time.monotonic()
        self.o0 = sum(proc_ticks(p) for p in pids) + proc_ticks(os.getpid())

    def share(self):
        own = sum(proc_ticks(p) for p in self.pids) + proc_ticks(os.getpid()) - self.o0
        wall = max(time.monotonic() - self.t0, 1e-9)
        return max(0.0, (busy_ticks() - self.b0 - own) / TICK / (wall * NCPU))


def read_events(addr, frames, stop):
    """Reads the frame stream; puts (arrival time, frame JSON without its image) on `frames`."""
    host, port = addr
    s = socket.create_connection((host, port))
    s.sendall(b"GET /events HTTP/1.1\r\nHost: x\r\n\r\n")
    f = s.makefile("rb")
    while f.readline() not in (b"\r\n", b"\n", b""):
        pass  # the response's header block
    data = []
    while not stop.is_set():
        line = f.readline()
        if not line:
            break
        line = line.rstrip(b"\r\n")
        if line.startswith(b"data: "):
            data.append(line[6:])
        elif not line and data:
            t = time.monotonic()
            v = json.loads(b"".join(data))
            v.pop("image", None)
            frames.put((t, v))
            data = []
    s.close()


def post(base, path):
    req = urllib.request.Request(base + path, data=b"", method="POST")
    with urllib.request.urlopen(req, timeout=30) as r:
        return r.read().decode()


def wait_converged(frames, generation, timeout=300):
    """The frames of `generation` (or later) up to its converged one: [(time, frame)]."""
    got, end = [], time.monotonic() + timeout
    while True:
        t, f = frames.get(timeout=max(0.1, end - time.monotonic()))
        if f["generation"] < generation:
            continue
        got.append((t, f))
        if f["converged"]:
            return got


def measure(binary, scene, flags, moves=5, offline_runs=3, log=lambda m: print(m, file=sys.stderr)):
    """The viewer's figures per move and the offline renders' figures, as a dict."""
    proc = subprocess.Popen([binary, "view", scene, *flags], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                            text=True)
    stop = threading.Event()
    try:
        url = proc.stdout.readline().strip()
        if not url.startswith("http://"):
            raise SystemExit(f"wavepath view printed {url!r}, not its URL")
        base = url.rstrip("/")
        host, port = base[len("http://"):].rsplit(":", 1)
        t0 = time.monotonic()
        with urllib.request.urlopen(base + "/", timeout=30) as r:
            page = r.read()
        page_s = time.monotonic() - t0
        if b"<html" not in page.lower():
            raise SystemExit("the page is not HTML")
        frames = queue.Queue()
        threading.Thread(target=read_events, args=((host, int(port)), frames, stop), daemon=True).start()
        wait_converged(frames, 0)
        out = []
        for k in range(moves):
            change = "m=5" if k % 2 == 0 else "reset=1"
            busy = Busy([proc.pid])
            t = time.monotonic()
            generation = int(post(base, "/control?" + change).split()[-1])
            got = wait_converged(frames, generation)
            (t_first, _), (t_last, last) = got[0], got[-1]
            m = {"change": change, "first_s": t_first - t, "converge_s": t_last - t, "frames": len(got),
                 "updates_per_s": (len(got) - 1) / (t_last - t_first) if t_last > t_first else 0.0,
                 "spp": last["spp"], "mrays_per_s": last["info"]["mrays_per_s"], "other_busy": busy.share()}
            log(f"view move {k + 1}/{moves} ({change}): first image {1e3 * m['first_s']:.1f} ms, "
                f"{m['updates_per_s']:.1f} updates/s, {m['spp']} spp in {m['converge_s']:.2f} s, "
                f"{m['mrays_per_s']:.1f} Mrays/s")
            out.append(m)
    finally:
        stop.set()
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
    offline = []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(offline_runs):
            st = os.path.join(tmp, "stats.json")
            busy_b0, own0, t = busy_ticks(), os.times(), time.monotonic()
            subprocess.run([binary, scene, *flags, "-f", os.path.join(tmp, "x.png"), "--stats", st], check=True,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            wall, own1 = time.monotonic() - t, os.times()
            own = (own1.children_user - own0.children_user) + (own1.children_system - own0.children_system)
            with open(st) as f:
                s = json.load(f)
            r = {"render_s": s["render_s"], "mrays_per_s": s["mrays_per_s"], "wall_s": wall,
                 "other_busy": max(0.0, (busy_ticks() - busy_b0) / TICK - own) / (wall * NCPU)}
            log(f"offline {k + 1}/{offline_runs}: render {r['render_s']:.2f} s, {r['mrays_per_s']:.1f} Mrays/s")
            offline.append(r)
    return {"page_s": page_s, "moves": out, "offline": offline}


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0], epilog=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", default=os.environ.get("WAVEPATH", "target/release/wavepath"))
    ap.add_argument("--moves", type=int, default=5)
    ap.add_argument("--offline", type=int, default=3)
    ap.add_argument("--json", action="store_true", help="print the figures as JSON on stdout")
    ap.add_argument("scene")
    args, flags = ap.parse_known_args(argv)
    res = measure(args.bin, args.scene, flags, args.moves, args.offline)
    if args.json:
        json.dump(res, sys.stdout, indent=1)
        print()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
