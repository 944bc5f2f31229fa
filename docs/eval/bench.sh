#!/usr/bin/env bash
# Benchmark of `desal eval` on SCAPE (issue 17): the warm evaluation — the pipeline's
# stages already cached — run RUNS times (default 2), with the wall seconds of each phase
# taken from eval's own log lines and eval.json, and the process's wall, user and system
# seconds (on a shared machine user + sys is the steadier figure).
#
#   docs/eval/bench.sh                          # target/release/desal, --methods all
#   METHODS=all,meshlab,meshlab-saliency DESAL_PYTHON=.venv-ci/bin/python docs/eval/bench.sh
#   DESAL=/tmp/desal-before docs/eval/bench.sh  # another build, same cache
#
# Environment: DESAL (binary), PIPELINE (default pipelines/scape.toml), OUT (output root,
# default /tmp/desal-eval-bench; its .cache keeps the stages warm), METHODS, RUNS.
set -euo pipefail
cd "$(dirname "$0")/../.."
DESAL=${DESAL:-target/release/desal}
PIPELINE=${PIPELINE:-pipelines/scape.toml}
OUT=${OUT:-/tmp/desal-eval-bench}
METHODS=${METHODS:-all}
RUNS=${RUNS:-2}
LOG=$(mktemp)
trap 'rm -f "$LOG"' EXIT

# The stages once, so every timed run below finds them cached.
"$DESAL" run "$PIPELINE" --out "$OUT" >/dev/null 2>&1

for run in $(seq 1 "$RUNS"); do
  TIMEFORMAT="%R %U %S"
  { time "$DESAL" eval "$PIPELINE" --out "$OUT" --methods "$METHODS" >/dev/null 2>"$LOG"; } 2>"$LOG.time"
  python3 - "$LOG" "$LOG.time" "$OUT" "$run" <<'PY'
import glob, json, re, sys
log, timing, out, run = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4]
wall, user, system = map(float, open(timing).read().split()[-3:])
report = json.load(open(glob.glob(f"{out}/*/eval/eval.json")[0]))
seconds = lambda pattern: sum(float(m) for m in re.findall(pattern, open(log).read()))
t = [m["timings"] for m in report["methods"]]
phases = [
    ("simplify + map (all methods)", sum(x["simplify"] + x["map"] + x["apply_map"] for x in t)),
    ("rigid fit + models + synthesis", sum(x["rotations"] + x["model_fit_total"] + x["synthesis_total"] for x in t)),
    ("upsampling error (all methods)", seconds(r"upsampled to full resolution.*\(([0-9.]+) s\)")),
    ("model floor", seconds(r"the model at full resolution.*\(([0-9.]+) s\)")),
    ("measure v2f/v2v", report["measure_seconds"]),
]
phases.append(("figures, reports, rest", report["total_seconds"] - sum(s for _, s in phases)))
phases.append(("stage cache, loading", wall - report["total_seconds"]))
print(f"run {run}: {len(report['methods'])} methods, wall {wall:.1f} s, user {user:.1f} s, sys {system:.1f} s")
for name, s in phases:
    print(f"  {name:34} {s:8.2f} s")
PY
  rm -f "$LOG.time"
done
