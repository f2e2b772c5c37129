# SPDX-License-Identifier: MIT
"""The Python module: scenes, the factory, rays and files as numpy records, tracing with the GIL
released, verification against Embree, rendering, and errors as bvhlab.Error."""
import os
import threading

import numpy as np
import pytest

import bvhlab

DATA = os.environ.get("BVHLAB_DATA", os.path.join(os.path.dirname(__file__), "..", "..", "data"))
CORNELL = os.path.join(DATA, "cornell_box.obj")
HAVE_GPU, NO_GPU_WHY = bvhlab.gpu_available()
needs_gpu = pytest.mark.skipif(not HAVE_GPU, reason=f"no GPU: {NO_GPU_WHY}")


def quad():
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=np.float32)
    i = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32)
    return v, i


@pytest.fixture(scope="module")
def cornell():
    return bvhlab.load(CORNELL)


def test_scene_from_arrays_keeps_ids_and_refuses_bad_triangles():
    v, i = quad()
    s = bvhlab.Scene(v, i)
    assert s.triangle_count == 2
    assert len(s.hash) == 16
    assert np.array_equal(s.indices, i)
    assert np.allclose(s.vertices, v)
    assert s.hash == bvhlab.Scene(v.astype(np.float64), i.astype(np.int64)).hash  # converted, same triangles
    with pytest.raises(bvhlab.Error, match="names vertex 7"):
        bvhlab.Scene(v, np.array([[0, 1, 7]]))
    with pytest.raises(bvhlab.Error, match="triangle 1 has zero area"):
        bvhlab.Scene(v, np.array([[0, 1, 2], [0, 0, 1]]))
    bad = v.copy()
    bad[3, 0] = np.nan
    with pytest.raises(bvhlab.Error, match="non-finite"):
        bvhlab.Scene(bad, i)
    with pytest.raises(bvhlab.Error, match=r"\(N, 3\)"):
        bvhlab.Scene(v[:, :2], i)
    dropped = bvhlab.Scene(v, np.array([[0, 0, 1], [0, 1, 2], [1, 1, 1], [0, 2, 3]]), drop_degenerate=True)
    assert dropped.triangle_count == 2
    assert list(dropped.kept) == [1, 3]
    with pytest.raises(bvhlab.Error, match="no usable triangles"):
        bvhlab.Scene(v, np.array([[0, 0, 1]]), drop_degenerate=True)


def test_load_and_generate(cornell):
    assert cornell.triangle_count > 30
    assert cornell.source == CORNELL
    with pytest.raises(bvhlab.Error, match="nothing.obj"):
        bvhlab.load(os.path.join(DATA, "nothing.obj"))
    g = bvhlab.generate("soup", 500, 3)
    assert g.triangle_count == 500
    assert g.hash == bvhlab.generate("soup", 500, 3).hash
    with pytest.raises(bvhlab.Error, match="blob"):
        bvhlab.generate("blob", 10)


def test_load_other_formats_and_instanced_scenes():
    ply = bvhlab.load(os.path.join(DATA, "cube_binary.ply"))
    assert ply.triangle_count == 12
    assert ply.hash == bvhlab.load(os.path.join(DATA, "cube_ascii.ply")).hash
    glb = os.path.join(DATA, "instances.glb")
    with pytest.raises(bvhlab.Error, match="places 2 meshes 4 times.*flatten"):
        bvhlab.load(glb)
    flat = bvhlab.load(glb, flatten=True)
    assert flat.triangle_count == 40
    assert flat.hash == bvhlab.load(os.path.join(DATA, "instances.gltf"), flatten=True).hash


@pytest.mark.parametrize("builder,layout,name", [
    ("binned", "bvh2", "bvh2/binned"), ("sweep", "bvh2", "bvh2/sweep"), ("sbvh", "bvh2", "bvh2/sbvh"),
    ("sbvh", "cwbvh", "cwbvh/sbvh"), ("kdtree", "bvh2", "kdtree")])
