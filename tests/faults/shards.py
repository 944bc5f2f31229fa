#!/usr/bin/env python3
"""Concurrency: N shards of one batch sharing one cache, R rounds, with and without
`--force`. Every shard run must succeed, and every dataset's outputs must be
byte-identical to a sequential run's.

Usage: shards.py DESAL_BINARY [--shards 4] [--rounds 8]
"""

import argparse
import hashlib
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
TARGETS = [1000, 1500, 2000, 2500]


def batch(work: Path, out: Path) -> Path:
    lines = [
        "schema = 1",
        f'out = "{out}"',
        "[defaults]",
        f'poses = "{ROOT / "data-samples/poses/*.ply"}"',
        'template = "00_rest"',
        f'labels = "{ROOT / "data-samples/labels.json"}"',
        'up_axis = "y"',
        "[defaults.simplify]",
        "saliency = true",
        "balance = true",
    ]
    for t in TARGETS:
        lines += ["[[dataset]]", f'name = "sample-{t}"', "[dataset.simplify]", f"target_vertices = {t}"]
    path = work / f"batch-{out.name}.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


def digest(folder: Path) -> dict:
    return {
        str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(folder.rglob("*"))
        if p.is_file() and p.suffix in (".dsa", ".ply", ".png", ".txt") and ".cache" not in p.parts
    }


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("binary")
    parser.add_argument("--shards", type=int, default=4)
    parser.add_argument("--rounds", type=int, default=8)
    args = parser.parse_args()
    binary = str(Path(args.binary).resolve())
    work = Path(tempfile.mkdtemp(prefix="desal-shards-"))
    reference = work / "sequential"
    subprocess.run([binary, "run", str(batch(work, reference)), "--quiet"], check=True, capture_output=True)
    expected = digest(reference)
    cache = work / "shared-cache"
    failures = []
    runs = 0
    for force in (False, True):
        for r in range(args.rounds):
            out = work / f"round-{int(force)}-{r}"
            pipeline = batch(work, out)
            procs = []
            for i in range(1, args.shards + 1):
                cmd = [binary, "run", str(pipeline), "--quiet", "--shard", f"{i}/{args.shards}", "--cache-dir", str(cache)]
                if force:
                    cmd.append("--force")
                procs.append(subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True))
            for i, p in enumerate(procs, 1):
                _, err = p.communicate()
                runs += 1
                if p.returncode != 0:
                    failures.append(f"force={force} round {r} shard {i}/{args.shards}: exit {p.returncode}: {err.strip()}")
            got = digest(out)
            if got != expected:
                failures.append(f"force={force} round {r}: outputs differ from the sequential run")
            shutil.rmtree(out, ignore_errors=True)
    print(f"shards: {args.shards} shards x {args.rounds} rounds x (plain, --force) = {runs} shard runs, "
          f"{len(failures)} failures")
    for f in failures[:20]:
        print(f"  {f}")
    shutil.rmtree(work, ignore_errors=True)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
