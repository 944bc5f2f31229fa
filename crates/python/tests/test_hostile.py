"""Issue 39's Python rows: hostile arguments, paths and files (one test per row, named
after it). Every bad argument is an ``InputError`` in the caller's words, no reader
follows a path into a FIFO or device, every writer follows desal's one rule for what may
be replaced, and no Rust panic escapes as ``PanicException``.

    python -m pytest crates/python/tests/test_hostile.py
"""

import json
import os
import pathlib
import stat
import struct
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import desal

ROOT = pathlib.Path(__file__).resolve().parents[3]
RIG = ROOT / "data-samples" / "rig.glb"


def grid(n=12, poses=5, seed=0):
    """An n x n vertex grid, `poses` jittered copies of it, and two parts (x <= 5, x > 5)."""
    xs, ys = np.meshgrid(np.arange(n), np.arange(n))
    vertices = np.stack([xs.ravel(), ys.ravel(), np.zeros(n * n)], 1).astype(float)
    faces = []
    for i in range(n - 1):
        for j in range(n - 1):
            a = i * n + j
            faces += [[a, a + 1, a + n], [a + 1, a + n + 1, a + n]]
    rng = np.random.default_rng(seed)
    stack = np.stack([vertices + rng.normal(0, 0.01, vertices.shape) for _ in range(poses)])
    return stack, np.array(faces), (vertices[:, 0] > 5).astype(np.int64)


@pytest.fixture(scope="module")
def small():
    poses, faces, labels = grid()
    return desal.PoseSet(poses, faces, labels)


@pytest.fixture(scope="module")
def small_hierarchy(small):
    return desal.hierarchy(small, [60])


def device(folder, name, major_minor):
    """A character device node: made in `folder` when we may (root), so that a writer
    that broke the rule would replace only this copy; else the system's own."""
    path = folder / name
    try:
        os.mknod(path, stat.S_IFCHR | 0o666, os.makedev(*major_minor))
        return path
    except (PermissionError, AttributeError):
        return pathlib.Path("/dev") / {(1, 3): "null", (1, 5): "zero", (1, 7): "full"}[major_minor]


def is_char_device(path):
    return stat.S_ISCHR(os.stat(path).st_mode)


def leftovers(folder):
    return sorted(p.name for p in folder.iterdir() if p.name.endswith(".tmp"))


# ---- D7: every Python writer follows desal-io's rule for what may be replaced ----

WRITERS = {
    "save_graphcmr": lambda h, path: desal.save_graphcmr(h, path),
    "Hierarchy.save": lambda h, path: h.save(path),
}


@pytest.mark.parametrize("writer", sorted(WRITERS))
def test_d7_a_character_device_is_written_through(small_hierarchy, tmp_path, writer):
    null = device(tmp_path, "null", (1, 3))
    WRITERS[writer](small_hierarchy, null)
    assert is_char_device(null), "the device was replaced by a file"
    full = device(tmp_path, "full", (1, 7))
    with pytest.raises(desal.Error, match="No space left"):
        WRITERS[writer](small_hierarchy, full)
    assert is_char_device(full)
    assert leftovers(tmp_path) == []


@pytest.mark.parametrize("writer", sorted(WRITERS))
def test_d7_a_folder_or_fifo_is_refused(small_hierarchy, tmp_path, writer):
    folder = tmp_path / "folder"
    folder.mkdir()
    (folder / "keep.txt").write_text("mine")
    with pytest.raises(desal.InputError, match="folder.*directory"):
        WRITERS[writer](small_hierarchy, folder)
    assert (folder / "keep.txt").read_text() == "mine"
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    with pytest.raises(desal.InputError, match="FIFO"):
        WRITERS[writer](small_hierarchy, fifo)
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    assert leftovers(tmp_path) == []


@pytest.mark.parametrize("writer", sorted(WRITERS))
def test_d7_a_symlink_is_replaced_not_written_into(small_hierarchy, tmp_path, writer):
    # The documented choice (desal_io::confine, rule 3): the rename replaces the link
    # itself; whatever it pointed at is left as it was.
    target = tmp_path / "target.npz"
    target.write_bytes(b"someone else's file")
    link = tmp_path / "link.npz"
    link.symlink_to(target)
    WRITERS[writer](small_hierarchy, link)
    assert not link.is_symlink() and link.read_bytes()[:2] == b"PK"
    assert target.read_bytes() == b"someone else's file"


