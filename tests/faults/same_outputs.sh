#!/usr/bin/env bash
# Byte-identity of two desal binaries' outputs (a refactor must not change them):
#   tests/faults/same_outputs.sh OLD_DESAL NEW_DESAL
# Runs `desal run` on the sample, the sample hierarchy, the rig sample and SCAPE (../shared
# beside the checkout) and `desal eval` on the sample with each binary, then compares the
# SHA-256 of every .dsa, .ply, .png, .txt, .npz and .glb file they wrote, and every JSON
# file with its timing fields (keys ending in `seconds`, `timings` objects, timings quoted in notes) removed and the output folder's
# path replaced by OUT.
set -euo pipefail
cd "$(dirname "$0")/../.."
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
hashes() {
  local bin=$1 out=$2
  for pipeline in pipelines/sample.toml pipelines/sample-hierarchy.toml pipelines/rig-sample.toml; do
    "$bin" run "$pipeline" --out "$out" --quiet >/dev/null
  done
  if [ -d ../shared/datasets/scape ]; then "$bin" run pipelines/scape.toml --out "$out" --quiet >/dev/null; fi
  "$bin" eval pipelines/sample.toml --out "$out" --quiet >/dev/null
  (cd "$out" && find . -path ./.cache -prune -o -type f \( -name '*.dsa' -o -name '*.ply' -o -name '*.png' \
      -o -name '*.txt' -o -name '*.npz' -o -name '*.glb' \) -print | sort | xargs sha256sum)
  (cd "$out" && find . -path ./.cache -prune -o -type f -name '*.json' -print | sort | while read -r f; do
    python3 - "$f" "$out" <<'PY'
import json, re, sys
def strip(v):
    if isinstance(v, dict):
        return {k: strip(x) for k, x in v.items() if not k.endswith("seconds") and k != "timings"}
    if isinstance(v, list):
        return [strip(x) for x in v]
    if isinstance(v, str):
        # Notes quote their timings ("42.2 ms").
        return re.sub(r"\b[0-9]+(\.[0-9]+)? ?(ms|s)\b", "TIME", v.replace(sys.argv[2], "OUT"))
    return v
text = json.dumps(strip(json.load(open(sys.argv[1]))), sort_keys=True)
import hashlib
print(hashlib.sha256(text.encode()).hexdigest(), sys.argv[1], "(json, timings removed)")
PY
  done)
}
hashes "$1" "$work/old" > "$work/old.txt"
hashes "$2" "$work/new" > "$work/new.txt"
sed -i "s#$work/old#OUT#g" "$work/old.txt"
sed -i "s#$work/new#OUT#g" "$work/new.txt"
if diff "$work/old.txt" "$work/new.txt"; then
  echo "identical: $(wc -l < "$work/new.txt") files"
else
  echo "outputs differ" >&2
  exit 1
fi
