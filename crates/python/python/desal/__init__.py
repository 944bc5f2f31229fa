"""desal: simplify deformable human body meshes so that they still deform well.

NumPy arrays in, NumPy arrays out. Every stage of ``desal run`` is here, computed by the
same Rust code, so the same arrays give the same bytes as the command line:

>>> import desal, numpy as np
>>> ps = desal.PoseSet(poses, faces, labels, template=0)       # (P, V, 3), (F, 3), (V,)
>>> out = desal.simplify_pose_set(ps, target_vertices=2500)    # the paper's method
>>> out.poses.shape, out.vertex_map.shape                      # (P, 2500, 3), (2500,)

Stages one at a time: :func:`fit`, :func:`saliency`, :func:`simplify` (any mesh),
:func:`map`. A skinned glTF rig in, a simplified rig out: :func:`simplify_rig`. Multi-level hierarchies for mesh networks: :func:`hierarchy`,
:func:`load_hierarchy`, :func:`save_graphcmr`. The driver with its cache: :func:`run`.
Any artifact: :func:`load`.

Bad input raises :class:`InputError` (a ``ValueError``) with the CLI's message, naming
the pose, vertex, face or part, or the argument and the value as it was passed; a
failure while computing raises :class:`Error` (an internal error in desal's Rust code
too: no call raises anything outside these two for any argument). Files are read only
when they are regular files, and written as ``desal run`` writes them (see
:func:`save_graphcmr`). The GIL is released while a stage computes. Long calls take ``progress=callback`` (called as
``callback(step, done, total)``) or ``progress=desal.tqdm_progress()``.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from os import PathLike
from typing import Any, Callable, Optional, Sequence, Union

import numpy as np

from . import _desal
from ._desal import Error, Fit, InputError, PoseSet, Saliency, load, read_labels, read_mesh

__version__ = _desal.__version__

#: The most frames :func:`simplify_rig` poses a rig at (per pose source).
MAX_RIG_FRAMES: int = _desal.MAX_RIG_FRAMES

__all__ = [
    "Error",
    "Fit",
    "Hierarchy",
    "InputError",
    "MAX_RIG_FRAMES",
    "PoseSet",
    "Saliency",
    "Simplification",
    "fit",
    "hierarchy",
    "load",
    "load_hierarchy",
    "map",
    "read_labels",
    "read_mesh",
    "run",
    "save_graphcmr",
    "saliency",
    "simplify",
    "simplify_pose_set",
    "simplify_rig",
    "tqdm_progress",
]

Progress = Optional[Callable[[str, int, int], Any]]
PathArg = Union[str, "PathLike[str]"]


def _json_value(what: str, name: str, value: Any) -> Any:
    """``value`` as JSON can hold it: NumPy scalars and arrays as Python numbers and
    lists; NaN, infinities, integers past 64 bits and anything JSON has no form for are
    refused naming the option (JSON would otherwise carry ``NaN`` that the Rust side
    could only report as "expected value at line 1 column 11")."""
    if isinstance(value, np.ndarray):
        value = value.tolist()
    elif isinstance(value, np.generic):
        value = value.item()
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, int):
        if not -(2**63) <= value < 2**64:
            raise InputError(f"{what}: {name}={value} is too large")
        return value
    if isinstance(value, float):
        if not math.isfinite(value):
            raise InputError(f"{what}: {name}={value!r} must be a finite number")
        return value
    if isinstance(value, (list, tuple)):
        return [_json_value(what, f"{name}[{k}]", v) for k, v in enumerate(value)]
    if isinstance(value, dict) and all(isinstance(k, str) for k in value):
        return {k: _json_value(what, f"{name}.{k}", v) for k, v in value.items()}
    kind = type(value).__name__
    raise InputError(f"{what}: {name}={value!r} must be a number, a str, a bool or a list, not {kind}")


def _table(what: str, values: dict) -> str:
    """The options of the pipeline table ``what`` (``fit``, ``simplify``, …) as JSON,
    unset (None) values left out. The Rust side parses it into the stage's own settings
    and names a bad option with its value."""
    return json.dumps({k: _json_value(what, k, v) for k, v in values.items() if v is not None})


def _options_dict(what: str, argument: str, options: Any) -> dict:
    """A ``*_options`` argument: a dict of a pipeline table's keys, or None."""
    if options is None:
        return {}
    if not isinstance(options, dict) or not all(isinstance(k, str) for k in options):
        raise InputError(f"{what}: {argument} must be a dict of [dataset.{what}] keys, not {options!r}")
    return dict(options)


