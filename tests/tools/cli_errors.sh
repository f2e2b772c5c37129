#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Bad input to the bvhlab CLI: every case must exit non-zero with exactly one line on stderr
# that names the problem, and nothing on stdout. Usage: cli_errors.sh BVHLAB DATA_DIR
set -u
bin=$1
data=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
export BVHLAB_CACHE_DIR=$tmp/scene-cache  # never the user's cache
pass=0
fail=0

# expect_error NAME PATTERN ARGS...: non-zero exit, one stderr line matching PATTERN.
expect_error() {
    local name=$1 pattern=$2
    shift 2
    "$bin" -q "$@" >"$tmp/out" 2>"$tmp/err"
    local rc=$?
    local lines
    lines=$(wc -l <"$tmp/err")
    if [ $rc -ne 0 ] && [ "$lines" -eq 1 ] && grep -qE -- "$pattern" "$tmp/err" && [ ! -s "$tmp/out" ]; then
        pass=$((pass + 1))
    else
        fail=$((fail + 1))
        echo "FAIL $name: rc=$rc, $lines stderr lines, expected /$pattern/:"
        sed 's/^/    /' "$tmp/err" | head -5
    fi
}

printf 'v 0 0 0\nv 1 0 abc\nv 0 1 0\nf 1 2 3\n' >"$tmp/malformed.obj"
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n' >"$tmp/range.obj"
printf 'v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\n' >"$tmp/degenerate.obj"
: >"$tmp/empty.obj"
head -c 100 /dev/urandom >"$tmp/random.obj"
printf 'NOTRAYS!\1\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0' >"$tmp/badmagic.rays"
printf 'BVHLRAYS\7\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0' >"$tmp/badversion.rays"
mkdir -p "$tmp/cat"
cp "$data/cornell_box.obj" "$tmp/cat/"
printf '{"scenes": {"a": {"file": "cornell_box.obj", "camera": null}}}' >"$tmp/cat/scenes.json"
BVHLAB_SCENES=$tmp/cat expect_error catalogue-null-camera "scenes.json': scene 'a': field 'camera' must be an object" build a
printf '{"scenes": {"a": {"file": "cornell_box.obj", "ao_length": 1e39}}}' >"$tmp/cat/scenes.json"
BVHLAB_SCENES=$tmp/cat expect_error catalogue-ao-length "scene 'a': field 'ao_length' is 1e\+39, outside" build a
rm "$tmp/cat/scenes.json" && mkdir "$tmp/cat/scenes.json"
BVHLAB_SCENES=$tmp/cat expect_error catalogue-folder "scenes.json' is not a regular file" build a
# Texture-coordinate and normal references are range-checked like vertex ones, negative too.
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/-2 2/1 3/1\n' >"$tmp/negvt.obj"
expect_error obj-negative-vt "line 5: texture coordinate index -2 out of range [(]1 texture coordinates before" build "$tmp/negvt.obj"
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n' >"$tmp/bigvt.obj"
expect_error obj-large-vt "line 5: texture coordinate index 2 out of range [(]the file has 1" build "$tmp/bigvt.obj"
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//-3 3//1\n' >"$tmp/negvn.obj"
expect_error obj-negative-vn "line 5: normal index -3 out of range" build "$tmp/negvn.obj"
# A scene must be a regular file: a pipe is refused by name (it was "no usable triangles").
mkfifo "$tmp/pipe.obj"
expect_error obj-fifo "cannot read '.*pipe.obj': it is a pipe [(]FIFO[)]; save it to a file" build "$tmp/pipe.obj"
# Outputs are regular files: a device or a pipe is refused, never replaced by a file.
expect_error build-out-device "cannot write '/dev/null': it is a device" build "$data/cornell_box.obj" -o /dev/null
expect_error rays-out-fifo "cannot write '.*pipe.obj': it is a pipe" rays "$data/cornell_box.obj" --width 4 --height 4 \
    -o "$tmp/pipe.obj"
# A PFM whose header claims more pixels than the file holds is refused before any allocation.
printf 'PF\n65536 65536\n-1.0\n' >"$tmp/huge.pfm"
expect_error pfm-huge-header "huge.pfm is truncated: its header says 65536 x 65536 pixels" render \
    "$data/cornell_box.obj" --width 4 --height 4 --spp 1 --env "$tmp/huge.pfm" -o "$tmp/huge-out.pfm"
# A folder or a device as an environment map, texture or material file says what it is.
mkdir -p "$tmp/envdir"
expect_error render-env-folder "cannot render with --env .*envdir: it is a directory" render "$data/cornell_box.obj" \
    --width 4 --height 4 --spp 1 --env "$tmp/envdir" -o "$tmp/envdir-out.pfm"
expect_error render-env-device "cannot render with --env /dev/null: it is a device" render "$data/cornell_box.obj" \
    --width 4 --height 4 --spp 1 --env /dev/null -o "$tmp/envdev-out.pfm"
mkdir -p "$tmp/texdir/maps/wall.png" "$tmp/mtldir/dir.mtl"
printf 'newmtl w\nKd 1 1 1\nmap_Kd maps/wall.png\n' >"$tmp/texdir/t.mtl"
printf 'mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nusemtl w\nf 1/1 2/1 3/1\n' >"$tmp/texdir/t.obj"
expect_error render-texture-folder "texture .*wall.png [(]map_Kd of material 'w'[)]: it is a directory" render \
    "$tmp/texdir/t.obj" --width 4 --height 4 --spp 1 -o "$tmp/texdir-out.pfm"
printf 'mtllib dir.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n' >"$tmp/mtldir/m.obj"
expect_error render-mtl-folder "its material file .*dir.mtl: it is a directory" render "$tmp/mtldir/m.obj" --width 4 \
    --height 4 --spp 1 -o "$tmp/mtldir-out.pfm"
printf 'v 0x10 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n' >"$tmp/hex.obj"
expect_error obj-hex "line 1: malformed 'v' line: '0x10' is not a number" build "$tmp/hex.obj"
expect_error render-env-scale-alone "--env-scale requires --env" render "$data/cornell_box.obj" --width 4 --height 4 \
    --spp 1 --env-scale 2 -o "$tmp/e.pfm"
expect_error render-focus-alone "--focus requires --aperture" render "$data/cornell_box.obj" --width 4 --height 4 \
    --spp 1 --focus 3 -o "$tmp/f.pfm"
printf 'BVHLRAYS\1\0\0\0\0\0\0\0\5\0\0\0\0\0\0\0' >"$tmp/truncated.rays"

expect_error missing-file "cannot open|no scene" build "$tmp/nope.obj"

# Out of host memory names the size asked for and the stage (under a 3 GB address-space limit;
# ASan builds reserve more address space than that at start-up, so they skip it).
if ldd "$bin" 2>/dev/null | grep -q libasan; then
    echo "skip host-oom: an ASan build cannot start under an address-space limit"
else
    printf '#!/bin/sh\nulimit -v 3000000\nexec "%s" "$@"\n' "$bin" >"$tmp/limited"
    chmod +x "$tmp/limited"
    bin_unlimited=$bin
    bin=$tmp/limited
    expect_error host-oom "out of host memory: an allocation of [0-9.]+ GB \([0-9]+ bytes\) failed while generating gen:soup:900000000" \
        build gen:soup:900000000
    bin=$bin_unlimited
fi
expect_error directory "no scene|directory" build "$tmp"
expect_error malformed-v "line 2: malformed 'v'" build "$tmp/malformed.obj"
expect_error face-range "out of range" build "$tmp/range.obj"
expect_error empty "no usable triangles" build "$tmp/empty.obj"
expect_error all-degenerate "dropped" build "$tmp/degenerate.obj"
expect_error garbage "no usable triangles|malformed" build "$tmp/random.obj"
expect_error ray-magic "magic" verify "$data/cornell_box.obj" --rays "$tmp/badmagic.rays"
expect_error ray-version "version 7" bench "$data/cornell_box.obj" --rays "$tmp/badversion.rays"
expect_error ray-truncated "truncated" verify "$data/cornell_box.obj" --rays "$tmp/truncated.rays"
expect_error unknown-flag "--frobnicate|frobnicate" build "$data/cornell_box.obj" --frobnicate
expect_error no-command "subcommand" 
expect_error bad-builder "builder" build "$data/cornell_box.obj" --builder magic
expect_error bad-bins "bins" build "$data/cornell_box.obj" --bins 1
expect_error contradictory "excludes" verify "$data/cornell_box.obj" --types primary --rays "$tmp/truncated.rays"
expect_error hits-needs-rays "requires|needs" verify "$data/cornell_box.obj" --hits "$tmp/truncated.rays"
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -9223372036854775808\n' >"$tmp/long_min.obj"
expect_error face-index-long-min "bad vertex reference '-9223372036854775808'" build "$tmp/long_min.obj"
printf 'v 1e38 1e38 1e38\nv -1e38 1e38 -1e38\nv 0 -1e38 0\nf 1 2 3\n' >"$tmp/huge.obj"
expect_error huge-coordinates "vertex 1 [(]1e[+]38, 1e[+]38, 1e[+]38[)] is outside [[]-1e[+]10, 1e[+]10[]], the numeric domain" build "$tmp/huge.obj"
expect_error rays-two-types "--types primary,diffuse: a ray file holds one ray type" rays "$data/cornell_box.obj" --types primary,diffuse -o "$tmp/x.rays"
expect_error rays-type-typo "--types prmary: not a ray type .* \(did you mean primary\?\)" rays "$data/cornell_box.obj" --types prmary -o "$tmp/x.rays"
if "$bin" -q rays "$data/cornell_box.obj" --types diffuse --width 8 --height 8 -o "$tmp/types.rays" >/dev/null &&
    "$bin" -q run "$data/cornell_box.obj" --no-epo --types primary --width 8 --height 8 --runs 1 --json |
    python3 -c 'import json,sys; b=[json.loads(l) for l in sys.stdin if "\"record\":\"build\"" in l]; assert b and b[0]["epo"] is None, b'; then
    pass=$((pass + 1))
