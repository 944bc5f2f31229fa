"""desal-bodymodel's evaluation against body-models' (NumPy backend), on the CC0 fixture.

    python -m venv .venv-bm && .venv-bm/bin/pip install body-models==0.26.2
    .venv-bm/bin/python crates/bodymodel/tests/against_body_models.py [--fixture DIR]

Without `--fixture`, builds the fixture first (`cargo run --release -p desal-sample
--example make_smpl_fixture`, into a temporary folder). Then:

1. loads `model.npz` and `model.pkl` in body-models' `SMPL` class, unchanged, and checks
   that both give the same model and that `J_regressor @ v_template` is the rig's `J`;
2. evaluates a few parameter sets (the zero pose, a shape alone, poses alone, both with a
   pelvis rotation and a translation), inputs in float64;
3. writes `crates/bodymodel/tests/data/body_models_expected.npz` (or `--out`): the parameters, the
   vertices at every 16th vertex index, the posed joints, and the fixture's SHA-256, which
   `tests/against_body_models.rs` checks against desal's evaluation to 1e-6.

With `--flame`, it also writes a tiny random model in FLAME's layout (5 joints, 300 shape
+ 10 expression columns in `shapedirs`, dense random `posedirs`; numbers drawn here,
seeded) as `tests/data/flame_random.npz`, and body-models' `FLAME` evaluation of it as
`tests/data/flame_random_expected.npz`: the expression split and a dense corrective basis,
which the CC0 SMPL fixture does not exercise.
"""

import argparse
import hashlib
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from body_models.smpl.numpy import SMPL

ROOT = Path(__file__).resolve().parents[3]
OUT = ROOT / "crates/bodymodel/tests/data/body_models_expected.npz"
STRIDE = 16


def build_fixture(folder: Path) -> None:
    subprocess.run(
        ["cargo", "run", "-q", "--release", "-p", "desal-sample", "--example", "make_smpl_fixture", "--", str(folder)],
        cwd=ROOT,
        check=True,
    )


def parameter_sets() -> list[dict]:
    rng = np.random.default_rng(41)
    sets = [dict(betas=np.zeros(10), pose=np.zeros((24, 3)), translation=np.zeros(3))]
    sets.append(dict(betas=np.clip(rng.normal(size=10) * 1.5, -2.5, 2.5), pose=np.zeros((24, 3)), translation=np.zeros(3)))
    for _ in range(2):
        sets.append(dict(betas=np.zeros(10), pose=rng.normal(scale=0.3, size=(24, 3)), translation=np.zeros(3)))
    for _ in range(2):
        sets.append(
            dict(
                betas=np.clip(rng.normal(size=10), -2.5, 2.5),
                pose=rng.normal(scale=0.4, size=(24, 3)),
                translation=rng.normal(scale=0.5, size=3),
            )
        )
    return sets


def evaluate(model: SMPL, p: dict) -> tuple[np.ndarray, np.ndarray]:
    args = dict(
        body_pose=p["pose"][1:],
        pelvis_rotation=p["pose"][0],
        shape=p["betas"],
        global_translation=p["translation"],
    )
    vertices = model.forward_vertices(**args)
    joints = model.forward_skeleton(**args)[:, :3, 3]
    return np.asarray(vertices, dtype=np.float64), np.asarray(joints, dtype=np.float64)


