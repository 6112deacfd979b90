#!/usr/bin/env python3
"""Writes the project's own Cornell box with meshes in three formats that load to the same scene.

    python3 tools/make_scenes.py [OUTDIR]      (default: scenes/ beside this tools/ folder)

Output: cornell_mesh.obj + .mtl, cornell_mesh.gltf + .bin, cornell_mesh.dae.

The box is the CS184 one (Y-up world: x in [-1,1], y in [0,1.5], z in [-1,1]; red left wall,
blue right wall, white elsewhere, an emissive quad of radiance 10 under the ceiling), holding a
tall rotated box and an icosahedron. All three files give the same triangles in the same order
(OBJ quads are fan-triangulated (v0,v1,v2),(v0,v2,v3) by the loader; the other two files
spell out those triangles), the same materials and the same camera: the one that
`Camera::framing(lo, hi)` (src/scene/camera.rs) gives the camera-less OBJ, fitted to 4:3.

* glTF: the tall box is stored in its local frame under a node with translation + rotation,
  so that loading exercises node flattening; its world positions equal the other files'.
* COLLADA: the CS184 dialect (Z_UP). The loader maps file (x, y, z) to world (-x, z, y), so
  positions, normals and the camera matrix are written pre-converted: file = (-X, Z, Y).

Standard library only.
"""

import json
import math
import os
import struct
import sys

# ---------------------------------------------------------------- small vector helpers


def add(a, b):
    return tuple(x + y for x, y in zip(a, b))


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def scale(a, s):
    return tuple(x * s for x in a)


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def norm(a):
    return scale(a, 1.0 / math.sqrt(dot(a, a)))


def fmt(x):
    """Nine significant digits: enough to read back the same float32."""
    return "%.9g" % x


# ---------------------------------------------------------------- the scene (world space)

MATERIALS = [
    # name, albedo, emission
    ("white", (0.6, 0.6, 0.6), (0.0, 0.0, 0.0)),
    ("red", (0.6, 0.2, 0.2), (0.0, 0.0, 0.0)),
    ("blue", (0.2, 0.2, 0.6), (0.0, 0.0, 0.0)),
    ("light", (0.0, 0.0, 0.0), (10.0, 10.0, 10.0)),
    ("gold", (0.8, 0.6, 0.2), (0.0, 0.0, 0.0)),
]
MAT_INDEX = {m[0]: i for i, m in enumerate(MATERIALS)}

# Tall box: local frame, then rotated about +Y and translated (the glTF node transform).
TALL_ANGLE = math.radians(-17.0)
TALL_OFFSET = (-0.35, 0.0, -0.3)


def tall_local():
    w, h = 0.27, 0.9
    c = [(-w, 0, -w), (w, 0, -w), (w, 0, w), (-w, 0, w), (-w, h, -w), (w, h, -w), (w, h, w), (-w, h, w)]
    # Outward-facing quads (counter-clockwise seen from outside).
    quads = [(4, 7, 6, 5), (0, 1, 2, 3), (3, 2, 6, 7), (1, 0, 4, 5), (0, 3, 7, 4), (2, 1, 5, 6)]
    return c, quads


def tall_to_world(p):
    s, co = math.sin(TALL_ANGLE), math.cos(TALL_ANGLE)
    x, y, z = p
    return add((co * x + s * z, y, -s * x + co * z), TALL_OFFSET)


