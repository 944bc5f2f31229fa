#!/usr/bin/env bash
# EVAL.md's held-out comparison with nothing of a test pose seen anywhere, on all 70
# poses. `desal eval` simplifies each method once, from stage 2's poses (all 71 on
# SCAPE), and holds out only the deformation model; blind-saliency.sh redid fold 0 alone.
# This runs the eval five times, run k with fold k's poses excluded from stage 2
# (`[dataset.saliency] exclude`, which multipose and desal-refit's model, residual,
# penalties and flips honour too), and takes each pose's figures from the run that was
# blind to it. Then every method against qslim-optimal, and desal-refit against every
# method, over the 70 poses, paired per pose (sign test, as docs/eval/versus.py).
#
# Methods: every one of `all` (qslim/saliency/paper x optimal/subset, desal, multipose,
# meshopt, meshopt-regularize, meshopt-priority) and desal-refit, MeshLab plain and with
# saliency when $DESAL_PYTHON (else python3) has pymeshlab, CGAL Lindstrom-Turk when the
# peers are set up ($PEERS_HOME, default /tmp/desal-peers) — as docs/eval/reproduce.sh.
# Minutes on 2 cores.
#
#   bash docs/eval/blind-all-folds.sh [WORK_DIR]   (default: /tmp/desal-blind-all)
set -euo pipefail
repo=$(cd "$(dirname "$0")/../.." && pwd)
work=${1:-/tmp/desal-blind-all}
peers=${PEERS_HOME:-/tmp/desal-peers}
scape="$repo/../shared/datasets/scape"
[ -d "$scape" ] || { echo "skipped: SCAPE is not at $scape (research-use data)"; exit 0; }
cargo build --release --quiet --manifest-path "$repo/Cargo.toml" --bin desal
mkdir -p "$work"
methods=all,desal-refit
. "$repo/docs/eval/peers.sh"
for k in 0 1 2 3 4; do
  python3 - "$repo" "$scape" "$work" "$k" <<'PY'
import glob, os, sys
repo, scape, work, k = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
names = [os.path.basename(f)[:-4] for f in sorted(glob.glob(f"{scape}/mesh*.ply"))]
# desal_measures::folds: the non-template poses (template = mesh000, index 0) dealt round-robin.
fold = [names[p] for p in range(1, len(names)) if (p - 1) % 5 == k]
text = open(f"{repo}/pipelines/scape.toml").read()
text = text.replace('out = "../out"', f'out = "{work}/fold{k}"').replace("../../shared/datasets/scape", scape)
text += "\n[dataset.saliency]\nexclude = [" + ", ".join(f'"{n}"' for n in fold) + "]\n"
open(f"{work}/scape-blind-{k}.toml", "w").write(text)
open(f"{work}/fold{k}.txt", "w").write("\n".join(fold))
PY
  "$repo/target/release/desal" eval "$work/scape-blind-$k.toml" --no-floor --quiet --methods "$methods" > /dev/null
done
python3 - "$work" <<'PY'
import json, math, sys
work = sys.argv[1]

def sign_test(wins, n):
    if n == 0:
        return 1.0
    k = min(wins, n - wins)
    return min(1.0, 2.0 * sum(math.comb(n, i) for i in range(k + 1)) / 2.0**n)

# figures[method][pose] = held-out record vs the full pose, from the run blind to the pose.
figures, order = {}, []
for k in range(5):
    fold = open(f"{work}/fold{k}.txt").read().split()
    report = json.load(open(f"{work}/fold{k}/scape/eval/eval.json"))
    for m in report["methods"]:
        if m["name"] not in figures:
            figures[m["name"]] = {}
            order.append(m["name"])
        for p in m["poses"]:
            if p["name"] in fold:
                figures[m["name"]][p["name"]] = p["held_out"]["vs_full"]
poses = sorted(figures["qslim-optimal"])
assert len(poses) == 70 and all(sorted(f) == poses for f in figures.values()), "every pose blind once"

def compare(a, b, key):
    x = [figures[a][p][key] for p in poses]
    y = [figures[b][p][key] for p in poses]
    won = sum(u < v for u, v in zip(x, y))
    differing = sum(u != v for u, v in zip(x, y))
    return f"{100 * (sum(x) / sum(y) - 1):+.1f} %, {won}, {sign_test(won, differing):.1g}"

print("# Output of `bash docs/eval/blind-all-folds.sh` (SCAPE, 2500 vertices, the default model: "
      "part-anchored SCAPE, 5 folds); do not edit by hand.\n")
print("Every figure is held out and blind: a pose's figures come from the run whose stage 2 "
      "(and so every pose-aware simplification) never read it. Δ is the mean over the 70 "
      "poses against the other method's; won counts the poses where the first is lower; p is "
      "the two-sided sign test.\n")
print("## Every method against qslim-optimal\n")
print("| method | mean v2f (m²) | mean v2v (m²) | v2f: Δ, won, p | v2v: Δ, won, p |")
print("|---|---|---|---|---|")
mean = lambda m, key: sum(figures[m][p][key] for p in poses) / len(poses)
for m in order:
    cells = ["—", "—"] if m == "qslim-optimal" else [compare(m, "qslim-optimal", k) for k in ("v2f", "v2v")]
    print(f"| {m} | {mean(m, 'v2f'):.4g} | {mean(m, 'v2v'):.4g} | {cells[0]} | {cells[1]} |")
print("\n## desal-refit against every method\n")
print("| against | v2f: Δ, won, p | v2v: Δ, won, p |")
print("|---|---|---|")
for m in order:
    if m != "desal-refit":
        print(f"| {m} | {compare('desal-refit', m, 'v2f')} | {compare('desal-refit', m, 'v2v')} |")
PY
