#!/usr/bin/env bash
# Reproduces EVAL.md's SCAPE run and refreshes the copies in docs/eval/:
# every built-in method and desal-refit, MeshLab plain and with saliency (when $DESAL_PYTHON, else python3,
# has pymeshlab: pip install pymeshlab), CGAL Lindstrom-Turk as the paper's third baseline
# (when the peers are set up: PEERS_HOME=/tmp/desal-peers bash ../shared/peers/setup.sh),
# the methods tried for desal's own and not kept (multipose-saliency, multipose-paper,
# multipose-normalized), 5 folds, and the 1000..6000-vertex sweep of desal, desal-refit, qslim-optimal,
# paper-subset, multipose (and meshlab-saliency), under the deformation model $MODEL
# (default scape).
# Minutes on 2 cores.
#
#   [MODEL=scape|scape-centroid|lbs] bash docs/eval/reproduce.sh [OUT_DIR]   (default: /tmp/desal-eval-scape)
set -euo pipefail
repo=$(cd "$(dirname "$0")/../.." && pwd)
out=${1:-/tmp/desal-eval-scape}
peers=${PEERS_HOME:-/tmp/desal-peers}
scape="$repo/../shared/datasets/scape"
[ -d "$scape" ] || { echo "skipped: SCAPE is not at $scape (research-use data)"; exit 0; }
cargo build --release --quiet --manifest-path "$repo/Cargo.toml" --bin desal
mkdir -p "$out"
methods=all,desal-refit,multipose-saliency,multipose-paper,multipose-normalized
sweep_methods=desal,desal-refit,qslim-optimal,paper-subset,multipose
work=$out
. "$repo/docs/eval/peers.sh"
[ -z "$have_meshlab" ] || sweep_methods="$sweep_methods,meshlab-saliency"
model=${MODEL:-scape}
"$repo/target/release/desal" eval "$repo/pipelines/scape.toml" --out "$out" --methods "$methods" --model "$model" \
  --sweep --sweep-methods "$sweep_methods" --quiet
eval_dir="$out/scape/eval"
dest="$repo/docs/eval"
suffix=""; [ "$model" = scape ] || suffix="-$model"
cp "$eval_dir/eval.md" "$dest/scape-eval$suffix.md"
cp "$eval_dir/sweep.json" "$dest/scape-sweep$suffix.json"
for png in sweep.png deformation.png face-area/qslim-optimal.png face-area/paper-optimal.png face-area/desal.png face-area/desal-refit.png \
           errors/qslim-optimal-rms.png errors/paper-optimal-rms.png errors/paper-subset-rms.png errors/desal-rms.png; do
  cp "$eval_dir/$png" "$dest/$(echo "$png" | tr / - | sed "s/\.png$/$suffix.png/")"
done
echo "eval.md, eval.json and every figure: $eval_dir; copies in docs/eval/"
