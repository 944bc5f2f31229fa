#!/usr/bin/env bash
# Makes the figures of docs/rig/lods.md: the two-mesh avatar through `desal run` with a
# three-level LOD chain, then the Khronos validator and three.js (under node) on every
# written level. Needs `cargo build`, and `npm ci` plus three (as .ci/run installs it) in
# tests/gltf.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
python3 "$root/docs/rig/lods_avatar.py" "$root/data-samples/rig.glb" "$work/avatar.glb"
cat > "$work/lods.toml" <<'TOML'
schema = 1
out = "out"
[[dataset]]
name = "avatar"
up_axis = "y"
[dataset.rig]
file = "avatar.glb"
poses = "animations"
frames = 11
lods = [0.5, 0.25, 0.1]
[dataset.simplify]
target_vertices = 5352
placement = "subset"
TOML
"${DESAL:-$root/target/debug/desal}" run "$work/lods.toml" --quiet
folder="$work/out/avatar"
python3 - "$folder/simplified-rig.json" <<'PY'
import json, sys
figures = json.load(open(sys.argv[1]))
print("| level | target faces | faces | welded vertices | written vertices | cross-chart faces |")
print("|---|---|---|---|---|---|")
for l in figures["lods"]:
    print(f"| {l['level']} | {l['target_faces']} | {l['output_faces']} | {l['vertices']} | {l['output_vertices']} | {l['cross_chart_faces']} |")
PY
node "$root/tests/gltf/validate.mjs" "$folder"/simplified-lod[0-9]*.glb "$folder/simplified-lods.glb"
node "$root/tests/gltf/lods.mjs" "$folder"/simplified-lod[0-9]*.glb "$folder/simplified-lods.glb"
