#!/usr/bin/env python3
"""Every result of the desal Python package's public API on the bundled samples, written
to files, so that two builds of the package can be compared byte for byte
(tests/faults/same_outputs.sh hashes the folder as it hashes the CLI's outputs).

Usage: python_outputs.py OUT_DIR     (with the interpreter whose `desal` is to be measured)

Arrays are written with np.save (C order; object arrays are never written), reports and
other values as JSON (sorted keys; arrays inside a report go to their own .npy files,
named after their key). Files the package writes itself (simplify_rig's .glb,
Hierarchy.save's .npz, desal.run's output folder) are kept as written, except
save_graphcmr's file, whose zip members carry the time of writing and pickles of
scipy objects: it is read back and written as its plain arrays.

Only the package's public API (`desal.__all__` and the Hierarchy/Fit/Saliency/PoseSet
attributes) is called. Everything is deterministic: the same package gives the same
bytes, run after run.
"""

import json
import os
import pathlib
import sys
from typing import Any

import numpy as np

import desal

ROOT = pathlib.Path(__file__).resolve().parents[2]
SAMPLE = ROOT / "data-samples"
RIG = SAMPLE / "rig.glb"

OUT = pathlib.Path(sys.argv[1]).resolve() if len(sys.argv) == 2 else None
if OUT is None:
    sys.exit(__doc__)


