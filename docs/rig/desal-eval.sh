#!/usr/bin/env bash
# Issue 15's LBS evaluation inside `desal eval` (docs/rig/desal-eval.md): the bundled rig
# (pipelines/rig-sample.toml, 21 animation frames, 5 folds over them) simplified by desal's
# methods, meshoptimizer and gltfpack (npm, pinned in tests/gltf) to the same 2676 welded
# vertices; every simplified rig skinned with its own weights (`--model rig`, the default
# for a rig dataset) and compared with the full rig's skinning at the held-out frames.
#
# Usage: bash docs/rig/desal-eval.sh [OUT_DIR]   (needs node/npm; default /tmp/desal-rig-harness)
set -euo pipefail
cd "$(dirname "$0")/../.."
out=$(realpath -m "${1:-/tmp/desal-rig-harness}")
(cd tests/gltf && npm ci --silent --no-audit --no-fund)
cargo build --release --locked -q --bin desal
export DESAL_GLTFPACK="$PWD/tests/gltf/node_modules/.bin/gltfpack"
target/release/desal eval pipelines/rig-sample.toml --out "$out" --quiet \
  --methods qslim,paper,desal,multipose,meshopt,meshopt-regularize,gltfpack,gltfpack-sa
echo "eval.md: $out/rig-sample/eval/eval.md"
