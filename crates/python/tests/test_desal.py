"""The desal Python package against the CLI's driver, on the bundled CC0 sample.

    pip install ./crates/python && pip install pytest trimesh
    python -m pytest crates/python/tests
"""

import pathlib
import threading

import numpy as np
import pytest
import trimesh

import desal

ROOT = pathlib.Path(__file__).resolve().parents[3]
SAMPLE = ROOT / "data-samples"
POSE_FILES = sorted((SAMPLE / "poses").glob("*.ply"))
TEMPLATE = [p.stem for p in POSE_FILES].index("00_rest")


@pytest.fixture(scope="module")
def sample():
    """The sample as a user has it: PLY files read with trimesh, labels from JSON."""
    meshes = [trimesh.load(p, process=False) for p in POSE_FILES]
    poses = np.stack([np.asarray(m.vertices) for m in meshes])
    faces = np.asarray(meshes[0].faces)
    ids, names = desal.read_labels(SAMPLE / "labels.json")
    return poses, faces, ids, names


@pytest.fixture(scope="module")
def pose_set(sample):
    poses, faces, ids, names = sample
    return desal.PoseSet(poses, faces, ids, template=TEMPLATE, names=[p.stem for p in POSE_FILES], part_names=names)


@pytest.fixture(scope="module")
def cli(tmp_path_factory):
    """`pipelines/sample-hierarchy.toml` with the paper's stage 3 (`method =
    "paper-optimal"`): the sample pipeline plus its hierarchy."""
    out = tmp_path_factory.mktemp("run")
    text = (ROOT / "pipelines" / "sample-hierarchy.toml").read_text()
    text = text.replace("../", f"{ROOT}/").replace("target_vertices = 2500\n", 'target_vertices = 2500\nmethod = "paper-optimal"\n')
    pipeline = out / "paper-hierarchy.toml"
    pipeline.write_text(text)
    reports = desal.run(pipeline, out=out)
    assert [r["dataset"] for r in reports] == ["sample"]
    return out / "sample"


@pytest.fixture(scope="module")
def cli_default(tmp_path_factory):
    """`desal run pipelines/sample-hierarchy.toml` as it is: simplified for its upsampler."""
    out = tmp_path_factory.mktemp("run-default")
    desal.run(ROOT / "pipelines" / "sample-hierarchy.toml", out=out)
    return out / "sample"


@pytest.fixture(scope="module")
def simplified(pose_set):
    # pipelines/sample.toml: 2500 vertices, optimal placement, saliency and balance.
    return desal.simplify_pose_set(pose_set, target_vertices=2500, method="paper", placement="optimal")


def test_simplify_pose_set_is_the_cli_exactly(simplified, cli):
    vertex_map = np.loadtxt(cli / "vertex_map.txt", dtype=np.int64)
    np.testing.assert_array_equal(simplified.vertex_map, vertex_map)
    m = desal.load(cli / "map.dsa")
    np.testing.assert_array_equal(simplified.faces, m["faces"])
    np.testing.assert_array_equal(simplified.vertex_map, m["simp_to_orig"])
    for k, path in enumerate(POSE_FILES):
        vertices, faces = desal.read_mesh(cli / "simplified" / path.name)
        # The CLI writes float32 PLY; the package keeps the same float32 values.
        np.testing.assert_array_equal(simplified.poses[k], vertices, err_msg=path.name)
        np.testing.assert_array_equal(simplified.faces, faces)
    s = desal.load(cli / "saliency.dsa")
    np.testing.assert_array_equal(simplified.saliency, s["saliency"])
    np.testing.assert_array_equal(simplified.weights, s["weights"])
    stage3 = desal.load(cli / "simplified.dsa")
    np.testing.assert_array_equal(simplified.simplified_vertices, stage3["positions"])