def test_d7_an_error_leaves_the_old_file_and_nothing_else(small_hierarchy, tmp_path):
    path = tmp_path / "mesh_downsampling.npz"
    path.write_bytes(b"old")
    broken = desal.Hierarchy(small_hierarchy.arrays)
    broken.A = [lambda: None]  # cannot be pickled: np.savez fails before any write
    with pytest.raises(Exception):
        desal.save_graphcmr(broken, path)
    assert path.read_bytes() == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mesh_downsampling.npz"]
    # A write that fails half-way (the file-size limit, as a full disk would) removes
    # its temp file and leaves the destination as it was.
    code = f"""
        import resource, signal, desal, pathlib
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (4096, resource.RLIM_INFINITY))
        try:
            desal._desal._write_file({str(path)!r}, b"x" * 100000)
        except desal.Error as e:
            print("Error", e)
    """
    out = run_python(code)
    assert out.startswith("Error") and "mesh_downsampling.npz" in out, out
    assert path.read_bytes() == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mesh_downsampling.npz"]


def test_d7_simplify_rig_refuses_a_folder_as_output_before_working(tmp_path):
    with pytest.raises(desal.InputError, match="directory"):
        desal.simplify_rig(RIG, tmp_path, target_vertices=100, frames=1)


# ---- D8: no frames count or integer kills the interpreter ----


def test_d8_huge_frames_refused(tmp_path):
    out = tmp_path / "out.glb"
    with pytest.raises(desal.InputError, match=rf"frames=1000000000000 .*{desal.MAX_RIG_FRAMES}"):
        desal.simplify_rig(RIG, out, target_vertices=100, frames=10**12)
    assert desal.MAX_RIG_FRAMES == 65_536
    with pytest.raises(desal.InputError, match=rf"frames={desal.MAX_RIG_FRAMES + 1} "):
        desal.simplify_rig(RIG, out, target_vertices=100, frames=desal.MAX_RIG_FRAMES + 1)
    for frames, words in [(10**30, "is too large"), (-1, "must be a non-negative integer"),
                          (True, "frames=True must be"), (1.5, "frames=1.5 must be")]:
        with pytest.raises(desal.InputError, match=words):
            desal.simplify_rig(RIG, out, target_vertices=100, frames=frames)
    assert not out.exists()


def test_d8_integers_too_big_for_rust_are_input_errors(small):
    poses, faces, labels = grid()
    for template in (10**30, -1, 2**64):
        with pytest.raises(desal.InputError, match=rf"template={template} "):
            desal.PoseSet(poses, faces, labels, template=template)
    with pytest.raises(desal.InputError, match=r"jobs=-1 must be a non-negative integer"):
        desal.run(ROOT / "pipelines" / "sample.toml", jobs=-1)
    with pytest.raises(desal.InputError, match=r"target_vertices=\d+ is too large"):
        desal.simplify(poses[0], faces, target_vertices=10**30)


# ---- D14: InputError, in the caller's words ----