def icosahedron(center, radius):
    t = (1 + math.sqrt(5)) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
         (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    v = [add(center, scale(norm(p), radius)) for p in v]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    return v, f


def objects():
    """[(name, material, world positions, polygons, local positions or None)] in file order."""
    x0, x1, y0, y1, z0, z1 = -1.0, 1.0, 0.0, 1.5, -1.0, 1.0
    quad = lambda *c: (list(c), [(0, 1, 2, 3)])  # noqa: E731
    out = []
    # Windings face into the box.
    for name, mat, (v, f) in [
        ("floor", "white", quad((x0, y0, z0), (x0, y0, z1), (x1, y0, z1), (x1, y0, z0))),
        ("ceiling", "white", quad((x0, y1, z0), (x1, y1, z0), (x1, y1, z1), (x0, y1, z1))),
        ("backWall", "white", quad((x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0))),
        ("leftWall", "red", quad((x0, y0, z0), (x0, y1, z0), (x0, y1, z1), (x0, y0, z1))),
        ("rightWall", "blue", quad((x1, y0, z0), (x1, y0, z1), (x1, y1, z1), (x1, y1, z0))),
        ("light", "light", quad((-0.3, 1.49, -0.4), (-0.3, 1.49, 0.4), (0.3, 1.49, 0.4), (0.3, 1.49, -0.4))),
    ]:
        out.append((name, mat, v, f, None))
    local, quads = tall_local()
    out.append(("tallBox", "white", [tall_to_world(p) for p in local], quads, local))
    v, f = icosahedron((0.4, 0.32, 0.35), 0.3)
    out.append(("ico", "gold", v, f, None))
    return out


def fan(poly):
    return [(poly[0], poly[k], poly[k + 1]) for k in range(1, len(poly) - 1)]


def bounds(objs):
    pts = [p for o in objs for p in o[2]]
    lo = tuple(min(p[i] for p in pts) for i in range(3))
    hi = tuple(max(p[i] for p in pts) for i in range(3))
    return lo, hi


def framing_camera(lo, hi, aspect=4.0 / 3.0):
    """src/scene/camera.rs Camera::framing (40 degrees across the shorter side, which is the
    vertical one at 4:3) and three_quarter_view, in double precision."""
    center = scale(add(lo, hi), 0.5)
    radius = max(0.5 * math.sqrt(dot(sub(hi, lo), sub(hi, lo))), 1e-6)
    vfov = 40.0
    dist = radius / math.sin(math.radians(vfov) * 0.5) * 1.05
    ext = sub(hi, lo)
    area = (ext[1] * ext[2], ext[0] * ext[2], ext[0] * ext[1])
    large = lambda a: a >= 0.5 * max(area)
    az, el = math.radians(30.0), math.radians(20.0)
    if large(area[2]):
        d = (math.sin(az) * math.cos(el), math.sin(el), math.cos(az) * math.cos(el))
    elif large(area[0]):
        d = (math.cos(az) * math.cos(el), math.sin(el), math.sin(az) * math.cos(el))
    else:
        el = math.radians(50.0)
        d = (math.sin(az) * math.cos(el), math.sin(el), math.cos(az) * math.cos(el))
    d = norm(d)
    eye = add(center, scale(d, dist))
    back = norm(sub(eye, center))
    right = norm(cross((0.0, 1.0, 0.0), back))
    up = norm(cross(back, right))
    nclip = max(dist - radius, dist * 1e-4) * 0.5
    fclip = (dist + radius) * 2.0
    return {"eye": eye, "right": right, "up": up, "back": back, "vfov": vfov, "aspect": aspect,
            "nclip": nclip, "fclip": fclip}


# ---------------------------------------------------------------- writers


def write_obj(out, objs):
    with open(os.path.join(out, "cornell_mesh.mtl"), "w") as f:
        f.write("# Written by tools/make_scenes.py\n")
        for name, albedo, emission in MATERIALS:
            f.write(f"newmtl {name}\nKd {' '.join(fmt(c) for c in albedo)}\n")
            if max(emission) > 0:
                f.write(f"Ke {' '.join(fmt(c) for c in emission)}\n")
            f.write("\n")
    with open(os.path.join(out, "cornell_mesh.obj"), "w") as f:
        f.write("# Written by tools/make_scenes.py: Cornell box with a tall box and an icosahedron\n")
        f.write("mtllib cornell_mesh.mtl\n")
        base = 1
        for name, mat, verts, polys, _ in objs:
            f.write(f"o {name}\nusemtl {mat}\n")
            for p in verts:
                f.write(f"v {' '.join(fmt(c) for c in p)}\n")
            for poly in polys:
                f.write(f"f {' '.join(str(base + i) for i in poly)}\n")
            base += len(verts)


def write_gltf(out, objs, cam):
    blob = bytearray()
    views, accessors, meshes, nodes = [], [], [], []

    def add_view(data, target):
        while len(blob) % 4:
            blob.append(0)
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data), "target": target})
        blob.extend(data)
        return len(views) - 1

    for name, mat, verts, polys, local in objs:
        stored = local if local is not None else verts
        pos = b"".join(struct.pack("<3f", *p) for p in stored)
        tris = [t for poly in polys for t in fan(poly)]
        idx = b"".join(struct.pack("<3I", *t) for t in tris)
        f32 = [struct.unpack("<3f", struct.pack("<3f", *p)) for p in stored]
        accessors.append({"bufferView": add_view(pos, 34962), "componentType": 5126, "count": len(stored),
                          "type": "VEC3", "min": [min(p[i] for p in f32) for i in range(3)],
                          "max": [max(p[i] for p in f32) for i in range(3)]})
        accessors.append({"bufferView": add_view(idx, 34963), "componentType": 5125, "count": 3 * len(tris),
                          "type": "SCALAR"})
        meshes.append({"name": name, "primitives": [{"attributes": {"POSITION": len(accessors) - 2},
                                                     "indices": len(accessors) - 1,
                                                     "material": MAT_INDEX[mat], "mode": 4}]})
        node = {"name": name, "mesh": len(meshes) - 1}
        if local is not None:
            half = TALL_ANGLE / 2
            node["rotation"] = [0.0, math.sin(half), 0.0, math.cos(half)]
            node["translation"] = list(TALL_OFFSET)
        nodes.append(node)

    r, u, b, e = cam["right"], cam["up"], cam["back"], cam["eye"]
    nodes.append({"name": "Camera", "camera": 0,
                  "matrix": [r[0], r[1], r[2], 0.0, u[0], u[1], u[2], 0.0, b[0], b[1], b[2], 0.0,
                             e[0], e[1], e[2], 1.0]})
    materials = []
    for name, albedo, emission in MATERIALS:
        m = {"name": name, "pbrMetallicRoughness": {"baseColorFactor": [*albedo, 1.0], "metallicFactor": 0.0,
                                                    "roughnessFactor": 1.0}}
        if max(emission) > 0:
            strength = max(emission)
            m["emissiveFactor"] = [c / strength for c in emission]
            m["extensions"] = {"KHR_materials_emissive_strength": {"emissiveStrength": strength}}
        materials.append(m)
    doc = {
        "asset": {"version": "2.0", "generator": "wavepath tools/make_scenes.py"},
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{"name": "Scene", "nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "cameras": [{"type": "perspective", "perspective": {
            "yfov": math.radians(cam["vfov"]), "aspectRatio": cam["aspect"],
            "znear": cam["nclip"], "zfar": cam["fclip"]}}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"uri": "cornell_mesh.bin", "byteLength": len(blob)}],
    }
    with open(os.path.join(out, "cornell_mesh.bin"), "wb") as f:
        f.write(blob)
    with open(os.path.join(out, "cornell_mesh.gltf"), "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")


