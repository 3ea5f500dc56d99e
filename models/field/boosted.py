"""Bagged boosted trees served in numpy: one field risk outcome's ranking score.

The offline fit (:mod:`models.offline.field.risk_boosted`) fits ``B`` gradient
boosted classifiers (scikit-learn's ``HistGradientBoostingClassifier``, trees
of depth at most :data:`TREE_DEPTH`), each on a bootstrap resample of whole
crashes, and stores them here as arrays. A member's raw score (log-odds) is its
baseline plus the sum of one leaf value per tree; the served ranking score is
the mean over members, and the spread over members is the bootstrap spread
that the service's 95 % interval comes from (as the regression's bootstrap
refits do).

Why our own evaluator: scikit-learn is not a serving dependency (the engine
serves with numpy and numba) and its per-call overhead is larger than the
whole answer's budget. Every tree is stored as a complete binary tree of depth
:data:`TREE_DEPTH` in heap order (node ``k``'s children are ``2k + 1`` and
``2k + 2``): a node that scikit-learn left as a leaf above the last level is
stored as a split that always goes left (threshold :data:`ALWAYS_LEFT`) down
to a leaf of the same value, so every walk is ``TREE_DEPTH`` steps; the walk is
one compiled loop over all the boosted outcomes' trees (:class:`Forest`). A
test checks it against scikit-learn.

The arrays travel in the artifact as base64 of little-endian bytes (exact,
and about a tenth of the size of JSON numbers).
"""

from __future__ import annotations

import base64
from dataclasses import dataclass
from functools import cached_property
from typing import Any, Final

import numpy as np
from numba import njit

from models.arrays import FloatArray, IntArray

__all__ = [
    "ALWAYS_LEFT",
    "TREE_DEPTH",
    "Forest",
    "TreeBag",
    "decode_array",
    "encode_array",
    "warm_up",
]

#: Depth of every stored tree (scikit-learn ``max_depth``; the fit uses it).
TREE_DEPTH: Final[int] = 3
#: Internal nodes and leaves of one complete tree of :data:`TREE_DEPTH`.
N_SPLITS: Final[int] = 2**TREE_DEPTH - 1
N_LEAVES: Final[int] = 2**TREE_DEPTH
if TREE_DEPTH != 3:  # pragma: no cover - _forest_scores writes out a depth-3 walk
    raise ImportError("models.field.boosted: _forest_scores walks trees of depth 3")
#: Threshold of a padding split: every finite value goes left (``x <= t``).
ALWAYS_LEFT: Final[float] = float(np.finfo(np.float64).max)

_DTYPES: Final[dict[str, str]] = {"float64": "<f8", "int16": "<i2"}


def encode_array(arr: np.ndarray, dtype: str) -> dict[str, Any]:
    """``{"dtype", "shape", "base64"}`` of `arr` as little-endian `dtype` bytes."""
    data = np.ascontiguousarray(arr, dtype=_DTYPES[dtype])
    return {
        "dtype": dtype,
        "shape": list(data.shape),
        "base64": base64.b64encode(data.tobytes()).decode("ascii"),
    }


def decode_array(doc: Any, where: str) -> np.ndarray:
    """The array of :func:`encode_array` (read-only).

    Raises
    ------
    ValueError
        Not such a document, or the bytes do not fill the shape.
    """
    try:
        dtype = _DTYPES[doc["dtype"]]
        shape = tuple(int(s) for s in doc["shape"])
        raw = base64.b64decode(doc["base64"], validate=True)
        arr = np.frombuffer(raw, dtype=dtype).reshape(shape)
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(f"`{where}`: not an encoded array ({exc})") from None
    out = arr.astype(arr.dtype.newbyteorder("="))
    out.setflags(write=False)
    return out


