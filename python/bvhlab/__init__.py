# SPDX-License-Identifier: MIT
"""bvhlab: acceleration structures for ray tracing, built, traced on the CPU and GPU, and
checked ray by ray against Embree.

    import bvhlab
    scene = bvhlab.load("data/cornell_box.obj")        # or bvhlab.Scene(vertices, indices)
    s = bvhlab.build(scene, builder="sbvh", layout="bvh2", max_leaf=4)
    rays, query = bvhlab.rays(scene, "diffuse", width=640, height=480)
    hits, info = bvhlab.trace(s, rays, query, device="gpu")   # numpy HIT_DTYPE records
    report = bvhlab.verify(scene, rays, hits, query)          # report["mismatches"] == 0

Errors are bvhlab.Error, with the command-line tool's one-line messages. See docs/python.md.
"""
from ._bvhlab import (  # noqa: F401
    HIT_DTYPE,
    RAY_DTYPE,
    Error,
    Scene,
    Structure,
    __commit__,
    build,
    generate,
    gpu_available,
    kernels,
    load,
    load_structure,
    rays,
    read_hits,
    read_rays,
    render,
    trace,
    verify,
    write_hits,
    write_rays,
)


def mrays_per_s(rays, info):
    """Mrays/s of a trace() call: the ray count over the median of its runs' times."""
    ms = sorted(info["ms"])
    mid = len(ms) // 2
    median = ms[mid] if len(ms) % 2 else 0.5 * (ms[mid - 1] + ms[mid])
    return len(rays) / (median * 1e3) if median > 0 else 0.0