def _mesh_overrides(meshes: Any) -> Optional[dict]:
    """``simplify_rig``'s ``meshes``: ``{name: ratio}`` as ``[dataset.rig.meshes]``'s
    tables (``{name: {"ratio": ratio}}``), or None."""
    if meshes is None:
        return None
    if not isinstance(meshes, dict) or not all(isinstance(k, str) for k in meshes):
        raise InputError(f"rig: meshes must be a dict of mesh names to ratios, not {meshes!r}")
    return {name: {"ratio": ratio} for name, ratio in meshes.items()}


def _text(argument: str, value: Any) -> str:
    if not isinstance(value, str):
        raise InputError(f"{argument}={value!r} must be a str")
    return value


def _flag(argument: str, value: Any) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise InputError(f"{argument}={value!r} must be True or False")
    return bool(value)


def _simplify_table(
    options: Any,
    placement: Optional[str],
    target_vertices: Optional[int],
    target_faces: Optional[int],
    ratio: Optional[float],
) -> str:
    """A pipeline file's ``[dataset.simplify]`` table as JSON: ``options`` with the
    placement (when given: unset, the table's default or the method's own) and whichever
    target is given."""
    table = _options_dict("simplify", "simplify_options", options)
    targets = dict(target_vertices=target_vertices, target_faces=target_faces, ratio=ratio)
    table.update({k: v for k, v in targets.items() if v is not None})
    if placement is not None:
        table["placement"] = placement
    return _table("simplify", table)


def _pose_set(poses: Any, faces: Any, labels: Any, template: int, progress: Progress) -> PoseSet:
    if isinstance(poses, PoseSet):
        if faces is not None or labels is not None:
            raise InputError("faces, labels: give them with arrays, not with a PoseSet")
        return poses
    if faces is None:
        raise InputError("faces: required with pose arrays")
    return PoseSet(poses, faces, labels, template=template, progress=progress)


def fit(ps: PoseSet, method: str = "rigid", progress: Progress = None) -> Fit:
    """Stage 1: a rigid fit per body part per pose.

    ``method`` is ``"rigid"`` (Kabsch, proper rotations) or ``"affine"`` (the paper's
    literal fit). The result has ``rotations`` (P, K, 3, 3), ``translations`` (P, K, 3),
    ``residuals`` (P, V) and ``report``.
    """
    return _desal.fit(ps, _table("fit", dict(method=method)), progress)


def saliency(
    ps: PoseSet,
    fit: Optional[Fit] = None,
    squared: bool = False,
    percentile: float = 100.0,
    exclude: Sequence[str] = (),
    floor: Optional[float] = None,
) -> Saliency:
    """Stage 2: per-vertex deformation saliency from a fit (computed when None).

    The result has ``saliency`` (V,) in [0, 1], ``weights`` (V,) in [floor, 1] (what
    :func:`simplify` takes), ``raw`` and ``report``. ``exclude`` names poses left out of
    the sum; ``percentile`` < 100 normalises by that percentile instead of the maximum.
    """
    if fit is None:
        fit = _desal.fit(ps, None, None)
    if isinstance(exclude, str):
        raise InputError(f"saliency: exclude={exclude!r} must be a list of pose names, not one str")
    options = _table("saliency", dict(squared=squared, percentile=percentile, exclude=exclude, floor=floor))
    return _desal.saliency(ps, fit, options)