else
    fail=$((fail + 1))
    echo "FAIL rays --types and run --no-epo"
fi
expect_error structure-typo "--structure 'sbhv' is neither a structure .* nor an existing file \(did you mean sbvh\?\)" \
    bench "$data/cornell_box.obj" --structure sbhv
expect_error fisheye-fov "--fov applies to --camera pinhole or thin-lens; a fish-eye takes --fisheye-fov" \
    rays "$data/cornell_box.obj" --camera fisheye --fov 30 -o "$tmp/x.rays"
expect_error fisheye-fov-alone "--fisheye-fov applies to --camera fisheye" rays "$data/cornell_box.obj" --fisheye-fov 90 -o "$tmp/x.rays"
expect_error rays-thin-lens "--camera thin-lens applies to render" bench "$data/cornell_box.obj" --camera thin-lens
expect_error camera-unknown "--camera: fish not in" rays "$data/cornell_box.obj" --camera fish -o "$tmp/x.rays"
expect_error render-thin-lens-no-aperture "--camera thin-lens needs --aperture R" \
    render "$data/cornell_box.obj" --camera thin-lens --width 4 --height 4 --spp 1 -o "$tmp/x.pfm"
expect_error render-pinhole-aperture "--aperture applies to --camera thin-lens \(a pinhole has no lens\)" \
    render "$data/cornell_box.obj" --camera pinhole --aperture 1 --width 4 --height 4 --spp 1 -o "$tmp/x.pfm"
expect_error render-panorama-aperture "--aperture applies to --camera thin-lens, not panorama" \
    render "$data/cornell_box.obj" --camera panorama --aperture 1 --width 4 --height 4 --spp 1 -o "$tmp/x.pfm"
if "$bin" -q rays "$data/cornell_box.obj" --types primary --camera panorama --width 8 --height 4 -o "$tmp/pano.rays" --json |
    python3 -c 'import json,sys; j=json.loads(sys.stdin.readline()); assert j["rays"] == 32, j' &&
    "$bin" -q bench "$data/cornell_box.obj" --types primary,diffuse --camera fisheye --fisheye-fov 200 --width 8 --height 8 --runs 1 --json |
    python3 -c 'import json,sys; r=[json.loads(l) for l in sys.stdin]; c=r[0]["protocol"]["camera"]; assert len(r)==2 and c["projection"]=="fisheye" and c["fisheye_fov_deg"]==200 and "fov_y_deg" not in c, c' &&
    "$bin" -q render "$data/cornell_box.obj" --camera panorama --width 8 --height 4 --spp 1 -o "$tmp/pano.pfm" --json |
    python3 -c 'import json,sys; j=json.loads(sys.stdin.readline()); assert j["camera"]=="panorama", j'; then
    pass=$((pass + 1))
else
    fail=$((fail + 1))
    echo "FAIL fisheye and panorama rays, bench and render"
fi
export BVHLAB_OIDN=$tmp/no-oidn
expect_error denoise-no-oidn "--denoise: BVHLAB_OIDN='.*no-oidn' holds no libOpenImageDenoise.so.2" \
    render "$data/cornell_box.obj" --denoise --width 4 --height 4 --spp 1 -o "$tmp/dn.pfm"
unset BVHLAB_OIDN
expect_error denoise-oidn-path "--denoise: --oidn '.*nowhere' holds no libOpenImageDenoise.so.2" \
    render "$data/cornell_box.obj" --denoise --oidn "$tmp/nowhere" --width 4 --height 4 --spp 1 -o "$tmp/dn.pfm"
expect_error oidn-without-denoise "--oidn requires --denoise" \
    render "$data/cornell_box.obj" --oidn "$tmp/nowhere" --width 4 --height 4 --spp 1 -o "$tmp/dn.pfm"
expect_error preview-every-alone "--preview-every applies to --preview or --serve" \
    render "$data/cornell_box.obj" --preview-every 2 --width 4 --height 4 --spp 1 -o "$tmp/pv.pfm"
expect_error serve-port-range "--serve: .*70000.*not in range|--serve" \
    render "$data/cornell_box.obj" --serve 70000 --width 4 --height 4 --spp 1 -o "$tmp/pv.pfm"
expect_error serve-bind-alone "--serve-bind requires --serve" \
    render "$data/cornell_box.obj" --serve-bind 0.0.0.0 --width 4 --height 4 --spp 1 -o "$tmp/pv.pfm"
expect_error serve-bind-foreign "--serve: cannot listen on 192.0.2.1:0 .*not one of this machine's" \
    render "$data/cornell_box.obj" --serve 0 --serve-bind 192.0.2.1 --width 4 --height 4 --spp 1 -o "$tmp/pv.pfm"
expect_error serve-bind-garbage "--serve: cannot listen on no.such.host.invalid:0" \
    render "$data/cornell_box.obj" --serve 0 --serve-bind no.such.host.invalid --width 4 --height 4 --spp 1 -o "$tmp/pv.pfm"
expect_error preview-is-out "--preview .* and --out are the same file|is also" \
    render "$data/cornell_box.obj" --preview "$tmp/pv.pfm" --width 4 --height 4 --spp 1 -o "$tmp/pv.pfm"
if "$bin" -q render "$data/cornell_box.obj" --width 8 --height 8 --spp 4 --preview "$tmp/preview.pfm" --preview-every 0.05 \
    -o "$tmp/final.pfm" --json | python3 -c 'import json,sys; j=json.loads(sys.stdin.readline()); assert j["preview"]["out"].endswith("preview.pfm"), j' &&
    cmp -s "$tmp/preview.pfm" "$tmp/final.pfm"; then
    pass=$((pass + 1))
else
    fail=$((fail + 1))
    echo "FAIL render --preview: the preview ends as the final image"
fi
expect_error denoise-device-bad "--denoise-device: gpu not in \{auto,cpu,cuda\}" \
    render "$data/cornell_box.obj" --denoise --denoise-device gpu --width 4 --height 4 --spp 1 -o "$tmp/dn.pfm"
expect_error preview-every-zero "--preview-every: .*0.*not a finite number in \[0.05, 3600\]|--preview-every" \
    render "$data/cornell_box.obj" --preview "$tmp/pv2.pfm" --preview-every 0 --width 4 --height 4 --spp 1 -o "$tmp/pv3.pfm"
expect_error spp-not-square "perfect square" verify "$data/cornell_box.obj" --spp 3 --width 4 --height 4
expect_error bad-type "ray type" bench "$data/cornell_box.obj" --types primary,sideways
expect_error bad-gen "procedural|generated" build gen:blobs:100
expect_error gpu-unavailable "device gpu: (no|this bvhlab)" bench "$data/cornell_box.obj" --device gpu
expect_error rays-needs-out "--out" rays "$data/cornell_box.obj"

# Structure cache: stale (other triangles, other config), damaged, and a name not built yet.
"$bin" -q build "$data/cornell_box.obj" --builder sbvh --out "$tmp/cb.tree" >/dev/null
expect_error cache-other-scene "stale structure file.*other triangles" verify gen:soup:50 --structure "$tmp/cb.tree"
# Header values out of range, with a checksum made right again (byte-wise FNV-1a with the
# README's basis): a NaN Ct (at byte 48) and a max depth of 0 (at byte 44) are refused by name.
patch_tree() {  # patch_tree IN OUT OFFSET FORMAT VALUE
    python3 - "$@" <<'PY'
import struct, sys
src, dst, off, fmt, val = sys.argv[1:6]
d = bytearray(open(src, "rb").read())
struct.pack_into("<" + fmt, d, int(off), float(val) if fmt == "f" else int(val))
h = 1469598103934665603
for c in d[:-8]:
    h = ((h ^ c) * 1099511628211) % 2**64
struct.pack_into("<Q", d, len(d) - 8, h)
open(dst, "wb").write(d)
PY
}
patch_tree "$tmp/cb.tree" "$tmp/nan-ct.tree" 48 f nan
expect_error tree-header-nan-ct "nan-ct.tree' has a header value out of range: ct nan" verify \
    "$data/cornell_box.obj" --structure "$tmp/nan-ct.tree"
patch_tree "$tmp/cb.tree" "$tmp/depth0.tree" 44 I 0
expect_error tree-header-depth-0 "header value out of range: max_depth 0 is not in [[]1, 64[]]" bench \
    "$data/cornell_box.obj" --structure "$tmp/depth0.tree" --runs 1
# Builder codes past the last (7, gpu-binned) are refused by number, with the checksum intact.
patch_tree "$tmp/cb.tree" "$tmp/builder8.tree" 12 I 8
expect_error tree-header-builder-8 "builder8.tree' names an unknown builder [(]8[)]" verify \
    "$data/cornell_box.obj" --structure "$tmp/builder8.tree"
expect_error cache-other-config "stale structure file.*asked for" bench "$data/cornell_box.obj" --structure "$tmp/cb.tree" --max-leaf 2
expect_error cache-other-reinsertion "stale structure file.*reinsert=3.*reinsert=0" bench "$data/cornell_box.obj" --structure "$tmp/cb.tree" --reinsert 0
expect_error bad-reinsert "reinsert" build "$data/cornell_box.obj" --builder sbvh --reinsert 99
# The GPU builders: options that apply to them only, and the device they run on.
cb=$data/cornell_box.obj
expect_error gpu-builder-on-cpu "--build-device cpu does not apply: builder hploc runs on the GPU" build "$cb" \
    --builder hploc --build-device cpu
expect_error cpu-builder-on-gpu "--build-device gpu applies to the GPU builders [(]lbvh, ploc, hploc, gpu-binned[)], not binned" build "$cb" \
    --build-device gpu
