"""The boosted kind of field risk model: a bag of boosted trees, fitted and exported.

Where cross-validation by crash prefers it to the penalised regression
(:func:`models.offline.field.risk_fit.select_spec`), an outcome is served as
``B`` gradient boosted classifiers (scikit-learn ``HistGradientBoostingClassifier``,
trees of depth :data:`models.field.boosted.TREE_DEPTH`, no early stopping: the
number of trees is chosen by cross-validated log loss; the score may only rise
with delta-V and age, :data:`MONOTONE_INCREASING`), each fitted unweighted
on a bootstrap resample of whole crashes of the training rows (the ranking fit;
the survey over-samples severe crashes and an unweighted fit uses them all).
The ranking score is the members' mean log-odds; ``logit P = a + b score`` is
fitted with the national weights on the out-of-bag scores (each row scored only
by members that did not see its crash: in-sample scores of boosted trees are
overconfident). The members' spread is the 95 % interval's, as the
regression's bootstrap refits are.

:func:`export_bag` turns fitted scikit-learn models into the served
:class:`models.field.boosted.TreeBag`; a test checks the two agree.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np
from sklearn.ensemble import HistGradientBoostingClassifier

from models.arrays import FloatArray, IntArray
from models.field.boosted import ALWAYS_LEFT, N_LEAVES, N_SPLITS, TREE_DEPTH, TreeBag
from models.field.risk_children import ALL_COLUMNS_3
from models.offline.field.risk_core import CalibratedScore, weighted_recalibration
from models.offline.field.risk_metrics import crash_resamples

__all__ = ["MONOTONE_INCREASING", "BoostedFitted", "export_bag", "fit_bag", "single_boosted"]

#: Shrinkage of every boosted fit (scikit-learn ``learning_rate``, dimensionless). Not
#: tuned: the number of trees, which trades against it, is chosen by cross-validation.
LEARNING_RATE = 0.05
#: L2 penalty on leaf values (scikit-learn ``l2_regularization``, dimensionless). Not
#: tuned: a mild shrinkage of leaves fed by few positives (scikit-learn's default is 0).
L2_LEAF = 1.0


#: Design columns the score may only rise with, all else equal: delta-V and its
#: spline and interaction columns (each non-decreasing in delta-V, so the score
#: is too) and age (Kent et al. 2005, Stapp 49: thoracic tolerance falls with
#: age; risk rising with age at a given crash is the field's finding as well).
#: Unconstrained trees wiggle downwards where data are thin (a test found it).
MONOTONE_INCREASING: Final[frozenset[str]] = frozenset(
    "delta_v_kmh delta_v_s1 delta_v_s2 near_side_dv far_side_dv rear_dv belted_dv "
    "age_years age_s1".split()
)


def single_boosted(
    n_trees: int, seed: int, columns: Sequence[int] | None = None
) -> HistGradientBoostingClassifier:
    """One unfitted member with the fit's settings (monotone where :data:`MONOTONE_INCREASING`
    names a design column of `columns`)."""
    cst = (
        None
        if columns is None
        else [1 if ALL_COLUMNS_3[c] in MONOTONE_INCREASING else 0 for c in columns]
    )
    return HistGradientBoostingClassifier(
        max_iter=n_trees,
        learning_rate=LEARNING_RATE,
        max_depth=TREE_DEPTH,
        l2_regularization=L2_LEAF,
        early_stopping=False,
        random_state=seed,
        monotonic_cst=cst,
    )


def _heap_tree(nodes: np.ndarray) -> tuple[IntArray, FloatArray, FloatArray]:
    """One scikit-learn tree (its ``nodes`` record array) as a complete heap tree."""
    feat = np.zeros(N_SPLITS, dtype=np.int64)
    thr = np.full(N_SPLITS, ALWAYS_LEFT)
    leaves = np.zeros(N_LEAVES)

    def place(k: int, node: int, depth: int) -> None:
        rec = nodes[node]
        if depth == TREE_DEPTH:
            if not rec["is_leaf"]:
                raise ValueError(f"a tree is deeper than {TREE_DEPTH}")
            leaves[k - N_SPLITS] = rec["value"]
            return
        if rec["is_leaf"]:  # padding split: always left, the same value below
            place(2 * k + 1, node, depth + 1)
            place(2 * k + 2, node, depth + 1)
            return
        if rec["is_categorical"]:
            raise ValueError("categorical splits are not exported")
        feat[k] = int(rec["feature_idx"])
        thr[k] = float(rec["num_threshold"])
        place(2 * k + 1, int(rec["left"]), depth + 1)
        place(2 * k + 2, int(rec["right"]), depth + 1)

    place(0, 0, 0)
    return feat, thr, leaves


def export_bag(
    members: Sequence[HistGradientBoostingClassifier], columns: Sequence[int]
) -> TreeBag:
    """The served form of fitted members (binary classifiers on design `columns`)."""
    feats, thrs, leaves, baselines = [], [], [], []
    n_trees = None
    for m in members:
        trees = [it[0] for it in m._predictors]
        if n_trees is None:
            n_trees = len(trees)
        if len(trees) != n_trees:
            raise ValueError("members must have the same number of trees")
        for t in trees:
            f, h, v = _heap_tree(t.nodes)
            feats.append(f)
            thrs.append(h)
            leaves.append(v)
        baselines.append(float(np.ravel(m._baseline_prediction)[0]))
    b = np.array(baselines)
    b.setflags(write=False)
    features = np.array(feats, dtype=np.int16)
    thresholds = np.array(thrs)
    leaf = np.array(leaves)
    for a in (features, thresholds, leaf):
        a.setflags(write=False)
    return TreeBag(tuple(columns), features, thresholds, leaf, b)


@dataclass(frozen=True, eq=False)
class BoostedFitted(CalibratedScore):
    """A bag of boosted trees and its weighted recalibration.

    The same face as :class:`models.offline.field.risk_core.Fitted`
    (``eta``, ``logit``, ``probability``, ``calibration``, ``columns``).

    Attributes
    ----------
    bag : TreeBag
    calibration : (float, float)
        ``(a, b)`` of ``logit P = a + b eta``.
    n_trees : int
    """

    bag: TreeBag
    calibration: tuple[float, float]
    n_trees: int

    @property
    def columns(self) -> tuple[int, ...]:
        """Design columns the trees use."""
        return self.bag.columns

    def member_logits(self, x_all: FloatArray) -> FloatArray:
        """Calibrated logit of every member, shape (n, B)."""
        a, b = self.calibration
        out: FloatArray = a + b * self.bag.member_scores(x_all)
        return out

    def eta(self, x_all: FloatArray) -> FloatArray:
        """Ranking score (members' mean log-odds), shape (n,)."""
        out: FloatArray = self.bag.member_scores(x_all).mean(axis=1)
        return out


def fit_bag(
    x_all: FloatArray,
    y: FloatArray,
    w: FloatArray,
    crash: IntArray,
    columns: Sequence[int],
    n_trees: int,
    n_members: int,
    seed: int,
    calibrate_on: np.ndarray | None = None,
) -> BoostedFitted:
    """Fit `n_members` boosted models on resamples of whole crashes, recalibrate out of bag.

    Parameters
    ----------
    x_all : ndarray, shape (n, K)
        Design rows of the training part.
    y, w : ndarray, shape (n,)
        Outcome and national weight.
    crash : ndarray of int, shape (n,)
    columns : sequence of int
        Design columns the trees may split on.
    n_trees, n_members, seed : int
    calibrate_on : ndarray of bool, shape (n,), optional
        Rows the recalibration is fitted on (default all; out of bag only).
    """
    cols = list(columns)
    x = x_all[:, cols]
    resamples = crash_resamples(crash, n_members, seed)
    members = []
    oob_sum = np.zeros(y.size)
    oob_n = np.zeros(y.size)
    for j, ix in enumerate(resamples):
        m = single_boosted(n_trees, seed + j, cols)
        m.fit(x[ix], y[ix])
        members.append(m)
        out = np.ones(y.size, dtype=bool)
        out[ix] = False
        oob_sum[out] += m.decision_function(x[out])
        oob_n[out] += 1.0
    bag = export_bag(members, cols)
    seen = oob_n > 0
    if calibrate_on is not None and y[seen & calibrate_on].min() < y[seen & calibrate_on].max():
        seen &= calibrate_on  # else both outcomes are not there: every row out of bag
    score = oob_sum[seen] / oob_n[seen]
    cal = weighted_recalibration(score, y[seen], w[seen])
    return BoostedFitted(bag=bag, calibration=cal, n_trees=n_trees)
