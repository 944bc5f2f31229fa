"""desal.simplify_rig against the CLI's driver, on the bundled CC0 rig (issue 15).

    pip install ./crates/python && pip install pytest
    python -m pytest crates/python/tests
"""

import pathlib

import pytest

import desal

ROOT = pathlib.Path(__file__).resolve().parents[3]
RIG = ROOT / "data-samples" / "rig.glb"

# pipelines/rig-sample.toml's settings, fewer frames to keep the test short.
SETTINGS = dict(target_vertices=2676, method="paper", placement="subset", mesh="Body", frames=7)


@pytest.fixture(scope="module")
def cli(tmp_path_factory):
    """`desal run` on a rig pipeline with SETTINGS: its simplified.glb."""
    folder = tmp_path_factory.mktemp("cli")
    (folder / "rig.toml").write_text(
        f"""schema = 1
out = "out"
[[dataset]]
name = "avatar"
up_axis = "y"
[dataset.rig]
file = "{RIG.as_posix()}"
mesh = "Body"
frames = 7
[dataset.simplify]
target_vertices = 2676
placement = "subset"
saliency = true
balance = true
"""
    )
    desal.run(folder / "rig.toml", out=folder / "out")
    return (folder / "out" / "avatar" / "simplified.glb").read_bytes()


def test_simplify_rig_writes_the_cli_bytes(cli, tmp_path):
    out = tmp_path / "avatar.glb"
    report = desal.simplify_rig(RIG, out, **SETTINGS)
    assert out.read_bytes() == cli
    assert report["rig"]["simplified_vertices"] == 2676
    assert report["rig"]["weights"].startswith("exact, capped at max_influences"), "4 by default"
    assert report["ingest"]["poses"] == 8, "the bind pose and 7 frames"
    assert report["glb"] == out


def test_optimal_placement_refits_weights(tmp_path):
    out = tmp_path / "optimal.glb"
    report = desal.simplify_rig(RIG, out, target_vertices=3000, placement="optimal", method="qslim", frames=5)
    assert report["rig"]["refitted_vertices"] > 0 and report["rig"]["max_influences"] <= 4
    assert out.read_bytes()[:4] == b"glTF"


def test_bad_rig_input_is_an_input_error_naming_it(tmp_path):
    not_a_rig = tmp_path / "broken.glb"
    not_a_rig.write_bytes(b"glTF but not really")
    with pytest.raises(desal.InputError, match="broken.glb"):
        desal.simplify_rig(not_a_rig, tmp_path / "out.glb", target_vertices=100)
    with pytest.raises(desal.InputError, match="NoSuchMesh"):
        desal.simplify_rig(RIG, tmp_path / "out.glb", target_vertices=100, mesh="NoSuchMesh")
    with pytest.raises(desal.InputError, match="everything"):
        desal.simplify_rig(RIG, tmp_path / "out.glb", target_vertices=100, poses="everything")
    assert not (tmp_path / "out.glb").exists()


def test_max_influences_caps_subset_weights(tmp_path):
    """The sample has up to 7 influences per vertex; max_influences=4 (the default) keeps
    4, as the summary and the written file both say; "all" keeps them all."""
    out = tmp_path / "four.glb"
    report = desal.simplify_rig(RIG, out, **SETTINGS, max_influences=4)
    assert report["rig"]["max_influences"] == 4
    assert report["rig"]["weights"].startswith("exact, capped")
    default = desal.simplify_rig(RIG, tmp_path / "default.glb", **SETTINGS)
    assert default["rig"]["max_influences"] == 4, "engines skin 4 (issue 42, item 5)"
    exact = desal.simplify_rig(RIG, tmp_path / "exact.glb", **SETTINGS, max_influences="all")
    assert exact["rig"]["max_influences"] > 4
    with pytest.raises(desal.InputError, match="max_influences"):
        desal.simplify_rig(RIG, tmp_path / "zero.glb", **SETTINGS, max_influences=0)


def test_lods_write_every_level_and_report_them(tmp_path):
    """Issue 42, item 6 and 12: lods writes each level beside out and the MSFT_lod chain;
    each level's faces are near its fraction of the original 26756 and its vertices
    fewer than the level before's; the report has each level's figures."""
    out = tmp_path / "avatar.glb"
    report = desal.simplify_rig(RIG, out, **SETTINGS, lods=[0.5, 0.2])
    assert report["lod_files"] == [tmp_path / "avatar-lod1.glb", tmp_path / "avatar-lod2.glb", tmp_path / "avatar-lods.glb"]
    assert all(path.read_bytes()[:4] == b"glTF" for path in report["lod_files"])
    levels = report["lods"]
    assert [level["level"] for level in levels] == [1, 2]
    assert [level["target_faces"] for level in levels] == [13378, 5351]
    for level in levels:
        assert abs(level["output_faces"] - level["target_faces"]) <= 1, level
    assert levels[1]["vertices"] < levels[0]["vertices"]
    assert report["rig"]["lods"] == levels
    chain = (tmp_path / "avatar-lods.glb").read_bytes()
    assert b"MSFT_lod" in chain and b"Body_LOD2" in chain


def test_mesh_lists_overrides_and_bad_lods(tmp_path):
    """Issue 42, items 2 and 12: mesh takes a list (here by mesh index), meshes a mesh's
    own ratio (1.0 keeps the one mesh whole); bad lods or an unknown mesh are input
    errors naming the key."""
    out = tmp_path / "whole.glb"
    report = desal.simplify_rig(RIG, out, frames=5, ratio=0.2, mesh=["0"], meshes={"Body": 1.0})
    assert report["rig"]["simplified_vertices"] == 13380, "kept whole"
    assert report["lods"] == [] and report["lod_files"] == []
    with pytest.raises(desal.InputError, match="strictly decreasing"):
        desal.simplify_rig(RIG, tmp_path / "bad.glb", target_vertices=100, lods=[0.2, 0.5])
    with pytest.raises(desal.InputError, match="rig.meshes names 'Nope'"):
        desal.simplify_rig(RIG, tmp_path / "bad.glb", target_vertices=100, frames=3, meshes={"Nope": 0.5})
    with pytest.raises(desal.InputError, match="names no skinned mesh"):
        desal.simplify_rig(RIG, tmp_path / "bad.glb", target_vertices=100, mesh=["Body", "Nope"])
    assert not (tmp_path / "bad.glb").exists()