expect_error kdtree-on-gpu "--build-device gpu applies to the GPU builders" build "$cb" --structure kdtree \
    --build-device gpu
expect_error morton-cpu-builder "--morton-bits applies to --builder lbvh, ploc or hploc, not sbvh" build "$cb" \
    --builder sbvh --morton-bits 60
expect_error radius-lbvh "--radius applies to --builder ploc or hploc, not lbvh" build "$cb" --builder lbvh --radius 4
expect_error bins-gpu "--bins does not apply to the GPU builders" build "$cb" --builder hploc --bins 8
expect_error bins-gpu-binned "--bins does not apply to the GPU builders [(]gpu-binned's are 32 a side" build "$cb" \
    --builder gpu-binned --bins 16
expect_error morton-gpu-binned "--morton-bits applies to --builder lbvh, ploc or hploc, not gpu-binned" build "$cb" \
    --builder gpu-binned --morton-bits 60
expect_error radius-gpu-binned "--radius applies to --builder ploc or hploc, not gpu-binned" build "$cb" \
    --builder gpu-binned --radius 4
expect_error gpu-binned-on-cpu "--build-device cpu does not apply: builder gpu-binned runs on the GPU" build "$cb" \
    --builder gpu-binned --build-device cpu
expect_error clusters-hploc "--clusters applies to --builder gpu-binned, not hploc" build "$cb" --builder hploc \
    --clusters 1.3
expect_error clusters-binned "--clusters applies to --builder gpu-binned, not binned" build "$cb" --clusters 1.3
expect_error clusters-half "--clusters 0.5 is neither 0 [(]off[)] nor in [[]1, 16[]]" build "$cb" \
    --builder gpu-binned --clusters 0.5
expect_error clusters-17 "--clusters" build "$cb" --builder gpu-binned --clusters 17
expect_error clusters-nan "--clusters" build "$cb" --builder gpu-binned --clusters nan
expect_error reinsert-17-gpu "--reinsert" build "$cb" --builder lbvh --reinsert 17
expect_error morton-bits-31 "--morton-bits" build "$cb" --builder lbvh --morton-bits 31
expect_error radius-0 "--radius" build "$cb" --builder hploc --radius 0
expect_error radius-17-ploc "--radius" build "$cb" --builder ploc --radius 17
expect_error ploc-on-cpu "--build-device cpu does not apply: builder ploc runs on the GPU" build "$cb" \
    --builder ploc --build-device cpu
expect_error runs-cpu-builder "--runs applies to a GPU builder" build "$cb" --runs 3
expect_error runs-tlas-cwbvh "--runs on an instanced scene rebuilds its TLAS on the GPU, which the two-level BVH2 layout has" \
    build "gen:instances:$data/cornell_box.obj:3:1" --builder lbvh --layout cwbvh --runs 3
if ! nvidia-smi >/dev/null 2>&1; then  # without a GPU the GPU builders say why
    expect_error gpu-builder-no-gpu "builder 'hploc' runs on the GPU, and there is none" build "$cb" --builder hploc
    expect_error ploc-no-gpu "builder 'ploc' runs on the GPU, and there is none" build "$cb" --builder ploc --radius 4
    expect_error gpu-binned-no-gpu "builder 'gpu-binned' runs on the GPU, and there is none" build "$cb" \
        --builder gpu-binned
fi
head -c 300 "$tmp/cb.tree" >"$tmp/trunc.tree"
expect_error cache-truncated "truncated" verify "$data/cornell_box.obj" --structure "$tmp/trunc.tree"
expect_error cache-not-a-tree "not a bvhlab structure file" verify "$data/cornell_box.obj" --structure "$data/cornell_box.obj"
"$bin" -q build "$data/cornell_box.obj" --structure kdtree --out "$tmp/kd.tree" >/dev/null
expect_error kd-cache-bvh-option "holds a kdtree.*--bins" verify "$data/cornell_box.obj" --structure "$tmp/kd.tree" --bins 8
expect_error kd-cache-other-ci "stale structure file.*Ci=5" verify "$data/cornell_box.obj" --structure "$tmp/kd.tree" --kd-ci 5
expect_error kd-bad-bonus "kd-bonus" build "$data/cornell_box.obj" --structure kdtree --kd-bonus 1.5
expect_error kdtree-no-gpu-or-bad-stack "kd-stack" verify "$data/cornell_box.obj" --structure kdtree --kd-stack 9
expect_error builder-and-structure "excludes" verify "$data/cornell_box.obj" --structure sbvh --builder binned

# Tracer choice (--device, --kernel, --block-size, --kd-stack) and options that do not apply.
expect_error kernel-needs-gpu "--kernel.*--device gpu" bench "$data/cornell_box.obj" --kernel speculative
expect_error block-needs-gpu "--block-size.*--device gpu" verify "$data/cornell_box.obj" --block-size 64
expect_error fetch-needs-gpu "--fetch-threshold.*--device gpu" bench "$data/cornell_box.obj" --fetch-threshold 4
expect_error fetch-range "fetch-threshold" bench "$data/cornell_box.obj" --device gpu --fetch-threshold 40
expect_error embree-no-structure "--structure does not apply to --device embree" bench "$data/cornell_box.obj" --device embree --structure sbvh
expect_error embree-no-bins "--bins does not apply to --device embree" bench "$data/cornell_box.obj" --device embree --bins 8
expect_error embree-no-kd-stack "--kd-stack does not apply to --device embree" bench "$data/cornell_box.obj" --device embree --kd-stack 4
expect_error bad-device "device" bench "$data/cornell_box.obj" --device tpu
expect_error embree-no-layout "--layout does not apply to --device embree" bench "$data/cornell_box.obj" --device embree --layout cwbvh
expect_error collapse-needs-cwbvh "--collapse applies to --layout cwbvh" build "$data/cornell_box.obj" --collapse greedy
expect_error cw-tris-needs-cwbvh "--cw-tris applies to --layout cwbvh" build "$data/cornell_box.obj" --cw-tris vertices
expect_error cw-tris-bad-value "--cw-tris: nope not in" build "$data/cornell_box.obj" --layout cwbvh --cw-tris nope
expect_error cache-bad-action "action: frob not in" cache frob
expect_error cache-no-scene-cache "not expected: --no-scene-cache" cache info --no-scene-cache
expect_error cw-tris-embree "--cw-tris does not apply to --device embree" bench "$data/cornell_box.obj" --device embree --cw-tris vertices
expect_error layout-not-for-kd "--layout applies to BVHs" build "$data/cornell_box.obj" --structure kdtree --layout cwbvh
expect_error layout-bad-value "layout" build "$data/cornell_box.obj" --layout wide
expect_error cwbvh-kernel-vs-layout "traces --layout cwbvh, not --layout bvh2" verify "$data/cornell_box.obj" --kernel cwbvh --layout bvh2
expect_error plain-kernel-vs-layout "traces --layout bvh2, not --layout cwbvh" verify "$data/cornell_box.obj" --kernel plain --layout cwbvh
expect_error cwbvh-kernel-kd "kd-tree" verify "$data/cornell_box.obj" --kernel cwbvh --structure kdtree
expect_error cpu-kernel-all "--kernel all chooses GPU kernels; it needs --device gpu" verify "$data/cornell_box.obj" --device cpu --kernel all
expect_error cpu-kernel-no-cpu-form "no CPU form" verify "$data/cornell_box.obj" --device cpu --kernel while-while
expect_error embree-not-for-verify "device" verify "$data/cornell_box.obj" --device embree
expect_error kd-stack-on-bvh "--kd-stack applies to kd-trees" bench "$data/cornell_box.obj" --kd-stack 4
expect_error bins-on-kdtree "--bins applies to BVH builders, not --structure kdtree" verify "$data/cornell_box.obj" --structure kdtree --bins 4
expect_error max-leaf-beyond-bvh2 "max_leaf 17 does not fit the bvh2 layout, whose leaves hold at most 16" build "$data/cornell_box.obj" --max-leaf 17
expect_error max-leaf-on-kdtree "--max-leaf applies to BVH builders" build "$data/cornell_box.obj" --structure kdtree --max-leaf 4
expect_error kd-ct-on-bvh "--kd-ct applies to --structure kdtree" build "$data/cornell_box.obj" --kd-ct 10
expect_error alpha-on-binned "--alpha applies to --builder sbvh, not binned" build "$data/cornell_box.obj" --alpha 0.5
expect_error spatial-bins-on-sweep "--spatial-bins applies to --builder sbvh, not sweep" build "$data/cornell_box.obj" --builder sweep --spatial-bins 4
expect_error bins-on-sweep "--bins does not apply to the sweep builder" build "$data/cornell_box.obj" --structure sweep --bins 8
expect_error gpu-kernel-unavailable "device gpu: (no|this bvhlab)" verify "$data/cornell_box.obj" --device gpu --kernel all

# The good path still works and --json prints parseable lines.
if "$bin" -q build "$data/cornell_box.obj" --json | python3 -c 'import json,sys; j=json.loads(sys.stdin.read()); assert j["triangles"]==32 and j["nodes"]>0 and "sah" in j and "epo" in j and j["builder"]=="binned"'; then
    pass=$((pass + 1))
else
    fail=$((fail + 1)); echo "FAIL build --json"
fi
"$bin" -q rays "$data/cornell_box.obj" --type ao --width 16 --height 12 --out "$tmp/a.rays" >/dev/null &&
"$bin" -q rays "$data/cornell_box.obj" --type ao --width 16 --height 12 --out "$tmp/b.rays" >/dev/null
if cmp -s "$tmp/a.rays" "$tmp/b.rays" && "$bin" -q verify "$data/cornell_box.obj" --rays "$tmp/a.rays" >/dev/null; then
    pass=$((pass + 1))
else
    fail=$((fail + 1)); echo "FAIL identical ray files / verify from file"
fi

