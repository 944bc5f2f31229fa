"""`desal eval` on the bundled rig with gltfpack as a method (issue 15, item 4): gltfpack
(npm `gltfpack`, pinned in tests/gltf) runs on the rig file itself, its ratio bisected to
the vertex target, its own skin kept; every method is skinned by the rig model and
compared with the full rig's skinning at held-out frames, against gltfpack as the
baseline.

    cargo build && (cd tests/gltf && npm ci) && python3 -m pytest tests/python

Needs target/debug/desal and gltfpack ($DESAL_GLTFPACK, tests/gltf/node_modules/.bin/gltfpack
or `gltfpack` on the PATH). Skipped without them, except under DESAL_REQUIRE_GLTFPACK=1
(`.ci/run` sets it), where that is a failure.
"""

import json
import os
import pathlib
import shutil
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
DESAL = ROOT / "target" / "debug" / "desal"
NPM_GLTFPACK = ROOT / "tests" / "gltf" / "node_modules" / ".bin" / "gltfpack"


def require(condition, reason):
    if condition:
        return
    if os.environ.get("DESAL_REQUIRE_GLTFPACK"):
        pytest.fail(f"{reason}, but DESAL_REQUIRE_GLTFPACK is set")
    pytest.skip(reason)


def gltfpack():
    if os.environ.get("DESAL_GLTFPACK"):
        return os.environ["DESAL_GLTFPACK"]
    if NPM_GLTFPACK.exists():
        return str(NPM_GLTFPACK)
    return shutil.which("gltfpack")


def eval_rig(out, methods, command):
    env = dict(os.environ, DESAL_GLTFPACK=command)
    return subprocess.run(
        [str(DESAL), "eval", str(ROOT / "pipelines" / "rig-sample.toml"), "--methods", methods,
         "--out", str(out), "--quiet"],
        env=env, capture_output=True, text=True)


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    require(DESAL.exists(), f"{DESAL} is not built (cargo build)")
    command = gltfpack()
    require(command is not None, "gltfpack is not installed (cd tests/gltf && npm ci)")
    out = tmp_path_factory.mktemp("eval")
    run = eval_rig(out, "qslim-optimal,qslim-subset,paper-subset,multipose,gltfpack", command)
    assert run.returncode == 0, run.stderr
    return json.loads((out / "rig-sample" / "eval" / "eval.json").read_text())


def test_gltfpack_is_the_baseline_and_reaches_the_target(report):
    assert report["model"] == "rig" and report["baseline"] == "gltfpack"
    rows = {m["name"]: m for m in report["methods"]}
    g = rows["gltfpack"]
    assert g["simplify_note"].startswith("gltfpack 1.3 "), g["simplify_note"]
    assert "-noq" in g["simplify_note"]
    assert g["stop"] == "target" and g["vertices"] <= 2676 and g["vertices"] > 2600, g["simplify_note"]
    # gltfpack keeps at most 4 influences of the sample's up to 7.
    assert "at most 4 influences" in g["simplify_note"]


def test_desal_s_best_skins_within_0_8_of_gltfpack_held_out(report):
    rows = {m["name"]: m for m in report["methods"]}
    held_out = lambda m: rows[m]["summary"]["held_out"]["vs_full"]
    best = min((m for m in rows if m != "gltfpack"), key=lambda m: held_out(m)["v2f"]["mean"])
    ratio = held_out(best)["v2f"]["mean"] / held_out("gltfpack")["v2f"]["mean"]
    assert ratio <= 0.8, (best, ratio)
    versus = rows[best]["versus_baseline"]["held_out"]["vs_full"]
    assert versus["v2f_wins"] == len(report["evaluated_poses"]) and versus["v2f_p"] < 0.01
    # Subset placement keeps each kept vertex's own joints, at most 4 by default (issue 42,
    # item 5: fitted over the poses), so a vertex skins where the full rig puts it up to
    # the cap's error: 6e-8 m² measured on the sample (0 with max_influences = "all").
    for subset in ("qslim-subset", "paper-subset", "multipose"):
        assert held_out(subset)["v2v"]["mean"] < 1e-6, "kept weights skin (nearly) exactly"


def test_a_failing_gltfpack_is_a_clear_error(tmp_path):
    require(DESAL.exists(), f"{DESAL} is not built (cargo build)")
    fake = tmp_path / "gltfpack"
    fake.write_text("#!/bin/sh\necho 'gltfpack: out of cheese' >&2\nexit 3\n")
    fake.chmod(0o755)
    run = eval_rig(tmp_path / "out", "qslim-subset,gltfpack", str(fake))
    assert run.returncode != 0
    assert "gltfpack" in run.stderr and "out of cheese" in run.stderr, run.stderr
    assert not (tmp_path / "out" / "rig-sample" / "eval").exists()