def simplify(
    vertices: Any,
    faces: Any,
    target_vertices: Optional[int] = None,
    target_faces: Optional[int] = None,
    ratio: Optional[float] = None,
    weights: Any = None,
    placement: str = "optimal",
    balance: bool = False,
    metric: str = "quadric",
    labels: Any = None,
    keep_part_borders: bool = False,
    boundary_weight: Optional[float] = None,
    progress: Progress = None,
) -> tuple[np.ndarray, np.ndarray, dict]:
    """Stage 3 on any mesh: quadric edge collapse, weighted by ``weights`` when given.

    Give one of ``target_vertices``, ``target_faces`` and ``ratio`` (none: ratio 0.2).
    ``placement`` is ``"optimal"`` (the quadric's best point) or ``"subset"`` (keep
    original vertices); ``balance`` multiplies the cost by the edge length (the paper's
    balance term); ``metric`` is ``"quadric"`` or ``"lindstrom-turk"``. With
    ``keep_part_borders``, vertices between two ``labels`` stay. The defaults are the
    library's, as in ``desal run``.

    Returns ``(vertices (n, 3) float64, faces (m, 3) int64, report)``; the report has the
    stage summary and ``simp_to_orig`` ((n,) int64, -1 for a moved vertex).
    """
    options = _table(
        "simplify",
        dict(
            target_vertices=target_vertices,
            target_faces=target_faces,
            ratio=ratio,
            placement=placement,
            balance=balance,
            metric=metric,
            keep_part_borders=keep_part_borders,
            boundary_weight=boundary_weight,
        ),
    )
    return _desal.simplify(vertices, faces, options, weights, labels, progress)


def map(  # noqa: A001 - the stage's name
    ps: PoseSet, simplified_vertices: Any, simplified_faces: Any, simp_to_orig: Any = None
) -> tuple[np.ndarray, np.ndarray]:
    """Stage 4: each simplified vertex's original vertex, applied to every pose.

    ``simp_to_orig`` (from :func:`simplify`'s report) maps kept vertices exactly; the
    rest, or every vertex of another tool's mesh, are mapped by the paper's greedy rule.
    Returns ``(simp_to_orig (n,) int64, poses (P, n, 3) float64)``.
    """
    return _desal.map(ps, simplified_vertices, simplified_faces, simp_to_orig)


@dataclass
class Simplification:
    """A simplified pose set: what ``desal run`` writes to its output folder."""

    #: (n,) int64: the original vertex of each simplified vertex (``vertex_map.txt``).
    vertex_map: np.ndarray
    #: (m, 3) int64 triangles over the simplified vertices.
    faces: np.ndarray
    #: (P, n, 3) float64: every pose at the simplified vertices (registered).
    poses: np.ndarray
    #: (n,) int64 part labels of the simplified vertices.
    labels: np.ndarray
    #: (V,) float64 deformation saliency of the input's vertices.
    saliency: np.ndarray
    #: (V,) float64 stage-3 weights of the input's vertices.
    weights: np.ndarray
    #: (n, 3) float64 simplified template as stage 3 placed it.
    simplified_vertices: np.ndarray
    #: Every stage's summary.
    report: dict = field(repr=False)


def simplify_pose_set(
    poses: Any,
    faces: Any = None,
    labels: Any = None,
    target_vertices: Optional[int] = None,
    method: str = "paper",
    placement: Optional[str] = None,
    template: int = 0,
    target_faces: Optional[int] = None,
    ratio: Optional[float] = None,
    fit_method: str = "rigid",
    saliency_options: Optional[dict] = None,
    simplify_options: Optional[dict] = None,
    progress: Progress = None,
) -> Simplification:
    """The whole pipeline on one pose set, as ``desal run`` computes it.

    ``poses`` is a :class:`PoseSet`, or (P, V, 3) arrays with ``faces`` (F, 3) and
    ``labels`` (V,) (None: parts discovered from the poses). ``method`` is ``"paper"``
    (saliency and balance), ``"qslim"``, ``"saliency"``, ``"balance"``,
    ``"multipose"`` (multi-pose QEM: the quadrics summed over the poses stage 2 reads,
    subset placement, the plain quadric cost; ``method = "multipose"`` in a pipeline
    file), ``"desal"`` (desal's own
    stage 3: the per-area quadric error, subset placement, no saliency;
    docs/eval/desal-method.md) or ``"desal-refit"`` (desal's whole method,
    the lowest deformation error on SCAPE: ``"desal"``, then again weighted where its
    mesh deforms worse than the full one under a SCAPE pose model fitted on these poses,
    keeping the vertices the model places best, then edges flipped to follow the poses;
    the mesh ``desal eval`` gives as ``desal-refit``; seconds, not milliseconds).
    ``placement`` is ``"optimal"`` or ``"subset"``; unset, it is ``"optimal"``, or the
    method's own for ``"desal"`` and ``"desal-refit"`` (which refuse another, as a
    pipeline file does). ``saliency_options`` and ``simplify_options`` take the keys of a
    pipeline file's ``[dataset.saliency]`` and ``[dataset.simplify]`` tables.
    """
    ps = _pose_set(poses, faces, labels, template, progress)
    simplify_table = _simplify_table(simplify_options, placement, target_vertices, target_faces, ratio)
    out = _desal.simplify_pose_set(
        ps,
        _text("method", method),
        _table("fit", dict(method=fit_method)),
        _table("saliency", _options_dict("saliency", "saliency_options", saliency_options)),
        simplify_table,
        progress,
    )
    return Simplification(**out)


