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
                    arrays[name[:-4]] = np.lib.format.read_array(
                        io.BytesIO(data), allow_pickle=False
                    )
    except (OSError, zipfile.BadZipFile, ValueError, KeyError) as exc:
        raise ValueError(f"{path.name}: not a readable surrogate artifact ({exc})") from exc
    if meta is None:
        raise ValueError(f"{path.name}: meta.json missing")
    return arrays, meta


def sha256_file(path: Path) -> str:
    """SHA-256 of a file's bytes, hex."""
    return hashlib.sha256(path.read_bytes()).hexdigest()
