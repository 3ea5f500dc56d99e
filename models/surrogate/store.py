"""Plain artifact files: deterministic npz (no pickles) and the manifest.

An artifact is a zip of ``.npy`` members (``numpy.lib.format``, never
pickled object arrays) plus a ``meta.json`` member. Members are written in
sorted order with a fixed timestamp (1980-01-01, the zip epoch) so the same
arrays give the same bytes, which makes the build reproducible bit for bit.
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import re
import zipfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

__all__ = [
    "FORMAT_VERSION",
    "MANIFEST_NAME",
    "read_artifact",
    "sha256_file",
    "write_artifact",
    "write_json",
]

#: Version of the artifact layout; bump when the members or their meaning change.
FORMAT_VERSION = "6"
#: File name of the manifest in the artifact directory.
MANIFEST_NAME = "manifest.json"
_ZIP_EPOCH = (1980, 1, 1, 0, 0, 0)


def _canonical_json(obj: Any) -> bytes:
    return (json.dumps(obj, indent=1, sort_keys=True, allow_nan=True) + "\n").encode()


def write_json(path: Path, obj: Any) -> None:
    """Write `obj` as sorted, indented JSON (deterministic bytes)."""
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_bytes(_canonical_json(obj))
    tmp.replace(path)


def write_artifact(
    path: Path, arrays: Mapping[str, npt.NDArray[Any]], meta: Mapping[str, Any]
) -> None:
    """Write arrays and metadata to `path` atomically (temp file, then rename).

    Parameters
    ----------
    path : Path
    arrays : mapping of str to ndarray
        Numeric arrays only (no object dtype).
    meta : mapping
        JSON-serialisable metadata, stored as ``meta.json``.
    """
    tmp = path.with_suffix(path.suffix + ".tmp")
    with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for name in sorted(arrays):
            arr = np.ascontiguousarray(arrays[name])
            if arr.dtype == object:
                raise TypeError(f"{name}: object arrays are not stored")
            buf = io.BytesIO()
            np.lib.format.write_array(buf, arr, allow_pickle=False)
            info = zipfile.ZipInfo(name + ".npy", date_time=_ZIP_EPOCH)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            zf.writestr(info, buf.getvalue())
        info = zipfile.ZipInfo("meta.json", date_time=_ZIP_EPOCH)
        info.compress_type = zipfile.ZIP_DEFLATED
        info.external_attr = 0o644 << 16
        zf.writestr(info, _canonical_json(dict(meta)))
    tmp.replace(path)


#: The header dict numpy's ``write_array`` writes for a plain array (format 1.0 to 3.0):
#: ``{'descr': '<f8', 'fortran_order': False, 'shape': (3, 4), }`` padded with spaces.
_NPY_HEADER = re.compile(
    r"\{'descr': '([<>|=][a-z]\d+)', 'fortran_order': (False|True), "
    r"'shape': \(((?:\d+, ?)*\d*)\), \} *\n",
    re.ASCII,
)
#: Magic string of the ``.npy`` format.
_NPY_MAGIC = b"\x93NUMPY"


def _read_npy(data: bytes) -> npt.NDArray[Any]:
    """A ``.npy`` member's array: ``numpy.lib.format.read_array``'s array, bytes for bytes.

    Why: numpy parses each header with :func:`ast.literal_eval`, which took about
    a third of the surrogate library's load (6,598 members; issue 51: start to
    ready). The headers ``write_array`` writes for numeric arrays are read here
    with one regular expression and the data copied from the member's bytes;
    any other header (an object dtype, a structured one) is left to numpy.
    """
    if data[:6] == _NPY_MAGIC and data[6] in (1, 2, 3):
        if data[6] == 1:
            hlen, start = int.from_bytes(data[8:10], "little"), 10
        else:
            hlen, start = int.from_bytes(data[8:12], "little"), 12
        header = data[start : start + hlen].decode("latin1")
        m = _NPY_HEADER.fullmatch(header)
        if m is not None:
            dtype = np.dtype(m.group(1))
            shape = tuple(int(d) for d in m.group(3).replace(" ", "").split(",") if d)
            count = math.prod(shape)
            flat = np.frombuffer(data, dtype=dtype, count=count, offset=start + hlen)
            if m.group(2) == "True":
                return flat.reshape(shape, order="F").copy(order="F")
            return flat.reshape(shape).copy()
    return np.lib.format.read_array(io.BytesIO(data), allow_pickle=False)


def read_artifact(path: Path) -> tuple[dict[str, npt.NDArray[Any]], dict[str, Any]]:
    """Read an artifact written by :func:`write_artifact`.

    Returns
    -------
    arrays : dict of str to ndarray
    meta : dict

    Raises
    ------
    ValueError
        When the file is not a readable artifact.
    """
    try:
        with zipfile.ZipFile(path) as zf:
            arrays: dict[str, npt.NDArray[Any]] = {}
            meta: dict[str, Any] | None = None
            for name in zf.namelist():
                data = zf.read(name)
                if name == "meta.json":
                    meta = json.loads(data)
                elif name.endswith(".npy"):
                    arrays[name[:-4]] = _read_npy(data)
    except (OSError, zipfile.BadZipFile, ValueError, KeyError) as exc:
        raise ValueError(f"{path.name}: not a readable surrogate artifact ({exc})") from exc
    if meta is None:
        raise ValueError(f"{path.name}: meta.json missing")
    return arrays, meta


def sha256_file(path: Path) -> str:
    """SHA-256 of a file's bytes, hex."""
    return hashlib.sha256(path.read_bytes()).hexdigest()