def simplify_rig(
    rig: PathArg,
    out: PathArg,
    target_vertices: Optional[int] = None,
    method: str = "paper",
    placement: str = "subset",
    target_faces: Optional[int] = None,
    ratio: Optional[float] = None,
    mesh: Union[str, Sequence[str], None] = None,
    poses: str = "animations",
    frames: Optional[int] = None,
    seed: Optional[int] = None,
    max_degrees: Optional[float] = None,
    min_part_vertices: Optional[int] = None,
    max_influences: Union[int, str, None] = None,
    fit_method: str = "rigid",
    saliency_options: Optional[dict] = None,
    simplify_options: Optional[dict] = None,
    progress: Progress = None,
    meshes: Optional[dict] = None,
    lods: Optional[Sequence[float]] = None,
) -> dict:
    """Simplifies the skinned glTF 2.0 rig ``rig`` (``.glb``/``.gltf``) and writes the
    simplified rig to ``out`` (``.glb``), as ``desal run`` does for a ``[dataset.rig]``:
    the same bytes as its ``simplified.glb`` for the same settings.

    The rig is posed by linear blend skinning at ``frames`` frames of its animations
    (``poses="animations"``), of seeded random joint turns (``"random"``) or both; its
    UV/normal seams are welded for simplification and kept in the output. Every skinned
    mesh (and mesh below a bone) is simplified under one budget; ``mesh`` picks some (a
    name or a list: mesh name, node name or mesh index), the others pass through
    unchanged; ``meshes`` gives a mesh its own ratio (``{"Eyes": 1.0}`` keeps it whole; a
    mesh whose share of the target is under 200 faces is kept whole unless named there);
    ``ratio`` applies to each mesh, ``target_faces``/``target_vertices`` are totals spread
    by error. ``lods`` (fractions of the original faces, strictly decreasing, in (0, 1])
    also writes each level beside ``out`` as ``<stem>-lod<k><suffix>`` and all of them with
    the input as ``<stem>-lods<suffix>`` (``MSFT_lod``), each level simplified from the one
    before; the report's ``lods`` has each level's figures and ``lod_files`` the paths. The output is the input document
    with only the simplified primitives changed (every other mesh, material, texture,
    animation, morph target and extension kept; images the file names by a relative path
    are written beside ``out``); with ``placement="subset"`` every
    kept vertex keeps its exact weights, with ``"optimal"`` at most 4 weights are
    refitted over the poses; ``max_influences`` caps both (default 4, what engines skin: a
    subset vertex with more keeps the ones of its own joints that skin it closest over the
    poses; ``"all"`` keeps every exact weight). ``method`` is as for :func:`simplify_pose_set`. Returns the
    report (``rig``: the output's vertex, face and seam counts; ``ingest``, ``labels``,
    ``fit``, ``saliency``, ``simplify``, ``map``: each stage's). A rig that cannot be
    read or posed raises :class:`InputError` naming the file and the element, as does
    ``frames`` above :data:`MAX_RIG_FRAMES` (65 536, the CLI's ``rig.frames`` limit too:
    the pose set's memory grows with frames × vertices, capped at 2^27 positions) and an ``out`` that is a folder, FIFO or socket; ``out`` is written
    as :func:`save_graphcmr` writes.
    """
    rig_table = _table(
        "rig",
        dict(
            mesh=mesh,
            poses=poses,
            frames=frames,
            seed=seed,
            max_degrees=max_degrees,
            min_part_vertices=min_part_vertices,
            max_influences=max_influences,
            lods=lods,
            meshes=_mesh_overrides(meshes),
        ),
    )
    simplify_table = _simplify_table(simplify_options, placement, target_vertices, target_faces, ratio)
    return _desal.simplify_rig(
        rig,
        out,
        rig_table,
        _text("method", method),
        _table("fit", dict(method=fit_method)),
        _table("saliency", _options_dict("saliency", "saliency_options", saliency_options)),
        simplify_table,
        progress,
    )