D14_CASES = {
    "ratio nan": (lambda ps, p, f: desal.simplify(p[0], f, ratio=float("nan")), r"simplify: ratio=nan must be a finite"),
    "ratio str": (lambda ps, p, f: desal.simplify(p[0], f, ratio="x"), r"ratio='x' must be a number"),
    "negative target": (lambda ps, p, f: desal.simplify(p[0], f, target_vertices=-5), r"target_vertices=-5 must be"),
    "bool target": (lambda ps, p, f: desal.simplify(p[0], f, target_vertices=True), r"target_vertices=True must be"),
    "placement": (lambda ps, p, f: desal.simplify(p[0], f, placement="bad"), r"placement='bad'"),
    "balance": (lambda ps, p, f: desal.simplify(p[0], f, balance="yes"), r"balance='yes' must be True or False"),
    "floor inf": (lambda ps, p, f: desal.saliency(ps, floor=float("inf")), r"floor=inf must be a finite"),
    "exclude str": (lambda ps, p, f: desal.saliency(ps, exclude="pose001"), r"exclude='pose001'"),
    "exclude unknown": (lambda ps, p, f: desal.saliency(ps, exclude=["nope"]), r"exclude pose 'nope'"),
    "fit method": (lambda ps, p, f: desal.fit(ps, method="nope"), r"method='nope'"),
    "fit_method": (
        lambda ps, p, f: desal.simplify_pose_set(ps, target_vertices=50, fit_method="nope"),
        r"fit_method='nope'",
    ),
    "options nan": (
        lambda ps, p, f: desal.simplify_pose_set(ps, target_vertices=50, simplify_options={"boundary_weight": np.nan}),
        r"boundary_weight=nan must be a finite",
    ),
    "options not a dict": (
        lambda ps, p, f: desal.simplify_pose_set(ps, target_vertices=50, simplify_options="ratio=0.1"),
        r"simplify_options must be a dict",
    ),
    "unknown option": (
        lambda ps, p, f: desal.simplify_pose_set(ps, simplify_options={"nonsense": 1}),
        r"unknown option nonsense=1",
    ),
    "complex option": (lambda ps, p, f: desal.simplify(p[0], f, ratio=0.5j), r"ratio=0.5j must be a number"),
    "levels int": (lambda ps, p, f: desal.hierarchy(ps, 5), r"levels=5 must be a list"),
    "levels str": (lambda ps, p, f: desal.hierarchy(ps, ["a"]), r"levels\[0\]|levels=\['a'\]"),
    "method type": (lambda ps, p, f: desal.simplify_pose_set(ps, method=3), r"method=3 must be a str"),
    "names str": (lambda ps, p, f: desal.PoseSet(p, f, names="abc"), r"names: must be a list of str"),
    "parts key": (lambda ps, p, f: desal.PoseSet(p, f, parts='{"count": "x"}'), r"count='x' must be"),
    "parts dict": (lambda ps, p, f: desal.PoseSet(p, f, parts={"count": -2}), r"count=-2 must be"),
    "parts nan": (lambda ps, p, f: desal.PoseSet(p, f, parts={"rigid_tolerance": np.nan}), r"parts=.*nan.* must hold"),
    "graphcmr not a hierarchy": (lambda ps, p, f: desal.save_graphcmr(5, "unused.npz"), r"h: must be a desal.Hierarchy"),
    "not a pose set": (lambda ps, p, f: desal.fit(5), r"ps: must be a desal.PoseSet, not int"),
    "progress": (lambda ps, p, f: desal.fit(ps, progress=5), r"progress=5 must be callable"),
    "run flag": (lambda ps, p, f: desal.run(ROOT / "pipelines" / "sample.toml", force="yes"), r"force='yes'"),
    "run missing pipeline": (lambda ps, p, f: desal.run("/nonexistent/pipeline.toml"), r"pipeline.toml"),
    "path type": (lambda ps, p, f: desal.load(5), r"path=5 must be a path"),
}


@pytest.mark.parametrize("case", sorted(D14_CASES))
def test_d14_bad_input_is_an_input_error_in_the_callers_words(small, case):
    poses, faces, _ = grid()
    call, words = D14_CASES[case]
    with pytest.raises(desal.InputError, match=words) as caught:
        call(small, poses, faces)
    message = str(caught.value)
    assert "line 1 column" not in message and "usize" not in message and "f64" not in message, message


def test_d14_numpy_scalars_are_numbers(small):
    poses, faces, _ = grid()
    v, f, _ = desal.simplify(poses[0], faces, target_vertices=np.int64(60), boundary_weight=np.float32(2.0))
    assert len(v) == 60
    desal.saliency(small, percentile=np.float64(90.0), exclude=np.array(["pose001"]))


# ---- D15: only real numbers are positions ----

D15_ARRAYS = {
    "complex": lambda a: a.astype(complex) + 1j,
    "bool": lambda a: a > 0,
    "str": lambda a: a.astype(str),
    "object": lambda a: a.astype(object),
}


@pytest.mark.parametrize("kind", sorted(D15_ARRAYS))
def test_d15_complex_poses_refused(kind):
    """Complex, bool, str and object arrays are refused like non-integer faces, naming
    the argument and the dtype, at every entry point that takes positions or weights."""
    poses, faces, labels = grid()
    small = desal.PoseSet(poses, faces, labels)
    bad = D15_ARRAYS[kind]
    calls = {
        "poses": lambda: desal.PoseSet(bad(poses), faces, labels),
        r"poses\[0\]": lambda: desal.PoseSet([bad(p) for p in poses], faces, labels),
        "vertices": lambda: desal.simplify(bad(poses[0]), faces, target_vertices=60),
        "weights": lambda: desal.simplify(poses[0], faces, target_vertices=60, weights=bad(np.ones(len(labels)))),
        "simplified_vertices": lambda: desal.map(small, bad(poses[0]), faces),
        "faces": lambda: desal.PoseSet(poses, bad(faces), labels),
        "labels": lambda: desal.PoseSet(poses, faces, bad(labels)),
    }
    for argument, call in calls.items():
        with pytest.raises(desal.InputError, match=rf"^{argument}: must be an? (float|integer) array, not "):
            call()


def test_d15_integer_poses_are_still_numbers():
    poses, faces, labels = grid()
    rounded = np.round(poses * 100).astype(np.int32)
    np.testing.assert_array_equal(desal.PoseSet(rounded, faces, labels).poses, rounded)


