#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Writes the small glTF and PLY scenes in data/ that the loader tests read.

    python3 data/make_format_scenes.py [OUT_DIR]   (default: the folder of this script)

Standard library only; the output is deterministic, so running it again changes nothing.
  instances.gltf / instances.glb  three meshes: a cube of two primitives (plastic, glass) placed
                                  by three nodes (one under a rotated parent), a gold floor quad
                                  and a lamp quad placed once each; a perspective camera
                                  (yfov 0.8, aspect 1.5) at (0.5, 0.5, 6) looking down -z.
  cube_ascii.ply / cube_binary.ply  the same unit cube (8 vertices, 6 quads) in both encodings.
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
            {"name": "quad", "primitives": [{"attributes": {"POSITION": quad_pos, "TEXCOORD_0": quad_uv},
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


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
    write_gltf(os.path.join(out, "instances.gltf"))
    write_glb(os.path.join(out, "instances.glb"))
    write_ply(os.path.join(out, "cube_ascii.ply"), binary=False)
    write_ply(os.path.join(out, "cube_binary.ply"), binary=True)


if __name__ == "__main__":
    main()