def test_every_structure_traces_like_embree_on_the_cpu(cornell, builder, layout, name):
    s = bvhlab.build(cornell, builder=builder, layout=layout, epo=False)
    assert s.name == name
    assert s.stats["structure"] == name
    assert s.stats["sah"] > 0 and s.stats["nodes"] >= 1
    for kind in ("primary", "diffuse", "shadow"):
        rays, query = bvhlab.rays(cornell, kind, width=80, height=60)
        assert rays.dtype == bvhlab.RAY_DTYPE and rays.dtype.itemsize == 32
        hits, info = bvhlab.trace(s, rays, query)
        assert hits.dtype == bvhlab.HIT_DTYPE and len(hits) == len(rays)
        assert info["device"] == "cpu" and len(info["ms"]) == 1
        report = bvhlab.verify(cornell, rays, hits, query)
        assert report["rays"] == len(rays)
        assert report["mismatches"] == 0, report["first_mismatches"]
        assert report["agree"] + report["ties"] == len(rays)


def test_embree_device_traces_the_reference(cornell):
    s = bvhlab.build(cornell, builder="sweep")
    for kind in ("primary", "shadow"):
        rays, query = bvhlab.rays(cornell, kind, width=40, height=30)
        hits, info = bvhlab.trace(s, rays, query, device="embree", runs=2)
        assert info["device"] == "embree" and info["kernel"] != s.name and len(info["ms"]) == 2
        report = bvhlab.verify(cornell, rays, hits, query)
        assert report["agree"] == len(rays) and report["ties"] == 0  # Embree's own hits
    with pytest.raises(bvhlab.Error, match="needs device='gpu'"):
        bvhlab.trace(s, rays, device="embree", kernel="plain")


def test_verify_catches_a_wrong_hit(cornell):
    s = bvhlab.build(cornell)
    rays, query = bvhlab.rays(cornell, "primary", width=40, height=30)
    hits, _ = bvhlab.trace(s, rays, query)
    i = int(np.flatnonzero(hits["tri"] >= 0)[0])
    hits["tri"][i] = (hits["tri"][i] + 5) % cornell.triangle_count  # a made-up hit
    report = bvhlab.verify(cornell, rays, hits, query)
    assert report["mismatches"] >= 1
    assert report["first_mismatches"][0]["ray"] == i


def test_build_options_and_their_errors(cornell):
    s = bvhlab.build(cornell, "sbvh", max_leaf=2, alpha=1e-4, reinsertion_passes=0)
    assert s.stats["max_leaf"] == 2 and s.stats["max_leaf_size"] <= 2
    assert s.stats["reinsertion_passes"] == 0
    with pytest.raises(bvhlab.Error, match="no option 'leaves'"):
        bvhlab.build(cornell, leaves=3)
    with pytest.raises(bvhlab.Error, match="bins 1 is not in"):
        bvhlab.build(cornell, bins=1)
    with pytest.raises(bvhlab.Error, match="octree"):
        bvhlab.build(cornell, builder="octree")
    with pytest.raises(bvhlab.Error, match="cwbvh"):
        bvhlab.build(cornell, builder="kdtree", layout="cwbvh")
    with pytest.raises(bvhlab.Error, match="runs on the GPU only"):
        bvhlab.build(cornell, builder="hploc", build_device="cpu")
    with pytest.raises(bvhlab.Error, match="morton_bits 31"):
        bvhlab.build(cornell, builder="lbvh", morton_bits=31)
    with pytest.raises(bvhlab.Error, match=r"clusters 0.5 is neither 0 \(off\) nor in \[1, 16\]"):
        bvhlab.build(cornell, builder="gpu-binned", clusters=0.5)
    with pytest.raises(bvhlab.Error, match="clusters applies to builder gpu-binned, not hploc"):
        bvhlab.build(cornell, builder="hploc", clusters=1.3)


