#!/usr/bin/env bash
# The saliency-weight floor measured by its effect on deformation error (docs/KNOBS.md):
# runs `desal eval` (paper-optimal, paper-subset, qslim-optimal; 5 folds) on the sample
# and, when ../shared/datasets/scape is present, on SCAPE, once per floor, and prints one
# Markdown table per dataset. About 1 min (sample) + 3 min (SCAPE) on 2 cores.
#
#   bash docs/knobs/floor-eval.sh [WORK_DIR]      (default: /tmp/desal-floor-eval)
set -euo pipefail
repo=$(cd "$(dirname "$0")/../.." && pwd)
work=${1:-/tmp/desal-floor-eval}
floors=(0.0 0.01 0.05 0.2 1.0)
cargo build --release --quiet --manifest-path "$repo/Cargo.toml" --bin desal
desal="$repo/target/release/desal"
datasets=(sample)
[ -d "$repo/../shared/datasets/scape" ] && datasets+=(scape)
mkdir -p "$work"
for name in "${datasets[@]}"; do
  for f in "${floors[@]}"; do
    pipeline="$work/$name-$f.toml"
    # The bundled pipeline, its paths made absolute, its output moved, the floor set.
    sed -e "s|^out = .*|out = \"$work/$name-$f\"|" \
        -e "s|\"\.\./|\"$repo/pipelines/../|g" "$repo/pipelines/$name.toml" > "$pipeline"
    printf '\n[dataset.saliency]\nfloor = %s\n' "$f" >> "$pipeline"
    "$desal" eval "$pipeline" --methods paper-optimal,paper-subset,qslim-optimal --quiet \
      --cache-dir "$work/cache" > /dev/null
  done
  python3 - "$work" "$name" "${floors[@]}" <<'PY'
import json, sys
work, name, floors = sys.argv[1], sys.argv[2], sys.argv[3:]
print(f"\n{name}: held-out = 5-fold; Δ = relative change of the mean vs qslim-optimal\n")
print("| floor | method | held-out v2v vs full GT (Δ) | held-out v2f vs full GT (Δ) "
      "| held-out v2v vs simplified GT (Δ) | in-sample v2v vs simplified GT (Δ) | head/hands/feet vertices |")
print("|---|---|---|---|---|---|---|")
for k, f in enumerate(floors):
    report = json.load(open(f"{work}/{name}-{f}/{name}/eval/eval.json"))
    for m in report["methods"]:
        if m["name"] == "qslim-optimal" and k > 0:
            continue  # no saliency: the same at every floor
        s, v = m["summary"], m["versus_baseline"]
        def cell(part, gt, fig):
            delta = f" ({v[part][gt][fig + '_percent']:+.1f} %)" if v else ""
            return f"{s[part][gt][fig]['mean']:.3e}{delta}"
        ext = next(r["vertices"] for r in m["regions"] if r["region"] == "head/hands/feet")
        label = "—" if m["name"] == "qslim-optimal" else f
        print(f"| {label} | {m['name']} | {cell('held_out', 'vs_full', 'v2v')} | {cell('held_out', 'vs_full', 'v2f')} "
              f"| {cell('held_out', 'vs_simplified', 'v2v')} | {cell('in_sample', 'vs_simplified', 'v2v')} | {ext} |")
PY
done