class Hierarchy:
    """Levels 0..L of a mesh hierarchy, in the layout of ``hierarchy.npz``.

    ``levels[k]`` vertices and ``faces[k]`` triangles per level; per step k → k+1 the
    down-sampler ``D[k]`` (n_{k+1} × n_k, a selection), the up-sampler ``U[k]``
    (n_k × n_{k+1}, rows sum to 1), ``map[k]`` (level k+1's vertex → level k's) and
    ``orig[k]`` (level k+1's vertex → level 0's); ``A[k]`` is level k's adjacency.
    The matrices are ``scipy.sparse.csc_matrix`` (float64), built from the arrays.
    """

    def __init__(self, arrays: dict, report: Any = None):
        self.arrays = dict(arrays)
        self.report = report
        self.levels = [int(n) for n in self.arrays["levels"]]
        steps = len(self.levels) - 1
        self.faces = [self.arrays[f"F{k}"] for k in range(steps + 1)]
        self.A = [self._matrix(f"A{k}") for k in range(steps + 1)]
        self.D = [self._matrix(f"D{k}") for k in range(steps)]
        self.U = [self._matrix(f"U{k}") for k in range(steps)]
        self.map = [self.arrays[f"map{k + 1}"] for k in range(steps)]
        self.orig = [self.arrays[f"orig{k + 1}"] for k in range(steps)]

    def _matrix(self, key: str) -> Any:
        # Imported here, not with desal: scipy.sparse is a dependency, but a slow import
        # for the calls that never make a hierarchy.
        import scipy.sparse

        row, col, data = (self.arrays[f"{key}_{p}"] for p in ("row", "col", "data"))
        shape = tuple(int(n) for n in self.arrays[f"{key}_shape"])
        return scipy.sparse.coo_matrix((data, (row, col)), shape=shape).tocsc()

    def save(self, path: PathArg) -> None:
        """Writes ``hierarchy.npz``, the bytes ``desal run`` writes."""
        _desal.write_hierarchy_npz(path, self.arrays)

    def __repr__(self) -> str:
        return f"Hierarchy(levels={self.levels})"


def hierarchy(
    poses: Any,
    levels: Sequence[int],
    faces: Any = None,
    labels: Any = None,
    upsampler: str = "fitted",
    neighbours: Optional[int] = None,
    ridge: Optional[float] = None,
    neighbourhood: Optional[str] = None,
    method: str = "desal-upsample",
    placement: Optional[str] = None,
    template: int = 0,
    simplify_options: Optional[dict] = None,
    progress: Progress = None,
) -> Hierarchy:
    """A multi-level hierarchy for mesh networks (COMA / GraphCMR style).

    ``levels`` are the coarse vertex counts, strictly decreasing (e.g. ``[2500, 625]``).
    Each level is simplified from the one above by ``method``: by default
    ``"desal-upsample"`` (multi-pose quadrics weighted by where the fitted upsampler does
    worst, held out: the lowest upsampling error measured, as a pipeline file's default
    with a hierarchy), or any method of :func:`simplify_pose_set` (a cost such as
    ``"paper"``, ``"multipose"``, ``"desal"``, ``"desal-refit"``, ``"qslim-optimal"``);
    ``upsampler`` is
    ``"fitted"`` (least squares over the poses) or ``"barycentric"`` (COMA's rule).
    ``neighbours`` and ``ridge`` left as ``None`` are chosen per level by held-out error
    on the level's own training poses (whole groups when ``poses`` has groups); each
    step of ``report`` names them under ``"knobs"``.
    The same as ``[dataset.hierarchy]`` in a pipeline file.
    """
    ps = _pose_set(poses, faces, labels, template, progress)
    options = _table(
        "hierarchy",
        dict(levels=levels, upsampler=upsampler, neighbours=neighbours, ridge=ridge, neighbourhood=neighbourhood),
    )
    simplify_table = _simplify_table(simplify_options, placement, None, None, None)
    arrays, report = _desal.hierarchy(ps, options, _text("method", method), None, None, simplify_table, progress)
    return Hierarchy(arrays, report)


