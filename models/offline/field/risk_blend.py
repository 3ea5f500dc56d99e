"""A blend of the two fitted kinds: the regression's and the bag's calibrated logits, weighted.

``logit P = (1 - w) logit_regression + w logit_bag``, ``w`` in (0, 1), chosen
with the kind by the cross-validated log loss (:func:`.risk_fit.choose_kind`):
the two see the inputs differently (smooth splines and slopes against
depth-3 splits) and their errors are not the same, so a mix can rank and
predict better than either; ``w`` = 0 and 1 are the two kinds themselves. Each
part keeps its own weighted recalibration, so the blend of calibrated logits
needs none of its own (its held-out P/O in the model card shows it). The
served form is :class:`models.field.risk_model.BlendOutcomeModel`.
"""

from __future__ import annotations

from dataclasses import dataclass

from models.arrays import FloatArray
from models.offline.field.risk_boosted import BoostedFitted
from models.offline.field.risk_core import Fitted, expit

__all__ = ["BlendFitted"]


@dataclass(frozen=True, eq=False)
class BlendFitted:
    """A fitted blend: the face of :class:`.risk_core.Fitted` (``eta``, ``logit``,
    ``probability``, ``columns``).

    Attributes
    ----------
    logistic : Fitted
    boosted : BoostedFitted
    weight : float
        ``w``, the bag's share of the logit.
    """

    logistic: Fitted
    boosted: BoostedFitted
    weight: float

    @property
    def columns(self) -> tuple[int, ...]:
        """Design columns either part uses."""
        return tuple(sorted(set(self.logistic.columns) | set(self.boosted.columns)))

    def logit(self, x_all: FloatArray) -> FloatArray:
        """Calibrated logit, shape (n,)."""
        w = self.weight
        out: FloatArray = (1.0 - w) * self.logistic.logit(x_all) + w * self.boosted.logit(x_all)
        return out

    def eta(self, x_all: FloatArray) -> FloatArray:
        """Ranking score: the calibrated logit (a blend has no uncalibrated score)."""
        return self.logit(x_all)

    def probability(self, x_all: FloatArray) -> FloatArray:
        """Calibrated probability, shape (n,)."""
        return expit(self.logit(x_all))