@needs_gpu
def test_gpu_builders(cornell):
    for builder in ("lbvh", "ploc", "hploc", "gpu-binned"):
        radius = builder in ("ploc", "hploc")
        s = bvhlab.build(cornell, builder, radius=4) if radius else bvhlab.build(cornell, builder)
        assert s.stats["build_device"] == "gpu" and s.stats["gpu_build"]["total_ms"] > 0
        assert s.stats.get("radius") == (4 if radius else None)
        assert s.stats.get("bins") == (32 if builder == "gpu-binned" else None)
        rays, query = bvhlab.rays(cornell, "primary", width=40, height=30)
        hits, _ = bvhlab.trace(s, rays, query, device="gpu")
        assert bvhlab.verify(cornell, rays, hits, query)["mismatches"] == 0
    s = bvhlab.build(cornell, "gpu-binned", clusters=1.3)  # clusters of nearly coincident triangles
    assert s.stats["cluster_alpha"] == pytest.approx(1.3) and s.stats["gpu_build"]["clusters"] > 0
    rays, query = bvhlab.rays(cornell, "diffuse", width=40, height=30)
    hits, _ = bvhlab.trace(s, rays, query, device="gpu")
    assert bvhlab.verify(cornell, rays, hits, query)["mismatches"] == 0


def test_files_round_trip_and_stale_structures_are_refused(cornell, tmp_path):
    rays, query = bvhlab.rays(cornell, "ao", width=32, height=24)
    assert query == "any"
    bvhlab.write_rays(str(tmp_path / "ao.rays"), rays, query)
    back, q = bvhlab.read_rays(str(tmp_path / "ao.rays"))
    assert q == "any" and back.tobytes() == rays.tobytes()
    s = bvhlab.build(cornell, "sweep")
    hits, _ = bvhlab.trace(s, rays, query)
    bvhlab.write_hits(str(tmp_path / "ao.hits"), hits, query)
    hback, _ = bvhlab.read_hits(str(tmp_path / "ao.hits"))
    assert hback.tobytes() == hits.tobytes()
    s.save(str(tmp_path / "s.bvh"))
    loaded = bvhlab.load_structure(str(tmp_path / "s.bvh"), cornell)
    assert loaded.name == "bvh2/sweep" and loaded.bytes == s.bytes
    other = bvhlab.generate("soup", 100)
    with pytest.raises(bvhlab.Error, match="stale structure file"):
        bvhlab.load_structure(str(tmp_path / "s.bvh"), other)
    with pytest.raises(bvhlab.Error, match="checksum|truncated|magic"):
        (tmp_path / "broken.rays").write_bytes((tmp_path / "ao.rays").read_bytes()[:-7])
        bvhlab.read_rays(str(tmp_path / "broken.rays"))


def test_bad_ray_arrays_are_refused(cornell):
    s = bvhlab.build(cornell)
    rays, _ = bvhlab.rays(cornell, width=8, height=8)
    with pytest.raises(bvhlab.Error, match="RAY_DTYPE"):
        bvhlab.trace(s, np.zeros(10, dtype=np.float32))
    with pytest.raises(bvhlab.Error, match="1-D"):
        bvhlab.trace(s, np.zeros((10, 8), dtype=np.float32))
    with pytest.raises(bvhlab.Error, match="C-contiguous"):
        bvhlab.trace(s, rays[::2])
    broken = rays.copy()
    broken["dir"][3] = 0
    with pytest.raises(bvhlab.Error, match="ray 3 is invalid"):
        bvhlab.trace(s, broken)
    with pytest.raises(bvhlab.Error, match="device 'tpu'"):
        bvhlab.trace(s, rays, device="tpu")
    with pytest.raises(bvhlab.Error, match="needs device='gpu'"):
        bvhlab.trace(s, rays, kernel="plain")
    with pytest.raises(bvhlab.Error, match="query 'nearest'"):
        bvhlab.trace(s, rays, query="nearest")
    with pytest.raises(bvhlab.Error, match="unknown ray type|flash"):
        bvhlab.rays(cornell, "flash")


