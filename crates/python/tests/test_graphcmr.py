"""Issue 41, item 7: save_graphcmr's mesh_downsampling.npz loads as GraphCMR loads it
(``np.load(path, encoding='latin1', allow_pickle=True)``, then ``A``, ``U``, ``D``), here
(numpy 2) and in GraphCMR's pinned environment (Python 3.6, numpy 1.15.4, scipy 1.2.0),
where a file that ``np.savez`` writes under numpy 2 fails with ``No module named
'numpy._core'`` and one written under scipy 1.8+ with ``No module named
'scipy.sparse._csc'``.

    python -m pytest crates/python/tests/test_graphcmr.py

The two tests that run another Python need one each (.ci/run makes both from pyenv's):
``DESAL_PY36``, a Python 3.6 with ``numpy==1.15.4 scipy==1.2.0``, and ``DESAL_PY39``, a
Python 3.9 with ``numpy==1.23.5 scipy==1.9.3`` (many body-regression projects pin
numpy < 1.24). Without them they skip, and the pickletools check of the names in the
file is what runs everywhere.
"""

import io
import json
import os
import pathlib
import pickletools
import subprocess
import warnings
import zipfile

import numpy as np
import pytest
import scipy.sparse

import desal

ROOT = pathlib.Path(__file__).resolve().parents[3]
SAMPLE = ROOT / "data-samples"

#: Every global a portable pickle may name, as "module name". Each is importable in
#: numpy 1.15.4 / scipy 1.2.0 on Python 3.6 (test_loads_in_graphcmrs_environment imports
#: them there) and, without a warning, in numpy 2 / scipy 1.14+ (the round trip below
#: turns warnings into errors). Not scipy.sparse.csc.csc_matrix: scipy 1.8+ warns on it.
PORTABLE_GLOBALS = {
    "numpy.core.multiarray _reconstruct",
    "numpy ndarray",
    "numpy dtype",
    "scipy.sparse csc_matrix",
}

#: GraphCMR's loading code (utils/mesh.py: get_graph_params and scipy_to_pytorch, without
#: torch), run in another Python: it loads the file, turns every matrix into COO as
#: GraphCMR does and A into CSR as adjmat_sparse does, imports each allowed global, saves
#: the COO arrays and faces as plain arrays (argv[2]) and prints what it found as JSON.
#: With argv[4] (the folder of desal/_graphcmr.py) and argv[5], it also writes the
#: matrices it loaded again with that numpy and scipy. Python 3.6 syntax.
LOAD_AS_GRAPHCMR = r"""
import importlib, json, sys
import numpy as np
import scipy, scipy.sparse

path, out, names = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
data = np.load(path, encoding='latin1', allow_pickle=True)
A, U, D = data['A'], data['U'], data['D']
found = {"python": list(sys.version_info[:2]), "numpy": np.__version__, "scipy": scipy.__version__,
         "kinds": {key: str(data[key].dtype) for key in ("A", "U", "D", "F")}, "matrices": {}}
arrays = {}
for key, matrices in (("A", A), ("U", U), ("D", D)):
    for k, m in enumerate(matrices):
        coo = scipy.sparse.coo_matrix(m)
        name = "%s%d" % (key, k)
        arrays[name + "_ij"] = np.array([coo.row, coo.col])
        arrays[name + "_data"] = coo.data
        found["matrices"][name] = {
            "csc_matrix": type(m) is scipy.sparse.csc_matrix, "shape": list(m.shape),
            "dtype": str(m.dtype), "indices": str(m.indices.dtype), "nnz": int(m.nnz),
            "sorted": bool(m.has_sorted_indices), "csr_nnz": int(scipy.sparse.csr_matrix(m).nnz)}
for k, f in enumerate(data['F']):
    arrays["F%d" % k] = f
for name in names:
    module, attr = name.split()
    getattr(importlib.import_module(module), attr)
np.savez(out, **arrays)
if len(sys.argv) > 4:
    sys.path.insert(0, sys.argv[4])
    import _graphcmr
    with open(sys.argv[5], "wb") as rewritten:
        rewritten.write(_graphcmr.npz_bytes({key: list(data[key]) for key in ("A", "D", "U", "F")}))
print(json.dumps(found))
"""