if "$bin" -q verify "$data/cornell_box.obj" --structure "$tmp/cb.tree" --width 32 --height 24 --json | python3 -c 'import json,sys; rows=[json.loads(l) for l in sys.stdin]; assert len(rows)==4 and all(r["mismatches"]==0 and r["structure"]=="bvh2/sbvh" for r in rows)'; then
    pass=$((pass + 1))
else
    fail=$((fail + 1)); echo "FAIL verify from a structure file"
fi

if "$bin" -q verify "$data/cornell_box.obj" --structure "$tmp/kd.tree" --kd-stack 1 --width 32 --height 24 --json | python3 -c 'import json,sys; rows=[json.loads(l) for l in sys.stdin]; assert len(rows)==4 and all(r["mismatches"]==0 and r["kernel"]=="cpu-kd-shortstack-1" for r in rows)'; then
    pass=$((pass + 1))
else
    fail=$((fail + 1)); echo "FAIL verify from a kd-tree structure file"
fi

# Numbers and specs checked where they are parsed; no internal check text, no source path.
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -9223372036854775808\n' >"$tmp/long_min.obj"
expect_error face-index-long-min "bad vertex reference '-9223372036854775808'" build "$tmp/long_min.obj"
printf 'v 1e38 1e38 1e38\nv -1e38 1e38 -1e38\nv 0 -1e38 0\nf 1 2 3\n' >"$tmp/huge.obj"
expect_error huge-coordinates "vertex 1 [(]1e[+]38, 1e[+]38, 1e[+]38[)] is outside [[]-1e[+]10, 1e[+]10[]], the numeric domain" build "$tmp/huge.obj"
expect_error spp-not-square "--spp 2 is not a perfect square" rays "$data/cornell_box.obj" --type primary --spp 2 -o "$tmp/x.rays"
expect_error min-leaf-above-max "--min-leaf 16 is larger than --max-leaf 4" build "$data/cornell_box.obj" --min-leaf 16 --max-leaf 4
expect_error gen-zero "triangle count must be 1..2\^30, not 0" build gen:soup:0
expect_error gen-negative "'-5' is not a whole number" build gen:soup:-5
expect_error eye-nan "--eye: 'nan' is not a finite number" rays "$data/cornell_box.obj" --type primary --eye nan 0 0 -o "$tmp/x.rays"
expect_error fov-nan "--fov: 'nan' is not a finite number" rays "$data/cornell_box.obj" --type primary --fov nan -o "$tmp/x.rays"
expect_error t-tol-nan "--t-tol: 'nan' is not a finite number" verify "$data/cornell_box.obj" --t-tol nan
expect_error edge-eps-nan "--edge-eps: 'nan' is not a finite number" verify "$data/cornell_box.obj" --edge-eps nan
expect_error alpha-nan "--alpha: 'nan' is not a finite number" build "$data/cornell_box.obj" --builder sbvh --alpha nan
expect_error kd-ct-nan "--kd-ct: 'nan' is not a finite number" build "$data/cornell_box.obj" --structure kdtree --kd-ct nan
expect_error eye-is-target "^bvhlab: error: camera eye and target coincide$" rays "$data/cornell_box.obj" --type primary --eye 1 2 3 --target 1 2 3 -o "$tmp/x.rays"
expect_error structure-folder "is a folder, not a structure file" build "$data/cornell_box.obj" --structure "$tmp"
expect_error unknown-command "unknown command 'frobnicate' \(commands: build" frobnicate
expect_error command-typo "unknown command 'bnech' \(did you mean bench\?\) \(commands: build" bnech
expect_error scene-typo "no scene 'cornell-bx': not a file, .* \(did you mean cornell-box\?\)" build cornell-bx
mkdir -p "$tmp/emptycat" "$tmp/evilcat"
echo '[]' >"$tmp/emptycat/scenes.json"
echo '{"scenes": {"x": {"file": "../../../etc/passwd"}}}' >"$tmp/evilcat/scenes.json"
BVHLAB_SCENES=/nonexistent-bvhlab expect_error scenes-missing "BVHLAB_SCENES='/nonexistent-bvhlab' is not a folder" run
BVHLAB_SCENES="$tmp/emptycat" expect_error scenes-empty "lists no scenes" run
BVHLAB_SCENES="$tmp/evilcat" expect_error scenes-escape "names a file outside its folder" build x
# A failed stage prints no "done" line (progress on, so the test sees stderr as a user does).
"$bin" build "$tmp/malformed.obj" >"$tmp/out" 2>"$tmp/err"
if grep -q "loading" "$tmp/err" && ! grep -q "done" "$tmp/err"; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL a failed stage printed done"; fi

# The CPU reference of the cwbvh kernel, and the CWBVH's build record.
if "$bin" -q verify "$data/cornell_box.obj" --device cpu --kernel cwbvh --width 32 --height 24 --json | python3 -c 'import json,sys; rows=[json.loads(l) for l in sys.stdin]; assert len(rows)==4 and all(r["mismatches"]==0 and r["kernel"]=="cpu-cwbvh" and r["structure"]=="cwbvh/binned" for r in rows)'; then
    pass=$((pass + 1))
else
    fail=$((fail + 1)); echo "FAIL verify --device cpu --kernel cwbvh"
fi
if "$bin" -q build "$data/cornell_box.obj" --layout cwbvh --collapse greedy --json | python3 -c 'import json,sys; r=json.loads(sys.stdin.read()); assert r["layout"]=="cwbvh" and r["wide"]["collapse"]=="greedy" and r["wide"]["nodes"]>0 and 0<r["bytes_vs_bvh2"]<1.5 and r["layout_bytes"]<r["bvh2_layout_bytes"]*1.5'; then
    pass=$((pass + 1))
else
    fail=$((fail + 1)); echo "FAIL build --layout cwbvh --json"
fi
if "$bin" -q build "$data/cornell_box.obj" --layout cwbvh --cw-tris vertices --json | python3 -c 'import json,sys; r=json.loads(sys.stdin.read()); assert r["structure"]=="cwbvh-vertices/binned" and r["wide"]["triangles"]=="vertices" and r["layout_bytes"]<r["bvh2_layout_bytes"]'; then
    pass=$((pass + 1))
else
    fail=$((fail + 1)); echo "FAIL build --layout cwbvh --cw-tris vertices --json"
fi

# The numeric domain (docs/bad-input.md): values Embree or float32 traversal cannot handle are refused by
# name before any work (they aborted inside Embree, or gave empty or NaN images).
expect_error domain-eye "the camera's eye [(]1e[+]19, 0, 0[)] is outside" verify "$data/cornell_box.obj" --eye 1e19 0 0 \
    --width 4 --height 4
expect_error domain-target "the camera's target" rays "$data/cornell_box.obj" --target 0 -2e10 0 -o "$tmp/d.rays"
expect_error domain-focus "--focus 1e[+]20 is not in [[]0, 1e[+]10[]]" render "$data/cornell_box.obj" --aperture 0.1 \
    --focus 1e20 --width 4 --height 4 --spp 1 -o "$tmp/d.pfm"
expect_error domain-aperture "--aperture 1e[+]12 is not in" render "$data/cornell_box.obj" --aperture 1e12 --width 4 \
    --height 4 --spp 1 -o "$tmp/d.pfm"
expect_error domain-eye-end "--eye-end [(]0, 5e[+]10, 0[)] is outside" render "$data/cornell_box.obj" --eye-end 0 5e10 0 \
    --width 4 --height 4 --spp 1 -o "$tmp/d.pfm"
printf 'v 0 0 0\nv 1e-10 0 0\nv 0 1e-10 0\nf 1 2 3\n' >"$tmp/tiny.obj"
expect_error domain-tiny-scene "bounding-box diagonal 1.41421e-10 is below 1e-08" verify "$tmp/tiny.obj" --width 4 --height 4
printf 'v 0 0 0\nv 2e12 0 0\nv 0 1 0\nf 1 2 3\n' >"$tmp/far.obj"
expect_error domain-far-vertex "vertex 2 [(]2e[+]12, 0, 0[)] is outside" build "$tmp/far.obj"
printf 'PF\n1 1\n-1.0\n' >"$tmp/bright.pfm"
python3 -c "import struct,sys; sys.stdout.buffer.write(struct.pack('<3f', 1e19, 1e19, 1e19))" >>"$tmp/bright.pfm"
expect_error domain-env-radiance "times --env-scale 100 has a texel of radiance 1e[+]21, above 1e[+]20" render \
    "$data/cornell_box.obj" --env "$tmp/bright.pfm" --env-scale 100 --width 4 --height 4 --spp 1 -o "$tmp/d.pfm"
for bad in "Kd -1 0 0" "Ke 1e38 1 1" "Ni -1" "d 2"; do
    printf 'newmtl m\n%s\n' "$bad" >"$tmp/badval.mtl"
    printf 'mtllib badval.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n' >"$tmp/badval.obj"
    expect_error "mtl-${bad%% *}" "material 'm': ${bad%% *} .*is not in" render "$tmp/badval.obj" --width 4 --height 4 \
        --spp 1 -o "$tmp/d.pfm"
done
# MTL numbers are scanned strictly, as OBJ ones: tinyobjloader read these as 0.
for bad in "Kd nan" "Ns 0x10"; do
    printf 'newmtl m\n%s\n' "$bad" >"$tmp/badval.mtl"
    expect_error "mtl-scan-${bad%% *}" "badval.mtl' line 2: ${bad%% *} value '${bad#* }' is not a finite number" build \
        "$tmp/badval.obj"
