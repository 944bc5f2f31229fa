"""A model dataset's model.npz loads in body-models unchanged and is the full model on its
kept vertices (issue 41, item 5).

Writes the CC0 SMPL-layout fixture (`cargo run -p desal-sample --example
make_smpl_fixture`), runs `desal run` on it as a `[dataset.model]` (subset placement,
the default there), then loads the fixture and the output's model.npz in body-models'
SMPL class (NumPy backend) and compares, at 10 random (betas, pose, translation) within
the fixture's 10 shape components, the simplified model's vertices with the full
model's at `vertex_map.txt`, and the joints.

    pip install body-models==0.26.2 pytest && python -m pytest tests/python/test_model_npz.py

Skips, saying why, when body-models is not installed. `DESAL_BIN` names the desal binary
to run (default: `cargo run --bin desal`).
"""

import os
import pathlib
import shlex
import subprocess

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
# body-models evaluates in float32: a vertex of the full and of the smaller model is the
# same float32 sum of the same float32 values up to the joints' regression (a sum over
# other vertices), ~1e-7 m at 1 m.
TOLERANCE = 1e-6


def desal_command():
    given = os.environ.get("DESAL_BIN")
    return shlex.split(given) if given else ["cargo", "run", "--quiet", "--bin", "desal", "--"]


@pytest.fixture(scope="module")
def models(tmp_path_factory):
    pytest.importorskip("body_models", reason="body-models is not installed (pip install body-models==0.26.2)")
    from body_models.smpl.numpy import SMPL

    folder = tmp_path_factory.mktemp("model")
    subprocess.run(
        ["cargo", "run", "--quiet", "-p", "desal-sample", "--example", "make_smpl_fixture", "--", str(folder)],
        cwd=ROOT,
        check=True,
    )
    pipeline = folder / "pipeline.toml"
    pipeline.write_text(
        'schema = 1\nout = "out"\n\n[[dataset]]\nname = "body"\n\n[dataset.model]\nfile = "model.npz"\n'
        "shapes = 2\nposes = 3\nseed = 7\n\n[dataset.simplify]\ntarget_vertices = 1500\n"
    )
    subprocess.run([*desal_command(), "run", str(pipeline), "--quiet"], cwd=ROOT, check=True)
    body = folder / "out" / "body"
    kept = np.loadtxt(body / "vertex_map.txt", dtype=np.int64)
    return SMPL(model_path=folder / "model.npz"), SMPL(model_path=body / "model.npz"), kept, body


def evaluate(model, betas, pose, translation):
    args = dict(body_pose=pose[1:], pelvis_rotation=pose[0], shape=betas, global_translation=translation)
    vertices = np.asarray(model.forward_vertices(**args), dtype=np.float64)
    joints = np.asarray(model.forward_skeleton(**args)[:, :3, 3], dtype=np.float64)
    return vertices, joints


def test_model_npz_is_the_full_model_on_its_kept_vertices(models):
    full, small, kept, body = models
    with np.load(body / "model.npz", allow_pickle=False) as data:
        assert data["v_template"].shape == (len(kept), 3)
        assert data["f"].max() < len(kept)
        assert data["J_regressor"].shape == (24, len(kept))
    rng = np.random.default_rng(41)
    worst_vertex = worst_joint = 0.0
    for _ in range(10):
        betas = np.clip(rng.normal(size=10), -2.5, 2.5)
        pose = rng.normal(scale=0.3, size=(24, 3))
        translation = rng.normal(scale=0.5, size=3)
        v_full, j_full = evaluate(full, betas, pose, translation)
        v_small, j_small = evaluate(small, betas, pose, translation)
        worst_vertex = max(worst_vertex, np.abs(v_small - v_full[kept]).max())
        worst_joint = max(worst_joint, np.abs(j_small - j_full).max())
    print(f"body-models, 10 parameter sets: vertices {worst_vertex:.1e} m, joints {worst_joint:.1e} m")
    assert worst_vertex < TOLERANCE, worst_vertex
    assert worst_joint < TOLERANCE, worst_joint