def test_gltfpack_stopping_early_is_reported(tmp_path):
    """At 350 vertices plain gltfpack stops at its error limit (417 on the sample): the
    note says so and names the count to compare at, and desal still reaches 350 without
    the part fits a pose model would need."""
    require(DESAL.exists(), f"{DESAL} is not built (cargo build)")
    command = gltfpack()
    require(command is not None, "gltfpack is not installed (cd tests/gltf && npm ci)")
    env = dict(os.environ, DESAL_GLTFPACK=command)
    run = subprocess.run(
        [str(DESAL), "eval", str(ROOT / "pipelines" / "rig-sample.toml"), "--methods", "qslim-optimal,gltfpack",
         "--target-vertices", "350", "--folds", "2", "--out", str(tmp_path), "--quiet"],
        env=env, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    rows = {m["name"]: m for m in json.loads((tmp_path / "rig-sample" / "eval" / "eval.json").read_text())["methods"]}
    assert rows["qslim-optimal"]["vertices"] == 350 and rows["qslim-optimal"]["stop"] == "target"
    g = rows["gltfpack"]
    assert g["vertices"] > 350 and g["stop"] != "target", g["simplify_note"]
    assert "stopped early" in g["simplify_note"] and f"--target-vertices {g['vertices']}" in g["simplify_note"]


@pytest.fixture(scope="module")
def lod_levels(tmp_path_factory):
    """`desal eval`'s LOD section (issue 42, item 9) on both samples, against gltfpack."""
    require(DESAL.exists(), f"{DESAL} is not built (cargo build)")
    command = gltfpack()
    require(command is not None, "gltfpack is not installed (cd tests/gltf && npm ci)")
    env = dict(os.environ, DESAL_GLTFPACK=command)
    out = tmp_path_factory.mktemp("lods")
    levels = {}
    for sample in ("rig-sample", "avatar-sample"):
        run = subprocess.run(
            [str(DESAL), "eval", str(ROOT / "pipelines" / f"{sample}.toml"), "--methods", "desal,gltfpack",
             "--skip", "scape,lbs,upsampling,surface", "--folds", "2", "--out", str(out), "--quiet"],
            env=env, capture_output=True, text=True)
        assert run.returncode == 0, run.stderr
        levels[sample] = json.loads((out / sample / "eval" / "eval.json").read_text())["lods"]
        assert "## LOD levels as written" in (out / sample / "eval" / "eval.md").read_text()
    return levels


def mean(values):
    return sum(values) / len(values)


@pytest.mark.parametrize("sample", ["rig-sample", "avatar-sample"])
def test_every_lod_level_beats_gltfpack_at_its_face_count(lod_levels, sample):
    """Issue 42's done-when, level by level: desal's chain as written (4 influences) skins
    held-out frames at most 0.8x gltfpack's v2f at the same face count, with no more
    spikes, every mesh and morph target kept, and no target worse than gltfpack's."""
    levels = lod_levels[sample]
    assert [level["level"] for level in levels] == [1, 2, 3]
    for level in levels:
        rows = {m["method"]: m for m in level["methods"]}
        desal, packed = rows["desal"], rows["gltfpack"]
        where = f"{sample} level {level['level']}"
        assert desal["max_influences"] <= 4 and packed["max_influences"] <= 4, where
        assert desal["faces"] == level["faces"] and packed["faces"] <= desal["faces"], where
        assert len(desal["v2f"]) >= 12, f"{where}: every held-out frame measured"
        assert mean(desal["v2f"]) <= 0.8 * mean(packed["v2f"]), (where, mean(desal["v2f"]), mean(packed["v2f"]))
        assert mean(desal["spikes"]) <= mean(packed["spikes"]), (where, desal["spikes"], packed["spikes"])
        assert all(f > 0 for f in desal["mesh_faces"]), f"{where}: a mesh lost every face"
        for ours, theirs in zip(desal["morphs"], packed["morphs"]):
            assert ours["v2f"] is not None, f"{where}: {ours['target']} lost"
            assert theirs["v2f"] is None or ours["v2f"] <= theirs["v2f"], (where, ours, theirs)
    if sample == "avatar-sample":
        assert {m["target"] for m in levels[0]["methods"][0]["morphs"]} >= {"jawOpen", "eyeBlinkLeft"}