def to_file(p):
    """World (X, Y, Z), Y up, to the CS184 Z_UP file frame: (-X, Z, Y)."""
    return (-p[0], p[2], p[1])


def write_dae(out, objs, cam):
    L = ['<?xml version="1.0" encoding="utf-8"?>',
         '<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">',
         "  <asset>",
         "    <contributor><authoring_tool>wavepath tools/make_scenes.py</authoring_tool></contributor>",
         '    <unit name="meter" meter="1"/>',
         "    <up_axis>Z_UP</up_axis>",
         "  </asset>"]
    xfov = 2 * math.degrees(math.atan(math.tan(math.radians(cam["vfov"]) / 2) * cam["aspect"]))
    L += ["  <library_cameras>",
          '    <camera id="Camera-camera" name="Camera">',
          "      <optics><technique_common><perspective>",
          f'        <xfov sid="xfov">{xfov!r}</xfov>',
          f"        <aspect_ratio>{cam['aspect']!r}</aspect_ratio>",
          f'        <znear sid="znear">{cam["nclip"]!r}</znear>',
          f'        <zfar sid="zfar">{cam["fclip"]!r}</zfar>',
          "      </perspective></technique_common></optics>",
          "    </camera>",
          "  </library_cameras>",
          "  <library_effects>"]
    for name, albedo, emission in MATERIALS:
        L += [f'    <effect id="{name}-effect">',
              '      <profile_COMMON><technique sid="common"><phong>',
              f'        <diffuse><color sid="diffuse">{" ".join(fmt(c) for c in albedo)} 1</color></diffuse>',
              "      </phong></technique></profile_COMMON>"]
        if max(emission) > 0:
            L += ['      <extra><technique profile="CGL">',
                  f"        <emission><radiance>{' '.join(fmt(c) for c in emission)}</radiance></emission>",
                  "      </technique></extra>"]
        L += ["    </effect>"]
    L += ["  </library_effects>", "  <library_materials>"]
    for name, _, _ in MATERIALS:
        L += [f'    <material id="{name}-material" name="{name}"><instance_effect url="#{name}-effect"/></material>']
    L += ["  </library_materials>", "  <library_geometries>"]
    for name, mat, verts, polys, _ in objs:
        tris = [t for poly in polys for t in fan(poly)]
        pos = [c for p in verts for c in to_file(p)]
        normals = []
        for a, b, c in tris:
            n = cross(sub(verts[b], verts[a]), sub(verts[c], verts[a]))
            normals.append(to_file(norm(n)))
        nrm = [c for n in normals for c in n]
        p = " ".join(f"{i} {k}" for k, t in enumerate(tris) for i in t)
        L += [f'    <geometry id="{name}-mesh" name="{name}"><mesh>',
              f'      <source id="{name}-mesh-positions">',
              f'        <float_array id="{name}-mesh-positions-array" count="{len(pos)}">'
              f'{" ".join(fmt(c) for c in pos)}</float_array>',
              f'        <technique_common><accessor source="#{name}-mesh-positions-array" count="{len(verts)}" '
              'stride="3"><param name="X" type="float"/><param name="Y" type="float"/>'
              '<param name="Z" type="float"/></accessor></technique_common>',
              "      </source>",
              f'      <source id="{name}-mesh-normals">',
              f'        <float_array id="{name}-mesh-normals-array" count="{len(nrm)}">'
              f'{" ".join(fmt(c) for c in nrm)}</float_array>',
              f'        <technique_common><accessor source="#{name}-mesh-normals-array" count="{len(normals)}" '
              'stride="3"><param name="X" type="float"/><param name="Y" type="float"/>'
              '<param name="Z" type="float"/></accessor></technique_common>',
              "      </source>",
              f'      <vertices id="{name}-mesh-vertices"><input semantic="POSITION" '
              f'source="#{name}-mesh-positions"/></vertices>',
              f'      <polylist material="{mat}-material" count="{len(tris)}">',
              f'        <input semantic="VERTEX" source="#{name}-mesh-vertices" offset="0"/>',
              f'        <input semantic="NORMAL" source="#{name}-mesh-normals" offset="1"/>',
              f'        <vcount>{" ".join("3" for _ in tris)}</vcount>',
              f"        <p>{p}</p>",
              "      </polylist>",
              "    </mesh></geometry>"]
    L += ["  </library_geometries>",
          "  <library_visual_scenes>",
          '    <visual_scene id="Scene" name="Scene">']
    # Camera matrix in the file frame: C * [R | t] with C the world->file axis map (C = C^-1).
    cols = [to_file(cam["right"]), to_file(cam["up"]), to_file(cam["back"]), to_file(cam["eye"])]
    rows = [[cols[j][i] for j in range(4)] for i in range(3)] + [[0.0, 0.0, 0.0, 1.0]]
    L += ['      <node id="Camera" name="Camera" type="NODE">',
          f'        <matrix sid="transform">{" ".join(repr(x) for r in rows for x in r)}</matrix>',
          '        <instance_camera url="#Camera-camera"/>',
          "      </node>"]
    for name, mat, _, _, _ in objs:
        L += [f'      <node id="{name}" name="{name}" type="NODE">',
              '        <matrix sid="transform">1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1</matrix>',
              f'        <instance_geometry url="#{name}-mesh"><bind_material><technique_common>'
              f'<instance_material symbol="{mat}-material" target="#{mat}-material"/>'
              "</technique_common></bind_material></instance_geometry>",
              "      </node>"]
    L += ["    </visual_scene>", "  </library_visual_scenes>",
          '  <scene><instance_visual_scene url="#Scene"/></scene>', "</COLLADA>", ""]
    with open(os.path.join(out, "cornell_mesh.dae"), "w") as f:
        f.write("\n".join(L))


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "scenes")
    os.makedirs(out, exist_ok=True)
    objs = objects()
    lo, hi = bounds(objs)
    cam = framing_camera(lo, hi)
    write_obj(out, objs)
    write_gltf(out, objs, cam)
    write_dae(out, objs, cam)
    ntri = sum(len(fan(p)) for o in objs for p in o[3])
    print(f"wrote cornell_mesh.{{obj,mtl,gltf,bin,dae}} to {os.path.normpath(out)}: {ntri} triangles, "
          f"bounds {lo} .. {hi}")


if __name__ == "__main__":
    main()
