#!/usr/bin/env python3
"""Error against render time from the e2e harness's JSON lines, as one log-log SVG.

Usage: tools/e2e_curves.py SCENE OUT.svg LABEL=RESULTS.jsonl[@RENDERER] ...

Each curve is one renderer's ladder in one results file of ../shared/peers/e2e/run.sh
(RENDERER defaults to wavepath; e.g. `Mitsuba llvm=final.jsonl@mitsuba:llvm_ad_rgb`): its
points are (render seconds, relative RMSE against its own reference), one per spp. Standard
library only, so it runs wherever the harness does.
"""
import json
import math
import sys

W, H, L, R, T, B = 640, 420, 70, 230, 30, 50
COLOURS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#7f7f7f", "#8c564b"]


def curve(scene, spec):
    label, _, rest = spec.partition("=")
    path, _, renderer = rest.partition("@")
    renderer = renderer or "wavepath"
    with open(path) as f:
        rows = [json.loads(line) for line in f if line.strip()]
    pts = sorted((r["spp"], r["render_s"], r["rel_rmse_own"]) for r in rows
                 if r.get("kind") == "ladder" and r.get("scene") == scene and r.get("renderer") == renderer)
    if not pts:
        sys.exit(f"{path}: no {renderer} ladder for scene {scene}")
    return label, [(t, e) for _, t, e in pts]


def main(argv):
    if len(argv) < 4:
        sys.exit(__doc__)
    scene, out = argv[1], argv[2]
    curves = [curve(scene, s) for s in argv[3:]]
    ts = [t for _, c in curves for t, _ in c]
    es = [e for _, c in curves for _, e in c]
    t0, t1 = math.floor(math.log10(min(ts))), math.ceil(math.log10(max(ts)))
    e0, e1 = math.floor(math.log10(min(es))), math.ceil(math.log10(max(es)))
    x = lambda t: L + (math.log10(t) - t0) / (t1 - t0) * (W - L - R)
    y = lambda e: T + (e1 - math.log10(e)) / (e1 - e0) * (H - T - B)
    svg = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="12">',
           f'<rect width="{W}" height="{H}" fill="white"/>',
           f'<text x="{L}" y="18" font-size="14">{scene}: relative RMSE against render time (log-log)</text>']
    for d in range(t0, t1 + 1):
        svg.append(f'<line x1="{x(10**d):.1f}" y1="{T}" x2="{x(10**d):.1f}" y2="{H - B}" stroke="#ddd"/>')
        svg.append(f'<text x="{x(10**d):.1f}" y="{H - B + 16}" text-anchor="middle">{10**d:g} s</text>')
    for d in range(e0, e1 + 1):
        svg.append(f'<line x1="{L}" y1="{y(10**d):.1f}" x2="{W - R}" y2="{y(10**d):.1f}" stroke="#ddd"/>')
        svg.append(f'<text x="{L - 6}" y="{y(10**d) + 4:.1f}" text-anchor="end">{10**d:g}</text>')
    svg.append(f'<text x="{(L + W - R) / 2}" y="{H - 12}" text-anchor="middle">render seconds</text>')
    for i, (label, pts) in enumerate(curves):
        c = COLOURS[i % len(COLOURS)]
        path = " ".join(f"{x(t):.1f},{y(e):.1f}" for t, e in pts)
        svg.append(f'<polyline points="{path}" fill="none" stroke="{c}" stroke-width="2"/>')
        svg += [f'<circle cx="{x(t):.1f}" cy="{y(e):.1f}" r="3" fill="{c}"/>' for t, e in pts]
        ly = T + 10 + 20 * i
        svg.append(f'<line x1="{W - R + 15}" y1="{ly}" x2="{W - R + 40}" y2="{ly}" stroke="{c}" stroke-width="2"/>')
        svg.append(f'<text x="{W - R + 46}" y="{ly + 4}">{label}</text>')
    svg.append("</svg>")
    with open(out, "w") as f:
        f.write("\n".join(svg) + "\n")


if __name__ == "__main__":
    main(sys.argv)
