"""Sampling a body-models model (SMPL family, ANNY, MHR, ...) into a registered pose set.

`desal.PoseSet.from_body_model` calls `sample`; it reads only what every body-models
model offers (`parameter_spec`, `forward_vertices`, `faces`, `skin_weights`,
`joint_names`, `parents`), so it works for any model the package has, on its NumPy
backend (no torch).

The draw, documented and seeded (`numpy.random.default_rng(seed)`):

- **Shapes.** Each parameter whose role is "identity", other than an expression: ANNY's
  phenotype values (default 0.5) uniform in [0, 1]; anything else (betas) N(0, 1) per
  component, clipped to +-2.5. One draw per shape; every pose of a shape shares it, and
  the shape is the pose's group.
- **Poses.** Each rotation whose role is "pose": per joint an axis-angle drawn from
  N(0, sigma^2) per axis, sigma = 0.3 rad for body joints (the head and neck among them)
  and 0.2 for hands, jaw, eyes and every other joint of a head pose (ANNY's facial rig:
  lips, tongue, cheeks, lids); `pose_sigma` overrides both. The joints' names come
  from the model's `pose_joint_indices`.
- **Expressions** ("expression" parameters: FLAME, SMPL-X): N(0, 1) per component for
  each pose when `expressions`, else zero.
- **Global rotation:** about the up axis (the rest mesh's longest extent), uniform in
  [-pi, pi); no translation.
- **The template**, pose 0 and its own group: every parameter at its default (the mean
  shape in the zero pose).
"""

from __future__ import annotations

import math
from typing import Any, Callable, Optional

import numpy as np

#: Pose sigma (rad) for body joints, and for hands, head and jaw.
BODY_SIGMA = 0.3
FINE_SIGMA = 0.2

_HAND_WORDS = ("hand", "finger", "metacarpal", "thumb", "index", "middle", "ring", "pinky")


def joint_sigma(parameter: str, joint: str) -> float:
    """The documented sigma (rad) of one joint of a pose parameter."""
    p, j = parameter.lower(), joint.lower()
    if "jaw" in j or "eye" in j or any(w in p or w in j for w in _HAND_WORDS):
        return FINE_SIGMA
    if "head" in p and not (j.startswith("head") or "neck" in j):
        return FINE_SIGMA
    return BODY_SIGMA


def _sigmas(model: Any, name: str, s: Any) -> Any:
    """Per-joint sigmas of a rotation parameter, shaped to broadcast over its draw."""
    if len(s.dims) < 2:
        return joint_sigma(name, name)
    count = s.dims[0]
    try:
        names = [model.joint_names[i] for i in model.pose_joint_indices[name]]
    except (AttributeError, KeyError, IndexError, TypeError):
        names = [name] * count
    if len(names) != count:
        names = [name] * count
    return np.array([joint_sigma(name, j) for j in names])[:, None]


def _spec(model: Any) -> dict:
    try:
        spec = dict(model.parameter_spec)
    except AttributeError as e:
        raise TypeError(
            f"from_body_model takes a body-models model (e.g. body_models.smplx.numpy.SMPLX); "
            f"{type(model).__name__} has no parameter_spec"
        ) from e
    for name, s in spec.items():
        if s.rotation_type not in (None, "axis_angle"):
            raise ValueError(
                f"parameter '{name}' uses rotation_type '{s.rotation_type}'; "
                "build the model with rotation_type='axis_angle' (the default)"
            )
    return spec


def _is_phenotype(model: Any, s: Any) -> bool:
    """ANNY's phenotype values live in [0, 1] (default 0.5); betas are N(0, 1)."""
    return type(model).__name__.upper() == "ANNY" or float(s.default) == 0.5


