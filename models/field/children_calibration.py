"""The children's calibration of the decision: P(ISS 15+) of a child, by age group and child seat.

The decision's model is shared by adults and children (feature set 3,
:mod:`models.field.risk_children`), and its national recalibration is one
``(a, b)`` for everyone. Held out by crash, that left the children's weighted
predicted/observed far apart by age group (3.3.1: 0.46 for ages 0-4, 1.53 for
5-9): the trees seldom split on the few children, and the one recalibration is
the adults'. The children get a calibration of their own, with the national
weights, on the shared model's held-out logit::

    logit P_child = a + b * logit P_shared + c_5_9 * age_5_9 + c_10_15 * age_10_15
                    + c_seat * child_seat

(ages 0-4 the reference group; the columns are the design's indicators, so a
child donor of an integration over unknown inputs takes it as a child sent
with its age does). It is fitted offline by weighted maximum likelihood on the
children's out-of-fold probabilities (:mod:`models.offline.field.risk_children_fit`),
which chose it by cross-validation by crash over a regression fitted on
children alone (model card, "Children"). Each of the decision's refits (the
bag's members) takes the calibration fitted on its own resample of the
children's crashes, so the interval carries the calibration's uncertainty too.
Adults' rows are untouched.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Final

import numpy as np

from models.arrays import FloatArray

__all__ = [
    "CHILDREN_CALIBRATION_TERMS",
    "ChildrenCalibration",
    "child_rows",
]

#: The design columns of the calibration's terms beside the shared logit (the
#: age group 0-4 is the reference; ``child_seat``: restrained in a child seat).
CHILDREN_CALIBRATION_TERMS: Final[tuple[str, ...]] = ("age_5_9", "age_10_15", "child_seat")

#: The design columns that mark a child row (one of them is 1 for a child).
_AGE_GROUP_COLUMNS: Final[tuple[str, ...]] = ("age_0_4", "age_5_9", "age_10_15")


def child_rows(x_all: FloatArray, candidates: Sequence[str]) -> np.ndarray:
    """Which design rows are a child's, shape (n,) of bool.

    Parameters
    ----------
    x_all : ndarray, shape (n, K)
        Full design rows of feature set 3.
    candidates : sequence of str
        The design's column names (``K``).
    """
    idx = [list(candidates).index(c) for c in _AGE_GROUP_COLUMNS]
    out: np.ndarray = x_all[:, idx].sum(axis=1) > 0.5
    return out


@dataclass(frozen=True, eq=False)
class ChildrenCalibration:
    """The children's calibration of the decision's logit (module docstring).

    Attributes
    ----------
    coefficients : ndarray, shape (2 + T,)
        ``(a, b, c_1 .. c_T)`` for the terms :data:`CHILDREN_CALIBRATION_TERMS`.
    bootstrap_coefficients : ndarray, shape (B, 2 + T)
        One set per refit of the decision (its ``B``), each fitted on a resample
        of the children's crashes.
    columns : tuple of int
        The terms' indices in the design.
    age_group_columns : tuple of int
        The indices of the three age-group indicators (a child row has one set).
    """

    coefficients: FloatArray
    bootstrap_coefficients: FloatArray
    columns: tuple[int, ...]
    age_group_columns: tuple[int, ...]

    @classmethod
    def from_document(
        cls, block: Mapping[str, Any], candidates: Sequence[str], n_refits: int
    ) -> ChildrenCalibration:
        """Read the artifact's ``children_calibration`` block.

        Raises
        ------
        ValueError
            Malformed, other terms, or not one coefficient set per refit of the
            decision (`n_refits`).
        """
        terms = tuple(block.get("terms", ()))
        if terms != CHILDREN_CALIBRATION_TERMS:
            raise ValueError(f"children_calibration: terms must be {CHILDREN_CALIBRATION_TERMS}")
        k = 2 + len(terms)
        coef = np.asarray(block.get("coefficients"), dtype=np.float64)
        boot = np.asarray(block.get("bootstrap_coefficients"), dtype=np.float64)
        if coef.shape != (k,) or boot.shape != (n_refits, k):
            raise ValueError(
                f"children_calibration: coefficients ({k},) and bootstrap_coefficients "
                f"({n_refits}, {k}) expected, got {coef.shape} and {boot.shape}"
            )
        if not (np.isfinite(coef).all() and np.isfinite(boot).all()):
            raise ValueError("children_calibration: coefficients must be finite")
        names = list(candidates)
        return cls(
            coefficients=coef,
            bootstrap_coefficients=boot,
            columns=tuple(names.index(t) for t in terms),
            age_group_columns=tuple(names.index(c) for c in _AGE_GROUP_COLUMNS),
        )

    def apply(
        self, eta: FloatArray, boot: FloatArray, x_all: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """The decision's logit and refits' logits with the children's rows calibrated.

        Parameters
        ----------
        eta : ndarray, shape (n,)
            The shared model's calibrated logit.
        boot : ndarray, shape (n, B)
            Its refits' logits.
        x_all : ndarray, shape (n, K)
            The design rows.

        Returns
        -------
        eta, boot : ndarray, shapes (n,) and (n, B)
            New arrays; adults' rows bit for bit the inputs'.
        """
        child = x_all[:, list(self.age_group_columns)].sum(axis=1) > 0.5
        if not child.any():
            return eta, boot
        eta, boot = eta.copy(), boot.copy()
        z = x_all[child][:, list(self.columns)]  # (m, T)
        c = self.coefficients
        eta[child] = c[0] + c[1] * eta[child] + z @ c[2:]
        cb = self.bootstrap_coefficients  # (B, 2 + T)
        boot[child] = cb[:, 0] + cb[:, 1] * boot[child] + z @ cb[:, 2:].T
        return eta, boot

    def to_document(self) -> dict[str, Any]:
        """The artifact block (floats as JSON numbers)."""
        return {
            "terms": list(CHILDREN_CALIBRATION_TERMS),
            "coefficients": [float(v) for v in self.coefficients],
            "bootstrap_coefficients": [[float(v) for v in r] for r in self.bootstrap_coefficients],
        }