def load_hierarchy(path: PathArg) -> Hierarchy:
    """Reads ``hierarchy.npz`` as ``desal run`` writes it (the layout is checked). Only
    a regular file is read: a FIFO, a device or a folder raises :class:`InputError`."""
    return Hierarchy(_desal.read_hierarchy_npz(path))


def save_graphcmr(h: Hierarchy, path: PathArg) -> None:
    """Writes GraphCMR's own layout: object arrays of ``scipy.sparse`` CSC matrices under
    ``A``, ``D``, ``U`` (float64, made canonical) and the faces under ``F`` (int32 as
    ``h`` has them, other integers as int64). GraphCMR's code loads it unchanged with
    ``np.load(path, allow_pickle=True, encoding="latin1")``, in its pinned environment
    (Python 3.6, numpy 1.15, scipy 1.2) as in numpy 2: the pickles inside name only
    modules that both have, whatever numpy and scipy write the file (``desal/_graphcmr.py``
    says how), and the same matrices give the same bytes. A matrix that is not
    ``scipy.sparse`` or faces that are not (m, 3) integers raise :class:`InputError`.

    Written as every desal writer writes (``desal_io::write_atomic``): the whole file is
    built in memory, written beside ``path`` and renamed over it, so a reader sees the
    old file or the new one and an error leaves nothing behind. A symlink at ``path`` is
    replaced by the file, its target left as it was; a character device (``/dev/null``)
    is written through; a folder, FIFO or socket raises :class:`InputError`.
    """
    import scipy.sparse

    from . import _graphcmr

    if not isinstance(h, Hierarchy):
        raise InputError(f"h: must be a desal.Hierarchy, not {type(h).__name__}")

    def matrices(name: str) -> list:
        items = list(getattr(h, name))
        for k, item in enumerate(items):
            if not scipy.sparse.issparse(item):
                raise InputError(f"h.{name}[{k}]: must be a scipy.sparse matrix, not {type(item).__name__}")
            items[k] = scipy.sparse.csc_matrix(item)
        return items

    def faces() -> list:
        items = [np.asarray(f) for f in h.faces]
        for k, f in enumerate(items):
            if f.dtype.kind not in "iu" or f.ndim != 2 or f.shape[1] != 3:
                raise InputError(f"h.faces[{k}]: must be (m, 3) integers, not {f.dtype} {f.shape}")
        # int32 (as hierarchy.npz has them) or int64: the two integer types in the file.
        return [f if f.dtype == np.int32 else f.astype(np.int64) for f in items]

    arrays = dict(A=matrices("A"), D=matrices("D"), U=matrices("U"), F=faces())
    _desal._write_file(path, _graphcmr.npz_bytes(arrays))


def run(
    pipeline: PathArg,
    out: Optional[PathArg] = None,
    force: bool = False,
    from_stage: Optional[str] = None,
    jobs: int = 1,
    cache_dir: Optional[PathArg] = None,
    explain: bool = False,
    progress: bool = False,
) -> list:
    """Runs a pipeline file with the cache, as ``desal run`` does.

    Returns one report per dataset (``report.json``'s content). ``from_stage`` recomputes
    that stage and the ones after it; ``progress`` shows the CLI's bars on stderr.
    """
    return _desal.run(
        pipeline,
        out,
        _flag("force", force),
        None if from_stage is None else _text("from_stage", from_stage),
        jobs,
        cache_dir,
        _flag("explain", explain),
        _flag("progress", progress),
    )


def tqdm_progress(**tqdm_kwargs: Any) -> Callable[[str, int, int], None]:
    """A progress callback drawing one tqdm bar per step (needs tqdm)."""
    from tqdm.auto import tqdm

    state: dict = {}

    def callback(step: str, done: int, total: int) -> None:
        bar = state.get("bar")
        if bar is None or state.get("step") != step or done == 0:
            if bar is not None:
                bar.close()
            bar = state["bar"] = tqdm(total=total, desc=step, **tqdm_kwargs)
            state["step"] = step
        bar.update(done - bar.n)
        if done >= total:
            bar.close()
            state["bar"] = None

    return callback
