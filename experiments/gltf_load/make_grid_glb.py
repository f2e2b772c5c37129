#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Writes a GLB of one grid mesh of 2 * N * N triangles with normals (the glTF load-time
measurement, experiments/NOTES.md, session 22). Standard library only.

    python3 make_grid_glb.py N OUT.glb        (N = 708: 1,002,528 triangles)
"""
import json
import math
import struct
import sys


def main():
    n, out = int(sys.argv[1]), sys.argv[2]
    pos, nrm, idx = bytearray(), bytearray(), bytearray()
    for j in range(n + 1):
        for i in range(n + 1):
            x, z = i / n, j / n
            y = 0.05 * math.sin(12 * x) * math.cos(9 * z)
            pos += struct.pack("<3f", x, y, z)
            nrm += struct.pack("<3f", 0.0, 1.0, 0.0)
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            idx += struct.pack("<6I", a, a + n + 1, a + 1, a + 1, a + n + 1, a + n + 2)
    blob = pos + nrm + idx
    nv = (n + 1) ** 2
    doc = {
        "asset": {"version": "2.0", "generator": "bvhlab experiments/gltf_load/make_grid_glb.py"},
        "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2}]}],
        "buffers": [{"byteLength": len(blob)}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(pos)},
                        {"buffer": 0, "byteOffset": len(pos), "byteLength": len(nrm)},
                        {"buffer": 0, "byteOffset": len(pos) + len(nrm), "byteLength": len(idx)}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": nv, "type": "VEC3",
                       "min": [0, -0.05, 0], "max": [1, 0.05, 1]},
                      {"bufferView": 1, "componentType": 5126, "count": nv, "type": "VEC3"},
                      {"bufferView": 2, "componentType": 5125, "count": 6 * n * n, "type": "SCALAR"}],
    }
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    blob += b"\0" * (-len(blob) % 4)
    with open(out, "wb") as f:
        f.write(struct.pack("<4sII", b"glTF", 2, 12 + 8 + len(text) + 8 + len(blob)))
        f.write(struct.pack("<I4s", len(text), b"JSON") + text)
        f.write(struct.pack("<I4s", len(blob), b"BIN\0") + blob)


if __name__ == "__main__":
    main()
