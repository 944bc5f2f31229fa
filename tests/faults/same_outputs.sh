#!/usr/bin/env bash
# Byte-identity of two desal binaries' outputs (a refactor must not change them):
#   tests/faults/same_outputs.sh OLD_DESAL NEW_DESAL
# Runs `desal run` on the sample and on SCAPE (../shared beside the checkout) and
# `desal eval` on the sample with each binary, then compares the SHA-256 of every .dsa,
# .ply, .png and .txt file they wrote (JSON files carry timings and are not compared).
set -euo pipefail
cd "$(dirname "$0")/../.."
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
hashes() {
  local bin=$1 out=$2
  "$bin" run pipelines/sample.toml --out "$out" --quiet >/dev/null
  if [ -d ../shared/datasets/scape ]; then "$bin" run pipelines/scape.toml --out "$out" --quiet >/dev/null; fi
  "$bin" eval pipelines/sample.toml --out "$out" --quiet >/dev/null
  (cd "$out" && find . -path ./.cache -prune -o -type f \( -name '*.dsa' -o -name '*.ply' -o -name '*.png' -o -name '*.txt' \) -print \
    | sort | xargs sha256sum)
}
hashes "$1" "$work/old" > "$work/old.txt"
hashes "$2" "$work/new" > "$work/new.txt"
if diff "$work/old.txt" "$work/new.txt"; then
  echo "identical: $(wc -l < "$work/new.txt") files"
else
  echo "outputs differ" >&2
  exit 1
fi
