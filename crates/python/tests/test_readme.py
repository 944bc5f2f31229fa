"""The README's "From Python" example runs as written and saves the registered poses."""

import pathlib
import re
import runpy

import numpy as np
import trimesh

ROOT = pathlib.Path(__file__).resolve().parents[3]


def readme_example() -> str:
    text = (ROOT / "README.md").read_text()
    section = text.split("## From Python", 1)[1]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


def test_readme_example(tmp_path, monkeypatch):
    code = readme_example()
    assert len(code.strip().splitlines()) <= 14
    # Run from a copy of the layout it expects: the sample beside it, outputs in tmp.
    (tmp_path / "data-samples").symlink_to(ROOT / "data-samples")
    script = tmp_path / "example.py"
    script.write_text(code)
    monkeypatch.chdir(tmp_path)
    namespace = runpy.run_path(str(script))
    out = namespace["out"]
    written = sorted((tmp_path / "out" / "python-sample").glob("*.ply"))
    assert [p.name for p in written] == [p.name for p in sorted((ROOT / "data-samples" / "poses").glob("*.ply"))]
    for k, path in enumerate(written):
        mesh = trimesh.load(path, process=False)
        assert mesh.vertices.shape == (2500, 3)
        np.testing.assert_allclose(mesh.vertices, out.poses[k], rtol=0, atol=1e-6)
        np.testing.assert_array_equal(mesh.faces, out.faces)
