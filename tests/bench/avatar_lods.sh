#!/usr/bin/env bash
# Issue 42: a whole avatar of ~30k triangles (data-samples/avatar.glb: 27296 triangles in
# three meshes, 5 morph targets, textures), three LOD levels, in <= 1 s, beside gltfpack on
# the same file. desal: a cold `desal run pipelines/avatar-sample.toml` (no cache: ingest,
# stages 1-4, simplified.glb, the three levels, simplified-lods.glb and view.html); gltfpack:
# its three levels, one run each (`-si 0.5`, `0.25`, `0.1`, `-noq`), which is all it makes.
# Timed pair by pair by farm-bench (the tool library's), median of 10.
#
# Usage: tests/bench/avatar_lods.sh [DESAL] [GLTFPACK]
#   DESAL     default target/release/desal (cargo build --release --bin desal)
#   GLTFPACK  default tests/gltf/node_modules/.bin/gltfpack (cd tests/gltf && npm ci)
set -euo pipefail
cd "$(dirname "$0")/../.."
desal=$(realpath "${1:-target/release/desal}")
gltfpack=$(realpath "${2:-tests/gltf/node_modules/.bin/gltfpack}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
desal_run="rm -rf $work/cache $work/out && exec $desal run pipelines/avatar-sample.toml --cache-dir $work/cache --out $work/out --quiet"
levels=""
for r in 0.5 0.25 0.1; do
  levels="$levels $gltfpack -i data-samples/avatar.glb -o $work/gltfpack-$r.glb -si $r -noq >/dev/null &&"
done
farm-bench -n 10 --timeout 300 --vs "sh -c '${levels} true'" -- sh -c "$desal_run"
ls "$work/out/avatar-sample/"simplified-lod{1,2,3}.glb >/dev/null
