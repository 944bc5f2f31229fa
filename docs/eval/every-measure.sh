#!/usr/bin/env bash
# Issue 43: every method under every measure, held out — the opening table of eval.md —
# on the bundled sample, the rig sample, the avatar sample and (when it is beside the
# checkout) SCAPE, with
# the method each `[simplify] objective` picks there. EVAL.md, "Every method under every
# measure", quotes these runs.
#
#   bash docs/eval/every-measure.sh        # writes out/every-measure/<dataset>/eval/eval.md
#
# Every dataset's eval.md also has the spikes (issue 42, item 7) of every method.
#
# gltfpack joins the rig sample's run when $DESAL_GLTFPACK or `gltfpack` is found (npm
# `gltfpack`, pinned in tests/gltf: `cd tests/gltf && npm ci`).
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo build --release --locked -p desal
desal=target/release/desal
out=out/every-measure
methods=qslim-optimal,paper-optimal,paper-subset,desal,desal-refit,desal-upsample,multipose,meshopt
"$desal" eval pipelines/sample.toml --methods "$methods" --out "$out" --pick --quiet
rig_methods=qslim-subset,paper-subset,desal,desal-upsample,multipose,meshopt-regularize
gltfpack=${DESAL_GLTFPACK:-$(command -v gltfpack || echo tests/gltf/node_modules/.bin/gltfpack)}
if [ -x "$gltfpack" ]; then
  rig_methods="$rig_methods,gltfpack,gltfpack-sa"
  export DESAL_GLTFPACK="$gltfpack"
fi
"$desal" eval pipelines/rig-sample.toml --methods "$rig_methods" --out "$out" --pick --quiet
"$desal" eval pipelines/avatar-sample.toml --methods "$rig_methods" --out "$out" --pick --quiet
if [ -d ../shared/datasets/scape ]; then
  "$desal" eval pipelines/scape.toml --methods "$methods" --out "$out" --pick --quiet
fi
