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
import os as _os

from ._bvhlab import render as _render
from ._bvhlab import (  # noqa: F401
    HIT_DTYPE,
    RAY_DTYPE,
    Refitter,
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


def render(structure, *args, denoise=False, oidn="", **kwargs):
    """Path-traces a structure's scene; returns a float32 (height, width, 3) image. With
    denoise=True also Intel Open Image Denoise's result, as (image, denoised): the library is
    oidn= (a file or folder), else the installed pyoidn wheel's, else what `bvhlab render
    --denoise` finds. Every other argument is the native render's (see its help)."""
    if denoise and not oidn:
        try:
            import pyoidn

            oidn = _os.path.join(_os.path.dirname(pyoidn.__file__), "oidn", "lib")
        except ImportError:
            pass
    return _render(structure, *args, denoise=denoise, oidn=oidn, **kwargs)


render.__doc__ += "\n\n" + (_render.__doc__ or "")
