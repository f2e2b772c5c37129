#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Writes the normal-mapping cost scenes into OUT: the glass-and-mirror Cornell box
(data/glass_mirror.obj, 672 triangles: shading outweighs tracing, the worst case for the maps'
cost) with box-projected texture coordinates (1 unit of u or v per 100 mm) and a checker map_Kd
on its diffuse walls and blocks, in three variants sharing that geometry:

  textured  map_Kd only
  normal    map_Kd and a tangent-space normal map (norm) of round bumps on every non-glass material
  height    map_Kd and the same bumps as a grey height map (map_Bump -bm 5: 5 mm bumps)

and, when SIBENIK (the shared sibenik.obj, 75,275 triangles) is given, the same three as
sibenik-textured, sibenik-normal and sibenik-height (one stone material, 1 unit of u or v per
metre, -bm 0.05); OUT/scenes.json has their cameras, so that BVHLAB_SCENES=OUT bvhlab render NAME
works. Textures are PFM, which every build reads. Usage: make_scenes.py OUT [SIBENIK]"""
import json
import math
import os
import struct
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SIZE = 256  # texels per side
BUMPS = 4  # bumps per side of the texture


def write_pfm(path, texels):
    """texels: rows top first, each a list of (r, g, b)."""
    with open(path, "wb") as f:
        f.write(b"PF\n%d %d\n-1.0\n" % (SIZE, SIZE))
        for row in reversed(texels):  # PFM stores the bottom row first
            f.write(b"".join(struct.pack("<3f", *c) for c in row))


def bump(x, y):
    """Height in [0, 1] of a round bump and its gradient per texel, at texel (x, y)."""
    cell = SIZE / BUMPS
    cx, cy = (x % cell) / cell - 0.5, (y % cell) / cell - 0.5
    r2 = (cx * cx + cy * cy) / 0.16
    if r2 >= 1.0:
        return 0.0, 0.0, 0.0
    h = math.sqrt(1.0 - r2)
    # d h / d texel, along +x and along +y of the image (down the rows)
    dh = -1.0 / max(h, 0.05) / 0.16 / cell
    return h, dh * cx, dh * cy


def write_textures(out):
    checker = [[(0.8, 0.8, 0.8) if ((x // 32) + (y // 32)) % 2 == 0 else (0.35, 0.35, 0.35) for x in range(SIZE)]
               for y in range(SIZE)]
    write_pfm(os.path.join(out, "checker.pfm"), checker)
    heights, normals = [], []
    for y in range(SIZE):
        hrow, nrow = [], []
        for x in range(SIZE):
            h, gx, gy = bump(x + 0.5, y + 0.5)
            hrow.append((h, h, h))
            # +v runs up the image (against the rows): the tangent-space y slope is -gy.
            n = (-gx * 8.0, gy * 8.0, 1.0)
            ln = math.sqrt(sum(c * c for c in n))
            nrow.append(tuple((c / ln + 1.0) / 2.0 for c in n))
        heights.append(hrow)
        normals.append(nrow)
    write_pfm(os.path.join(out, "heights.pfm"), heights)
    write_pfm(os.path.join(out, "bumps.pfm"), normals)


def read_obj(path):
    verts, faces, lines = [], [], []
    for line in open(path):
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "v":
            verts.append(tuple(float(p) for p in parts[1:4]))
        elif parts[0] == "f":
            idx = [int(p.split("/")[0]) for p in parts[1:]]
            for k in range(1, len(idx) - 1):  # fan
                lines.append(("f", (idx[0], idx[k], idx[k + 1])))
        elif parts[0] in ("usemtl", "o"):
            lines.append((parts[0], parts[1]))
    return verts, lines


def write_obj(out, name, mtl, verts, lines, uv_per_unit):
    with open(os.path.join(out, name + ".obj"), "w") as f:
        f.write("# %s: the glass-and-mirror box with box-projected texture coordinates (make_scenes.py)\n" % name)
        f.write("mtllib %s\n" % mtl)
        for v in verts:
            f.write("v %g %g %g\n" % v)
        t = 0
        for kind, data in lines:
            if kind != "f":
                f.write("%s %s\n" % (kind, data))
                continue
            a, b, c = (verts[i - 1] for i in data)
            e1 = [b[k] - a[k] for k in range(3)]
            e2 = [c[k] - a[k] for k in range(3)]
            n = [abs(e1[1] * e2[2] - e1[2] * e2[1]), abs(e1[2] * e2[0] - e1[0] * e2[2]), abs(e1[0] * e2[1] - e1[1] * e2[0])]
            axis = n.index(max(n))  # project along the dominant axis
            u_axis, v_axis = [(2, 1), (0, 2), (0, 1)][axis]
            for p in (a, b, c):
                f.write("vt %g %g\n" % (p[u_axis] * uv_per_unit, p[v_axis] * uv_per_unit))
            f.write("f %d/%d %d/%d %d/%d\n" % (data[0], t + 1, data[1], t + 2, data[2], t + 3))
            t += 3


def write_mtl(out, name, base, extra):
    blocks = base.split("newmtl ")
    text = blocks[0]
    for b in blocks[1:]:
        mat = b.split()[0]
        body = b.rstrip("\n") + "\n"
        if mat in ("white", "plastic", "stone"):
            body += "map_Kd checker.pfm\n"
        if mat not in ("glass", "light") and extra:
            body += extra + "\n"
        text += "newmtl " + body + "\n"
    open(os.path.join(out, name + ".mtl"), "w").write(text)


def main():
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    write_textures(out)
    sources = [("", os.path.join(ROOT, "data", "glass_mirror.obj"), open(os.path.join(ROOT, "data", "glass_mirror.mtl")).read(),
                json.load(open(os.path.join(ROOT, "data", "scenes.json")))["scenes"]["glass-mirror"]["camera"], 0.01, 5)]
    if len(sys.argv) > 2:
        # The shared scene's camera (scenes.json beside its folder).
        shared = json.load(open(os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[2]))), "scenes.json")))
        sources.append(("sibenik-", sys.argv[2], "newmtl stone\nKd 0.7 0.7 0.7\n", shared["scenes"]["sibenik"]["camera"],
                        1.0, 0.05))
    scenes = {}
    for prefix, obj, base, camera, uv_per_unit, bm in sources:
        verts, lines = read_obj(obj)
        if not any(kind == "usemtl" for kind, _ in lines):
            lines.insert(0, ("usemtl", "stone"))
        for name, extra in (("textured", ""), ("normal", "norm bumps.pfm"), ("height", "map_Bump -bm %g heights.pfm" % bm)):
            write_mtl(out, prefix + name, base, extra)
            write_obj(out, prefix + name, prefix + name + ".mtl", verts, lines, uv_per_unit)
            scenes[prefix + name] = {"file": prefix + name + ".obj", "camera": camera}
    json.dump({"scenes": scenes}, open(os.path.join(out, "scenes.json"), "w"), indent=1)


if __name__ == "__main__":
    main()