@dataclass(frozen=True, eq=False)
class TreeBag:
    """``B`` members of ``M`` complete trees each, over some design columns.

    Attributes
    ----------
    columns : tuple of int
        Design columns (indices into ``ALL_COLUMNS``) the trees split on;
        ``features`` index this tuple.
    features : ndarray of int16, shape (B * M, N_SPLITS)
        Column (position in `columns`) of each split, heap order.
    thresholds : ndarray, shape (B * M, N_SPLITS)
        Go left when ``x <= threshold``.
    leaves : ndarray, shape (B * M, N_LEAVES)
        Leaf values (log-odds contributions).
    baselines : ndarray, shape (B,)
        Each member's initial log-odds.
    """

    columns: tuple[int, ...]
    features: np.ndarray
    thresholds: FloatArray
    leaves: FloatArray
    baselines: FloatArray

    def __post_init__(self) -> None:
        t = self.features.shape[0]
        b = self.baselines.shape[0]
        if (
            b < 1
            or t % b
            or self.features.shape != (t, N_SPLITS)
            or self.thresholds.shape != (t, N_SPLITS)
            or self.leaves.shape != (t, N_LEAVES)
        ):
            raise ValueError("tree arrays do not agree in shape")
        if self.features.size and (
            int(self.features.min()) < 0 or int(self.features.max()) >= len(self.columns)
        ):
            raise ValueError("a split names a column the bag does not have")
        finite = (self.thresholds, self.leaves, self.baselines)
        if not all(np.all(np.isfinite(a)) for a in finite):
            raise ValueError("tree values must be finite")

    @property
    def n_members(self) -> int:
        """``B``."""
        return int(self.baselines.shape[0])

    @property
    def trees_per_member(self) -> int:
        """``M``."""
        return int(self.features.shape[0] // self.n_members)

    def member_scores(self, x_all: FloatArray) -> FloatArray:
        """Raw score (log-odds) of every member for design rows.

        Parameters
        ----------
        x_all : ndarray, shape (n, K)
            Full design rows.

        Returns
        -------
        ndarray, shape (n, B)
        """
        return Forest.of((self,)).member_scores(x_all)

    def to_document(self, names: tuple[str, ...]) -> dict[str, Any]:
        """The artifact's form; `names` are the design column names."""
        return {
            "columns": [names[i] for i in self.columns],
            "depth": TREE_DEPTH,
            "features": encode_array(self.features, "int16"),
            "thresholds": encode_array(self.thresholds, "float64"),
            "leaves": encode_array(self.leaves, "float64"),
            "baselines": [float(v) for v in self.baselines],
        }

    @classmethod
    def from_document(cls, doc: Any, names: tuple[str, ...], where: str) -> TreeBag:
        """Read :meth:`to_document`'s form.

        Raises
        ------
        ValueError
            Malformed, another depth, or unknown columns.
        """
        if not isinstance(doc, dict) or doc.get("depth") != TREE_DEPTH:
            raise ValueError(f"`{where}`: trees of depth {TREE_DEPTH} expected")
        cols = doc.get("columns")
        if not isinstance(cols, list) or not cols or not set(cols) <= set(names):
            raise ValueError(f"`{where}.columns` must name known design columns")
        baselines = np.array(doc.get("baselines"), dtype=np.float64)
        baselines.setflags(write=False)
        return cls(
            columns=tuple(names.index(c) for c in cols),
            features=decode_array(doc.get("features"), f"{where}.features"),
            thresholds=decode_array(doc.get("thresholds"), f"{where}.thresholds"),
            leaves=decode_array(doc.get("leaves"), f"{where}.leaves"),
            baselines=baselines,
        )


@dataclass(frozen=True, eq=False)
class Forest:
    """Several bags evaluated in one pass: their trees side by side over the full design.

    Built once per loaded model (:meth:`of`); :meth:`member_scores` gives every
    member of every bag at once, so that a model with several boosted outcomes
    walks its trees in ``TREE_DEPTH`` vectorised steps in all.

    Attributes
    ----------
    features : ndarray of int64, shape (T, N_SPLITS)
        Design column (index into the full design row) of each split.
    thresholds : ndarray, shape (T, N_SPLITS)
    leaf_values : ndarray, shape (T * N_LEAVES,)
        Leaves of tree ``t`` at ``t * N_LEAVES ...``.
    member_starts : ndarray of int64, shape (M,)
        First tree of each member (members are contiguous runs of trees).
    baselines : ndarray, shape (M,)
    bag_members : tuple of int
        Members of each bag, in order (to split the scores).
    """

    features: IntArray
    thresholds: FloatArray
    leaf_values: FloatArray
    member_starts: IntArray
    baselines: FloatArray
    bag_members: tuple[int, ...]

    @classmethod
    def of(cls, bags: tuple[TreeBag, ...]) -> Forest:
        """The forest of `bags` (in order)."""
        feats: list[IntArray] = []
        starts: list[int] = []
        first = 0
        for bag in bags:
            cols = np.asarray(bag.columns, dtype=np.int64)
            feats.append(cols[bag.features.astype(np.int64)])
            m = bag.trees_per_member
            starts.extend(first + m * j for j in range(bag.n_members))
            first += bag.features.shape[0]
        return cls(
            features=np.concatenate(feats),
            thresholds=np.concatenate([b.thresholds for b in bags]),
            leaf_values=np.concatenate([b.leaves for b in bags]).ravel(),
            member_starts=np.asarray(starts, dtype=np.int64),
            baselines=np.concatenate([b.baselines for b in bags]),
            bag_members=tuple(b.n_members for b in bags),
        )

    @cached_property
    def _member_of_tree(self) -> IntArray:
        counts = np.diff(np.append(self.member_starts, self.features.shape[0]))
        out: IntArray = np.repeat(np.arange(counts.size, dtype=np.int64), counts)
        return out

    def member_scores(self, x_all: FloatArray) -> FloatArray:
        """Raw score of every member of every bag, shape (n, M).

        One compiled loop (:func:`_forest_scores`): each tree walked
        ``TREE_DEPTH`` levels in heap order, its leaf added to its member's
        baseline in tree order (scikit-learn's order of summation). Rows that
        repeat (the same bytes) are walked once: a row's scores depend on that
        row alone, so they are copied, not recomputed (the integration over
        unknown inputs repeats about a quarter of its rows).
        """
        x = np.ascontiguousarray(x_all, dtype=np.float64)
        inverse = None
        if x.shape[0] >= _DEDUPLICATE_FROM_ROWS:
            unique, inverse = np.unique(x.view(np.void(8 * x.shape[1])), return_inverse=True)
            if unique.shape[0] < x.shape[0]:
                x = np.ascontiguousarray(unique.view(np.float64).reshape(-1, x.shape[1]))
            else:
                inverse = None
        scores = _forest_scores(
            np.ascontiguousarray(x.T),
            self.features,
            self.thresholds,
            self.leaf_values,
            self._member_of_tree,
            self.baselines,
        )
        return scores if inverse is None else np.ascontiguousarray(scores[inverse.ravel()])

    def split(self, scores: FloatArray) -> list[FloatArray]:
        """`scores` (n, M) cut into each bag's (n, B_i)."""
        edges = np.cumsum(self.bag_members)[:-1]
        return list(np.split(scores, edges, axis=1))


#: Rows from which :meth:`Forest.member_scores` looks for repeated rows first. [R]
#: Below it the search costs about what it saves (one occupant's few rows).
_DEDUPLICATE_FROM_ROWS: Final[int] = 16


@njit(cache=True, nogil=True)
def _forest_scores(
    xt: FloatArray,
    features: IntArray,
    thresholds: FloatArray,
    leaf_values: FloatArray,
    member_of_tree: IntArray,
    baselines: FloatArray,
) -> FloatArray:  # pragma: no cover - compiled (tested through Forest.member_scores)
    """Members' raw scores (n, M) of design rows given as columns, `xt` (K, n); see :class:`Forest`.

    Why compiled: the trees of a model (about 20,000 for five boosted outcomes)
    walked in numpy cost 0.8 ms per occupant and 1,600 occupants/s in a batch
    (measured); a loop touches only the three nodes on each tree's path. The
    walk of a depth-3 tree is written out (node 0, then 1 or 2, then 3 to 6,
    leaf 0 to 7: heap order), with a tree's seven features and thresholds read
    once and each design column contiguous over the rows: [R] 2.6 times faster
    than the loop over levels on the rows of 60 NASS-CDS vehicles (133 -> 46 ms,
    numba's generic target, measured 2026-12-08). The same leaves, added in the
    same order: the same bits.
    """
    n = xt.shape[1]
    acc = np.empty((baselines.shape[0], n))  # members x rows: one tree's adds are contiguous
    for m in range(baselines.shape[0]):
        acc[m, :] = baselines[m]
    for t in range(features.shape[0]):  # trees outside: each tree's nodes read once
        m = member_of_tree[t]
        f0, f1, f2 = features[t, 0], features[t, 1], features[t, 2]
        f3, f4, f5, f6 = features[t, 3], features[t, 4], features[t, 5], features[t, 6]
        t0, t1, t2 = thresholds[t, 0], thresholds[t, 1], thresholds[t, 2]
        t3, t4, t5, t6 = thresholds[t, 3], thresholds[t, 4], thresholds[t, 5], thresholds[t, 6]
        base = t * N_LEAVES
        for i in range(n):  # right when x > threshold (left when x <= t, or NaN)
            if xt[f0, i] > t0:
                if xt[f2, i] > t2:
                    leaf = 6 + (xt[f6, i] > t6)
                else:
                    leaf = 4 + (xt[f5, i] > t5)
            elif xt[f1, i] > t1:
                leaf = 2 + (xt[f4, i] > t4)
            else:
                leaf = 0 + (xt[f3, i] > t3)
            acc[m, i] += leaf_values[base + leaf]
    return np.ascontiguousarray(acc.T)


def warm_up() -> None:
    """Compile (or load from the numba cache) the forest's loop."""
    one = np.zeros((1, N_SPLITS), dtype=np.int64)
    _forest_scores(
        np.zeros((1, 1)),
        one,
        np.zeros((1, N_SPLITS)),
        np.zeros(N_LEAVES),
        np.zeros(1, dtype=np.int64),
        np.zeros(1),
    )