done
# EPO's work is bounded: a 20,000-vertex polygon (a fan of thin triangles around one vertex,
# every one overlapping every node) builds with a warning and "epo": null instead of minutes.
python3 -c "
import math
n = 20000
print('v 0 0 0')
for i in range(n): print('v %.7f %.7f 0' % (math.cos(2 * math.pi * i / n), math.sin(2 * math.pi * i / n)))
print('f ' + ' '.join(str(i + 2) for i in range(n)))" >"$tmp/bigpoly.obj"
if timeout 120 "$bin" build "$tmp/bigpoly.obj" --json >"$tmp/out" 2>"$tmp/err" &&
    grep -q "warning: EPO skipped: it needs more than" "$tmp/err" &&
    python3 -c 'import json,sys; r=json.loads(open(sys.argv[1]).readline()); assert r["epo"] is None and "work" not in r and r["epo_skipped"], r' "$tmp/out"; then
    pass=$((pass + 1))
else
    fail=$((fail + 1)); echo "FAIL bigpoly-epo:"; sed 's/^/    /' "$tmp/err" | tail -3
fi
# Outputs never overwrite the command's inputs; invalid rays and foreign hits are refused by index.
cp "$data/cornell_box.obj" "$tmp/cb_in.obj"
expect_error build-out-is-input "--out .* is this command's input" build "$tmp/cb_in.obj" -o "$tmp/cb_in.obj"
expect_error rays-out-is-input "--out .* is this command's input" rays "$tmp/cb_in.obj" --type primary -o "$tmp/cb_in.obj"
"$bin" -q rays "$tmp/cb_in.obj" --type primary --width 8 --height 8 -o "$tmp/small.rays" >/dev/null
expect_error hits-out-is-rays "--hits-out .* is this command's input" bench "$tmp/cb_in.obj" --rays "$tmp/small.rays" --hits-out "$tmp/small.rays"
# Every output against every input (environment map, textures, material files, structure
# file, other names of one file) and against every other output.
mkdir -p "$tmp/clash"
printf 'PF\n1 1\n-1.0\n' >"$tmp/clash/env.pfm" && head -c 12 /dev/zero >>"$tmp/clash/env.pfm"
cp "$tmp/clash/env.pfm" "$tmp/clash/wood.pfm"
printf 'newmtl w\nKd 1 1 1\nmap_Kd wood.pfm\n' >"$tmp/clash/c.mtl"
printf 'mtllib c.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nusemtl w\nf 1/1 2/1 3/1\n' >"$tmp/clash/c.obj"
cp "$tmp/clash/env.pfm" "$tmp/clash/env.keep"
cp "$tmp/clash/c.mtl" "$tmp/clash/mtl.keep"
r=(render "$tmp/clash/c.obj" --width 4 --height 4 --spp 1)
expect_error render-out-is-env "--out .*env.pfm' is this command's input [(]--env[)]" "${r[@]}" --env "$tmp/clash/env.pfm" \
    -o "$tmp/clash/env.pfm"
expect_error render-out-is-texture "--out .*wood.pfm' is this command's input [(]the texture of material 'w'[)]" \
    "${r[@]}" -o "$tmp/clash/wood.pfm"
expect_error render-cost-is-env "--cost-image .* is this command's input [(]--env[)]" "${r[@]}" --env "$tmp/clash/env.pfm" \
    -o "$tmp/clash/out.pfm" --cost-image "$tmp/clash/env.pfm"
expect_error render-cost-is-out "--cost-image .* is also --out; two outputs cannot share a file" "${r[@]}" \
    -o "$tmp/clash/out.pfm" --cost-image "$tmp/clash/out.pfm"
expect_error render-cost-is-aov "--cost-image .* is also the albedo AOV" "${r[@]}" -o "$tmp/clash/out.pfm" --aov \
    --cost-image "$tmp/clash/out-albedo.pfm"
expect_error build-out-is-mtl "--out .*c.mtl' is this command's input [(]material file[)]" build "$tmp/clash/c.obj" \
    -o "$tmp/clash/c.mtl"
ln "$tmp/clash/c.obj" "$tmp/clash/hardlink.obj"
expect_error build-out-is-hardlink "--out .*hardlink.obj' is this command's input [(]the scene[)]" build \
    "$tmp/clash/c.obj" -o "$tmp/clash/hardlink.obj"
"$bin" -q build "$tmp/clash/c.obj" -o "$tmp/clash/c.bvh" >/dev/null
"$bin" -q rays "$tmp/clash/c.obj" --type primary --width 4 --height 4 -o "$tmp/clash/c.rays" >/dev/null
cp "$tmp/clash/c.bvh" "$tmp/clash/bvh.keep"
expect_error hits-out-is-structure "--hits-out .* is this command's input [(]--structure[)]" bench "$tmp/clash/c.obj" \
    --rays "$tmp/clash/c.rays" --structure "$tmp/clash/c.bvh" --device cpu --kernel plain --hits-out "$tmp/clash/c.bvh"
for k in env:env.pfm mtl:c.mtl bvh:c.bvh; do
    if cmp -s "$tmp/clash/${k%%:*}.keep" "$tmp/clash/${k#*:}"; then pass=$((pass + 1)); else
        fail=$((fail + 1)); echo "FAIL ${k#*:} was changed"; fi
done
if [ ! -e "$tmp/clash/out.pfm" ]; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL out.pfm was written"; fi
# A catalogue name is the file it names: an output onto that file is refused too.
mkdir -p "$tmp/cbcat"
cp "$data/cornell_box.obj" "$tmp/cbcat/cb.obj"
echo '{"scenes": {"mycb": {"file": "cb.obj"}}}' >"$tmp/cbcat/scenes.json"
BVHLAB_SCENES="$tmp/cbcat" expect_error build-out-is-catalogue-file "--out .* is this command's input" build mycb -o "$tmp/cbcat/cb.obj"
if cmp -s "$data/cornell_box.obj" "$tmp/cbcat/cb.obj"; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL the catalogue's file was changed"; fi
if cmp -s "$data/cornell_box.obj" "$tmp/cb_in.obj"; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL the input was changed"; fi
# edit_records IN OUT FORMAT OFFSET VALUES... [--keep-checksum]: writes IN with one record
# field packed at OFFSET after the 48-byte header, then, unless --keep-checksum, the checksum
# made again (a file that another tool wrote with bad values, not a damaged one).
edit_records() {
    python3 - "$@" <<'PY'
import struct, sys
src, dst, fmt, off = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
keep = sys.argv[-1] == '--keep-checksum'
vals = [float(v) if '.' in v or v == 'nan' else int(v) for v in sys.argv[5:len(sys.argv) - keep]]
d = bytearray(open(src, 'rb').read())
struct.pack_into('<' + fmt, d, 48 + off, *vals)
if not keep:  # FNV-1a over 8-byte words of everything before the checksum (docs/formats.md)
    h, body = 1469598103934665603, d[:-8]
    for i in range(0, len(body) - len(body) % 8, 8):
        h = ((h ^ struct.unpack_from('<Q', body, i)[0]) * 1099511628211) % 2**64
    for c in body[len(body) - len(body) % 8:]:
        h = ((h ^ c) * 1099511628211) % 2**64
    struct.pack_into('<Q', d, len(d) - 8, h)
open(dst, 'wb').write(d)
PY
}
edit_records "$tmp/small.rays" "$tmp/nan.rays" f $((3 * 32 + 16)) nan  # ray 3: direction x
expect_error nan-ray "ray 3 has a non-finite direction" verify "$tmp/cb_in.obj" --rays "$tmp/nan.rays"
# Origins and directions outside the numeric domain are refused by ray index (3e18 aborted
# inside Embree).
edit_records "$tmp/small.rays" "$tmp/far.rays" f $((2 * 32)) 3.0e18  # ray 2: origin x
expect_error far-ray "ray 2 has an origin [(]3e[+]18, .*[)] is outside [[]-1e[+]10, 1e[+]10[]]" verify "$tmp/cb_in.obj" \
    --rays "$tmp/far.rays"
expect_error far-ray-bench "ray 2 has an origin" bench "$tmp/cb_in.obj" --rays "$tmp/far.rays" --runs 1
# Options that do not apply are refused, not ignored: protocol options with a ray file, ray
# counts for types not asked for, structure and kernel options for the reference renderer.
expect_error rays-file-width "--rays excludes --width" verify "$tmp/cb_in.obj" --rays "$tmp/small.rays" --width 9
expect_error rays-file-eye "--rays excludes --eye" bench "$tmp/cb_in.obj" --rays "$tmp/small.rays" --eye 1 2 3
expect_error rays-file-seed "--rays excludes --seed" verify "$tmp/cb_in.obj" --rays "$tmp/small.rays" --seed 5
expect_error ao-rays-without-ao "--ao-rays applies to ao rays; --types primary has none" verify "$tmp/cb_in.obj" \
    --types primary --ao-rays 4 --width 4 --height 4
expect_error diffuse-rays-without-diffuse "--diffuse-rays applies to diffuse rays; --types primary,ao has none" \
    quality "$tmp/cb_in.obj" --types primary,ao --diffuse-rays 4 --width 4 --height 4
for f in "--structure $tmp/nope.bvh" "--bins 8" "--kd-stack 4" "--fetch-threshold 4" "--layout cwbvh" "--kernel plain"; do
    expect_error "reference-render-${f%% *}" "${f%% *} does not apply to render --device embree" render \
        "$tmp/cb_in.obj" $f --width 4 --height 4 --spp 1 -o "$tmp/ref.pfm"
done
expect_error verify-device-embree "verify checks a tracer against Embree; --device embree would check Embree against itself" \
    verify "$tmp/cb_in.obj" --device embree --width 4 --height 4
