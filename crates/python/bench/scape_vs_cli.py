#!/usr/bin/env python3
"""`desal.simplify_pose_set` on SCAPE-sized arrays against the same pipeline in the CLI.

    pip install ./crates/python && cargo build --release
    python crates/python/bench/scape_vs_cli.py [--rounds 5]

The CLI side is `desal run pipelines/scape.toml --force`; its compute time is the sum of
the fit, saliency, simplify and map stages' seconds in report.json (ingest, which reads
the PLY files, is left out: the Python side gets arrays read beforehand). The Python side
is `PoseSet(...)` (the arrays' validation, ingest's share) plus `simplify_pose_set` on the
71 x 12500 x 3 array. Rounds alternate the two, on one shared machine, and the medians
are compared. Both sides must give the same vertex map.
"""

import argparse
import json
import pathlib
import statistics
import subprocess
import tempfile
import time

import numpy as np

import desal

ROOT = pathlib.Path(__file__).resolve().parents[3]
SCAPE = ROOT.parent / "shared" / "datasets" / "scape"
STAGES = ("fit", "saliency", "simplify", "map")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--desal", default=str(ROOT / "target" / "release" / "desal"))
    args = parser.parse_args()

    files = sorted(SCAPE.glob("mesh*.ply"))
    meshes = [desal.read_mesh(f) for f in files]
    poses = np.stack([v for v, _ in meshes])
    faces = meshes[0][1]
    ids, names = desal.read_labels(SCAPE / "vertex_part_labels_16.txt")
    template = [f.stem for f in files].index("mesh000")
    print(f"arrays: poses {poses.shape} {poses.dtype}, faces {faces.shape}, labels {ids.shape}")

    cli_times, py_times, validate_times = [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(args.rounds):
            out = pathlib.Path(tmp) / "out"
            subprocess.run(
                [args.desal, "run", str(ROOT / "pipelines" / "scape.toml"), "--force", "--quiet", "--out", str(out)],
                check=True,
            )
            report = json.loads((out / "scape" / "report.json").read_text())
            seconds = {s["name"]: s["seconds"] for s in report["stages"]}
            cli_times.append(sum(seconds[s] for s in STAGES))
            cli_map = np.loadtxt(out / "scape" / "vertex_map.txt", dtype=np.int64)

            start = time.perf_counter()
            ps = desal.PoseSet(poses, faces, ids, template=template, part_names=names)
            validated = time.perf_counter()
            result = desal.simplify_pose_set(ps, target_vertices=2500, method="paper", placement="optimal")
            done = time.perf_counter()
            validate_times.append(validated - start)
            py_times.append(done - start)
            assert np.array_equal(result.vertex_map, cli_map), "the package and the CLI differ"
            print(f"round {r + 1}: cli {cli_times[-1]:.3f} s, python {py_times[-1]:.3f} s "
                  f"(of which PoseSet {validate_times[-1]:.3f} s)")
    cli, py = statistics.median(cli_times), statistics.median(py_times)
    print(f"median of {args.rounds}: cli stages {cli:.3f} s, python {py:.3f} s "
          f"(PoseSet {statistics.median(validate_times):.3f} s): ratio {py / cli:.2f}")


if __name__ == "__main__":
    main()
