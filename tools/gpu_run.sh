#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# One batched GPU session over an installed bvhlab (cmake --install), as logs and JSON lines
# in OUT (at most 8 files, so that a lent machine can send them all back). Phases:
#   tests     the gpu-labelled tests (every registered kernel x structure x query)
#   bench     the anchors' ray files (bvhlab rays at the default seed: 480x320x16 4x4-tiled
#             primary, protocol diffuse), every kernel on binned, SBVH and kd-trees, checked
#             against Embree before timing, and Embree on every core on the same rays
#   kdbench   the bench phase for the kd-tree kernels alone (kd-full-stack, kd-short-stack with a
#             4-entry stack), with the kd-tree's build figures (kdbuild.jsonl): run it with two
#             installs, interleaved, to compare kd-trees and traversals
#   bvhbench  the bench phase for the BVH2 kernels alone (binned and SBVH; no kd-tree, no Embree)
#   cwbench   the CWBVH kernels (--layout cwbvh) on binned and SBVH trees, with Woop and with vertex
#             leaf triangles (--cw-tris), beside the bvh2 bench
#   cwverify  the CWBVH kernels against Embree on the protocol's four ray types, both leaf
#             triangle formats (verify does them too)
#   verify    every kernel against Embree on the protocol's four ray types
#   profile   ncu metrics of every kernel on bunny primary and furball diffuse (PROFILE_SETS:
#             scene:raytype pairs; PROFILE_KERNEL: one kernel instead of all)
#   sanitize  compute-sanitizer memcheck and racecheck of every kernel on the Cornell box, and
#             memcheck, racecheck, synccheck and initcheck of the GPU builders (build --reinsert 2)
#   threshold the dynamic-fetch threshold swept on bunny, dragon and furball (threshold.jsonl)
#   sass      the SASS of while-while-fma and dynamic-speculative-fma (closest hit), sass.txt
#   render    the renderer's experiment on data/'s Cornell box (open and closed) and
#             glass-and-mirror scene and the named scenes, 640x480, max depth 8: a timed render
#             (RENDER_SPP, default 512; render.jsonl, images in renders.tar.xz); the first wave's
#             dumped rays of every bounce (render_dumps.jsonl) through every kernel
#             (render_bench.jsonl); the switches (SWITCH_SPP, default 256, three rounds;
#             render_switches.jsonl): material sorting, the first-hit cache, no compaction;
#             and compute-sanitizer memcheck of small renders.
#             experiments/render_report.py turns OUT into docs/results.md's renderer section
#             (RENDER_DATA_SCENES=0 leaves data/'s three scenes out, to split the run in two
#             whose OUT folders the report reads together)
# GPU_TESTS: a gtest filter for the tests phase (default: all). BENCH_KERNELS: the kernels of
# bvhbench and cwbench (default: all).
# Usage: tools/gpu_run.sh PREFIX SCENES_DIR OUT PHASE[,PHASE...] [SCENE ...]
set -uo pipefail
prefix=$1 scenes=$2 out=$3 phases=$4
shift 4
names=("$@")
[ ${#names[@]} -gt 0 ] || names=(stanford-bunny dragon-100k buddha-100k furball)
export BVHLAB_SCENES=$scenes BVHLAB_DATA=$prefix/share/bvhlab/data
mkdir -p "$out"
bin=$prefix/bin
rays=${BVHLAB_RAYS_DIR:-/tmp/bvhlab-rays}
mkdir -p "$rays"
status=0
has() { [[ ",$phases," == *",$1,"* || "$phases" == all ]]; }
log() { echo "[gpu_run $(date +%T)] $*" | tee -a "$out/summary.txt"; }

{ nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.sm,clocks.max.sm --format=csv 2>&1
  "$bin/bvhlab" --version; nproc; } >"$out/machine.txt" 2>&1

# The anchors' ray files (../shared/anchors/README.md), made here once per machine.
make_rays() {
    local s=$1
    [ -s "$rays/$s-primary.rays" ] || "$bin/bvhlab" -q rays "$s" --type primary --width 480 --height 320 --spp 16 \
        --tile 4 -o "$rays/$s-primary.rays" || status=1
    [ -s "$rays/$s-diffuse.rays" ] || "$bin/bvhlab" -q rays "$s" --type diffuse -o "$rays/$s-diffuse.rays" || status=1
}

if has tests; then
    log "tests"
    "$bin/bvhlab_gpu_tests" --gtest_filter="${GPU_TESTS:-*}" >"$out/gpu_tests.log" 2>&1 || status=1
    tail -3 "$out/gpu_tests.log" | tee -a "$out/summary.txt"
fi

if has bench; then
    for s in "${names[@]}"; do
        make_rays "$s"
        for r in primary diffuse; do
            log "bench $s $r"
            f=$rays/$s-$r.rays
            "$bin/bvhlab" -q bench "$s" --rays "$f" --device gpu --kernel all --json >>"$out/bench.jsonl" || status=1
            "$bin/bvhlab" -q bench "$s" --rays "$f" --device gpu --kernel all --structure sbvh --json >>"$out/bench.jsonl" || status=1
            "$bin/bvhlab" -q bench "$s" --rays "$f" --device gpu --kernel all --structure kdtree --kd-stack 4 --json \
                >>"$out/bench.jsonl" || status=1
            "$bin/bvhlab" -q bench "$s" --rays "$f" --device embree --json >>"$out/bench.jsonl" || status=1
        done
    done
fi

if has kdbench; then
    for s in "${names[@]}"; do
        make_rays "$s"
        log "kd build $s"
        "$bin/bvhlab" -q build "$s" --structure kdtree --json >>"$out/kdbuild.jsonl" || status=1
        for r in primary diffuse; do
            log "kd bench $s $r"
            "$bin/bvhlab" -q bench "$s" --rays "$rays/$s-$r.rays" --device gpu --kernel all --structure kdtree \
                --kd-stack 4 --json >>"$out/kdbench.jsonl" || status=1
        done
    done
fi

# every_layout_bench FILE ARGS...: every kernel of one layout on binned and SBVH trees, both ray sets.
every_layout_bench() {
    local file=$1
    shift
    for s in "${names[@]}"; do
        make_rays "$s"
        for r in primary diffuse; do
            log "bench $* $s $r"
            for b in binned sbvh; do
                for k in ${BENCH_KERNELS:-all}; do
                    "$bin/bvhlab" -q bench "$s" --rays "$rays/$s-$r.rays" --device gpu --kernel "$k" --builder $b "$@" \
                        --json >>"$out/$file" || status=1
                done
            done
        done
    done
}
if has bvhbench; then every_layout_bench bench.jsonl --layout bvh2; fi
if has cwbench; then
    every_layout_bench cwbench.jsonl --layout cwbvh
    every_layout_bench cwbench.jsonl --layout cwbvh --cw-tris vertices
fi

if has verify; then
    for s in cornell-box "${names[@]}"; do
        log "verify $s"
        "$bin/bvhlab" -q verify "$s" --device gpu --kernel all --json >>"$out/verify.jsonl" || status=1
        "$bin/bvhlab" -q verify "$s" --device gpu --kernel all --structure kdtree --kd-stack 2 --json \
            >>"$out/verify.jsonl" || status=1
        "$bin/bvhlab" -q verify "$s" --device gpu --layout cwbvh --kernel all --json >>"$out/verify.jsonl" || status=1
    done
fi

if has cwverify; then
    for s in cornell-box "${names[@]}"; do
        log "cwbvh verify $s"
        for tris in woop vertices; do
            "$bin/bvhlab" -q verify "$s" --device gpu --layout cwbvh --cw-tris $tris --kernel all --json \
                >>"$out/verify.jsonl" || status=1
        done
    done
fi

if has profile; then
    metrics=gpu__time_duration.sum,sm__cycles_elapsed.avg.per_second,smsp__inst_executed.sum,smsp__thread_inst_executed.sum
    metrics+=,smsp__thread_inst_executed_per_inst_executed.ratio,sm__inst_issued.avg.pct_of_peak_sustained_active
    metrics+=,sm__warps_active.avg.pct_of_peak_sustained_active,launch__registers_per_thread,launch__grid_size,launch__block_size
    metrics+=,l1tex__t_sector_hit_rate.pct,lts__t_sector_hit_rate.pct,l1tex__t_bytes.sum,lts__t_bytes.sum,dram__bytes_read.sum
    metrics+=,dram__throughput.avg.pct_of_peak_sustained_elapsed,l1tex__throughput.avg.pct_of_peak_sustained_active
    metrics+=,lts__throughput.avg.pct_of_peak_sustained_elapsed,smsp__average_warp_latency_issue_stalled_long_scoreboard.ratio
    for sr in ${PROFILE_SETS:-stanford-bunny:primary furball:diffuse}; do
        s=${sr%%:*} r=${sr##*:}
        make_rays "$s"
        log "ncu $s $r"
        ncu --metrics "$metrics" --csv --page raw -k regex:"per_ray_kernel|persistent_kernel|dynamic_fetch_kernel" \
            "$bin/bvhlab" -q bench "$s" --rays "$rays/$s-$r.rays" --device gpu --kernel "${PROFILE_KERNEL:-all}" --runs 1 \
            --warmup 0 --json >>"$out/ncu.csv" 2>>"$out/profile.log" || status=1
    done
fi

if has threshold; then
    for s in stanford-bunny dragon-100k furball; do
        make_rays "$s"
        for r in primary diffuse; do
            log "fetch thresholds $s $r"
            for th in 2 4 8 16 24; do
                "$bin/bvhlab" -q bench "$s" --rays "$rays/$s-$r.rays" --device gpu --kernel dynamic-speculative-fma \
                    --fetch-threshold $th --json >>"$out/threshold.jsonl" || status=1
            done
        done
    done
fi

if has sass; then
    # Closest-hit while-while-fma (per ray) and dynamic-speculative-fma, for instruction counting.
    cuobjdump -sass "$bin/bvhlab" | awk '/Function :/ { keep = /per_ray_kernelINS0_15WhileWhileTraceILb0ELb0ELb1ELb0E/ ||
        /dynamic_fetch_kernelINS0_15WhileWhileTraceILb0ELb1ELb1ELb0E/ } keep' >"$out/sass.txt" || status=1
    log "sass: $(grep -c "Function :" "$out/sass.txt") functions, $(wc -l <"$out/sass.txt") lines"
fi

if has sanitize; then
    for tool in memcheck racecheck; do
        log "compute-sanitizer $tool"
        for st in "--structure bvh" "--structure kdtree" "--layout cwbvh" "--layout cwbvh --cw-tris vertices"; do
            # shellcheck disable=SC2086
            compute-sanitizer --tool $tool --error-exitcode 3 "$bin/bvhlab" -q verify cornell-box --device gpu \
                --kernel all $st --width 64 --height 48 --json >>"$out/sanitizer.log" 2>&1 || status=1
        done
    done
    # The GPU builders with two reinsertion passes, on the Cornell box (one small task) and a
    # 30,000-triangle soup (gpu-binned's large levels, warps' subtrees and exact sweeps), and
    # their TLAS over 2,000 instances.
    for tool in memcheck racecheck synccheck initcheck; do
        log "compute-sanitizer $tool: GPU builders"
        for b in lbvh ploc hploc gpu-binned; do
            for s in cornell-box gen:soup:30000:1 gen:instances:cornell-box:2000; do
                passes=(--reinsert 2)
                [[ $s == gen:instances:* ]] && passes=()
                compute-sanitizer --tool $tool --error-exitcode 3 "$bin/bvhlab" -q build "$s" --builder $b \
                    "${passes[@]}" --runs 1 --no-epo --json >>"$out/sanitizer.log" 2>&1 || status=1
            done
        done
    done
    grep -E "ERROR SUMMARY|RACECHECK SUMMARY" "$out/sanitizer.log" | tee -a "$out/summary.txt"
fi

if has render; then
    # The renderer's experiment (issue 19), one run that experiments/render_report.py turns
    # into docs/results.md's renderer section and its plots.
    kernel=${RENDER_KERNEL:-dynamic-speculative-fma}
    switch_spp=${SWITCH_SPP:-256}
    mkdir -p /tmp/renders
    rm -f /tmp/renders/*
    run_render() {  # OUTPUT.jsonl SCENE IMAGE ARGS...: one render, its JSON line appended
        local o=$1 s=$2 img=$3
        shift 3
        "$bin/bvhlab" -q render "$s" --device gpu --kernel "$kernel" --width 640 --height 480 --max-depth 8 \
            -o "$img" --json "$@" >>"$o" 2>>"$out/render.err" || status=1
    }
    data_scenes=("$BVHLAB_DATA/cornell_box.obj" "$BVHLAB_DATA/cornell_closed.obj" "$BVHLAB_DATA/glass_mirror.obj")
    [ "${RENDER_DATA_SCENES:-1}" = 1 ] || data_scenes=()
    for s in "${data_scenes[@]}" "${names[@]}"; do
        n=$(basename "$s" .obj)
        log "render $n"
        d=$rays/render-$n
        rm -rf "$d"
        # 1. Overhead: timed without --dump-rays (dumping copies every queue back and writes
        #    files inside the pass); then the first wave again, dumped, for the kernel-only figure.
        run_render "$out/render.jsonl" "$s" "/tmp/renders/$n.pfm" --spp "${RENDER_SPP:-512}"
        #    Its record (render_dumps.jsonl) says how the ray files were made, so that a bench
        #    record on them can be rerun after the same render (the files' hashes are checked).
        run_render "$out/render_dumps.jsonl" "$s" "/tmp/renders/$n-dump.pfm" --spp 6 --wave 6 --dump-rays "$d"
        # 2. Every bounce's rays through every BVH2 kernel and the CWBVH one (the coherence
        #    report on real path-tracer rays); each record names its ray file.
        for f in "$d"/*.rays; do
            "$bin/bvhlab" -q bench "$s" --rays "$f" --device gpu --kernel all --runs 3 --json \
                >>"$out/render_bench.jsonl" || status=1
            "$bin/bvhlab" -q bench "$s" --rays "$f" --device gpu --kernel dynamic-cwbvh --runs 3 --json \
                >>"$out/render_bench.jsonl" || status=1
        done
        # 3. The switches, all through pixel centres so that the first-hit cache compares
        #    like with like: plain, material sorting, the first-hit cache, both, no compaction;
        #    three rounds, interleaved (the report takes each variant's median).
        for round in 1 2 3; do
            for v in "" "--sort-materials" "--first-hit-cache" "--sort-materials --first-hit-cache" "--no-compaction"; do
                # shellcheck disable=SC2086
                run_render "$out/render_switches.jsonl" "$s" /tmp/renders/switch.pfm --spp "$switch_spp" \
                    --pixel-centres $v
            done
        done
    done
    rm -f /tmp/renders/*-dump.pfm /tmp/renders/switch.pfm
    tar cJf "$out/renders.tar.xz" -C /tmp/renders . || status=1
    log "render compute-sanitizer memcheck"
    compute-sanitizer --tool memcheck --error-exitcode 3 "$bin/bvhlab" -q render "$BVHLAB_DATA/glass_mirror.obj" \
        --device gpu --width 64 --height 48 --spp 4 --sort-materials -o /tmp/renders/sanitized.pfm \
        >>"$out/render.err" 2>&1 || status=1
    compute-sanitizer --tool memcheck --error-exitcode 3 "$bin/bvhlab" -q render "$BVHLAB_DATA/cornell_box.obj" \
        --device gpu --width 64 --height 48 --spp 4 --no-compaction --first-hit-cache -o /tmp/renders/sanitized.pfm \
        >>"$out/render.err" 2>&1 || status=1
    grep -E "ERROR SUMMARY" "$out/render.err" | tee -a "$out/summary.txt"
fi

log "status $status"
exit $status
