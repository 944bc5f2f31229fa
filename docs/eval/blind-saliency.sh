#!/usr/bin/env bash
# How much of EVAL.md's held-out gain comes from the simplification having seen the test
# poses? `desal eval` computes each method's simplification once, from the saliency (and,
# for multipose, the shapes) of all 71 poses; only the deformation model is held out. This
# re-runs the pose-aware methods with the poses of fold 0 excluded
# (`[dataset.saliency] exclude`, which multipose and desal-refit's residual and flips honour too), so for those 14 poses the
# whole chain is blind, and compares their held-out change vs qslim-optimal with the same
# poses in the regular run (docs/eval/reproduce.sh's output).
#
#   bash docs/eval/blind-saliency.sh [REGULAR_RUN_DIR] [WORK_DIR]
#   (defaults: /tmp/desal-eval-scape, /tmp/desal-blind-saliency; ~20 s after a regular run)
set -euo pipefail
repo=$(cd "$(dirname "$0")/../.." && pwd)
regular=${1:-/tmp/desal-eval-scape}
work=${2:-/tmp/desal-blind-saliency}
scape="$repo/../shared/datasets/scape"
[ -d "$scape" ] || { echo "skipped: SCAPE is not at $scape (research-use data)"; exit 0; }
[ -f "$regular/scape/eval/eval.json" ] || { echo "run docs/eval/reproduce.sh first" >&2; exit 1; }
cargo build --release --quiet --manifest-path "$repo/Cargo.toml" --bin desal
mkdir -p "$work"
python3 - "$repo" "$scape" "$work" <<'PY'
import glob, os, sys
repo, scape, work = sys.argv[1:]
names = [os.path.basename(f)[:-4] for f in sorted(glob.glob(f"{scape}/mesh*.ply"))]
# desal_measures::folds: the non-template poses (template = mesh000, index 0) dealt round-robin.
fold0 = [names[p] for p in range(1, len(names)) if (p - 1) % 5 == 0]
text = open(f"{repo}/pipelines/scape.toml").read()
text = text.replace('out = "../out"', f'out = "{work}/out"').replace("../../shared/datasets/scape", scape)
text += "\n[dataset.saliency]\nexclude = [" + ", ".join(f'"{n}"' for n in fold0) + "]\n"
open(f"{work}/scape-blind.toml", "w").write(text)
open(f"{work}/fold0.txt", "w").write("\n".join(fold0))
PY
"$repo/target/release/desal" eval "$work/scape-blind.toml" --quiet \
  --methods qslim-optimal,saliency-optimal,paper-optimal,saliency-subset,paper-subset,multipose,desal-refit > /dev/null
python3 - "$regular/scape/eval/eval.json" "$work/out/scape/eval/eval.json" "$work/fold0.txt" <<'PY'
import json, sys
regular, blind, fold0 = sys.argv[1], sys.argv[2], open(sys.argv[3]).read().split()
def table(path):
    return {m["name"]: {r["name"]: r for r in m["poses"]} for m in json.load(open(path))["methods"]}
a, b = table(regular), table(blind)
def change(t, name, gt, fig):
    q = [t["qslim-optimal"][p]["held_out"][gt][fig] for p in fold0]
    m = [t[name][p]["held_out"][gt][fig] for p in fold0]
    return f"{100 * (sum(m) / sum(q) - 1):+.1f} % ({sum(x < y for x, y in zip(m, q))}/{len(fold0)})"
print(f"Held-out change vs qslim-optimal on the {len(fold0)} poses of fold 0 (poses won):\n")
print("| method | figure | saliency of all poses | saliency blind to fold 0 |")
print("|---|---|---|---|")
for name in ["saliency-optimal", "paper-optimal", "saliency-subset", "paper-subset", "multipose", "desal-refit"]:
    for gt in ["vs_full", "vs_simplified"]:
        for fig in ["v2v", "v2f"]:
            print(f"| {name} | {fig} {gt.replace('_', ' ')} GT | {change(a, name, gt, fig)} | {change(b, name, gt, fig)} |")
PY
