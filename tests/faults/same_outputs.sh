#!/usr/bin/env bash
# Byte-identity of two builds' outputs (a refactor must not change them; issue 40):
#
#   tests/faults/same_outputs.sh OLD_DESAL NEW_DESAL [OLD_PY NEW_PY]
#
# OLD_DESAL, NEW_DESAL: two `desal` binaries. OLD_PY, NEW_PY (or the environment variables
# of those names): two Python interpreters (venvs) with the `desal` package installed; without
# them the Python package is not compared (said on stderr).
#
# With each build, in turn, in the same folder (so paths written into files are the same):
# - `desal run` on every bundled pipeline (sample, sample-hierarchy, sample-desal-refit,
#   batch-sample, rig-sample) and, with ../shared/datasets/scape beside the checkout, on scape
#   and scape-hierarchy; each pipeline into its own --out, with its own cache;
# - `desal eval` with the default methods on the sample, the rig sample and SCAPE (the
#   SCAPE eval takes minutes: SAME_OUTPUTS_SCAPE_EVAL=0 leaves it out), and once on the
#   sample with other options (--sweep, --save-deformed, --model lbs, --folds 3, ...);
# - the single-stage subcommands (`desal parts|fit|saliency|simplify|map|hierarchy|inspect`)
#   on the sample's artifacts, and `desal map --glb` on the rig sample's;
# - tests/faults/python_outputs.py with each interpreter: every result of the package's
#   public API on the samples, as files;
# then compares the SHA-256 of every file written, except `view.html`, `viewer/` and the
# caches (`.cache/`). JSON files are compared with their timing fields (keys ending in
# `seconds`, `timings` objects, timings quoted in strings: "42.2 ms") removed, and eval.md
# with its timings (quoted in prose, and the table columns headed "(s)" or "(ms/...)") removed.
# SAME_OUTPUTS_SCAPE=0 leaves SCAPE out altogether. SAME_OUTPUTS_KEEP=DIR keeps both output
# folders in DIR/old and DIR/new (to look at a difference). A command that fails stops the
# script, naming the command.
set -euo pipefail
cd "$(dirname "$0")/../.."
root=$PWD
usage() { echo "usage: $0 OLD_DESAL NEW_DESAL [OLD_PY NEW_PY]" >&2; exit 2; }
[ $# -eq 2 ] || [ $# -eq 4 ] || usage
old_desal=$(realpath "$1")
new_desal=$(realpath "$2")
old_py=${3:-${OLD_PY:-}}
new_py=${4:-${NEW_PY:-}}
if { [ -n "$old_py" ] && [ -z "$new_py" ]; } || { [ -z "$old_py" ] && [ -n "$new_py" ]; }; then usage; fi
for py in "$old_py" "$new_py"; do
  if [ -n "$py" ]; then "$py" -c 'import desal, numpy, scipy' || { echo "$py: no desal, numpy or scipy" >&2; exit 2; }; fi
done
[ -n "$old_py" ] || echo "note: no OLD_PY/NEW_PY given: the Python package is not compared" >&2
scape=${SAME_OUTPUTS_SCAPE:-1}
if [ "$scape" != 0 ] && [ ! -d ../shared/datasets/scape ]; then
  echo "note: ../shared/datasets/scape is missing: SCAPE is not compared" >&2
  scape=0
fi
scape_eval=${SAME_OUTPUTS_SCAPE_EVAL:-1}
[ "$scape" != 0 ] || scape_eval=0
[ "$scape_eval" != 0 ] || echo "note: desal eval on SCAPE is left out" >&2

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
out=$work/out

step() {
  if ! "$@" >"$work/step.log" 2>&1; then
    cat "$work/step.log" >&2
    echo "failed: $*" >&2
    exit 1
  fi
}

cli_outputs() {
  local bin=$1
  local p
  for p in sample sample-hierarchy sample-desal-refit batch-sample rig-sample; do
    step "$bin" run "pipelines/$p.toml" --out "$out/run/$p" --quiet
  done
  if [ "$scape" != 0 ]; then
    for p in scape scape-hierarchy; do step "$bin" run "pipelines/$p.toml" --out "$out/run/$p" --quiet; done
  fi
  # One stage at a time, on the sample run's artifacts.
  local s=$out/run/sample/sample t=$out/stages r=$out/run/rig-sample/rig-sample
  mkdir -p "$t"
  step "$bin" parts --poses "$s/poses.dsa" --parts 16 -o "$t/parts16.dsa" --txt "$t/parts16.txt" --png "$t/parts16.png" --up-axis y
  step "$bin" parts --poses "$s/poses.dsa" -o "$t/parts.dsa" --txt "$t/parts.txt"
  step "$bin" fit --poses "$s/poses.dsa" --labels "$s/labels.dsa" -o "$t/fit.dsa"
  step "$bin" fit --poses "$s/poses.dsa" --labels "$s/labels.dsa" -o "$t/fit-affine.dsa" --method affine
  step "$bin" saliency --poses "$s/poses.dsa" --fit "$t/fit.dsa" -o "$t/saliency.dsa" --png "$t/saliency.png" \
    --ply "$t/saliency.ply" --up-axis y
  step "$bin" saliency --poses "$s/poses.dsa" --fit "$t/fit-affine.dsa" -o "$t/saliency-options.dsa" --squared \
    --percentile 95 --exclude 03_elbows_bent --exclude 06_lunge --floor 0.1 --png "$t/saliency-options.png"
  step "$bin" simplify --input "$t/saliency.ply" --output "$t/simplify-paper.ply" --target-vertices 2500 \
    --saliency "$t/saliency.dsa" --balance
  step "$bin" simplify --input "$t/saliency.ply" --output "$t/simplify-subset.ply" --target-vertices 800 --placement subset
  step "$bin" simplify --input data-samples/poses/00_rest.ply --output "$t/simplify-lt.ply" --ratio 0.1 \
    --metric lindstrom-turk --boundary-weight 5
  step "$bin" simplify --input data-samples/poses/00_rest.ply --output "$t/simplify-faces.ply" --target-faces 3000 \
    --saliency "$t/saliency.ply" --floor 0.2
  step "$bin" map --poses "$s/poses.dsa" --labels "$s/labels.dsa" --simplified "$s/simplified.dsa" -o "$t/map.dsa" \
    --out-dir "$t/map"
  step "$bin" map --poses "$s/poses.dsa" --labels "$s/labels.dsa" --simplified "$t/simplify-paper.ply" \
    -o "$t/map-ply.dsa" --out-dir "$t/map-ply"
  step "$bin" hierarchy --poses "$s/poses.dsa" --labels "$s/labels.dsa" --levels 2500,625 -o "$t/hierarchy.npz" \
    --json "$t/hierarchy.json"
  step "$bin" hierarchy --poses "$s/poses.dsa" --labels "$s/labels.dsa" --levels 3000,1000,300 --upsampler barycentric \
    --balance -o "$t/hierarchy-barycentric.npz" --json "$t/hierarchy-barycentric.json"
  step "$bin" map --poses "$r/poses.dsa" --labels "$r/labels.dsa" --simplified "$r/simplified.dsa" -o "$t/rig-map.dsa" \
    --glb "$t/rig.glb" --rig data-samples/rig.glb
  # The eval after the run, in its folder, as a user runs it (it reuses the run's cache).
  step "$bin" eval pipelines/sample.toml --out "$out/run/sample" --quiet
  step "$bin" eval pipelines/rig-sample.toml --out "$out/run/rig-sample" --quiet
  if [ "$scape_eval" != 0 ]; then step "$bin" eval pipelines/scape.toml --out "$out/run/scape" --quiet; fi
  step "$bin" eval pipelines/sample.toml --out "$out/eval-options" --quiet --methods desal-refit,paper,multipose,desal \
    --model lbs --folds 3 --target-vertices 2000 --save-deformed --sweep --sweep-vertices 1000,3000 \
    --figure-poses 02_arms_up,06_lunge
  step "$bin" eval pipelines/sample.toml --out "$out/eval-centroid" --quiet --methods qslim,paper-subset \
    --model scape-centroid --baseline paper-subset --no-floor

  local dsa
  mapfile -t dsa < <(find "$s" "$r" "$t" -name .cache -prune -o -name '*.dsa' -print | LC_ALL=C sort)
  step "$bin" inspect "${dsa[@]}"
  sed "s#$out#OUT#g" "$work/step.log" >"$t/inspect.txt"
}

# One line per file: the SHA-256 and the path under $out.
hashes() {
  python3 - "$out" <<'PY'
import hashlib, json, os, re, sys

out = sys.argv[1]

TIME = re.compile(r"\b[0-9]+(\.[0-9]+)? ?(ms|s)\b")
# A Markdown table column of timings: "rigid fit (s)", "synthesis (ms/pose)".
TIME_COLUMN = re.compile(r"\((ms|s)(/[^)]*)?\)|seconds")


def markdown(text):
    """eval.md with its timings (quoted in prose, and timing columns of tables) removed."""
    lines, columns = [], None
    for line in text.replace(out, "OUT").split("\n"):
        if line.startswith("|"):
            cells = line.split("|")
            if columns is None:
                columns = {k for k, c in enumerate(cells) if TIME_COLUMN.search(c)}
            elif not all(set(c.strip()) <= set("-:") for c in cells):
                cells = ["TIME" if k in columns else c for k, c in enumerate(cells)]
            line = "|".join(cells)
        else:
            columns = None
        lines.append(TIME.sub("TIME", line))
    return "\n".join(lines)


def strip(v):
    if isinstance(v, dict):
        return {k: strip(x) for k, x in v.items() if not k.endswith("seconds") and k != "timings"}
    if isinstance(v, list):
        return [strip(x) for x in v]
    if isinstance(v, str):
        # Notes quote their timings ("42.2 ms").
        return TIME.sub("TIME", v.replace(out, "OUT"))
    return v

files = []
for folder, dirs, names in os.walk(out):
    dirs[:] = [d for d in dirs if d not in (".cache", "viewer")]
    files += [os.path.join(folder, n) for n in names if n != "view.html"]
for path in sorted(files):
    rel = os.path.relpath(path, out)
    if os.path.islink(path) or not os.path.isfile(path):
        print("not-a-regular-file", rel)
    elif path.endswith(".json"):
        text = json.dumps(strip(json.load(open(path))), sort_keys=True)
        print(hashlib.sha256(text.encode()).hexdigest(), rel, "(json, timings removed)")
    elif path.endswith(".md"):
        text = markdown(open(path, encoding="utf-8").read())
        print(hashlib.sha256(text.encode()).hexdigest(), rel, "(markdown, timings removed)")
    else:
        print(hashlib.sha256(open(path, "rb").read()).hexdigest(), rel)
PY
}

# Runs everything with one build in $out, hashes it into $work/$side.txt, moves $out away.
outputs() {
  local side=$1 bin=$2 py=$3
  local start=$SECONDS
  mkdir "$out"
  cli_outputs "$bin"
  if [ -n "$py" ]; then step "$py" tests/faults/python_outputs.py "$out/python"; fi
  hashes >"$work/$side.txt"
  mv "$out" "$work/$side"
  echo "$side: $(wc -l <"$work/$side.txt") files in $((SECONDS - start)) s" >&2
}

outputs old "$old_desal" "$old_py"
outputs new "$new_desal" "$new_py"
if [ -n "${SAME_OUTPUTS_KEEP:-}" ]; then
  mkdir -p "$SAME_OUTPUTS_KEEP"
  rm -rf "$SAME_OUTPUTS_KEEP/old" "$SAME_OUTPUTS_KEEP/new"
  mv "$work/old" "$work/new" "$work/old.txt" "$work/new.txt" "$SAME_OUTPUTS_KEEP/"
  work_txt=$SAME_OUTPUTS_KEEP
else
  work_txt=$work
fi
if diff "$work_txt/old.txt" "$work_txt/new.txt"; then
  echo "identical: $(wc -l <"$work_txt/new.txt") files"
else
  echo "outputs differ" >&2
  exit 1
fi