# One vocabulary: render's default (and --device embree) is the reference integrator, --device
# cpu bvhlab's CPU traversal of the structure, as in bench.
if r1=$("$bin" -q render "$data/cornell_box.obj" --width 4 --height 4 --spp 1 -o "$tmp/dev1.pfm" --json 2>"$tmp/err") &&
    r2=$("$bin" -q render "$data/cornell_box.obj" --device cpu --width 4 --height 4 --spp 1 -o "$tmp/dev2.pfm" --json 2>>"$tmp/err") &&
    r3=$("$bin" -q bench "$tmp/cb_in.obj" --device embree --width 4 --height 4 --json 2>>"$tmp/err") &&
    python3 -c 'import json,sys; a,b=json.loads(sys.argv[1]),json.loads(sys.argv[2]); c=[json.loads(l) for l in sys.argv[3].splitlines()]; assert a["device"]=="embree" and a["kernel"].startswith("embree") and b["device"]=="cpu" and b["kernel"].startswith("cpu-") and b["structure"]=="bvh2/binned" and all(x["device"]=="embree" for x in c), (a,b,c)' "$r1" "$r2" "$r3"; then
    pass=$((pass + 1))
else
    fail=$((fail + 1)); echo "FAIL device-vocabulary: render/bench --device records:"; sed 's/^/    /' "$tmp/err" | head -5
fi
# ... but with --cost-image the reference renderer builds a structure, and its options apply.
if "$bin" -q render "$data/cornell_box.obj" --bins 8 --builder binned --width 4 --height 4 --spp 1 \
    -o "$tmp/ref-ok.pfm" --cost-image "$tmp/ref-cost.pfm" >/dev/null 2>"$tmp/err" && [ -s "$tmp/ref-cost.pfm" ]; then
    pass=$((pass + 1))
else
    fail=$((fail + 1)); echo "FAIL reference render with --cost-image and structure options:"; sed 's/^/    /' "$tmp/err"
fi
edit_records "$tmp/small.rays" "$tmp/damaged.rays" f $((3 * 32 + 16)) 0.5 --keep-checksum
expect_error damaged-rays "damaged.rays' is damaged: its checksum does not match" verify "$tmp/cb_in.obj" --rays "$tmp/damaged.rays"
"$bin" -q bench "$tmp/cb_in.obj" --rays "$tmp/small.rays" --hits-out "$tmp/small.hits" --runs 1 >/dev/null
# Hit records (version 3): tri, t, u, v, then the instance and the triangle of its mesh; 24 bytes.
edit_records "$tmp/small.hits" "$tmp/foreign.hits" ifffii $((5 * 24)) 999999 1.0 0.1 0.1 0 999999  # hit 5: a triangle the scene lacks
expect_error foreign-hits "hit 5 names triangle 999999" verify "$tmp/cb_in.obj" --rays "$tmp/small.rays" --hits "$tmp/foreign.hits"
# Made-up hits never pass as ties: "triangle 5, t = 0" in records 0-5 (once 2,065 of 3,072 such
# records passed as interval-end ties), and a real hit file still passes.
cp "$tmp/small.hits" "$tmp/fake.hits"
for r in 0 1 2 3 4 5; do
    edit_records "$tmp/fake.hits" "$tmp/fake2.hits" ifffii $((r * 24)) 5 0.0 0.0 0.0 0 5 && mv "$tmp/fake2.hits" "$tmp/fake.hits"
done
if "$bin" -q verify "$tmp/cb_in.obj" --rays "$tmp/small.rays" --hits "$tmp/fake.hits" --json >"$tmp/out" 2>"$tmp/err"; then
    fail=$((fail + 1)); echo "FAIL fake-hits: verify passed a hit file with made-up hits"
elif grep -q "MISMATCH.*wrong-t: the ray meets triangle 5's plane" "$tmp/err" &&
    python3 -c 'import json,sys; r=json.loads(open(sys.argv[1]).readline()); k=r["mismatch_kinds"]; assert r["mismatches"]==6 and k["wrong-t"]+k["off-triangle"]+k["outside-interval"]==6, r' "$tmp/out" &&
    tail -1 "$tmp/err" | grep -q "real mismatches against Embree"; then
    pass=$((pass + 1))
else
    fail=$((fail + 1)); echo "FAIL fake-hits: expected 6 made-up hits named as such:"; sed 's/^/    /' "$tmp/err" | head -8
fi
if "$bin" -q verify "$tmp/cb_in.obj" --rays "$tmp/small.rays" --hits "$tmp/small.hits" >/dev/null 2>"$tmp/err"; then
    pass=$((pass + 1))
else
    fail=$((fail + 1)); echo "FAIL real-hits: verify refused the hits bench wrote:"; sed 's/^/    /' "$tmp/err" | head -5
fi
# An instanced scene's hit file names (instance, triangle) beside the scene-wide id: it verifies
# against the same scene, and against the scene made one mesh (--flatten) its numbering is refused.
"$bin" -q rays "gen:instances:$tmp/cb_in.obj:3:1" --type primary --width 8 --height 8 -o "$tmp/inst.rays" >/dev/null &&
    "$bin" -q bench "gen:instances:$tmp/cb_in.obj:3:1" --rays "$tmp/inst.rays" --device cpu --hits-out "$tmp/inst.hits" \
        --runs 1 >/dev/null
if "$bin" -q verify "gen:instances:$tmp/cb_in.obj:3:1" --rays "$tmp/inst.rays" --hits "$tmp/inst.hits" >/dev/null 2>"$tmp/err" &&
    python3 -c 'import struct,sys; d=open(sys.argv[1],"rb").read(); n=struct.unpack_from("<Q",d,16)[0]; w=[struct.unpack_from("<ifffii",d,48+24*i)[0::4] for i in range(n)]; assert struct.unpack_from("<I",d,8)[0]==3 and {x[1] for x in w if x[0]>=0}=={0,1,2}, w' "$tmp/inst.hits"; then
    pass=$((pass + 1))
else
    fail=$((fail + 1)); echo "FAIL instanced-hits: an instanced hit file did not verify or name 3 instances:"; sed 's/^/    /' "$tmp/err" | head -5
fi
expect_error instanced-hits-flattened "as instance [12]'s triangle .* but in this scene it is instance 0's" \
    --flatten verify "gen:instances:$tmp/cb_in.obj:3:1" --rays "$tmp/inst.rays" --hits "$tmp/inst.hits"
# --structure all: every structure in one table (8 structures x 1 ray type), and its refusals.
if [ "$("$bin" -q verify "$tmp/cb_in.obj" --structure all --types primary --width 32 --height 24 --json 2>/dev/null |
    python3 -c 'import json,sys; print(sorted({(r["structure"], r["kernel"]) for r in map(json.loads, sys.stdin) if r["mismatches"] == 0}))')" = \
    "[('bvh2/binned', 'cpu-bvh2-stack'), ('bvh2/sbvh', 'cpu-bvh2-stack'), ('bvh2/sweep', 'cpu-bvh2-stack'), ('cwbvh/binned', 'cpu-cwbvh'), ('cwbvh/sbvh', 'cpu-cwbvh'), ('cwbvh/sweep', 'cpu-cwbvh'), ('kdtree', 'cpu-kd-shortstack-2'), ('kdtree', 'cpu-kd-stack')]" ]; then
    pass=$((pass + 1))
else
    fail=$((fail + 1)); echo "FAIL structure-all: not every structure and tracer verified"
fi
expect_error structure-all-one-flag "--bins sets up one structure; --structure all checks every structure" verify "$tmp/cb_in.obj" --structure all --bins 8
expect_error structure-all-layout "--layout sets up one structure" verify "$tmp/cb_in.obj" --structure all --layout cwbvh
expect_error structure-all-kernel "--kernel plain traces one layout; --structure all" verify "$tmp/cb_in.obj" --structure all --kernel plain
expect_error structure-all-hits "--hits checks a hit file; --structure all" verify "$tmp/cb_in.obj" --structure all --rays "$tmp/small.rays" --hits "$tmp/small.hits"
expect_error structure-all-bench "--structure: all applies to .bvhlab verify. only" bench "$tmp/cb_in.obj" --structure all
expect_error structure-all-render "--structure: all applies to .bvhlab verify. only" render "$tmp/cb_in.obj" --structure all -o "$tmp/x.pfm"
expect_error structure-all-build "--structure: all applies to .bvhlab verify. only" build "$tmp/cb_in.obj" --structure all

# bench and verify lines name the structure's whole configuration, options included.
"$bin" -q bench "$cb" --builder sbvh --max-leaf 4 --runs 1 --json >"$tmp/cfg.json" 2>/dev/null
if grep -q '"config":"sbvh leaf=1..4 ' "$tmp/cfg.json"; then
    pass=$((pass + 1))
else
    fail=$((fail + 1)); echo "FAIL bench-config: $(head -c 300 "$tmp/cfg.json")"
fi
# Every command's --json lines carry the identifying fields of the schema (docs/formats.md, "JSON lines").
check_schema() {
    local name=$1
    shift
    if "$bin" -q "$@" --json 2>/dev/null | python3 -c '
import json, sys
lines = [l for l in sys.stdin if l.strip()]
assert lines, "no JSON lines"
for l in lines:
    r = json.loads(l)
    for k in ("record", "schema", "tool", "commit", "build_type", "machine"):
        assert k in r and r[k] not in (None, ""), k
    assert r["schema"] == 1 and r["tool"] == "bvhlab"
'; then
        pass=$((pass + 1))
    else
        fail=$((fail + 1)); echo "FAIL JSON schema of $name"
    fi
}
# render: bad options and outputs
expect_error render-no-out "out.*required|--out" render "$data/cornell_box.obj"
expect_error render-bad-ext "cannot write .*\\.xyz" render "$data/cornell_box.obj" -o "$tmp/img.xyz"
if "$bin" -q kernels --json | grep -q .; then
    expect_error render-kernel-all "not all" render "$data/cornell_box.obj" --device gpu --kernel all -o "$tmp/x.pfm"
    expect_error render-kernel-unknown "no-such-kernel" render "$data/cornell_box.obj" --device gpu --kernel no-such-kernel -o "$tmp/x.pfm"
else
    expect_error render-gpu-missing "--device gpu|CUDA" render "$data/cornell_box.obj" --device gpu -o "$tmp/x.pfm"