def triangles(faces: Any) -> np.ndarray:
    """Triangles of a face array: triangles as they are, quads split along 0-2, a
    padded quad (fourth index negative or repeating the third) as one triangle."""
    f = np.asarray(faces, dtype=np.int64)
    if f.ndim != 2 or f.shape[1] not in (3, 4):
        raise ValueError(f"the model's faces have shape {f.shape}; expected (F, 3) or (F, 4)")
    if f.shape[1] == 3:
        return f
    first = f[:, [0, 1, 2]]
    quad = (f[:, 3] >= 0) & (f[:, 3] != f[:, 2])
    second = f[quad][:, [0, 2, 3]]
    out = np.empty((len(f) + len(second), 3), dtype=np.int64)
    # Each quad's two triangles side by side, in face order.
    index = np.arange(len(f)) + np.concatenate([[0], np.cumsum(quad)[:-1]])
    out[index] = first
    out[index[quad] + 1] = second
    return out


def _axis_rotation(up: int, angles: np.ndarray) -> np.ndarray:
    rot = np.zeros((len(angles), 3))
    rot[:, up] = angles
    return rot


def sample(
    model: Any,
    shapes: int,
    poses: int,
    seed: int = 0,
    pose_sigma: Optional[float] = None,
    expressions: bool = True,
    progress: Optional[Callable[[str, int, int], None]] = None,
) -> dict:
    """`shapes` x `poses` samples of `model` after the template: positions
    (1 + shapes * poses, V, 3) float32, triangles, names (`template`, `s000-p000`, ...),
    groups (0 for the template, k + 1 for shape k) and the skin (weights, parents, joint
    names) for labels."""
    if shapes < 1 or poses < 1:
        raise ValueError(f"shapes = {shapes} and poses = {poses}: both must be at least 1")
    if pose_sigma is not None and not (math.isfinite(pose_sigma) and pose_sigma >= 0):
        raise ValueError(f"pose_sigma = {pose_sigma}: give a finite angle in radians, >= 0")
    spec = _spec(model)
    rng = np.random.default_rng(seed)
    defaults = {name: np.full(s.dims, float(s.default)) for name, s in spec.items()}
    rest = np.asarray(model.forward_vertices(**defaults), dtype=np.float64)
    up = int(np.argmax(rest.max(axis=0) - rest.min(axis=0)))

    count = 1 + shapes * poses
    positions = np.empty((count, rest.shape[0], 3), dtype=np.float32)
    positions[0] = rest
    names = ["template"]
    groups = np.zeros(count, dtype=np.int64)
    for shape in range(shapes):
        batch = {}
        for name, s in spec.items():
            dims = (poses, *s.dims)
            if s.role == "identity" and name == "expression":
                draw = rng.standard_normal(dims) if expressions else np.zeros(dims)
            elif s.role == "identity":
                if _is_phenotype(model, s):
                    one = rng.uniform(0.0, 1.0, s.dims)
                else:
                    one = np.clip(rng.standard_normal(s.dims), -2.5, 2.5)
                draw = np.broadcast_to(one, dims).copy()
            elif s.role == "pose" and s.rotation_type == "axis_angle":
                sigma = _sigmas(model, name, s) if pose_sigma is None else pose_sigma
                draw = rng.standard_normal(dims) * sigma
            elif name == "global_rotation" and s.rotation_type == "axis_angle":
                draw = _axis_rotation(up, rng.uniform(-math.pi, math.pi, poses))
            else:
                draw = np.broadcast_to(defaults[name], dims).copy()
            batch[name] = draw
        vertices = np.asarray(model.forward_vertices(**batch))
        start = 1 + shape * poses
        positions[start : start + poses] = vertices
        groups[start : start + poses] = shape + 1
        names.extend(f"s{shape:03}-p{p:03}" for p in range(poses))
        if progress is not None:
            progress("sample", shape + 1, shapes)
    if not np.isfinite(positions).all():
        raise ValueError("the model gave non-finite vertices for a sampled shape or pose")
    parents = [(-1 if p is None else int(p)) for p in model.parents]
    return {
        "poses": positions,
        "faces": triangles(model.faces),
        "names": names,
        "groups": groups,
        "weights": np.asarray(model.skin_weights, dtype=np.float64),
        "parents": parents,
        "joint_names": [str(n) for n in model.joint_names],
        "rest": rest,
    }