# ---- D16: a fit belongs to the pose set it was computed from ----


def test_d16_a_fit_of_another_pose_set_refused():
    poses, faces, labels = grid()
    big = desal.PoseSet(poses, faces, labels)
    other = desal.PoseSet(grid(seed=1)[0], faces, labels)  # same sizes, other positions
    keep = (faces < 100).all(axis=1)
    small = desal.PoseSet(poses[:, :100], faces[keep], labels[:100])
    fit = desal.fit(big)
    with pytest.raises(desal.InputError, match=r"fit: was computed from another pose set \(5 poses x 144 vertices\)"):
        desal.saliency(small, fit)
    with pytest.raises(desal.InputError, match="another pose set"):
        desal.saliency(other, fit)
    # The same arrays are the same pose set: its fit applies.
    again = desal.PoseSet(poses, faces, labels)
    np.testing.assert_array_equal(desal.saliency(again, fit).saliency, desal.saliency(big, fit).saliency)


# ---- D17: every reader refuses what is not a regular file ----


def run_python(code, timeout=60):
    """`code` in a fresh interpreter (a reader that blocked on a FIFO would hang the
    test run otherwise); its stdout."""
    done = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, timeout=timeout
    )
    assert done.returncode == 0, done.stderr
    return done.stdout.strip()


READERS = {
    "load": ("dsa", "desal.load(path)"),
    "load_hierarchy": ("npz", "desal.load_hierarchy(path)"),
    "read_mesh": ("ply", "desal.read_mesh(path)"),
    "read_labels": ("txt", "desal.read_labels(path)"),
    "simplify_rig": ("glb", "desal.simplify_rig(path, folder / 'out.glb', target_vertices=100, frames=1)"),
    "run": ("toml", "desal.run(path, out=folder / 'out')"),
}


@pytest.mark.parametrize("kind", ["fifo", "device", "folder"])
@pytest.mark.parametrize("reader", sorted(READERS))
def test_d17_readers_refuse_non_regular_files(tmp_path, reader, kind):
    extension, call = READERS[reader]
    path = tmp_path / f"input.{extension}"
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "device":
        zero = device(tmp_path, f"input.{extension}", (1, 5))
        if zero != path:
            path.symlink_to(zero)  # not root: a symlink to /dev/zero, followed
    else:
        path.mkdir()
    what = {"fifo": "a FIFO", "device": "a device", "folder": "a directory"}[kind]
    out = run_python(
        f"""
        import pathlib, desal
        folder = pathlib.Path({str(tmp_path)!r})
        path = folder / {path.name!r}
        try:
            {call}
            print("accepted")
        except desal.InputError as e:
            print("InputError", e)
        """
    )
    assert out.startswith("InputError") and what in out and path.name in out, out


# ---- No Rust panic reaches Python as PanicException ----


def short_stride_glb(folder):
    """The sample rig with its body's POSITION view given a byteStride of 4, smaller than
    the 12-byte element (issue 39, D1): the gltf crate panics reading it."""
    data = RIG.read_bytes()
    (json_length,) = struct.unpack_from("<I", data, 12)
    doc = json.loads(data[20 : 20 + json_length])
    body = next(m for m in doc["meshes"] if m.get("name") == "Body")
    accessor = doc["accessors"][body["primitives"][0]["attributes"]["POSITION"]]
    doc["bufferViews"][accessor["bufferView"]]["byteStride"] = 4
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    chunks = struct.pack("<II", len(text), 0x4E4F534A) + text + data[20 + json_length :]
    path = folder / "short-stride.glb"
    path.write_bytes(struct.pack("<III", 0x46546C67, 2, 12 + len(chunks)) + chunks)
    return path


def test_panics_a_glb_that_panics_the_gltf_crate_is_an_exception(tmp_path):
    # `except Exception` catches it: desal.Error today (the panic, caught), InputError
    # once the rig reader refuses the stride itself.
    with pytest.raises((desal.Error, desal.InputError), match="simplify_rig|short-stride.glb"):
        desal.simplify_rig(short_stride_glb(tmp_path), tmp_path / "out.glb", target_vertices=100, frames=1)
    assert not (tmp_path / "out.glb").exists()


def test_panics_become_desal_error_naming_the_call():
    with pytest.raises(desal.Error, match=r"_panic_for_tests: internal error \(a Rust panic: boom\)"):
        desal._desal._panic_for_tests("boom")
    # The interpreter and the package still work afterwards.
    poses, faces, labels = grid()
    assert desal.PoseSet(poses, faces, labels).vertex_count == 144