def test_the_desal_method_is_its_settings_by_name(pose_set):
    # method="desal" (docs/eval/desal-method.md) is QSlim with subset placement and the
    # per-area error, whatever `placement` says; the per-area error changes the result.
    ours = desal.simplify_pose_set(pose_set, target_vertices=1500, method="desal")
    spelled = desal.simplify_pose_set(
        pose_set, target_vertices=1500, method="qslim", placement="subset", simplify_options={"normalized_error": True}
    )
    np.testing.assert_array_equal(ours.vertex_map, spelled.vertex_map)
    np.testing.assert_array_equal(ours.faces, spelled.faces)
    template = pose_set.poses[TEMPLATE]
    np.testing.assert_array_equal(ours.simplified_vertices, template[ours.vertex_map])
    plain = desal.simplify_pose_set(pose_set, target_vertices=1500, method="qslim", placement="subset")
    assert not np.array_equal(np.sort(plain.vertex_map), np.sort(ours.vertex_map))


def test_the_desal_refit_method_keeps_original_vertices_and_flips_edges(pose_set):
    # method="desal-refit" (docs/eval/desal-method.md) is `desal eval`'s desal-refit on
    # these arrays (tests/e2e/eval.rs checks the Rust side against the eval's mesh): the
    # vertices are original ones, distinct, in the target's number, and the mesh is not
    # desal's; the report counts the flips.
    ours = desal.simplify_pose_set(pose_set, target_vertices=1500, method="desal-refit")
    assert ours.vertex_map.shape == (1500,) and len(np.unique(ours.vertex_map)) == 1500
    template = pose_set.poses[TEMPLATE]
    np.testing.assert_array_equal(ours.simplified_vertices, template[ours.vertex_map])
    plain = desal.simplify_pose_set(pose_set, target_vertices=1500, method="desal")
    assert not np.array_equal(np.sort(plain.vertex_map), np.sort(ours.vertex_map))
    assert ours.report["method"] == "desal-refit"
    assert "edge flips: " in ours.report["simplify"]["note"], ours.report["simplify"]
    # A hierarchy level made by desal-refit is this simplification: D selects its vertices.
    h = desal.hierarchy(pose_set, [1500], method="desal-refit")
    row, col = h.arrays["D0_row"], h.arrays["D0_col"]
    np.testing.assert_array_equal(col[np.argsort(row)], ours.vertex_map)


def test_stage_by_stage_is_the_pipeline(pose_set, simplified):
    fit = desal.fit(pose_set)
    assert fit.rotations.shape == (11, 16, 3, 3) and fit.translations.shape == (11, 16, 3)
    assert fit.residuals.shape == (11, pose_set.vertex_count)
    r = fit.rotations.reshape(-1, 3, 3)
    np.testing.assert_allclose(r @ r.transpose(0, 2, 1), np.broadcast_to(np.eye(3), r.shape), atol=1e-9)
    sal = desal.saliency(pose_set, fit)
    np.testing.assert_array_equal(sal.saliency, simplified.saliency)
    template = pose_set.poses[TEMPLATE]
    v, f, report = desal.simplify(template, pose_set.faces, target_vertices=2500, weights=sal.weights, balance=True)
    np.testing.assert_array_equal(v, simplified.simplified_vertices)
    vertex_map, poses = desal.map(pose_set, v, f, report["simp_to_orig"])
    np.testing.assert_array_equal(vertex_map, simplified.vertex_map)
    np.testing.assert_array_equal(poses, simplified.poses)


def test_subset_placement_maps_exactly(pose_set):
    template = pose_set.poses[TEMPLATE]
    v, f, report = desal.simplify(template, pose_set.faces, target_vertices=800, placement="subset")
    kept = report["simp_to_orig"]
    assert (kept >= 0).all()
    np.testing.assert_array_equal(template[kept], v)
    vertex_map, poses = desal.map(pose_set, v, f, kept)
    np.testing.assert_array_equal(vertex_map, kept)
    np.testing.assert_array_equal(poses, pose_set.poses[:, kept])


