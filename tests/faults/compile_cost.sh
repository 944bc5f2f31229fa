#!/usr/bin/env bash
# Compile cost of a checkout's commit, from a fresh clone (issue 40, "Done when"):
#
#   tests/faults/compile_cost.sh CHECKOUT_DIR OUT_DIR
#
# Clones CHECKOUT_DIR's HEAD commit (`git clone --no-hardlinks`; uncommitted changes are not
# measured) into a temporary folder with ../shared beside it (a symlink to CHECKOUT_DIR/../shared
# when that exists, as in development; no build needs it: build.rs only sets a cfg for the tests)
# and DESAL_REQUIRE_SHARED_DATA unset, then measures, each with an empty CARGO_TARGET_DIR:
#  (a) the README's main job cold: `cargo run --release --timings -- run pipelines/sample.toml`
#      (the compile `cargo build --release --bin desal` does, plus the run, which takes under
#      a second), then `cargo build --release --timings` after it (the other binaries, warm);
#  (b) the Python package: `pip install ./crates/python` into a fresh venv (numpy installed
#      first, not measured), with MATURIN_PEP517_ARGS=--timings; the size of the installed
#      `_desal*.so` (and stripped) and of the wheel maturin leaves in CARGO_TARGET_DIR/wheels.
# Wall and CPU seconds (user + sys of everything the command ran) come from /usr/bin/time -v;
# per-crate CPU-seconds from rustc_cpu.sh, a RUSTC_WRAPPER that times every rustc (the caller's
# RUSTC_WRAPPER, e.g. sccache, is not used: the build must be cold); per-crate wall seconds from
# cargo's timing report (the UNIT_DATA of cargo-timing.html: each unit's wall duration, which a
# loaded machine inflates; CPU-seconds are the figures to compare). The load average is
# sampled every 15 s throughout.
# Writes OUT_DIR/compile_cost.md (the report), the timing HTML files, /usr/bin/time's
# outputs and the build logs. COMPILE_COST_KEEP=1 keeps the temporary folder (printed);
# COMPILE_COST_COMMIT=REV measures that commit of CHECKOUT_DIR's repository instead of HEAD.
set -euo pipefail
[ $# -eq 2 ] || { echo "usage: $0 CHECKOUT_DIR OUT_DIR" >&2; exit 2; }
checkout=$(cd "$1" && pwd)
mkdir -p "$2"
outdir=$(cd "$2" && pwd)
rm -f "$outdir"/*.rustc-cpu  # appended to by rustc_cpu.sh
here=$(cd "$(dirname "$0")" && pwd)
commit=$(git -C "$checkout" rev-parse "${COMPILE_COST_COMMIT:-HEAD}^{commit}")
tmp=$(mktemp -d /tmp/compile-cost.XXXXXX)
sampler=
cleanup() {
  [ -z "$sampler" ] || kill "$sampler" 2>/dev/null || true
  if [ -n "${COMPILE_COST_KEEP:-}" ]; then echo "kept $tmp" >&2; else rm -rf "$tmp"; fi
}
trap cleanup EXIT

git clone -q --no-hardlinks "$checkout" "$tmp/desal"
git -C "$tmp/desal" checkout -q --detach "$commit"
if [ -d "$checkout/../shared" ]; then ln -s "$(cd "$checkout/../shared" && pwd)" "$tmp/shared"; fi
unset DESAL_REQUIRE_SHARED_DATA CARGO_BUILD_TARGET_DIR CARGO_BUILD_RUSTC_WRAPPER
caller_wrapper=${RUSTC_WRAPPER:-}
export RUSTC_WRAPPER=$here/rustc_cpu.sh
cd "$tmp/desal"

{
  echo "commit $commit ($(git log -1 --format='%cd %s' --date=short))"
  echo "checkout $checkout"
  echo "date $(date -u +%Y-%m-%dT%H:%M:%SZ)"
  echo "nproc $(nproc)"
  rustc -V
  cargo -V
  python3 -V
  echo "RUSTFLAGS=${RUSTFLAGS:-} RUSTC_WRAPPER=$caller_wrapper (replaced by rustc_cpu.sh)"
} >"$outdir/environment.txt"
uptime >"$outdir/load-start.txt"
(while sleep 15; do echo "$(date +%s) $(cut -d' ' -f1-3 /proc/loadavg)"; done) >"$outdir/load-samples.txt" &
sampler=$!

# (a) The README's main job, cold.
export CARGO_TARGET_DIR=$tmp/target
echo "(a) cargo run --release -- run pipelines/sample.toml, cold ..." >&2
RUSTC_CPU_LOG=$outdir/main-job.rustc-cpu /usr/bin/time -v -o "$outdir/main-job.time" cargo run --release --timings -- run pipelines/sample.toml \
  >"$outdir/main-job.log" 2>&1 || { tail -30 "$outdir/main-job.log" >&2; exit 1; }
cp "$CARGO_TARGET_DIR/cargo-timings/cargo-timing.html" "$outdir/main-job-timing.html"
echo "(a) cargo build --release, after it ..." >&2
RUSTC_CPU_LOG=$outdir/all-bins.rustc-cpu /usr/bin/time -v -o "$outdir/all-bins.time" cargo build --release --timings \
  >"$outdir/all-bins.log" 2>&1 || { tail -30 "$outdir/all-bins.log" >&2; exit 1; }
cp "$CARGO_TARGET_DIR/cargo-timings/cargo-timing.html" "$outdir/all-bins-timing.html"

# (b) The Python package, cold, in a fresh venv.
echo "(b) pip install ./crates/python, cold ..." >&2
python3 -m venv "$tmp/venv"
"$tmp/venv/bin/pip" install -q numpy >"$outdir/python-numpy.log" 2>&1
export CARGO_TARGET_DIR=$tmp/target-python
MATURIN_PEP517_ARGS=--timings RUSTC_CPU_LOG=$outdir/python.rustc-cpu /usr/bin/time -v -o "$outdir/python.time" "$tmp/venv/bin/pip" install -v ./crates/python \
  >"$outdir/python.log" 2>&1 || { tail -30 "$outdir/python.log" >&2; exit 1; }
cp "$CARGO_TARGET_DIR/cargo-timings/cargo-timing.html" "$outdir/python-timing.html"
so=$(find "$tmp/venv" -name '_desal*.so' | head -1)
wheel=$(find "$CARGO_TARGET_DIR/wheels" -name '*.whl' | head -1)
stripped=
if command -v strip >/dev/null; then strip -o "$tmp/stripped.so" "$so" && stripped=$(stat -c %s "$tmp/stripped.so"); fi
{
  echo "so $(stat -c %s "$so") $(basename "$so")"
  echo "so_stripped ${stripped:-?}"
  echo "wheel $(stat -c %s "$wheel") $(basename "$wheel")"
} >"$outdir/python-sizes.txt"

kill "$sampler" 2>/dev/null || true
sampler=
uptime >"$outdir/load-end.txt"
python3 "$here/compile_cost_report.py" "$outdir" >"$outdir/compile_cost.md"
echo "wrote $outdir/compile_cost.md" >&2