def test_trace_releases_the_gil():
    scene = bvhlab.generate("structured", 200000, 1)
    s = bvhlab.build(scene, epo=False)
    rays, query = bvhlab.rays(scene, "diffuse", width=256, height=256)
    done = []
    t = threading.Thread(target=lambda: done.append(bvhlab.trace(s, rays, query, runs=3)))
    t.start()
    ticks = 0
    while t.is_alive():
        ticks += 1
    t.join()
    assert done and len(done[0][0]) == len(rays)
    assert ticks > 1000, "the main thread did not run while trace() traced: the GIL was held"


CORNELL_CAMERA = dict(eye=[278, 273, -800], target=[278, 273, 0], up=[0, 1, 0], fov=39.3)  # data/scenes.json


def read_pfm(path):
    with open(path, "rb") as f:
        kind, size, scale = f.readline(), f.readline(), f.readline()
        w, h = map(int, size.split())
        assert kind.strip() == b"PF" and float(scale) < 0
        return np.frombuffer(f.read(), dtype="<f4").reshape(h, w, 3)[::-1]  # PFM rows run bottom to top


def test_render_on_the_cpu(cornell):
    s = bvhlab.build(cornell)
    img = bvhlab.render(s, width=32, height=24, spp=4, **CORNELL_CAMERA)
    assert img.shape == (24, 32, 3) and img.dtype == np.float32
    assert np.isfinite(img).all() and (img >= 0).all()
    assert img.mean() > 0.01
    with pytest.raises(bvhlab.Error, match="sky"):
        bvhlab.render(s, sky=[1, 2])


@pytest.mark.skipif("BVHLAB_CLI" not in os.environ, reason="BVHLAB_CLI (the bvhlab binary) is not set")
def test_render_and_trace_equal_the_command_line_tool(cornell, tmp_path):
    import subprocess
    cli = os.environ["BVHLAB_CLI"]
    out = tmp_path / "cli.pfm"
    subprocess.run([cli, "render", CORNELL, "-o", str(out), "--width", "32", "--height", "24", "--spp", "4",
                    "--device", "cpu", "--kernel", "plain", "--quiet"], check=True)
    s = bvhlab.build(cornell)
    img = bvhlab.render(s, width=32, height=24, spp=4, **CORNELL_CAMERA)
    assert np.array_equal(img, read_pfm(out)), "the module's render differs from `bvhlab render`"
    subprocess.run([cli, "render", CORNELL, "-o", str(out), "--width", "32", "--height", "24", "--spp", "4",
                    "--device", "embree", "--quiet"], check=True)
    ref = bvhlab.render(s, width=32, height=24, spp=4, device="embree", **CORNELL_CAMERA)
    assert np.array_equal(ref, read_pfm(out)), "the module's reference render differs from `bvhlab render`"
    assert np.abs(ref - img).mean() < 0.01 * img.mean()  # the same integrator, traced by Embree
    rays, query = bvhlab.rays(cornell, "diffuse", width=40, height=30, **CORNELL_CAMERA)
    bvhlab.write_rays(str(tmp_path / "d.rays"), rays, query)
    subprocess.run([cli, "bench", CORNELL, "--rays", str(tmp_path / "d.rays"), "--hits-out", str(tmp_path / "d.hits"),
                    "--runs", "1", "--quiet"], check=True, stdout=subprocess.DEVNULL)
    cli_hits, _ = bvhlab.read_hits(str(tmp_path / "d.hits"))
    hits, _ = bvhlab.trace(s, rays, query)
    assert hits.tobytes() == cli_hits.tobytes(), "the module's hits differ from `bvhlab bench --hits-out`"