@pytest.fixture(scope="module")
def h():
    """The sample's three-level hierarchy (13380 → 2500 → 625 vertices, GraphCMR's SMPL
    file has 6890 → 1723 → 431), from desal's own readers."""
    files = sorted((SAMPLE / "poses").glob("*.ply"))
    meshes = [desal.read_mesh(p) for p in files]
    ids, _ = desal.read_labels(SAMPLE / "labels.json")
    template = [p.stem for p in files].index("00_rest")
    ps = desal.PoseSet(np.stack([v for v, _ in meshes]), meshes[0][1], ids, template=template)
    return desal.hierarchy(ps, [2500, 625])


@pytest.fixture(scope="module")
def saved(h, tmp_path_factory):
    path = tmp_path_factory.mktemp("graphcmr") / "mesh_downsampling.npz"
    desal.save_graphcmr(h, path)
    return path


def matrices(h):
    """Every matrix of ``h`` by its file name (A0, U1, ...) with its COO arrays from the
    hierarchy.npz layout (row, col, data, shape), the reference computed without scipy."""
    for key in ("A", "U", "D"):
        for k, m in enumerate(getattr(h, key)):
            row, col, data, shape = (h.arrays[f"{key}{k}_{p}"] for p in ("row", "col", "data", "shape"))
            yield f"{key}{k}", m, (row, col, data, tuple(int(n) for n in shape))


def sorted_coo(row, col, data):
    order = np.lexsort((col, row))
    return row[order], col[order], data[order]


def test_hierarchy_matrices_are_scipy_csc_from_both_constructors(h, tmp_path):
    h.save(tmp_path / "hierarchy.npz")
    loaded = desal.load_hierarchy(tmp_path / "hierarchy.npz")
    for hierarchy in (h, loaded):
        assert [len(hierarchy.A), len(hierarchy.D), len(hierarchy.U)] == [3, 2, 2]
        for name, m, (row, col, data, shape) in matrices(hierarchy):
            assert type(m) is scipy.sparse.csc_matrix and m.dtype == np.float64, name
            assert m.shape == shape and m.has_canonical_format, name
            coo = m.tocoo()
            for got, want in zip(sorted_coo(coo.row, coo.col, coo.data), sorted_coo(row, col, data)):
                np.testing.assert_array_equal(got, want, err_msg=name)


def test_round_trip_as_graphcmr_loads_it(h, saved):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # numpy 2 loads numpy.core.* names without a warning
        data = np.load(saved, encoding="latin1", allow_pickle=True)
        A, U, D, F = data["A"], data["U"], data["D"], data["F"]
    assert sorted(data.files) == ["A", "D", "F", "U"]
    assert [x.dtype for x in (A, U, D, F)] == [np.dtype(object)] * 4
    assert [x.shape for x in (A, U, D, F)] == [(3,), (2,), (2,), (3,)]
    assert [a.shape for a in A] == [(13380, 13380), (2500, 2500), (625, 625)]
    assert [u.shape for u in U] == [(13380, 2500), (2500, 625)]
    assert [d.shape for d in D] == [(2500, 13380), (625, 2500)]
    loaded = {"A": A, "U": U, "D": D}
    for name, m, _ in matrices(h):
        got = loaded[name[0]][int(name[1:])]
        assert type(got) is scipy.sparse.csc_matrix and got.dtype == np.float64, name
        assert got.indices.dtype == got.indptr.dtype == np.int32, name
        for part in ("indptr", "indices", "data"):
            np.testing.assert_array_equal(getattr(got, part), getattr(m, part), err_msg=f"{name}.{part}")
        # GraphCMR's scipy_to_pytorch: COO row and col as one LongTensor, data as floats.
        coo = scipy.sparse.coo_matrix(got)
        assert np.array([coo.row, coo.col]).shape == (2, m.nnz)
    for k in range(2):
        np.testing.assert_allclose(np.asarray(U[k].sum(axis=1)).ravel(), 1.0, atol=1e-12)
        np.testing.assert_array_equal(np.asarray(D[k].argmax(axis=1)).ravel(), h.map[k])
    for k in range(3):
        np.testing.assert_array_equal(F[k], h.faces[k])
        assert F[k].dtype == h.faces[k].dtype