fi
expect_error render-kernel-cpu "kernel" render "$data/cornell_box.obj" --kernel dynamic-speculative-fma -o "$tmp/x.pfm"
expect_error render-spp-zero "spp" render "$data/cornell_box.obj" --spp 0 -o "$tmp/x.pfm"
expect_error render-sky-nan "sky" render "$data/cornell_box.obj" --sky 1 nan 1 -o "$tmp/x.pfm"
expect_error render-shutter-still "--shutter applies to a moving camera" render "$data/cornell_box.obj" --shutter 0 0.5 -o "$tmp/x.pfm"
expect_error render-degenerate-camera "degenerate camera" render "$data/cornell_box.obj" --eye 1 2 3 --target 1 2 3 -o "$tmp/x.pfm"
expect_error render-empty "no usable triangles" render "$tmp/empty.obj" -o "$tmp/x.pfm"
expect_error render-out-is-input "cannot write .*cornell_box[.]obj: .*[.]obj" render "$data/cornell_box.obj" -o "$data/cornell_box.obj"
expect_error render-bad-strategy "strategy" render "$data/cornell_box.obj" --strategy none -o "$tmp/x.pfm"
expect_error render-cost-bad-ext "cannot write .*cost[.]xyz" render "$data/cornell_box.obj" --cost-image "$tmp/cost.xyz" -o "$tmp/x.pfm"
printf 'mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n' >"$tmp/nomtl.obj"
expect_error render-missing-mtl "material file .*gone[.]mtl does not exist" render "$tmp/nomtl.obj" -o "$tmp/x.pfm"
# A render that warns about a missing file and still writes its image.
expect_warned_render() {
    local name=$1 pattern=$2 scene=$3 image=$4
    if "$bin" render "$scene" --missing-textures warn --width 4 --height 4 --spp 1 -o "$image" \
        2>"$tmp/err" >/dev/null && grep -q -- "$pattern" "$tmp/err" && [ -s "$image" ]; then
        pass=$((pass + 1))
    else
        fail=$((fail + 1)); echo "FAIL $name"; sed 's/^/    /' "$tmp/err" | head -3
    fi
}
expect_warned_render render-missing-mtl-warn "warning: material file .*gone.mtl" "$tmp/nomtl.obj" "$tmp/warn.pfm"
mkdir -p "$tmp/texq"
printf 'newmtl t\nKd 0.5 0.5 0.5\nmap_Kd maps\\gone.png\n' >"$tmp/texq/q.mtl"
printf 'mtllib q.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nusemtl t\nf 1/1 2/1 3/1\n' >"$tmp/texq/q.obj"
expect_error render-missing-texture "texture .*texq/maps/gone[.]png .*does not exist" render "$tmp/texq/q.obj" -o "$tmp/x.pfm"
printf 'newmtl t\nKd 0.5 0.5 0.5\nmap_Kd broken.pfm\n' >"$tmp/texq/b.mtl"
printf 'mtllib b.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nusemtl t\nf 1/1 2/1 3/1\n' >"$tmp/texq/b.obj"
printf 'PF\n2 2\n-1.0\nshort' >"$tmp/texq/broken.pfm"
expect_error render-truncated-texture "broken[.]pfm is truncated" render "$tmp/texq/b.obj" --missing-textures warn -o "$tmp/x.pfm"
# Normal and height maps: texels a normal map cannot hold, a bad -bm, one that does not exist,
# and the output over one.
printf 'newmtl t\nKd 0.5 0.5 0.5\nnorm n.pfm\n' >"$tmp/texq/n.mtl"
printf 'mtllib n.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl t\nf 1/1 2/2 3/3\n' >"$tmp/texq/n.obj"
python3 -c "
import struct, sys
sys.stdout.buffer.write(b'PF\\n2 1\\n-1.0\\n' + struct.pack('<6f', 0.5, 0.5, 1.0, 0.5, 0.5, 2.0))" >"$tmp/texq/n.pfm"
expect_error render-normal-map-above-one "texture .*n[.]pfm [(]norm of material 't'[)] has a texel above 1" render "$tmp/texq/n.obj" -o "$tmp/x.pfm"
expect_error render-normal-map-is-output "n[.]pfm' is this command's input [(]the normal map of material 't'[)]" render "$tmp/texq/n.obj" -o "$tmp/texq/n.pfm"
printf 'newmtl t\nKd 0.5 0.5 0.5\nbump -bm nan h.pfm\n' >"$tmp/texq/bm.mtl"
sed 's/n[.]mtl/bm.mtl/' "$tmp/texq/n.obj" >"$tmp/texq/bm.obj"
printf 'newmtl t\nKd 0.5 0.5 0.5\nbump -bm 1e9 h.pfm\n' >"$tmp/texq/big.mtl"
sed 's/n[.]mtl/big.mtl/' "$tmp/texq/n.obj" >"$tmp/texq/big.obj"
expect_error render-bump-multiplier-huge "material 't': -bm 1e[+]09 is not in" render "$tmp/texq/big.obj" -o "$tmp/x.pfm"
expect_error render-bump-multiplier-nan "bm[.]mtl' line 3: bump -bm value 'nan' is not a finite number" render "$tmp/texq/bm.obj" -o "$tmp/x.pfm"
printf 'newmtl t\nKd 0.5 0.5 0.5\nmap_Bump gone.png\n' >"$tmp/texq/g.mtl"
sed 's/n[.]mtl/g.mtl/' "$tmp/texq/n.obj" >"$tmp/texq/g.obj"
expect_error render-missing-bump-map "texture .*gone[.]png [(]map_Bump of material 't'[)] does not exist" render "$tmp/texq/g.obj" -o "$tmp/x.pfm"
expect_warned_render render-missing-bump-map-warn "renders without its map_Bump" "$tmp/texq/g.obj" "$tmp/warn.pfm"
# A truncated PNG: one line naming it (libpng and OpenImageIO print their own copies; without
# OpenImageIO the build reads .pfm only and says so, also in one line).
python3 -c "
import struct, sys, zlib
w = h = 64
raw = b''.join(b'\\0' + bytes(sum(([x * 7 % 256, y * 5 % 256, 128] for x in range(w)), [])) for y in range(h))
chunk = lambda t, d: struct.pack('>I', len(d)) + t + d + struct.pack('>I', zlib.crc32(t + d))
png = b'\\x89PNG\\r\\n\\x1a\\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, 2, 0, 0, 0)) + chunk(b'IDAT', zlib.compress(raw)) + chunk(b'IEND', b'')
open(sys.argv[1], 'wb').write(png[: len(png) // 2])
" "$tmp/texq/half.png"
printf 'newmtl t\nKd 0.5 0.5 0.5\nmap_Kd half.png\n' >"$tmp/texq/h.mtl"
printf 'mtllib h.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nusemtl t\nf 1/1 2/1 3/1\n' >"$tmp/texq/h.obj"
expect_error render-truncated-png "cannot read .*half[.]png: " render "$tmp/texq/h.obj" -o "$tmp/x.pfm"
expect_warned_render render-missing-texture-warn "warning: texture .*maps/gone.png does not exist" "$tmp/texq/q.obj" \
    "$tmp/warn_tex.pfm"
expect_error render-cache-lens "--first-hit-cache needs camera rays that repeat" render "$data/cornell_box.obj" --first-hit-cache --aperture 2 -o "$tmp/x.pfm"
expect_error render-sort-cpu "--sort-materials and --no-compaction apply to --device gpu" render "$data/cornell_box.obj" --sort-materials -o "$tmp/x.pfm"
expect_error render-no-compaction-cpu "--sort-materials and --no-compaction apply to --device gpu" render "$data/cornell_box.obj" --no-compaction -o "$tmp/x.pfm"
expect_error render-missing-env "--env .*nope[.]exr: no such file" render "$data/cornell_box.obj" --env "$tmp/nope.exr" -o "$tmp/x.pfm"
expect_error render-env-and-sky "excludes|--sky" render "$data/cornell_box.obj" --env "$tmp/nope.exr" --sky 1 1 1 -o "$tmp/x.pfm"
printf 'PF\n2 1\n-1.0\n' >"$tmp/bad_env.pfm"
expect_error render-truncated-env "bad_env[.]pfm is truncated" render "$data/cornell_box.obj" --env "$tmp/bad_env.pfm" -o "$tmp/x.pfm"
expect_error render-wave-zero "wave" render "$data/cornell_box.obj" --wave 0 -o "$tmp/x.pfm"
expect_error render-max-depth-zero "max-depth" render "$data/cornell_box.obj" --max-depth 0 -o "$tmp/x.pfm"
expect_error render-env-scale-negative "env-scale" render "$data/cornell_box.obj" --env-scale -1 -o "$tmp/x.pfm"
expect_error render-time-limit-nan "time-limit" render "$data/cornell_box.obj" --time-limit nan -o "$tmp/x.pfm"
expect_error render-aperture-negative "aperture" render "$data/cornell_box.obj" --aperture -2 -o "$tmp/x.pfm"
expect_error render-missing-textures-value "missing-textures" render "$data/cornell_box.obj" --missing-textures maybe -o "$tmp/x.pfm"
head -c 64 /dev/urandom >"$tmp/garbage_env.exr"
expect_error render-garbage-env "cannot read .*garbage_env[.]exr|cannot read .*garbage_env" render "$data/cornell_box.obj" --env "$tmp/garbage_env.exr" -o "$tmp/x.pfm"
printf 'BVHLRAYS\1\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0' >"$tmp/zero.rays"
expect_error verify-zero-rays "zero.rays' has no rays: nothing to verify" verify "$data/cornell_box.obj" --rays "$tmp/zero.rays"
expect_error bench-zero-rays "zero.rays' has no rays: nothing to bench" bench "$data/cornell_box.obj" --rays "$tmp/zero.rays"
expect_error seed-overflow "--seed: 99999999999999999999 is larger than 2\^64 - 1" rays "$data/cornell_box.obj" \
    --type primary --seed 99999999999999999999 -o "$tmp/seed.rays"
expect_error seed-negative "--seed: '-1' is not a non-negative integer" rays "$data/cornell_box.obj" --type primary \
    --seed -1 -o "$tmp/seed.rays"
expect_error gen-seed-negative "--seed: '-1' is not a non-negative integer" gen --kind soup -n 10 --seed -1 \
    -o "$tmp/seed.obj"
# Scene formats through Assimp, instanced scenes and gen:instances.
expect_error instanced-kdtree "the kd-tree is single-level and the scene places a mesh more than once: --flatten" \
    build --structure kdtree "$data/instances.glb"
# The cwbvh layout of an instanced scene is two-level with CWBVH bottom levels.
if "$bin" -q build --layout cwbvh gen:instances:cornell-box:3 --json | python3 -c '
import json, sys
r = json.loads(sys.stdin.readline())
assert r["structure"] == "two-level-cwbvh/binned" and r["layout"] == "two-level-cwbvh" and r["instances"] == 3, r
'; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL instanced-cwbvh: not a two-level-cwbvh build"; fi
# PLY headers are checked before Assimp reads them: its reader loops forever on an end_header
# line broken by a NUL byte (a fuzz finding).
printf 'ply\nformat ascii 1.0\nend_hea\004\000\000\000der\n' >"$tmp/nul.ply"
expect_error ply-header-nul "nul[.]ply': has a byte that is not text [(]4[)] in its PLY header, at offset 28" build "$tmp/nul.ply"
printf 'ply\nformat ascii 1.0\nelement vertex 3\n' >"$tmp/noend.ply"
expect_error ply-no-end-header "noend[.]ply': has no end_header line ending its PLY header" build "$tmp/noend.ply"
# A face of no vertices made Assimp's triangulation assert (abort); it is a point now, dropped.
printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n0\n' >"$tmp/emptyface.ply"
expect_error ply-empty-face "emptyface[.]ply': has no triangles" build "$tmp/emptyface.ply"
printf 'solid x\n' >"$tmp/notply.ply"
expect_error ply-not-ply "notply[.]ply': is not a PLY file" build "$tmp/notply.ply"
expect_error instanced-out "--out writes a structure file, .* is built two-level .*--flatten" build "$data/instances.glb" \
    -o "$tmp/two-level.tree"
[ ! -e "$tmp/two-level.tree" ] && pass=$((pass + 1)) || { fail=$((fail + 1)); echo "FAIL instanced-out wrote a file"; }
expect_error instanced-structure-file "structure files hold single-level structures" verify "$data/instances.glb" \
    --structure "$tmp/cb.tree"
expect_error instanced-render-kdtree "the kd-tree is single-level and the scene places a mesh more than once: --flatten" \
    render "$data/instances.glb" --device cpu --kernel plain --structure kdtree --width 4 --height 4 --spp 1 -o "$tmp/inst.pfm"
# An instanced scene renders two-level (the CPU two-level BVH here) and flattened, the same paths.
if r1=$("$bin" -q render gen:instances:cornell-box:3:1 --device cpu --kernel plain --width 16 --height 12 --spp 4 \
        -o "$tmp/inst2.pfm" --json 2>"$tmp/err") &&
    r2=$("$bin" -q --flatten render gen:instances:cornell-box:3:1 --device cpu --kernel plain --width 16 --height 12 \
        --spp 4 -o "$tmp/inst1.pfm" --json 2>>"$tmp/err") &&
    python3 -c 'import json,sys; a,b=json.loads(sys.argv[1]),json.loads(sys.argv[2]); assert a["structure"]=="two-level/binned" and b["structure"]=="bvh2/binned" and a["bounces"][0]==b["bounces"][0], (a,b)' "$r1" "$r2"; then
    pass=$((pass + 1))
else
    fail=$((fail + 1)); echo "FAIL instanced-render: two-level and flattened renders differ:"; sed 's/^/    /' "$tmp/err" | head -5
fi
expect_error gen-instances-zero "the instance count must be 1..2\^24, not 0" build --flatten gen:instances:cornell-box:0
expect_error gen-instances-no-count "expected gen:instances:SCENE:N\[:SEED\]" build --flatten gen:instances:cornell-box
expect_error gen-instances-bad-seed "the seed 'x' is not a whole number" build --flatten gen:instances:cornell-box:2:x
expect_error gen-instances-missing "no scene 'nowhere'" build --flatten gen:instances:nowhere:2
printf 'nothing\n' >"$tmp/scene.xyz"
expect_error unknown-format "scene.xyz': unknown scene format '.xyz'" build "$tmp/scene.xyz"
sed 's/"extensionsUsed"/"extensionsRequired": ["KHR_draco_mesh_compression"], "extensionsUsed"/' \
    "$data/instances.gltf" >"$tmp/draco.gltf"
expect_error gltf-required-extension "draco.gltf': requires the glTF extension KHR_draco_mesh_compression" \
    build --flatten "$tmp/draco.gltf"
sed 's|"uri": "data:[^"]*"|"uri": "missing.bin"|' "$data/instances.gltf" >"$tmp/nobuffer.gltf"
expect_error gltf-missing-buffer "nobuffer.gltf': Assimp cannot read it" build --flatten "$tmp/nobuffer.gltf"
head -c 1000 "$data/instances.glb" >"$tmp/truncated.glb"
expect_error glb-truncated "truncated.glb': is a damaged GLB file: its header claims [0-9]* bytes and the file has 1000" \
    build --flatten "$tmp/truncated.glb"
python3 - "$data/instances.glb" "$tmp/long-chunk.glb" <<'PY'
import struct, sys
b = bytearray(open(sys.argv[1], "rb").read())
struct.pack_into("<I", b, 12, 1953261448)  # the JSON chunk claims 1.95 GB
open(sys.argv[2], "wb").write(b)
PY
expect_error glb-long-chunk "long-chunk.glb': is a damaged GLB file: its header claims 1953261468 bytes" \
    build --flatten "$tmp/long-chunk.glb"
printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n' \
    >"$tmp/points.ply"
printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\340\340\nend_header\n' >"$tmp/ply-inside.gltf"
expect_error gltf-holding-ply "ply-inside.gltf': has a byte that is not text [(]224[)] in its PLY header" \
    build --flatten "$tmp/ply-inside.gltf"
printf 'ply\nformat ascii 1.0\nelement vertex 5000\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n' >"$tmp/ply-count.ply"
expect_error ply-huge-count "ply-count.ply': has a PLY element 'vertex' of 5000 entries, more than the file's [0-9]+ bytes can hold" \
    build "$tmp/ply-count.ply"
printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nply\nproperty float y\nend_header\n' >"$tmp/ply-stray.ply"
expect_error ply-stray-line "ply-stray.ply': has a PLY header line that is not format, comment, obj_info, element or property: 'ply'" \
    build "$tmp/ply-stray.ply"
expect_error ply-no-faces "points.ply': has no triangles" build "$tmp/points.ply"
cp "$data/instances.glb" "$tmp/copy.glb"
expect_error out-over-gltf "copy.glb. is this command.s input [(]the scene[)]" build --flatten "$tmp/copy.glb" -o "$tmp/copy.glb"
expect_error render-unwritable "cannot" render "$data/cornell_box.obj" --width 4 --height 4 --spp 1 -o "$tmp/no/such/dir/x.pfm"
check_schema build build "$data/cornell_box.obj"
check_schema build-gltf build --flatten "$data/instances.gltf"
check_schema build-two-level build "$data/instances.gltf"
# Memory figures of every build record: layout bytes per triangle, the process's peak.
for args in "$data/cornell_box.obj" "$data/instances.gltf" "--flatten $data/instances.gltf"; do
    # shellcheck disable=SC2086
    if "$bin" -q build $args --json | python3 -c '
import json, sys
r = json.loads(sys.stdin.readline())
assert r["peak_host_bytes"] > 1e6, r
assert abs(r["bytes_per_triangle"] * r["triangles"] - r["layout_bytes"]) < 1e-6 * r["layout_bytes"], r
# Device memory: null without a GPU; with one, the upload is the layout or more, the peak no less.
d, p = r["device_structure_bytes"], r["device_peak_bytes"]
assert (d is None and p is None) or (d >= r["layout_bytes"] and p >= d), r
# ... and the GPU and driver they were measured on (null without a GPU).
assert (d is None) == (r["gpu"] is None) == (r["driver"] is None), r
'; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL build memory figures: $args"; fi
done

check_schema verify-two-level verify gen:instances:cornell-box:4 --width 8 --height 8
check_schema build-ply build "$data/cube_binary.ply"
check_schema build-cwbvh build "$data/cornell_box.obj" --layout cwbvh
check_schema rays rays "$data/cornell_box.obj" --type ao --width 8 --height 8 -o "$tmp/schema.rays"
check_schema rays-info rays --info "$tmp/schema.rays"
check_schema gen gen --kind soup -n 10 -o "$tmp/schema.obj"
check_schema bench bench "$data/cornell_box.obj" --types primary --width 8 --height 8 --runs 1
check_schema verify verify "$data/cornell_box.obj" --width 8 --height 8
check_schema quality quality "$data/cornell_box.obj" --types primary --width 8 --height 8
check_schema run run "$data/cornell_box.obj" --runs 1 --width 8 --height 8
check_schema render render "$data/cornell_box.obj" --width 8 --height 8 --spp 2 -o "$tmp/schema.pfm" --aov \
    --cost-image "$tmp/cost.pfm"
for f in schema-albedo.pfm schema-normal.pfm cost.pfm; do
    if [ -s "$tmp/$f" ]; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL render wrote no $f"; fi
done
# A build without CUDA has no kernels to list.
if "$bin" -q kernels --json | grep -q .; then check_schema kernels kernels; fi

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