def test_kernels_name_one_default_per_layout():
    ks = bvhlab.kernels()
    if not ks:
        pytest.skip("built without CUDA: no GPU kernels")
    assert len({k["name"] for k in ks}) == len(ks)
    defaults = [(k["layout"], k["short_stack"]) for k in ks if k["default"]]
    assert sorted(defaults) == sorted({("bvh2", False), ("cwbvh", False), ("kdtree", False), ("kdtree", True),
                                       ("two-level", False), ("two-level-cwbvh", False)})


def test_refitter_needs_a_bvh2_structure_and_a_gpu(cornell):
    with pytest.raises(bvhlab.Error, match="single-level BVH2"):
        bvhlab.Refitter(bvhlab.build(cornell, layout="cwbvh", epo=False))
    if not HAVE_GPU:
        with pytest.raises(bvhlab.Error, match="refit runs on the GPU, and there is none"):
            bvhlab.Refitter(bvhlab.build(cornell, epo=False))


@needs_gpu
def test_refit_follows_moving_vertices():
    scene = bvhlab.generate("structured", 6000, 3)
    v = scene.vertices
    lo, hi = v.min(axis=0), v.max(axis=0)
    diag = float(np.linalg.norm(hi - lo))
    for builder in ("sbvh", "hploc"):
        s = bvhlab.build(scene, builder=builder, epo=False)
        r = bvhlab.Refitter(s)
        for frame in range(3):
            # A travelling wave, and the whole mesh carried away from its old boxes.
            moved = v + np.stack([0.05 * diag * np.sin(8.0 * v[:, 1] / diag + frame),
                                  np.zeros(len(v)), np.full(len(v), 2.0 * diag * (frame + 1))], axis=1)
            moved = moved.astype(np.float32)
            moved_scene = bvhlab.Scene(moved, scene.indices)
            rays, query = bvhlab.rays(moved_scene, "primary", width=64, height=48)
            if frame == 0:  # before the refit the old boxes miss the moved mesh
                stale, _ = r.trace(rays, query)
                assert bvhlab.verify(moved_scene, rays, stale, query)["mismatches"] > 0
            info = r.refit(moved)
            assert info["ms"] > 0
            for k in [k["name"] for k in bvhlab.kernels() if k["layout"] == "bvh2"]:
                hits, tinfo = r.trace(rays, query, kernel=k)
                assert tinfo["kernel"] == k and (hits["tri"] >= 0).sum() > len(rays) // 20  # 16% hit
                report = bvhlab.verify(moved_scene, rays, hits, query)
                assert report["mismatches"] == 0, (builder, frame, k, report["first_mismatches"])
        bad = v.copy()
        bad[7, 1] = np.nan
        with pytest.raises(bvhlab.Error):
            r.refit(bad)
        with pytest.raises(bvhlab.Error, match="vertices for a scene of"):
            r.refit(v[:-1])
        hits, _ = r.trace(rays, query)  # the failed refits left the last frame in place
        assert bvhlab.verify(moved_scene, rays, hits, query)["mismatches"] == 0


@needs_gpu
def test_every_gpu_kernel_agrees_with_embree(cornell):
    for builder, layout in (("sbvh", "bvh2"), ("binned", "cwbvh"), ("kdtree", "bvh2")):
        s = bvhlab.build(cornell, builder=builder, layout=layout, epo=False)
        for kind in ("primary", "diffuse", "shadow"):
            rays, query = bvhlab.rays(cornell, kind, width=64, height=48)
            for k in [k["name"] for k in bvhlab.kernels() if k["layout"] == s.layout]:
                hits, info = bvhlab.trace(s, rays, query, device="gpu", kernel=k)
                assert info["kernel"] == k and info["device"] == "gpu"
                report = bvhlab.verify(cornell, rays, hits, query)
                assert report["mismatches"] == 0, (k, kind, report["first_mismatches"])
        hits, info = bvhlab.trace(s, rays, query, device="gpu")
        assert info["kernel"] == s.default_kernel