def _plain(name: str, value: Any) -> Any:
    """`value` as JSON can hold it; arrays are saved beside it and named."""
    if isinstance(value, np.ndarray):
        save(name, value)
        return f"<array {name}.npy>"
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, dict):
        return {str(k): _plain(f"{name}.{k}", v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(f"{name}.{k}", v) for k, v in enumerate(value)]
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    raise TypeError(f"{name}: cannot write a {type(value).__name__}")


def save(name: str, value: Any) -> None:
    """Writes `value` as OUT/name.npy (an array) or OUT/name.json (anything else)."""
    if isinstance(value, np.ndarray):
        if value.dtype == object:
            raise TypeError(f"{name}: object array")
        np.save(OUT / f"{name}.npy", np.ascontiguousarray(value), allow_pickle=False)
        return
    text = json.dumps(_plain(name, value), sort_keys=True, indent=1)
    (OUT / f"{name}.json").write_text(text + "\n")


def save_attrs(name: str, obj: Any, attrs: list) -> None:
    for attr in attrs:
        save(f"{name}.{attr}", getattr(obj, attr))


def save_simplification(name: str, s: "desal.Simplification") -> None:
    save_attrs(
        name,
        s,
        ["vertex_map", "faces", "poses", "labels", "saliency", "weights", "simplified_vertices", "report"],
    )


def save_hierarchy(name: str, h: "desal.Hierarchy") -> None:
    save(f"{name}.levels", h.levels)
    for key in sorted(h.arrays):
        save(f"{name}.arrays.{key}", np.asarray(h.arrays[key]))
    save(f"{name}.report", h.report)
    for what in ("A", "D", "U"):
        for k, m in enumerate(getattr(h, what)):
            save_sparse(f"{name}.{what}{k}", m)
    for k, (m, o) in enumerate(zip(h.map, h.orig)):
        save(f"{name}.map{k}", m)
        save(f"{name}.orig{k}", o)


def save_sparse(name: str, m: Any) -> None:
    """A scipy.sparse matrix as CSC arrays (or the package's COO tuple without scipy)."""
    if isinstance(m, tuple):
        row, col, data, shape = m
        save(f"{name}.coo", dict(row=row, col=col, data=data, shape=list(shape)))
        return
    m = m.tocsc()
    save(f"{name}.csc", dict(format=m.format, shape=list(m.shape), data=m.data, indices=m.indices, indptr=m.indptr))


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=False)
    save("api", dict(all=sorted(desal.__all__), max_rig_frames=desal.MAX_RIG_FRAMES, version=desal.__version__))

    # Reading files.
    files = sorted((SAMPLE / "poses").glob("*.ply"))
    meshes = [desal.read_mesh(p) for p in files]
    save("read_mesh.00_rest", dict(vertices=meshes[0][0], faces=meshes[0][1]))
    poses = np.stack([v for v, _ in meshes])
    faces = meshes[0][1]
    save("read_mesh.poses", poses)
    ids, part_names = desal.read_labels(SAMPLE / "labels.json")
    save("read_labels.json", dict(ids=ids, names=part_names))
    save("read_labels.txt", dict(zip(("ids", "names"), desal.read_labels(SAMPLE / "labels.txt"))))
    names = [p.stem for p in files]
    template = names.index("00_rest")

    # Pose sets, given labels and discovered ones.
    ps = desal.PoseSet(poses, faces, ids, template=template, names=names, part_names=part_names)
    pose_set_attrs = ["poses", "faces", "labels", "part_names", "names", "template", "vertex_count", "pose_count"]
    pose_set_attrs += ["parts_report", "removed_faces"]
    save_attrs("pose_set", ps, pose_set_attrs)
    save("pose_set.len", len(ps))
    auto = desal.PoseSet(poses, faces, None, template=template)
    save_attrs("pose_set_auto", auto, pose_set_attrs)
    auto12 = desal.PoseSet(poses, faces, None, template=template, parts={"count": 12})
    save_attrs("pose_set_auto12", auto12, ["labels", "part_names", "parts_report"])

    # Stage 1.
    fits = {}
    for method in ("rigid", "affine"):
        fits[method] = f = desal.fit(ps, method=method)
        save_attrs(f"fit.{method}", f, ["rotations", "translations", "residuals", "model", "report"])
    save_attrs("fit.auto", desal.fit(auto), ["rotations", "translations", "residuals", "report"])

    # Stage 2.
    saliencies = {
        "default": desal.saliency(ps, fits["rigid"]),
        "no_fit": desal.saliency(ps),
        "affine": desal.saliency(ps, fits["affine"]),
        "options": desal.saliency(ps, fits["rigid"], squared=True, percentile=95.0, exclude=[names[3]], floor=0.1),
    }
    for key, s in saliencies.items():
        save_attrs(f"saliency.{key}", s, ["saliency", "weights", "raw", "report"])
    weights = saliencies["default"].weights

    # Stage 3 on a plain mesh.
    rest = ps.poses[template]
    simplified = {
        "paper": desal.simplify(rest, ps.faces, target_vertices=2500, weights=weights, balance=True),
        "subset": desal.simplify(rest, ps.faces, target_vertices=800, placement="subset"),
        "lindstrom_turk": desal.simplify(rest, ps.faces, target_faces=3000, metric="lindstrom-turk"),
        "borders": desal.simplify(
            rest, ps.faces, ratio=0.1, labels=ps.labels, keep_part_borders=True, boundary_weight=5.0, weights=weights
        ),
        "default": desal.simplify(rest, ps.faces),
    }
    for key, (v, f, report) in simplified.items():
        save(f"simplify.{key}", dict(vertices=v, faces=f, report=report))

    # Stage 4: with stage 3's map and by the greedy rule.
    for key in ("paper", "subset"):
        v, f, report = simplified[key]
        vertex_map, mapped = desal.map(ps, v, f, report["simp_to_orig"])
        save(f"map.{key}", dict(vertex_map=vertex_map, poses=mapped))
        vertex_map, mapped = desal.map(ps, v, f)
        save(f"map.{key}.greedy", dict(vertex_map=vertex_map, poses=mapped))

    # The whole chain.
    chains = {
        "paper": dict(target_vertices=2500, method="paper", placement="optimal"),
        "paper_subset": dict(target_vertices=2500, method="paper", placement="subset"),
        "qslim": dict(target_vertices=1500, method="qslim"),
        "saliency": dict(target_vertices=1500, method="saliency"),
        "balance": dict(target_vertices=1500, method="balance"),
        "multipose": dict(target_vertices=1500, method="multipose"),
        "desal": dict(target_vertices=1500, method="desal"),
        "desal_refit": dict(target_vertices=1500, method="desal-refit"),
        "faces": dict(target_faces=4000),
        "ratio_affine": dict(ratio=0.15, fit_method="affine"),
        "options": dict(
            target_vertices=2000,
            saliency_options={"squared": True, "floor": 0.2},
            simplify_options={"metric": "lindstrom-turk", "boundary_weight": 3.0},
        ),
    }
    for key, kwargs in chains.items():
        save_simplification(f"simplify_pose_set.{key}", desal.simplify_pose_set(ps, **kwargs))
    save_simplification("simplify_pose_set.auto", desal.simplify_pose_set(auto, target_vertices=2500))
    arrays = desal.simplify_pose_set(poses, faces, ids, target_vertices=2500, template=template)
    save_simplification("simplify_pose_set.arrays", arrays)

    # Hierarchies.
    hierarchies = {
        "fitted": desal.hierarchy(ps, [2500, 625]),
        "barycentric": desal.hierarchy(ps, [2500, 625], upsampler="barycentric"),
        "options": desal.hierarchy(ps, [3000, 1000, 300], neighbours=8, ridge=1e-2, neighbourhood="geodesic"),
        "desal": desal.hierarchy(ps, [1500, 400], method="desal"),
        "desal_refit": desal.hierarchy(ps, [1500], method="desal-refit"),
    }
    for key, h in hierarchies.items():
        save_hierarchy(f"hierarchy.{key}", h)
    h = hierarchies["fitted"]
    h.save(OUT / "hierarchy.fitted.saved.npz")
    save_hierarchy("load_hierarchy.fitted", desal.load_hierarchy(OUT / "hierarchy.fitted.saved.npz"))
    graphcmr = OUT / "save_graphcmr.npz.tmp"
    desal.save_graphcmr(h, graphcmr)
    data = np.load(graphcmr, encoding="latin1", allow_pickle=True)
    assert sorted(data.files) == ["A", "D", "F", "U"], data.files
    for key in ("A", "D", "U"):
        for k, m in enumerate(data[key]):
            save_sparse(f"save_graphcmr.{key}{k}", m)
    for k, f in enumerate(data["F"]):
        save(f"save_graphcmr.F{k}", np.asarray(f))
    data.close()
    graphcmr.unlink()

    # Rigs: simplify_rig writes the .glb `desal run` would.
    rigs = {
        "paper": dict(target_vertices=2676, method="paper", placement="subset", mesh="Body", frames=21),
        "optimal": dict(target_vertices=3000, method="qslim", placement="optimal", frames=5),
        "capped": dict(target_vertices=2676, mesh="Body", frames=7, max_influences=4),
        "random": dict(target_vertices=2000, poses="random", frames=6, seed=7, max_degrees=30.0),
        "desal": dict(target_vertices=2000, method="desal", frames=7),
    }
    for key, kwargs in rigs.items():
        save(f"simplify_rig.{key}.report", desal.simplify_rig(RIG, OUT / f"simplify_rig.{key}.glb", **kwargs))

    # The driver, and every artifact it wrote read back.
    reports = desal.run(ROOT / "pipelines" / "sample-hierarchy.toml", out=OUT / "run")
    save("run.reports", reports)
    for path in sorted((OUT / "run" / "sample").glob("*.dsa")):
        save(f"load.{path.stem}", desal.load(path))


if __name__ == "__main__":
    main()
