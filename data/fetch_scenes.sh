#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Fetches the scenes bvhlab's tables were measured on into a folder (default ./scenes) and
# writes its scenes.json (cameras, AO lengths, the ray protocol), so that
# `BVHLAB_SCENES=./scenes bvhlab run` and the documented commands reproduce the tables.
#
# The benchmark scenes are rebuilt byte for byte and checked against the SHA-256 of the files
# the tables used (a mismatch is an error that names the scene):
#   cornell-box     Embree's sample, from Debian's embree-tools package (apt-get download)
#   furball         Embree's furBall_A hair model from the same package, every segment made a
#                   thin 3-sided prism (data/make_benchmark_scenes.py furball)
#   sibenik         the Sibenik cathedral's geometry, from taqu/BoundingVolumeHierarchy's sibenik.zip
#                   (data/make_benchmark_scenes.py sibenik)
#   stanford-bunny  the full-resolution bunny as alecjacobson/common-3d-test-models has it
#   dragon-100k     the Stanford dragon decimated to 100k triangles, from The Ray Tracer
#                   Challenge's bonus assets (its header cites mrbluesummers.com)
#   buddha-100k     has no public source this script knows: taken from --from DIR/buddha.obj
#                   (checked like the others), else skipped with a note
# The classic architectural scenes (crytek-sponza, conference, sibenik-full, san-miguel from
# McGuire's archive) are fetched as archives whose checksum is pinned in data/scenes.sha256 on
# first download (trust on first use); --strict refuses unpinned ones.
#
# Usage: data/fetch_scenes.sh [--dest DIR] [--from DIR] [--strict] [NAME ...]   (--list: the names)
#   --from DIR: look for the downloads (embree-tools_*.deb, sibenik.zip, stanford-bunny.obj,
#   dragon.zip, buddha.obj, ...) in DIR before the network, for machines without internet.
# Needs curl, python3 with numpy (tools/install_deps.sh), unzip, and dpkg/apt-get on Debian.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
sums="$here/scenes.sha256"
dest=./scenes
from=
strict=0

# name | what to fetch | SHA-256 of the scene's OBJ as the tables used it
benchmark=(
  "cornell-box|deb:embree-tools|1df799353b985e1862a590c6c37814227990e0338220e2e9a575fcd54031a667"
  "furball|deb:embree-tools|7c7d5a81cc748a7f24b98d48af49a930113d1d1f14643b264505e61cf95bc9ec"
  "sibenik|https://github.com/taqu/BoundingVolumeHierarchy/raw/a1b3c4acb57c9276ed36dc945766d4f3ef28d5a2/sibenik.zip|03658967cdfa370d0856aa9ada4e5223db547212aff56089d73b0a4348515e17"
  "stanford-bunny|https://raw.githubusercontent.com/alecjacobson/common-3d-test-models/29339feae9a77dbd839d0a83f8349c2e7f978c8f/data/stanford-bunny.obj|1eb35d1e21ce99e5ce911353b6be278990713448dd9e8f5c9387f9de39b32205"
  "dragon-100k|http://raytracerchallenge.com/bonus/assets/dragon.zip|cab43170b1a682b21817805bd02ee96e4e958efc68d1716f0d82b4c7a255e3fb"
  "buddha-100k|none|1b2479c77154f90c31281cb69ff1963dcd2ceb52d9803555eb70a2a1a09111de"
)
# name | URL | format (archives pinned on first download)
classic=(
  "crytek-sponza|https://casual-effects.com/g3d/data10/common/model/crytek_sponza/sponza.zip|zip"
  "conference|https://casual-effects.com/g3d/data10/research/model/conference/conference.zip|zip"
  "sibenik-full|https://casual-effects.com/g3d/data10/research/model/sibenik/sibenik.zip|zip"
  "san-miguel|https://casual-effects.com/g3d/data10/research/model/San_Miguel/San_Miguel.zip|zip"
)

die() { echo "fetch_scenes.sh: $*" >&2; exit 1; }
names=()
while [ $# -gt 0 ]; do
    case "$1" in
        --dest) [ $# -ge 2 ] || die "--dest needs a folder"; dest=$2; shift 2 ;;
        --from) [ $# -ge 2 ] && [ -d "$2" ] || die "--from needs an existing folder"; from=$(cd "$2" && pwd); shift 2 ;;
        --strict) strict=1; shift ;;
        --list) for s in "${benchmark[@]}" "${classic[@]}"; do echo "${s%%|*}"; done; exit 0 ;;
        -h|--help) sed -n '2,26p' "$0"; exit 0 ;;
        -*) die "unknown option '$1' (see --help)" ;;
        *) names+=("$1"); shift ;;
    esac
