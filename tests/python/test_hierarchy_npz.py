"""hierarchy.npz reads back with numpy, exactly, and means what its layout says.

Runs the Rust example `write_npz_fixture` (a hand-made three-level hierarchy) into a
temp folder, then loads the npz with `allow_pickle=False` and compares every array with
the JSON of expected values the example printed from memory.

    python3 -m pytest tests/python
"""

import json
import pathlib
import subprocess

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    out = tmp_path_factory.mktemp("npz")
    npz, expected = out / "hierarchy.npz", out / "expected.json"
    subprocess.run(
        ["cargo", "run", "--quiet", "-p", "desal-hierarchy", "--example", "write_npz_fixture", "--", str(npz), str(expected)],
        cwd=ROOT,
        check=True,
    )
    with np.load(npz, allow_pickle=False) as data:
        arrays = {key: data[key] for key in data.files}
    return arrays, json.loads(expected.read_text())


def test_every_array_has_exact_values(written):
    arrays, expected = written
    assert sorted(arrays) == sorted(expected)
    for key, want in expected.items():
        got = arrays[key]
        assert got.dtype == np.dtype(want["dtype"]), key
        assert list(got.shape) == want["shape"], key
        # Exact: float64 survives JSON's shortest round-trip representation.
        np.testing.assert_array_equal(got.ravel(), np.array(want["values"], dtype=want["dtype"]), err_msg=key)


def coo(arrays, key):
    shape = tuple(int(n) for n in arrays[f"{key}_shape"])
    dense = np.zeros(shape)
    np.add.at(dense, (arrays[f"{key}_row"], arrays[f"{key}_col"]), arrays[f"{key}_data"])
    return dense


def test_layout_semantics(written):
    arrays, _ = written
    levels = arrays["levels"]
    assert list(levels) == [81, 25, 9]
    for k in range(len(levels) - 1):
        down, up = coo(arrays, f"D{k}"), coo(arrays, f"U{k}")
        assert down.shape == (levels[k + 1], levels[k])
        assert up.shape == (levels[k], levels[k + 1])
        # D selects map{k+1}: one 1 per row, in the mapped column.
        np.testing.assert_array_equal(down.sum(axis=1), 1.0)
        np.testing.assert_array_equal(np.argmax(down, axis=1), arrays[f"map{k + 1}"])
        np.testing.assert_allclose(up.sum(axis=1), 1.0, atol=1e-12)
        # The maps nest: orig{k+1} = orig{k}[map{k+1}] (orig0 is the identity).
        orig_k = arrays[f"orig{k}"] if k > 0 else np.arange(levels[0])
        np.testing.assert_array_equal(arrays[f"orig{k + 1}"], orig_k[arrays[f"map{k + 1}"]])
    for k in range(len(levels)):
        a = coo(arrays, f"A{k}")
        np.testing.assert_array_equal(a, a.T)
        assert arrays[f"F{k}"].dtype == np.int32 and arrays[f"F{k}"].shape[1] == 3
        assert arrays[f"F{k}"].max() < levels[k]
