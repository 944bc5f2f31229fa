#!/usr/bin/env bash
# Issue 41, item 4: a model source of 64 shapes x 32 poses (2048 samples) of the CC0
# SMPL-layout fixture (13380 vertices), with the two-level hierarchy, timed and its peak
# RSS measured. Target on the 2-core VM: <= 60 s and <= 1 GB.
#
# Usage: tests/bench/model_2048.sh [DESAL] [WORK_DIR]
#   DESAL     the desal binary (default target/release/desal; build it with
#             `cargo build --release --bin desal`)
#   WORK_DIR  where the fixture, the pipeline and the output go (default target/bench-model)
set -euo pipefail
desal=${1:-target/release/desal}
work=${2:-target/bench-model}
mkdir -p "$work"
if [ ! -f "$work/models/model.npz" ]; then
  cargo run --release --locked -p desal-sample --example make_smpl_fixture -- "$work/models" >/dev/null
fi
cat >"$work/model-2048.toml" <<'TOML'
schema = 1
out = "out"
[[dataset]]
name = "model"
[dataset.model]
file = "models/model.npz"
shapes = 64
poses = 32
seed = 0
[dataset.simplify]
placement = "subset"
[dataset.hierarchy]
levels = [2500, 625]
TOML
rm -rf "$work/out"
/usr/bin/time -f "wall %e s, cpu %U+%S s, peak RSS %M KiB" \
  "$desal" run "$work/model-2048.toml" --cache-dir "$work/cache-$$" 2>&1 | grep -E "ran|wall"
rm -rf "$work/cache-$$"