@pytest.mark.parametrize(
    "variant",
    ["float32", "fortran", "strided", "list"],
)
def test_dtypes_and_layouts_give_identical_results(sample, simplified, variant):
    poses, faces, ids, _ = sample
    if variant == "float32":
        poses, faces, ids = poses.astype(np.float32), faces.astype(np.int32), ids.astype(np.uint8)
    elif variant == "fortran":
        poses, faces = np.asfortranarray(poses), np.asfortranarray(faces)
    elif variant == "strided":
        wide = np.zeros(poses.shape[:2] + (6,))
        wide[..., ::2] = poses
        poses = wide[..., ::2]
        assert not poses.flags.c_contiguous
        faces = np.repeat(faces, 2, axis=0)[::2]
    elif variant == "list":
        poses = [p for p in poses]
    ps = desal.PoseSet(poses, faces, ids, template=TEMPLATE)
    out = desal.simplify_pose_set(ps, target_vertices=2500)
    np.testing.assert_array_equal(out.vertex_map, simplified.vertex_map)
    np.testing.assert_array_equal(out.faces, simplified.faces)
    np.testing.assert_array_equal(out.poses, simplified.poses)


def test_input_errors_name_the_element(sample):
    poses, faces, ids, _ = sample

    def refused(match, *args, **kwargs):
        with pytest.raises(desal.InputError, match=match):
            desal.PoseSet(*args, **kwargs)

    short = [p for p in poses]
    short[4] = short[4][:-1]
    refused(r"pose004.*13379.*13380|13379.*pose004", short, faces, ids)
    refused(r"face 7 has vertex index -1", poses, np.where(np.arange(len(faces))[:, None] == 7, -1, faces), ids)
    big = faces.copy()
    big[9, 1] = 20000
    refused(r"face 9 .*20000", poses, big, ids)
    nan = poses.copy()
    nan[3, 17, 1] = np.nan
    refused(r"vertex 17 of pose 'pose003'.*NaN", nan, faces, ids)
    refused(r"13379 labels .*13380 vertices|13379.*13380", poses, faces, ids[:-1])
    tiny = ids.copy()
    tiny[:] = 0
    tiny[[5, 6]] = 1
    refused(r"part 1 .*2 vertices|part1", poses, faces, tiny)
    refused(r"poses: must have shape \(poses, vertices, 3\)", poses[..., :2], faces, ids)
    refused(r"faces: must be an integer array", poses, faces.astype(float), ids)
    refused(r"template 11 is out of range", poses, faces, ids, template=11)
    ps = desal.PoseSet(poses, faces, ids)
    with pytest.raises(desal.InputError, match="simplify: give one of target_vertices, target_faces and ratio"):
        desal.simplify_pose_set(ps, target_vertices=100, ratio=0.1)
    with pytest.raises(desal.InputError, match="unknown option nonsense=1"):
        desal.simplify_pose_set(ps, simplify_options={"nonsense": 1})
    with pytest.raises(desal.InputError, match="method"):
        desal.simplify_pose_set(ps, method="fastest")
    with pytest.raises(desal.InputError, match="does not lie on this template"):
        desal.map(ps, poses[0][:500] + 1.0, faces[:10] % 500)
    assert issubclass(desal.InputError, ValueError)


def test_load_reads_every_artifact_kind(cli, tmp_path):
    kinds = {}
    for path in sorted(cli.glob("*.dsa")):
        a = desal.load(path)
        kinds[a["kind"]] = a
        assert a["producer"]["stage"]
    assert sorted(kinds) == sorted(["pose-set", "labels", "fit", "saliency", "simplified", "map", "hierarchy-level"])
    assert kinds["pose-set"]["positions"].shape == (11, 13380, 3)
    assert kinds["fit"]["linear"].shape == (11 * 16, 9)
    assert kinds["simplified"]["simp_to_orig"].dtype == np.int64
    assert kinds["hierarchy-level"]["coarse_to_fine"].shape == (625,)
    forged = tmp_path / "forged.dsa"
    data = bytearray((cli / "map.dsa").read_bytes())
    data[-5] ^= 0xFF
    forged.write_bytes(bytes(data))
    with pytest.raises(desal.InputError, match="forged.dsa"):
        desal.load(forged)
    with pytest.raises(desal.InputError, match="truncated.dsa"):
        truncated = tmp_path / "truncated.dsa"
        truncated.write_bytes(bytes(data[:40]))
        desal.load(truncated)


