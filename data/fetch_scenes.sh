#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Downloads the standard ray-tracing benchmark scenes from their public homes into a folder
# (default: ./scenes), checks each archive's SHA-256, unpacks it, and converts the Stanford PLY
# scans to OBJ with assimp (Debian: assimp-utils). For users with internet access; the tests
# never need these.
#
# Checksums: data/scenes.sha256 pins each archive. This project's own machines have no internet,
# so an archive whose pin is still blank is verified on first download by recording its hash
# there (trust on first use) and strictly on every later download; --strict refuses blank pins.
#
# Usage: data/fetch_scenes.sh [--dest DIR] [--strict] [NAME ...]   (NAME: see --list)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
sums="$here/scenes.sha256"
dest=./scenes
strict=0

# name | URL | format
scenes=(
  "crytek-sponza|https://casual-effects.com/g3d/data10/common/model/crytek_sponza/sponza.zip|zip"
  "conference|https://casual-effects.com/g3d/data10/research/model/conference/conference.zip|zip"
  "sibenik|https://casual-effects.com/g3d/data10/research/model/sibenik/sibenik.zip|zip"
  "san-miguel|https://casual-effects.com/g3d/data10/research/model/San_Miguel/San_Miguel.zip|zip"
  "stanford-bunny|http://graphics.stanford.edu/pub/3Dscanrep/bunny.tar.gz|ply"
  "stanford-dragon|http://graphics.stanford.edu/pub/3Dscanrep/dragon/dragon_recon.tar.gz|ply"
  "stanford-buddha|http://graphics.stanford.edu/pub/3Dscanrep/happy/happy_recon.tar.gz|ply"
)

die() { echo "fetch_scenes.sh: $*" >&2; exit 1; }
names=()
while [ $# -gt 0 ]; do
    case "$1" in
        --dest) [ $# -ge 2 ] || die "--dest needs a folder"; dest=$2; shift 2 ;;
        --strict) strict=1; shift ;;
        --list) for s in "${scenes[@]}"; do echo "${s%%|*}"; done; exit 0 ;;
        -h|--help) sed -n '2,13p' "$0"; exit 0 ;;
        -*) die "unknown option '$1' (see --help)" ;;
        *) names+=("$1"); shift ;;
    esac
done
command -v curl >/dev/null || die "curl is needed (apt-get install curl)"
mkdir -p "$dest"
touch "$sums"

fetch_one() {
    local name=$1 url=$2 fmt=$3
    local file="$dest/$name.${url##*.}"
    [ "$fmt" = ply ] && file="$dest/$name.tar.gz"
    if [ ! -s "$file" ]; then
        echo "fetch_scenes.sh: downloading $name from $url"
        curl -fL --retry 3 -o "$file.part" "$url" || die "download of $name failed"
        mv "$file.part" "$file"
    fi
    local got pinned
    got=$(sha256sum "$file" | cut -d' ' -f1)
    pinned=$(awk -v n="$name" '$2 == n {print $1}' "$sums")
    if [ -z "$pinned" ]; then
        [ "$strict" -eq 1 ] && die "$name has no pinned checksum in $sums (--strict)"
        echo "$got $name" >>"$sums"
        echo "fetch_scenes.sh: $name: recorded sha256 $got (first download; pin it by committing $sums)"
    elif [ "$pinned" != "$got" ]; then
        die "$name: checksum mismatch: expected $pinned, got $got (delete $file to retry)"
    fi
    local out="$dest/$name"
    mkdir -p "$out"
    case "$fmt" in
        zip) command -v unzip >/dev/null || die "unzip is needed"; unzip -qo "$file" -d "$out" ;;
        ply)
            tar xzf "$file" -C "$out"
            command -v assimp >/dev/null || die "assimp is needed to turn PLY into OBJ (apt-get install assimp-utils)"
            # The full-resolution reconstruction is the largest PLY in the archive.
            local ply
            ply=$(find "$out" -name '*.ply' -printf '%s %p\n' | sort -n | tail -1 | cut -d' ' -f2-)
            assimp export "$ply" "$out/$name.obj" >/dev/null
            ;;
    esac
    echo "fetch_scenes.sh: $name ready in $out"
}

for s in "${scenes[@]}"; do
    IFS='|' read -r name url fmt <<<"$s"
    if [ ${#names[@]} -gt 0 ] && [[ ! " ${names[*]} " =~ " $name " ]]; then continue; fi
    fetch_one "$name" "$url" "$fmt"
done