done
known=" $(for s in "${benchmark[@]}" "${classic[@]}"; do printf '%s ' "${s%%|*}"; done)"
for n in "${names[@]}"; do [[ "$known" == *" $n "* ]] || die "unknown scene '$n' (known:$known)"; done
wanted() { [ ${#names[@]} -eq 0 ] || [[ " ${names[*]} " == *" $1 "* ]]; }
py=/usr/bin/python3
[ -x "$py" ] || py=python3
command -v unzip >/dev/null || die "unzip is needed (apt-get install unzip; tools/install_deps.sh installs it)"
mkdir -p "$dest"
dest=$(cd "$dest" && pwd)
work="$dest/.downloads"
mkdir -p "$work"
touch "$sums"

# download URL FILE: from --from when it holds FILE's name, else with curl.
download() {
    local url=$1 file=$2
    [ -s "$file" ] && return 0
    if [ -n "$from" ] && [ -s "$from/$(basename "$file")" ]; then cp "$from/$(basename "$file")" "$file"; return 0; fi
    command -v curl >/dev/null || die "curl is needed to download $url (apt-get install curl), or give --from DIR"
    echo "fetch_scenes.sh: downloading $url"
    curl -fL --retry 3 -o "$file.part" "$url" || die "download of $url failed"
    mv "$file.part" "$file"
}

# check NAME FILE SHA: the scene's OBJ must be the one the tables used.
check() {
    local got
    got=$(sha256sum "$2" | cut -d' ' -f1)
    [ "$got" = "$3" ] || die "$1: $2 has SHA-256 $got, not $3 (the file bvhlab's tables used); the source changed"
}

embree_tools() {  # unpacks Debian's embree-tools once; prints the models folder
    local deb
    deb=$(ls "$work"/embree-tools_*.deb "${from:-/nonexistent}"/embree-tools_*.deb 2>/dev/null | head -1 || true)
    if [ -z "$deb" ]; then
        (cd "$work" && apt-get download embree-tools >/dev/null) || die "cannot download Debian's embree-tools package (apt-get download embree-tools)"
        deb=$(ls "$work"/embree-tools_*.deb | head -1)
    fi
    [ -d "$work/embree-tools" ] || dpkg -x "$deb" "$work/embree-tools"
    echo "$work/embree-tools/usr/share/doc/embree3/models"
}

fetched=()
for s in "${benchmark[@]}"; do
    IFS='|' read -r name src sha <<<"$s"
    wanted "$name" || continue
    out="$dest/$name"
    mkdir -p "$out"
    case "$name" in
        cornell-box)
            m=$(embree_tools)
            cp "$m/cornell_box.obj" "$m/cornell_box.mtl" "$out/"
            check "$name" "$out/cornell_box.obj" "$sha" ;;
        furball)
            m=$(embree_tools)
            "$py" "$here/make_benchmark_scenes.py" furball "$m/furBall_A.bin.gz" "$out/furball.obj.part"
            mv "$out/furball.obj.part" "$out/furball.obj"
            check "$name" "$out/furball.obj" "$sha" ;;
        sibenik)
            download "$src" "$work/sibenik.zip"
            unzip -qo "$work/sibenik.zip" -d "$work/sibenik-zip"
            "$py" "$here/make_benchmark_scenes.py" sibenik "$work/sibenik-zip/sibenik/sibenik.bin" "$out/sibenik.obj"
            check "$name" "$out/sibenik.obj" "$sha" ;;
        stanford-bunny)
            download "$src" "$work/stanford-bunny.obj"
            cp "$work/stanford-bunny.obj" "$out/"
            check "$name" "$out/stanford-bunny.obj" "$sha" ;;
        dragon-100k)
            download "$src" "$work/dragon.zip"
            unzip -qo "$work/dragon.zip" -d "$work/dragon-zip"
            obj=$(find "$work/dragon-zip" -name 'dragon.obj' | head -1)
            [ -n "$obj" ] || die "dragon-100k: dragon.zip holds no dragon.obj"
            cp "$obj" "$out/dragon.obj"
            check "$name" "$out/dragon.obj" "$sha" ;;
        buddha-100k)
            if [ -z "$from" ] || [ ! -f "$from/buddha.obj" ]; then
                echo "fetch_scenes.sh: buddha-100k skipped: the decimated Happy Buddha the tables used has no public" \
                    "source this script knows (SHA-256 $sha); with a copy, give its folder as --from DIR (DIR/buddha.obj);" \
                    "the full scan is at http://graphics.stanford.edu/pub/3Dscanrep/happy/"
                rmdir "$out" 2>/dev/null || true
                continue
            fi
            cp "$from/buddha.obj" "$out/buddha.obj"
            check "$name" "$out/buddha.obj" "$sha" ;;
    esac
    fetched+=("$name")
    echo "fetch_scenes.sh: $name ready in $out (SHA-256 as in the tables)"
done

for s in "${classic[@]}"; do
    IFS='|' read -r name url fmt <<<"$s"
    [ ${#names[@]} -gt 0 ] && wanted "$name" || continue  # only when asked for by name
    file="$work/$name.zip"
    download "$url" "$file"
    got=$(sha256sum "$file" | cut -d' ' -f1)
    pinned=$(awk -v n="$name" '$2 == n {print $1}' "$sums")
    if [ -z "$pinned" ]; then
        [ "$strict" -eq 1 ] && die "$name has no pinned checksum in $sums (--strict)"
        echo "$got $name" >>"$sums"
        echo "fetch_scenes.sh: $name: recorded sha256 $got (first download; pin it by committing $sums)"
    elif [ "$pinned" != "$got" ]; then
        die "$name: checksum mismatch: expected $pinned, got $got (delete $file to retry)"
    fi
    command -v unzip >/dev/null || die "unzip is needed"
    unzip -qo "$file" -d "$dest/$name"
    echo "fetch_scenes.sh: $name ready in $dest/$name (no catalogue entry: give bvhlab its OBJ file)"
done

if [ ${#fetched[@]} -gt 0 ]; then
    # Keep the entries of scenes fetched earlier into the same folder.
    for s in "${benchmark[@]}"; do
        n=${s%%|*}
        [[ " ${fetched[*]} " == *" $n "* ]] && continue
        [ -d "$dest/$n" ] && [ -n "$(ls "$dest/$n" 2>/dev/null)" ] && fetched+=("$n")
    done
    "$py" "$here/make_benchmark_scenes.py" catalogue "$here/benchmark_scenes.json" "$dest" "${fetched[@]}"
    echo "fetch_scenes.sh: wrote $dest/scenes.json (${fetched[*]}); use it with: export BVHLAB_SCENES=$dest"
fi
