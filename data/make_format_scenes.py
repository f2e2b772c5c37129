#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Writes the small glTF and PLY scenes in data/ that the loader tests read.

    python3 data/make_format_scenes.py [OUT_DIR]   (default: the folder of this script)

Standard library only; the output is deterministic, so running it again changes nothing.
  instances.gltf / instances.glb  three meshes: a cube of two primitives (plastic, glass) placed
                                  by three nodes (one under a rotated parent), a gold floor quad
                                  (with vertex normals) and a lamp quad placed once each; a perspective camera
                                  (yfov 0.8, aspect 1.5) at (0.5, 0.5, 6) looking down -z.
  cube_ascii.ply / cube_binary.ply  the same unit cube (8 vertices, 6 quads) in both encodings.
  smooth_spheres.obj              five icospheres of radius 1 (320 triangles each; white, plastic,
                                  glass, metal, mirror of glass_mirror.mtl) with their analytic
                                  normals as `vn`, on a floor and under a lamp that have none.
"""
import base64
import json
import math
import os
import struct
import sys

CUBE_V = [(x, y, z) for x in (0.0, 1.0) for y in (0.0, 1.0) for z in (0.0, 1.0)]  # vertex i: bits x y z
CUBE_QUADS = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
CUBE_TRIS = [t for q in CUBE_QUADS for t in ((q[0], q[1], q[2]), (q[0], q[2], q[3]))]
QUAD_V = [(-2.0, 0.0, -2.0), (2.0, 0.0, -2.0), (2.0, 0.0, 2.0), (-2.0, 0.0, 2.0)]
QUAD_UV = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
QUAD_TRIS = [(0, 2, 1), (0, 3, 2)]
LAMP_V = [(0.0, 3.0, 0.0), (1.0, 3.0, 0.0), (1.0, 3.0, 1.0), (0.0, 3.0, 1.0)]


def gltf_document():
    """The glTF JSON (without buffers) and the binary buffer it refers to."""
    blob = bytearray()
    views, accessors = [], []

    def add(data, fmt, count, ctype, type_, target, minmax=None):
        while len(blob) % 4:
            blob.append(0)
        offset = len(blob)
        blob.extend(struct.pack("<" + fmt * count, *data))
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(blob) - offset, "target": target})
        acc = {"bufferView": len(views) - 1, "componentType": ctype, "count": count // {"VEC3": 3, "VEC2": 2, "SCALAR": 1}[type_],
               "type": type_}
        if minmax:
            acc["min"], acc["max"] = minmax
        accessors.append(acc)
        return len(accessors) - 1

    flat = lambda rows: [c for r in rows for c in r]
    cube_pos = add(flat(CUBE_V), "f", 24, 5126, "VEC3", 34962, ([0, 0, 0], [1, 1, 1]))
    cube_idx_a = add(flat(CUBE_TRIS[:6]), "H", 18, 5123, "SCALAR", 34963)
    cube_idx_b = add(flat(CUBE_TRIS[6:]), "H", 18, 5123, "SCALAR", 34963)
    quad_pos = add(flat(QUAD_V), "f", 12, 5126, "VEC3", 34962, ([-2, 0, -2], [2, 0, 2]))
    quad_uv = add(flat(QUAD_UV), "f", 8, 5126, "VEC2", 34962)
    quad_normal = add([0.0, 1.0, 0.0] * 4, "f", 12, 5126, "VEC3", 34962)
    quad_idx = add(flat(QUAD_TRIS), "H", 6, 5123, "SCALAR", 34963)
    lamp_pos = add(flat(LAMP_V), "f", 12, 5126, "VEC3", 34962, ([0, 3, 0], [1, 3, 1]))
    s = math.sqrt(0.5)
    doc = {
        "asset": {"version": "2.0", "generator": "bvhlab data/make_format_scenes.py"},
        "extensionsUsed": ["KHR_materials_transmission"],
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2, 3, 5, 6]}],
        "nodes": [
            {"name": "floor", "mesh": 1, "translation": [0.0, -0.5, 0.0]},
            {"name": "cube-a", "mesh": 0},
            {"name": "cube-b", "mesh": 0, "translation": [2.0, 0.0, 0.0], "scale": [0.5, 0.5, 0.5]},
            # a parent turned 90 degrees about y, holding the third cube one unit along its x
            {"name": "turntable", "rotation": [0.0, s, 0.0, s], "children": [4]},
            {"name": "cube-c", "mesh": 0, "translation": [1.0, 0.0, 0.0]},
            {"name": "camera", "camera": 0, "translation": [0.5, 0.5, 6.0]},
            {"name": "lamp", "mesh": 2},
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "aspectRatio": 1.5, "znear": 0.01}}],
        "meshes": [
            {"name": "cube", "primitives": [{"attributes": {"POSITION": cube_pos}, "indices": cube_idx_a, "material": 0},
                                            {"attributes": {"POSITION": cube_pos}, "indices": cube_idx_b, "material": 3}]},
            {"name": "quad", "primitives": [{"attributes": {"POSITION": quad_pos, "NORMAL": quad_normal,
                                                            "TEXCOORD_0": quad_uv},
                                             "indices": quad_idx, "material": 1}]},
            {"name": "lamp", "primitives": [{"attributes": {"POSITION": lamp_pos}, "indices": quad_idx, "material": 2}]},
        ],
        "materials": [
            {"name": "red-plastic", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.1, 0.1, 1.0],
                                                             "metallicFactor": 0.0, "roughnessFactor": 0.3}},
            {"name": "gold", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.78, 0.34, 1.0],
                                                      "metallicFactor": 1.0, "roughnessFactor": 0.2}},
            {"name": "lamp", "emissiveFactor": [1.0, 0.9, 0.8],
             "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0}},
            {"name": "glass", "pbrMetallicRoughness": {"metallicFactor": 0.0, "roughnessFactor": 0.0},
             "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}}},
        ],
        "accessors": accessors,
        "bufferViews": views,
    }
    return doc, bytes(blob)


def write_gltf(path):
    doc, blob = gltf_document()
    doc["buffers"] = [{"byteLength": len(blob),
                       "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}]
    with open(path, "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")


def write_glb(path):
    doc, blob = gltf_document()
    doc["buffers"] = [{"byteLength": len(blob)}]
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    blob += b"\0" * (-len(blob) % 4)
    total = 12 + 8 + len(text) + 8 + len(blob)
    with open(path, "wb") as f:
        f.write(struct.pack("<4sII", b"glTF", 2, total))
        f.write(struct.pack("<I4s", len(text), b"JSON") + text)
        f.write(struct.pack("<I4s", len(blob), b"BIN\0") + blob)


def write_ply(path, binary):
    header = ["ply", "format " + ("binary_little_endian" if binary else "ascii") + " 1.0",
              "comment bvhlab data/make_format_scenes.py: the unit cube", "element vertex 8",
              "property float x", "property float y", "property float z", "element face 6",
              "property list uchar int vertex_indices", "end_header"]
    with open(path, "wb") as f:
        f.write(("\n".join(header) + "\n").encode())
        for v in CUBE_V:
            f.write(struct.pack("<3f", *v) if binary else ("%g %g %g\n" % v).encode())
        for q in CUBE_QUADS:
            f.write(struct.pack("<B4i", 4, *q) if binary else ("4 %d %d %d %d\n" % q).encode())


def icosphere(levels):
    """Vertices on the unit sphere and triangles of an icosahedron subdivided `levels` times."""
    t = (1.0 + math.sqrt(5.0)) / 2.0
    unit = lambda p: tuple(c / math.sqrt(sum(x * x for x in p)) for c in p)
    v = [unit(p) for p in [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
                           (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
         (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11),
         (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(levels):
        mid = {}

        def midpoint(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                v.append(unit(tuple((x + y) / 2 for x, y in zip(v[a], v[b]))))
                mid[key] = len(v) - 1
            return mid[key]
        g = []
        for a, b, c in f:
            ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
            g += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = g
    return v, f


def write_smooth_spheres(path):
    lines = ["# Shading-normal test scene, written by bvhlab data/make_format_scenes.py: five icospheres of",
             "# radius 1 (320 triangles each) with their analytic normals as vn, one per renderer BSDF, on a",
             "# floor and under a lamp whose faces have no vn (the geometric normal shades them).",
             "mtllib glass_mirror.mtl"]
    fmt = lambda p: " ".join("%.9g" % c for c in p)
    nv = 0
    for p in [(-7, -1, -7), (7, -1, -7), (7, -1, 7), (-7, -1, 7), (-1, 6, -1), (1, 6, -1), (1, 6, 1), (-1, 6, 1)]:
        lines.append("v " + fmt(p))
    lines += ["usemtl white", "f 1 3 2", "f 1 4 3", "usemtl light", "f 5 6 7", "f 5 7 8"]
    nv = 8
    sv, sf = icosphere(2)
    for k, mtl in enumerate(["white", "plastic", "glass", "metal", "mirror"]):
        cx = -4.4 + 2.2 * k
        lines.append("o sphere-" + mtl)
        lines += ["v " + fmt((cx + x, y, z)) for x, y, z in sv]
        lines += ["vn " + fmt(n) for n in sv]
        lines.append("usemtl " + mtl)
        lines += ["f " + " ".join("%d//%d" % (nv + i + 1, nv + i + 1 - 8) for i in tri) for tri in sf]
        nv += len(sv)
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
    write_gltf(os.path.join(out, "instances.gltf"))
    write_glb(os.path.join(out, "instances.glb"))
    write_ply(os.path.join(out, "cube_ascii.ply"), binary=False)
    write_ply(os.path.join(out, "cube_binary.ply"), binary=True)
    write_smooth_spheres(os.path.join(out, "smooth_spheres.obj"))


if __name__ == "__main__":
    main()
