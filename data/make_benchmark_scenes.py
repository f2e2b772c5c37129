#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Turns downloaded sources into the benchmark scenes' OBJ files, byte for byte the files that
bvhlab's tables were measured on (data/fetch_scenes.sh checks their SHA-256), and writes the
scenes.json of a folder of fetched scenes.

  make_benchmark_scenes.py furball furBall_A.bin.gz OUT.obj
      Embree's furBall_A hair model (Debian's embree-tools: 455,505 round line segments) with
      every segment made a thin 3-sided prism: 2,733,030 triangles.
  make_benchmark_scenes.py sibenik sibenik.bin OUT.obj
      the Sibenik cathedral's positions and triangles from the C arrays of sibenik.bin
      (taqu/BoundingVolumeHierarchy's sibenik.zip): 75,284 triangles.
  make_benchmark_scenes.py catalogue TEMPLATE.json DEST NAME...
      DEST/scenes.json with the cameras, AO lengths and the ray protocol of TEMPLATE for the
      scenes NAME... (those fetched).
"""
import gzip
import json
import math
import os
import sys

SIBENIK_HEADER = (
    "# Sibenik cathedral by Marko Dabrovic (RNA studio, www.RNA.HR), with holes corrected by Kenzie Lamar "
    "(Vicarious Visions);\n"
    "# version distributed in Morgan McGuire's Computer Graphics Archive (copyright.txt: originally from "
    "http://hdri.cgtechniques.com/~sibenik2/download/).\n"
    "# Geometry taken from taqu/BoundingVolumeHierarchy sibenik.zip (sibenik/sibenik.bin, C arrays of positions "
    "and triangle indices; commit a1b3c4acb57c). Positions + triangles only; no materials.\n"
    "# 75284 triangles.\n")


def furball(src, out):
    import numpy as np
    data = gzip.open(src).read()
    # furBall_A.xml: <indices ofs="0" size="455505"/>, <positions ofs="1822020" size="485872"/> (x, y, z, r).
    idx = np.frombuffer(data, dtype=np.uint32, count=455505, offset=0)
    pos = np.frombuffer(data, dtype=np.float32, count=485872 * 4, offset=1822020).reshape(-1, 4).astype(np.float64)
    p0, r0 = pos[idx, :3], pos[idx, 3]
    p1, r1 = pos[idx + 1, :3], pos[idx + 1, 3]
    d = p1 - p0
    d /= np.linalg.norm(d, axis=1)[:, None]
    # The prism's frame: u across the segment (against the x axis, or y where the segment runs along x).
    ref = np.where((np.abs(d[:, 0]) < 0.9)[:, None], np.array([1.0, 0, 0]), np.array([0, 1.0, 0]))
    u = np.cross(d, ref)
    u /= np.linalg.norm(u, axis=1)[:, None]
    w = np.cross(d, u)
    verts = np.empty((len(idx), 6, 3))
    for k in range(3):
        c, s = math.cos(2 * math.pi * k / 3), math.sin(2 * math.pi * k / 3)
        verts[:, k] = p0 + r0[:, None] * (c * u + s * w)
        verts[:, 3 + k] = p1 + r1[:, None] * (c * u + s * w)
    with open(out, "w") as f:
        f.write("# embree furBall_A.bin.gz (Debian embree-tools 3.13.5) line segments tessellated to 3-sided prisms\n")
        f.write("".join("v %g %g %g\n" % tuple(v) for v in verts.reshape(-1, 3)))
        faces = []
        for seg in range(len(idx)):
            a = 6 * seg + 1
            for i in range(3):
                j = (i + 1) % 3
                faces.append("f %d %d %d\nf %d %d %d\n" % (a + i, a + j, a + 3 + j, a + i, a + 3 + j, a + 3 + i))
        f.write("".join(faces))


def sibenik(src, out):
    import re
    text = open(src).read()
    verts = text[text.index("sibenik_vertices"):]
    verts = verts[verts.index("=") + 1:verts.index("};")]
    tris = text[text.index("sibenik_indices"):]
    tris = tris[tris.index("=") + 1:tris.index("};")]
    v = [float(x) for x in re.findall(r"[-+]?[0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?", verts)]
    t = [int(x) for x in re.findall(r"\d+", tris)]
    with open(out, "w") as f:
        f.write(SIBENIK_HEADER)
        f.write("".join("v %g %g %g\n" % tuple(v[i:i + 3]) for i in range(0, len(v), 3)))
        f.write("".join("f %d %d %d\n" % (t[i] + 1, t[i + 1] + 1, t[i + 2] + 1) for i in range(0, len(t), 3)))


def catalogue(template, dest, names):
    t = json.load(open(template))
    out = {"scenes": {n: t["scenes"][n] for n in names if n in t["scenes"]}, "ray_protocol": t["ray_protocol"]}
    tmp = os.path.join(dest, ".scenes.json.tmp")
    with open(tmp, "w") as f:
        json.dump(out, f, indent=1)
        f.write("\n")
    os.replace(tmp, os.path.join(dest, "scenes.json"))


if __name__ == "__main__":
    if len(sys.argv) < 3 or sys.argv[1] not in ("furball", "sibenik", "catalogue"):
        sys.exit(__doc__)
    if sys.argv[1] == "catalogue":
        catalogue(sys.argv[2], sys.argv[3], sys.argv[4:])
    else:
        {"furball": furball, "sibenik": sibenik}[sys.argv[1]](sys.argv[2], sys.argv[3])
