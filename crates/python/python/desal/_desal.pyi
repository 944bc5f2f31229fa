"""Type stubs of desal's native module. The public API is `desal` (__init__.py)."""

from os import PathLike
from typing import Any, Callable, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

__version__: str
MAX_RIG_FRAMES: int

_Path = Union[str, PathLike[str]]
_Progress = Optional[Callable[[str, int, int], Any]]

class InputError(ValueError):
    """Bad input: the message names the argument and the pose, vertex, face or part."""

class Error(RuntimeError):
    """A failure while computing, reading or writing."""

class PoseSet:
    """A registered pose set: P poses of one body, one triangle list, and part labels.

    Validated as ``desal run`` validates pose files; positions are stored at float32.
    ``labels=None`` discovers the near-rigid parts from the poses.
    """

    def __init__(
        self,
        poses: Union[npt.ArrayLike, Sequence[npt.ArrayLike]],
        faces: npt.ArrayLike,
        labels: Optional[npt.ArrayLike] = None,
        template: int = 0,
        names: Optional[Sequence[str]] = None,
        part_names: Optional[Sequence[str]] = None,
        parts: Optional[str] = None,
        progress: _Progress = None,
        groups: Optional[npt.ArrayLike] = None,
    ) -> None: ...
    @classmethod
    def from_body_model(
        cls,
        model: Any,
        shapes: int = 24,
        poses: int = 6,
        seed: int = 0,
        pose_sigma: Optional[float] = None,
        expressions: bool = True,
        parts: int = 16,
        progress: _Progress = None,
    ) -> "PoseSet":
        """Samples a body-models model: the template, then ``shapes`` x ``poses``
        samples, one group per shape, labels from the skin weights."""
    @property
    def poses(self) -> npt.NDArray[np.float64]:
        """(P, V, 3) positions."""
    @property
    def faces(self) -> npt.NDArray[np.int64]:
        """(F, 3) triangles (degenerate and duplicate ones removed)."""
    @property
    def labels(self) -> npt.NDArray[np.int64]:
        """(V,) part id per vertex."""
    @property
    def part_names(self) -> list[str]: ...
    @property
    def names(self) -> list[str]: ...
    @property
    def template(self) -> int: ...
    @property
    def groups(self) -> Optional[npt.NDArray[np.int64]]:
        """(P,) group id per pose, or None; held-out figures hold out whole groups."""
    @property
    def vertex_count(self) -> int: ...
    @property
    def pose_count(self) -> int: ...
    @property
    def parts_report(self) -> Optional[dict]:
        """The part discovery's report when ``labels`` was None."""
    @property
    def removed_faces(self) -> tuple[int, int]:
        """(degenerate, duplicate) faces removed from the input."""
    def __len__(self) -> int: ...

class Fit:
    """Stage 1's result."""

    @property
    def rotations(self) -> npt.NDArray[np.float64]:
        """(P, K, 3, 3) linear part per pose and part (a rotation for the rigid fit)."""
    @property
    def translations(self) -> npt.NDArray[np.float64]:
        """(P, K, 3)."""
    @property
    def residuals(self) -> npt.NDArray[np.float32]:
        """(P, V) residual distance per pose and vertex."""
    @property
    def model(self) -> str: ...
    @property
    def report(self) -> dict: ...

class Saliency:
    """Stage 2's result."""

    @property
    def saliency(self) -> npt.NDArray[np.float64]:
        """(V,) in [0, 1]."""
    @property
    def weights(self) -> npt.NDArray[np.float64]:
        """(V,) stage-3 weights in [floor, 1]."""
    @property
    def raw(self) -> npt.NDArray[np.float64]: ...
    @property
    def report(self) -> dict: ...

def fit(ps: PoseSet, options: Optional[str] = None, progress: _Progress = None) -> Fit: ...
def saliency(ps: PoseSet, fit: Fit, options: Optional[str] = None) -> Saliency: ...
def simplify(
    vertices: npt.ArrayLike,
    faces: npt.ArrayLike,
    options: Optional[str] = None,
    weights: Optional[npt.ArrayLike] = None,
    labels: Optional[npt.ArrayLike] = None,
    progress: _Progress = None,
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int64], dict]: ...
def map(
    ps: PoseSet,
    simplified_vertices: npt.ArrayLike,
    simplified_faces: npt.ArrayLike,
    simp_to_orig: Optional[npt.ArrayLike] = None,
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.float64]]: ...
def simplify_pose_set(
    ps: PoseSet,
    method: str = "paper",
    fit: Optional[str] = None,
    saliency: Optional[str] = None,
    simplify: Optional[str] = None,
    progress: _Progress = None,
) -> dict: ...
def simplify_rig(
    file: _Path,
    out: _Path,
    rig: Optional[str] = None,
    method: str = "paper",
    fit: Optional[str] = None,
    saliency: Optional[str] = None,
    simplify: Optional[str] = None,
    progress: _Progress = None,
) -> dict: ...
def hierarchy(
    ps: PoseSet,
    hierarchy: str,
    method: str = "paper",
    fit: Optional[str] = None,
    saliency: Optional[str] = None,
    simplify: Optional[str] = None,
    progress: _Progress = None,
) -> tuple[dict, list]: ...
def run(
    pipeline: _Path,
    out: Optional[_Path] = None,
    force: bool = False,
    from_stage: Optional[str] = None,
    jobs: int = 1,
    cache_dir: Optional[_Path] = None,
    explain: bool = False,
    progress: bool = False,
) -> list: ...
def load(path: _Path) -> dict:
    """A desal artifact (.dsa) as a dict of arrays and values, with kind, version and producer."""
def read_hierarchy_npz(path: _Path) -> dict: ...
def write_hierarchy_npz(path: _Path, arrays: dict) -> None: ...
def _write_file(path: _Path, data: bytes) -> None:
    """Writes ``data`` as desal's writers do (temp file and rename; devices written through)."""
def _panic_for_tests(message: str) -> None:
    """Panics in Rust; raises :class:`Error` (the tests' proof that no panic escapes)."""
def read_mesh(path: _Path) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]:
    """A PLY, OBJ or OFF mesh as desal reads it: (vertices, faces)."""
def read_labels(path: _Path) -> tuple[npt.NDArray[np.int64], list[str]]:
    """A labels file (.txt ids or .json with part names): (ids, names)."""
