"""GraphCMR's ``mesh_downsampling.npz``, written so that old and new numpy and scipy load
it: GraphCMR's pinned environment (Python 3.6, numpy 1.15.4, scipy 1.2.0) as well as the
package's own (Python 3.9+, numpy 1.21+ or 2.x, scipy 1.7+).

numpy keeps an object array in a ``.npy`` as a pickle of the whole array, and a pickle
names the module of every class and function that rebuilds it. ``np.savez`` writes the
names of the numpy and scipy that write the file: ``numpy._core.multiarray`` under
numpy 2, ``scipy.sparse._csc`` under scipy 1.8+, modules that older versions do not have
(``No module named 'numpy._core'``). So this module writes the pickle itself, opcode by
opcode, in the form numpy 1.15 and scipy 1.2 wrote it (protocol 3, the protocol
``np.save`` uses): it names only the four globals of :data:`GLOBALS`, which every
version above imports, numpy 2 without a warning (it keeps
``numpy.core.multiarray._reconstruct`` for old pickles, GraphCMR's own file among them).
The bytes depend only on the matrices, not on the numpy or scipy that writes them.

The pickle's form, as ``pickletools.dis`` shows it for a file numpy 1.15 writes:

- an array is ``_reconstruct(ndarray, (0,), b"b")``, then ``__setstate__`` with
  ``(1, shape, dtype, False, data)``: ``data`` the C-order bytes, or a list of the
  elements for an object array;
- a dtype is ``dtype(code, False, True)``, then ``__setstate__`` with the version-3 state
  of :data:`DTYPES`;
- a CSC matrix is ``csc_matrix.__new__(csc_matrix)``, then its ``__dict__`` (scipy 1.2
  and 1.17 both keep exactly these attributes, and neither has a ``__setstate__``).
"""

from __future__ import annotations

import io
import pickle
import struct
import zipfile
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse


@dataclass(frozen=True)
class _Global:
    """A module-level name the unpickler imports (the GLOBAL opcode)."""

    module: str
    name: str


@dataclass(frozen=True)
class _Reduce:
    """``func(*args)``, then ``__setstate__(state)``: REDUCE and BUILD."""

    func: _Global
    args: tuple
    state: Any


@dataclass(frozen=True)
class _NewObject:
    """``cls.__new__(cls)``, then ``__dict__.update(state)``: NEWOBJ and BUILD."""

    cls: _Global
    state: dict


RECONSTRUCT = _Global("numpy.core.multiarray", "_reconstruct")
NDARRAY = _Global("numpy", "ndarray")
DTYPE = _Global("numpy", "dtype")
CSC_MATRIX = _Global("scipy.sparse", "csc_matrix")

#: Every global the file names. Each exists in numpy 1.15 / scipy 1.2 and in numpy 2 /
#: scipy 1.17 (``scipy.sparse.csc_matrix``, not the module that defines it: that was
#: ``scipy.sparse.csc`` and is ``scipy.sparse._csc`` since scipy 1.8).
GLOBALS = (RECONSTRUCT, NDARRAY, DTYPE, CSC_MATRIX)

#: The element types the file holds, each with the arguments and the version-3 state
#: numpy 1.15 pickles it with: the type code, the byte order ('|' when it has none) and
#: the flags (63 for the object type, which holds references; 0 for numbers).
DTYPES = {
    np.dtype("<f8"): ("f8", "<", 0),
    np.dtype("<i4"): ("i4", "<", 0),
    np.dtype("<i8"): ("i8", "<", 0),
    np.dtype(object): ("O8", "|", 63),
}

#: scipy's default ``maxprint``, kept in every matrix's ``__dict__``.
_MAXPRINT = 50


def _dtype(dtype: np.dtype) -> _Reduce:
    code, byte_order, flags = DTYPES[dtype]
    return _Reduce(DTYPE, (code, False, True), (3, byte_order, None, None, None, -1, -1, flags))


def _array(array: np.ndarray) -> _Reduce:
    """An array of one of :data:`DTYPES` (little-endian for numbers) as numpy pickles it."""
    if array.dtype == object:
        data: Any = [_node(item) for item in array.ravel()]
    else:
        array = np.ascontiguousarray(array, dtype=array.dtype.newbyteorder("<"))
        data = array.tobytes()
    state = (1, tuple(int(n) for n in array.shape), _dtype(array.dtype), False, data)
    return _Reduce(RECONSTRUCT, (NDARRAY, (0,), b"b"), state)


