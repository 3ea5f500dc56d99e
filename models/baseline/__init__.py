"""Statistical baseline: survey-weighted logistic regression on NASS-CDS 1997-2000.

Prediction (numpy only) is in :mod:`models.baseline.logistic`; the reproducible
fit (statsmodels, scikit-learn) is in :mod:`models.offline.baseline.fit`
(``python -m models.offline.baseline.fit``). See ``MODEL_CARD.md``.
"""

from models.baseline.logistic import (
    BaselineFeatures,
    BaselineModel,
    BaselinePrediction,
    BaselinePredictions,
    default_artifact_path,
    load_default,
)

__all__ = [
    "BaselineFeatures",
    "BaselineModel",
    "BaselinePrediction",
    "BaselinePredictions",
    "default_artifact_path",
    "load_default",
]