def write_flame(folder: Path) -> None:
    from body_models.flame.numpy import FLAME

    rng = np.random.default_rng(5)
    v, j = 12, 5
    weights = rng.uniform(0.0, 1.0, size=(v, j))
    regressor = rng.uniform(0.0, 1.0, size=(j, v))
    model = dict(
        v_template=rng.uniform(-0.1, 0.1, size=(v, 3)).astype(np.float32),
        f=np.array([[0, 1, 2], [2, 3, 4], [5, 6, 7], [8, 9, 10], [9, 10, 11]], dtype=np.int32),
        shapedirs=rng.normal(scale=0.01, size=(v, 3, 310)).astype(np.float32),
        posedirs=rng.normal(scale=0.01, size=(v, 3, 9 * (j - 1))).astype(np.float32),
        weights=(weights / weights.sum(axis=1, keepdims=True)).astype(np.float32),
        J_regressor=(regressor / regressor.sum(axis=1, keepdims=True)).astype(np.float32),
        kintree_table=np.array([[4294967295, 0, 1, 1, 1], [0, 1, 2, 3, 4]], dtype=np.int64),
    )
    np.savez(folder / "flame_random.npz", **model)
    flame = FLAME(model_path=folder / "flame_random.npz")
    sets = []
    for _ in range(3):
        sets.append(
            dict(
                betas=rng.normal(size=20),
                expression=rng.normal(size=10),
                pose=rng.normal(scale=0.3, size=(5, 3)),
                translation=rng.normal(scale=0.1, size=3),
            )
        )
    vertices, joints = [], []
    for p in sets:
        args = dict(
            head_pose=p["pose"][1:],
            head_rotation=p["pose"][0],
            shape=p["betas"],
            expression=p["expression"],
            global_translation=p["translation"],
        )
        vertices.append(np.asarray(flame.forward_vertices(**args), dtype=np.float64))
        joints.append(np.asarray(flame.forward_skeleton(**args)[:, :3, 3], dtype=np.float64))
    np.savez(
        folder / "flame_random_expected.npz",
        betas=np.stack([p["betas"] for p in sets]),
        expression=np.stack([p["expression"] for p in sets]),
        pose=np.stack([p["pose"] for p in sets]),
        translation=np.stack([p["translation"] for p in sets]),
        vertices=np.stack(vertices),
        joints=np.stack(joints),
    )
    print(f"wrote flame_random.npz and flame_random_expected.npz into {folder}")


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--fixture", type=Path, help="folder with model.npz and model.pkl (built when absent)")
    parser.add_argument("--out", type=Path, default=OUT, help=f"where to write the expected values (default {OUT.relative_to(ROOT)})")
    parser.add_argument("--flame", action="store_true", help="also write the random FLAME-layout model and its values")
    args = parser.parse_args()
    out = args.out
    if args.flame:
        write_flame(out.parent)
    with tempfile.TemporaryDirectory() as tmp:
        folder = args.fixture or Path(tmp)
        if args.fixture is None:
            build_fixture(folder)
        npz_path, pkl_path = folder / "model.npz", folder / "model.pkl"
        from_npz, from_pkl = SMPL(model_path=npz_path), SMPL(model_path=pkl_path)
        raw = np.load(npz_path)
        rig_joints = raw["J"].astype(np.float64)
        regressed = raw["J_regressor"].astype(np.float64) @ raw["v_template"].astype(np.float64)
        joint_error = np.abs(regressed - rig_joints).max()
        print(f"J_regressor @ v_template vs the rig's joints: max |diff| {joint_error:.2e} m")
        assert joint_error < 1e-5, joint_error
        nonzeros = (raw["J_regressor"] != 0).sum(axis=1)
        print(f"J_regressor nonzeros per joint: {nonzeros.min()}..{nonzeros.max()}, all >= 0: {(raw['J_regressor'] >= 0).all()}")

        sets = parameter_sets()
        vertices, joints, pkl_difference = [], [], 0.0
        for p in sets:
            v_npz, j_npz = evaluate(from_npz, p)
            v_pkl, _ = evaluate(from_pkl, p)
            # Same values; body-models regresses the joints in float32, and the pickle's
            # CSC regressor densifies in Fortran order, so the sums round differently.
            pkl_difference = max(pkl_difference, np.abs(v_npz - v_pkl).max())
            vertices.append(v_npz)
            joints.append(j_npz)
        vertices = np.stack(vertices)
        print(f"model.npz vs model.pkl in body-models: max |diff| {pkl_difference:.2e} m")
        assert pkl_difference < 1e-6, pkl_difference
        print(f"{len(sets)} parameter sets; largest displacement from the template: "
              f"{np.abs(vertices - vertices[0]).max():.3f} m")
        index = np.arange(0, vertices.shape[1], STRIDE)
        digest = hashlib.sha256(npz_path.read_bytes()).hexdigest()
        np.savez(
            out,
            betas=np.stack([p["betas"] for p in sets]),
            pose=np.stack([p["pose"] for p in sets]),
            translation=np.stack([p["translation"] for p in sets]),
            vertex_index=index.astype(np.int64),
            vertices=vertices[:, index],
            joints=np.stack(joints),
            fixture_sha256=np.array(digest),
        )
        print(f"wrote {out} ({out.stat().st_size} bytes); fixture sha256 {digest}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