@needs_gpu
def test_gpu_render_matches_the_cpu_render(cornell):
    s = bvhlab.build(cornell)
    cpu = bvhlab.render(s, width=48, height=36, spp=64, seed=3, **CORNELL_CAMERA)
    gpu = bvhlab.render(s, width=48, height=36, spp=64, seed=3, device="gpu", **CORNELL_CAMERA)
    assert gpu.shape == cpu.shape and np.isfinite(gpu).all()
    assert cpu.mean() > 0.05
    assert abs(gpu.mean() - cpu.mean()) < 0.05 * cpu.mean()


# The documented checksums (README, "The checksums and the scene hash"), written from the
# README alone: FNV-1a steps from the offset basis 1469598103934665603.
FNV_BASIS, FNV_PRIME, MASK = 1469598103934665603, 1099511628211, (1 << 64) - 1


def fnv_bytes(data, h=FNV_BASIS):
    for b in data:
        h = ((h ^ b) * FNV_PRIME) & MASK
    return h


def fnv_words(data):
    h = FNV_BASIS
    n8 = len(data) // 8 * 8
    for w in np.frombuffer(data[:n8], dtype="<u8").tolist():
        h = ((h ^ w) * FNV_PRIME) & MASK
    return fnv_bytes(data[n8:], h)


def test_file_checksums_and_scene_hash_follow_the_documented_algorithm(cornell, tmp_path):
    rays, query = bvhlab.rays(cornell, "primary", width=16, height=9)
    bvhlab.write_rays(str(tmp_path / "p.rays"), rays, query)
    data = (tmp_path / "p.rays").read_bytes()
    assert int.from_bytes(data[-8:], "little") == fnv_words(data[:-8])
    s = bvhlab.build(cornell)
    hits, _ = bvhlab.trace(s, rays, query)
    bvhlab.write_hits(str(tmp_path / "p.hits"), hits, query)
    data = (tmp_path / "p.hits").read_bytes()
    assert int.from_bytes(data[-8:], "little") == fnv_words(data[:-8])
    s.save(str(tmp_path / "s.bvh"))
    data = (tmp_path / "s.bvh").read_bytes()
    assert int.from_bytes(data[-8:], "little") == fnv_bytes(data[:-8])
    tri = cornell.vertices[cornell.indices].astype("<f4")  # (triangles, 3 corners, xyz)
    assert "%016x" % fnv_bytes(tri.tobytes()) == cornell.hash


def _has_pyoidn():
    try:
        import pyoidn  # noqa: F401
        return True
    except ImportError:
        return False


@pytest.mark.skipif(not _has_pyoidn(), reason="pyoidn (Intel Open Image Denoise's wheel) is not installed")
def test_render_denoised_with_pyoidn(cornell):
    s = bvhlab.build(cornell)
    ref = bvhlab.render(s, width=32, height=32, spp=1024, seed=7, **CORNELL_CAMERA)
    raw, denoised = bvhlab.render(s, width=32, height=32, spp=4, denoise=True, **CORNELL_CAMERA)
    assert denoised.shape == raw.shape == (32, 32, 3) and np.isfinite(denoised).all()
    mse = lambda a: float(np.mean((np.clip(a, 0, 1) - np.clip(ref, 0, 1)) ** 2))  # noqa: E731
    assert mse(denoised) * 2 < mse(raw), (mse(raw), mse(denoised))


def test_render_denoise_without_oidn_says_how_to_get_it(cornell, tmp_path):
    s = bvhlab.build(cornell)
    with pytest.raises(bvhlab.Error, match="denoise: --oidn '.*' holds no libOpenImageDenoise"):
        bvhlab.render(s, width=8, height=8, spp=1, denoise=True, oidn=str(tmp_path / "none"), **CORNELL_CAMERA)
