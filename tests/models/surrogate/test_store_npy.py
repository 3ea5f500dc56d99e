"""The artifact reader's own ``.npy`` header parse gives numpy's arrays (issue 51)."""

from __future__ import annotations

import io
import zipfile

import numpy as np
import numpy.typing as npt
import pytest

from models.surrogate import store
from models.surrogate.library import default_artifact_dir


def _numpy_read(data: bytes) -> npt.NDArray[np.generic]:
    return np.lib.format.read_array(io.BytesIO(data), allow_pickle=False)


def _same(a: npt.NDArray[np.generic], b: npt.NDArray[np.generic]) -> None:
    assert a.dtype == b.dtype
    assert a.shape == b.shape
    assert a.flags.f_contiguous == b.flags.f_contiguous
    assert a.tobytes(order="A") == b.tobytes(order="A")
    assert b.flags.writeable


@pytest.mark.parametrize(
    "arr",
    [
        np.arange(12.0).reshape(3, 4),
        np.asfortranarray(np.arange(12.0).reshape(3, 4)),
        np.zeros((0, 3)),
        np.array(3.5),
        np.arange(5, dtype=np.int64),
        np.array([True, False]),
        np.arange(6, dtype=">i4").reshape(2, 3),
        np.zeros(3, dtype=[("a", "<f8"), ("b", "<i4")]),  # numpy's own reader
    ],
)
def test_members_read_as_numpy_reads_them(arr: npt.NDArray[np.generic]) -> None:
    buf = io.BytesIO()
    np.lib.format.write_array(buf, arr, allow_pickle=False)
    data = buf.getvalue()
    _same(_numpy_read(data), store._read_npy(data))


def test_every_shipped_member_reads_as_numpy_reads_it() -> None:
    paths = sorted(default_artifact_dir().glob("*.npz"))
    assert paths
    with zipfile.ZipFile(paths[0]) as zf:
        names = [n for n in zf.namelist() if n.endswith(".npy")]
        for name in names:
            data = zf.read(name)
            _same(_numpy_read(data), store._read_npy(data))