def test_the_same_matrices_give_the_same_bytes(h, saved, tmp_path):
    # Another format for A, and for U[0] unsorted row indices with every entry split in
    # two halves: the writer makes each matrix canonical CSC, so the file is the same.
    other = desal.Hierarchy(h.arrays)
    other.A = [m.tocsr() for m in h.A]
    u = h.U[0]
    columns = np.repeat(np.arange(u.shape[1]), np.diff(u.indptr))
    rows_descending = np.lexsort((-u.indices, columns))
    messy = scipy.sparse.csc_matrix(
        (np.repeat(u.data[rows_descending] / 2, 2), np.repeat(u.indices[rows_descending], 2), 2 * u.indptr),
        shape=u.shape,
    )
    assert not messy.has_canonical_format
    other.U = [messy, h.U[1]]
    desal.save_graphcmr(other, tmp_path / "other.npz")
    assert (tmp_path / "other.npz").read_bytes() == saved.read_bytes()
    assert messy.nnz == 2 * u.nnz and not messy.has_sorted_indices  # the caller's, as it was


def test_what_is_not_a_sparse_matrix_or_faces_is_an_input_error(h, tmp_path):
    path = tmp_path / "mesh_downsampling.npz"
    other = desal.Hierarchy(h.arrays)
    other.D = [h.D[0], h.D[1].toarray()]
    with pytest.raises(desal.InputError, match=r"h\.D\[1\]: must be a scipy.sparse matrix, not ndarray"):
        desal.save_graphcmr(other, path)
    other = desal.Hierarchy(h.arrays)
    other.faces = [f.astype(float) for f in h.faces]
    with pytest.raises(desal.InputError, match=r"h\.faces\[0\]: must be \(m, 3\) integers, not float64"):
        desal.save_graphcmr(other, path)
    assert not path.exists()


def pickled_globals(npz_bytes):
    """Every global the pickles of an .npz name ("module name"), and the highest
    protocol of their opcodes, read by pickletools (nothing is unpickled)."""
    names, protocol = set(), 0
    with zipfile.ZipFile(io.BytesIO(npz_bytes)) as archive:
        for entry in archive.namelist():
            raw = io.BytesIO(archive.read(entry))
            version = np.lib.format.read_magic(raw)
            read_header = {(1, 0): np.lib.format.read_array_header_1_0, (2, 0): np.lib.format.read_array_header_2_0}
            _, _, dtype = read_header[version](raw)
            if not dtype.hasobject:
                continue
            # STACK_GLOBAL (protocol 4) takes its two names from the stack: follow the
            # strings pushed, directly or through the memo; anything else pushes None.
            pushed, memo = [], {}
            for opcode, arg, _ in pickletools.genops(raw):
                protocol = max(protocol, opcode.proto)
                if opcode.name == "GLOBAL":
                    names.add(arg)
                elif opcode.name == "STACK_GLOBAL":
                    names.add(" ".join(str(name) for name in pushed[-2:]))
                elif opcode.name == "MEMOIZE":
                    memo[len(memo)] = pushed[-1]
                elif opcode.name in ("PUT", "BINPUT", "LONG_BINPUT"):
                    memo[arg] = pushed[-1]
                elif opcode.name in ("GET", "BINGET", "LONG_BINGET"):
                    pushed.append(memo[arg])
                else:
                    pushed.append(arg if "UNICODE" in opcode.name else None)
    return names, protocol