def test_the_default_hierarchy_is_the_cli_default(pose_set, cli_default):
    # Both simplify for the upsampler (objective = "hierarchy", method "desal-upsample").
    h = desal.hierarchy(pose_set, [2500, 625])
    from_cli = desal.load_hierarchy(cli_default / "hierarchy.npz")
    for key in h.arrays:
        np.testing.assert_array_equal(h.arrays[key], from_cli.arrays[key], err_msg=key)
    paper = desal.hierarchy(pose_set, [2500, 625], method="paper-optimal")
    errors = [[step["heldout_fitted"]["mse"] for step in x.report] for x in (h, paper)]
    assert all(a < b for a, b in zip(*errors)), errors


def test_hierarchy_is_the_cli_and_round_trips_through_graphcmr(pose_set, cli, tmp_path):
    h = desal.hierarchy(pose_set, [2500, 625], method="paper-optimal")
    assert h.levels == [13380, 2500, 625]
    from_cli = desal.load_hierarchy(cli / "hierarchy.npz")
    assert sorted(h.arrays) == sorted(from_cli.arrays)
    for key in h.arrays:
        np.testing.assert_array_equal(h.arrays[key], from_cli.arrays[key], err_msg=key)
    h.save(tmp_path / "hierarchy.npz")
    assert (tmp_path / "hierarchy.npz").read_bytes() == (cli / "hierarchy.npz").read_bytes()

    path = tmp_path / "mesh_downsampling.npz"
    desal.save_graphcmr(h, path)
    # GraphCMR's own loading code, unchanged.
    data = np.load(path, encoding="latin1", allow_pickle=True)
    A, U, D = data["A"], data["U"], data["D"]
    assert [a.shape for a in A] == [(n, n) for n in h.levels]
    assert [u.shape for u in U] == [(13380, 2500), (2500, 625)]
    assert [d.shape for d in D] == [(2500, 13380), (625, 2500)]
    for k in range(2):
        assert U[k].format == "csc" and D[k].format == "csc"
        np.testing.assert_array_equal(U[k].toarray(), h.U[k].toarray())
        np.testing.assert_allclose(np.asarray(U[k].sum(axis=1)).ravel(), 1.0, atol=1e-12)
        np.testing.assert_array_equal(np.asarray(D[k].argmax(axis=1)).ravel(), h.map[k])
    np.testing.assert_array_equal(data["F"][1], h.faces[1])


def test_progress_callback_and_released_gil(pose_set):
    calls = []
    ticks = []
    stop = threading.Event()

    def ticker():
        while not stop.is_set():
            ticks.append(1)
            stop.wait(0.001)

    thread = threading.Thread(target=ticker)
    thread.start()
    try:
        desal.hierarchy(pose_set, [2500, 625], progress=lambda step, done, total: calls.append((step, done, total)))
    finally:
        stop.set()
        thread.join()
    assert calls and all(0 <= done <= total for _, done, total in calls)
    steps = {step for step, _, _ in calls}
    assert steps, calls
    # A thread that needs the GIL kept running while the hierarchy was computed.
    assert len(ticks) > 10


def test_discovered_parts_without_labels(sample):
    poses, faces, _, _ = sample
    ps = desal.PoseSet(poses, faces, None, template=TEMPLATE)
    assert ps.parts_report is not None and len(ps.part_names) >= 2
    out = desal.simplify_pose_set(ps, target_vertices=2500)
    assert out.poses.shape == (11, 2500, 3)


def test_help_reads_well():
    doc = desal.simplify.__doc__
    assert "target_vertices" in doc and "placement" in doc
    assert "InputError" in desal.PoseSet.__doc__ and "template" in desal.PoseSet.__doc__
    for f in (desal.fit, desal.saliency, desal.map, desal.simplify_pose_set, desal.hierarchy, desal.run, desal.load):
        assert f.__doc__ and len(f.__doc__) > 80, f.__name__

