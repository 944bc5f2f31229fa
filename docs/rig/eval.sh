#!/usr/bin/env bash
# Issue 15's LBS evaluation on the rig sample, as a script (not yet inside `desal eval`):
# gltfpack (npm, pinned in tests/gltf) simplifies data-samples/rig.glb with `-si 0.2`;
# desal simplifies the same rig to the welded vertex count gltfpack reached, one
# pipeline per method; `lbs_eval` poses every result and the full rig by LBS at
# held-out frames and prints the table in docs/rig/lbs-eval.md.
#
# Usage: bash docs/rig/eval.sh [OUT_DIR]   (needs node/npm; writes OUT_DIR, default /tmp/desal-rig-eval)
set -euo pipefail
cd "$(dirname "$0")/../.."
out=$(realpath -m "${1:-/tmp/desal-rig-eval}")
mkdir -p "$out"
(cd tests/gltf && npm ci --silent --no-audit --no-fund)
cargo build --release --locked -q --bin desal
cargo build --release --locked -q -p desal-rig --example lbs_eval
eval_bin=target/release/examples/lbs_eval
rig=$(realpath data-samples/rig.glb)

# gltfpack: 20 % of the triangles, no quantisation (so positions stay f32 for the reader).
gltfpack_version=$(node tests/gltf/node_modules/gltfpack/cli.js -v 2>&1 | head -1 || true)
node tests/gltf/node_modules/gltfpack/cli.js -i "$rig" -o "$out/gltfpack.glb" -si 0.2 -noq >/dev/null
target=$("$eval_bin" "$rig" --count "$out/gltfpack.glb")
echo "gltfpack ($gltfpack_version): $target welded vertices; desal targets the same count"

# Training frames: the animation every 0.5 s (21 frames: keyframes and midpoints).
# Held-out frames: every 0.5 s from 0.25 s (20 frames), never seen by saliency or refit.
methods=()
for spec in "qslim-subset:false:false:subset" "qslim-optimal:false:false:optimal" \
            "paper-subset:true:true:subset" "paper-optimal:true:true:optimal" \
            "saliency-subset:true:false:subset"; do
  IFS=: read -r name saliency balance placement <<<"$spec"
  cat >"$out/$name.toml" <<TOML
schema = 1
out = "$out/runs"
[[dataset]]
name = "$name"
up_axis = "y"
[dataset.rig]
file = "$rig"
poses = "animations"
frames = 21
[dataset.simplify]
target_vertices = $target
placement = "$placement"
saliency = $saliency
balance = $balance
TOML
  target/release/desal run "$out/$name.toml" --quiet
  node tests/gltf/validate.mjs "$out/runs/$name/simplified.glb" >/dev/null
  methods+=("$name=$out/runs/$name/simplified.glb")
done
echo "gltfpack version: $gltfpack_version"
"$eval_bin" "$rig" 0.5 0.25 20 "${methods[@]}" "gltfpack=$out/gltfpack.glb"