def test_pickles_name_only_globals_numpy_1_15_and_scipy_1_2_have(h, saved):
    names, protocol = pickled_globals(saved.read_bytes())
    assert names == PORTABLE_GLOBALS
    assert protocol <= 3  # Python 3.6 reads up to 4
    # The check can fail: what np.savez writes here names this numpy's and scipy's own
    # modules (numpy._core, scipy.sparse._csc, or scipy.sparse.csc under scipy 1.7).
    buffer = io.BytesIO()
    objects = np.empty(len(h.D), dtype=object)
    objects[:] = h.D
    np.savez(buffer, D=objects)
    savez_names, _ = pickled_globals(buffer.getvalue())
    assert any("csc_matrix" in n for n in savez_names) and savez_names - PORTABLE_GLOBALS


def run_graphcmr_loader(python, saved, tmp_path, rewrite=None):
    """LOAD_AS_GRAPHCMR under ``python`` (warnings are errors): what it found, and the
    arrays it saved."""
    out = tmp_path / "loaded.npz"
    command = [python, "-W", "error", "-c", LOAD_AS_GRAPHCMR, str(saved), str(out), json.dumps(sorted(PORTABLE_GLOBALS))]
    if rewrite is not None:
        command += [str(pathlib.Path(desal.__file__).parent), str(rewrite)]
    done = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout), np.load(out)


def check_loaded_as_graphcmr(h, found, arrays):
    assert found["kinds"] == {"A": "object", "U": "object", "D": "object", "F": "object"}
    assert sorted(found["matrices"]) == ["A0", "A1", "A2", "D0", "D1", "U0", "U1"]
    for name, m, (row, col, data, shape) in matrices(h):
        seen = found["matrices"][name]
        assert seen == {
            "csc_matrix": True, "shape": list(shape), "dtype": "float64", "indices": "int32",
            "nnz": m.nnz, "sorted": True, "csr_nnz": m.nnz,
        }, name
        i, j = arrays[f"{name}_ij"]
        for got, want in zip(sorted_coo(i, j, arrays[f"{name}_data"]), sorted_coo(row, col, data)):
            np.testing.assert_array_equal(got, want, err_msg=name)
    for k in range(3):
        np.testing.assert_array_equal(arrays[f"F{k}"], h.faces[k])


def test_loads_in_graphcmrs_environment(h, saved, tmp_path):
    python = os.environ.get("DESAL_PY36")
    if not python:
        pytest.skip("needs DESAL_PY36: a Python 3.6 with numpy==1.15.4 scipy==1.2.0 (.ci/run makes one)")
    found, arrays = run_graphcmr_loader(python, saved, tmp_path)
    assert (found["python"], found["numpy"], found["scipy"]) == ([3, 6], "1.15.4", "1.2.0")
    check_loaded_as_graphcmr(h, found, arrays)


def test_loads_in_numpy_1_23_which_writes_the_same_bytes(h, saved, tmp_path):
    python = os.environ.get("DESAL_PY39")
    if not python:
        pytest.skip("needs DESAL_PY39: a Python 3.9 with numpy==1.23.5 scipy==1.9.3 (.ci/run makes one)")
    rewritten = tmp_path / "rewritten.npz"
    found, arrays = run_graphcmr_loader(python, saved, tmp_path, rewrite=rewritten)
    assert found["numpy"].startswith("1.") and found["scipy"].startswith("1.")
    check_loaded_as_graphcmr(h, found, arrays)
    # The file written under numpy 1.23 / scipy 1.9 is this one, byte for byte: what
    # loads here and in GraphCMR's environment.
    assert rewritten.read_bytes() == saved.read_bytes()