def _csc(matrix: scipy.sparse.csc_matrix) -> _NewObject:
    """A CSC matrix as scipy pickles it, made canonical first (sorted indices, no
    duplicates: what its flags then say) on a float64 copy (the caller's is unchanged)."""
    matrix = scipy.sparse.csc_matrix(matrix, dtype=np.float64, copy=True)
    matrix.sum_duplicates()
    state = {
        "_shape": tuple(int(n) for n in matrix.shape),
        "maxprint": _MAXPRINT,
        "indices": _array(matrix.indices),
        "indptr": _array(matrix.indptr),
        "data": _array(matrix.data),
        "_has_canonical_format": True,
        "_has_sorted_indices": True,
    }
    return _NewObject(CSC_MATRIX, state)


def _node(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return _array(value)
    if isinstance(value, scipy.sparse.csc_matrix):
        return _csc(value)
    return value


def _emit(value: Any, out: bytearray) -> None:
    """Appends the opcodes that rebuild ``value``: a plain Python value, or a node."""
    if isinstance(value, _Global):
        out += pickle.GLOBAL + f"{value.module}\n{value.name}\n".encode("ascii")
    elif isinstance(value, _Reduce):
        _emit(value.func, out)
        _emit(value.args, out)
        out += pickle.REDUCE
        _emit(value.state, out)
        out += pickle.BUILD
    elif isinstance(value, _NewObject):
        _emit(value.cls, out)
        out += pickle.EMPTY_TUPLE + pickle.NEWOBJ
        _emit(value.state, out)
        out += pickle.BUILD
    elif value is None:
        out += pickle.NONE
    elif isinstance(value, bool):
        out += pickle.NEWTRUE if value else pickle.NEWFALSE
    elif isinstance(value, int):
        if -(2**31) <= value < 2**31:
            out += pickle.BININT + struct.pack("<i", value)
        else:
            raw = value.to_bytes((value.bit_length() + 8) // 8, "little", signed=True)
            out += pickle.LONG1 + struct.pack("<B", len(raw)) + raw
    elif isinstance(value, str):
        raw = value.encode("utf-8")
        out += pickle.BINUNICODE + struct.pack("<I", len(raw)) + raw
    elif isinstance(value, bytes):
        if len(value) >= 2**32:
            raise ValueError(f"an array of {len(value)} bytes is past protocol 3's 4 GiB")
        out += pickle.BINBYTES + struct.pack("<I", len(value)) + value
    elif isinstance(value, tuple):
        out += pickle.MARK
        for item in value:
            _emit(item, out)
        out += pickle.TUPLE
    elif isinstance(value, list):
        out += pickle.EMPTY_LIST + pickle.MARK
        for item in value:
            _emit(item, out)
        out += pickle.APPENDS
    elif isinstance(value, dict):
        out += pickle.EMPTY_DICT + pickle.MARK
        for key, item in value.items():
            _emit(key, out)
            _emit(item, out)
        out += pickle.SETITEMS
    else:
        raise TypeError(f"no portable pickle for {type(value).__name__}")


def pickle_object_array(items: list) -> bytes:
    """The pickle of a 1-D object array of ``items`` (arrays of :data:`DTYPES` and CSC
    matrices), as numpy 1.15 writes it into a ``.npy``."""
    array = np.empty(len(items), dtype=object)
    for k, item in enumerate(items):
        array[k] = item
    out = bytearray(pickle.PROTO + b"\x03")
    _emit(_array(array), out)
    out += pickle.STOP
    return bytes(out)


def _npy_object_array(items: list) -> bytes:
    """A version-1.0 ``.npy`` of a 1-D object array: magic, header length, the header
    dict padded with spaces to a multiple of 64 bytes and ended by a newline, the pickle."""
    header = f"{{'descr': '|O', 'fortran_order': False, 'shape': ({len(items)},), }}"
    header += " " * (-(10 + len(header) + 1) % 64) + "\n"
    return b"\x93NUMPY\x01\x00" + struct.pack("<H", len(header)) + header.encode("latin1") + pickle_object_array(items)


def npz_bytes(arrays: dict) -> bytes:
    """An ``.npz`` (an uncompressed zip of ``NAME.npy``, as ``np.savez`` writes) of the
    object arrays ``arrays`` (name → list of items), in the dict's order, with a fixed
    date so that the same matrices give the same bytes."""
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_STORED) as archive:
        for name, items in arrays.items():
            info = zipfile.ZipInfo(f"{name}.npy", date_time=(1980, 1, 1, 0, 0, 0))
            info.external_attr = 0o644 << 16
            archive.writestr(info, _npy_object_array(items))
    return buffer.getvalue()
