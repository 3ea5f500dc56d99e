"""A field risk artifact recalibrated on local outcomes: its version and its document.

The document is the served artifact's, with (:func:`recalibrated_document`):

- ``model.version``: ``<served version>+local.<site>.<n>`` (:func:`local_version`;
  semantic versioning's build metadata: the same model, locally recalibrated, the
  ``n``-th time for that site);
- ``recalibration``: the map ``logit P = a + b logit P_decided`` applied by the loader
  (:class:`models.field.risk_model.RiskModel`) to the decision, relative to the
  national model as fitted (a recalibration of a recalibrated model is composed), with
  its provenance: the served version and checksum it was fitted on, the number of
  cases, occupants and outcomes, the SHA-256 of the sorted list of ``case_id:seat``
  it learned from and that list itself, the precision plan and the cross-validation;
- ``operating_points``: every threshold (and threshold by knowledge) mapped through the
  map (:func:`models.field.recalibration.map_threshold`): the same occupants are
  flagged, so each operating point keeps its sensitivity; the served threshold is kept
  as ``threshold_before_recalibration``. The high tier's fixed 20 % is not mapped: it
  applies to the recalibrated probability;
- ``content_sha256``: recomputed (canonical JSON, as every artifact).
"""

from __future__ import annotations

import copy
import hashlib
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import asdict
from typing import Any, Final

from models.field.model import canonical_content_sha256
from models.field.recalibration import (
    CrossValidation,
    PrecisionPlan,
    Recalibration,
    compose,
    map_threshold,
)

__all__ = [
    "SITE_PATTERN",
    "base_version",
    "cases_sha256",
    "local_version",
    "recalibrated_document",
]

#: A site's name in a version: lower-case letters, digits and hyphens (semver build
#: metadata identifiers), at most 40 characters.
SITE_PATTERN: Final[re.Pattern[str]] = re.compile(r"[a-z0-9][a-z0-9-]{0,39}")
_LOCAL: Final[str] = "+local."


def base_version(version: str) -> str:
    """The national version a (possibly recalibrated) version stands on."""
    return version.split("+", 1)[0]


def local_version(served_version: str, site: str, existing: Sequence[str]) -> str:
    """``<national version>+local.<site>.<n>``, `n` one more than the highest in `existing`.

    Raises
    ------
    ValueError
        `site` does not match :data:`SITE_PATTERN`.
    """
    if SITE_PATTERN.fullmatch(site) is None:
        raise ValueError(
            f"site {site!r}: lower-case letters, digits and hyphens, at most 40 characters"
        )
    prefix = f"{base_version(served_version)}{_LOCAL}{site}."
    taken = [int(v[len(prefix) :]) for v in existing if v.startswith(prefix)]
    return f"{prefix}{max(taken, default=0) + 1}"


def cases_sha256(occupants: Sequence[str]) -> str:
    """SHA-256 of the sorted ``case_id:seat`` lines, one per line (UTF-8)."""
    return hashlib.sha256("\n".join(sorted(occupants)).encode()).hexdigest()


def _finite(values: Mapping[str, Any]) -> dict[str, Any]:
    """JSON has no infinity: an infinite figure (no information) is null."""
    return {
        k: None if isinstance(v, float) and not math.isfinite(v) else v for k, v in values.items()
    }


def recalibrated_document(
    served: Mapping[str, Any],
    *,
    version: str,
    site: str,
    recalibration: Recalibration,
    plan: PrecisionPlan,
    cross_validation: CrossValidation,
    occupants: Sequence[str],
    cases: int,
) -> dict[str, Any]:
    """The served artifact's document recalibrated (module docstring); pure.

    Parameters
    ----------
    served : Mapping
        The served artifact's document (verified).
    version : str
        The new version (:func:`local_version`).
    site : str
    recalibration : Recalibration
        Fitted on the served model's decided probabilities.
    plan : PrecisionPlan
    cross_validation : CrossValidation
    occupants : sequence of str
        ``case_id:seat`` of every linked occupant it learned from.
    cases : int
        Distinct cases (crashes) among them.
    """
    doc = copy.deepcopy(dict(served))
    a, b = recalibration.intercept, recalibration.slope
    prior = doc.get("recalibration")
    total = (a, b) if prior is None else compose((prior["intercept"], prior["slope"]), (a, b))
    for point in doc["operating_points"].values():
        before = float(point["threshold"])
        point["threshold_before_recalibration"] = before
        point["threshold"] = map_threshold(before, a, b)
        if "thresholds_by_knowledge" in point:
            point["thresholds_by_knowledge"] = {
                k: map_threshold(float(t), a, b)
                for k, t in point["thresholds_by_knowledge"].items()
            }
        point["description"] = (
            f"{point['description']}; recalibrated on {site}'s outcomes: the threshold "
            f"{before:.4g} mapped to {point['threshold']:.4g} (the same occupants flagged)"
        )
    doc["model"] = {**doc["model"], "version": version}
    doc["recalibration"] = {
        "intercept": total[0],
        "slope": total[1],
        "applies_to": "iss15",
        "formula": "logit P = intercept + slope * logit P_decided (the national model's)",
        "fitted": {
            "intercept": a,
            "slope": b,
            "intercept_se": recalibration.intercept_se,
            "slope_se": recalibration.slope_se,
            "method": recalibration.method,
            "on_version": served["model"]["version"],
            "on_content_sha256": served["content_sha256"],
        },
        "site": site,
        "learned_from": {
            "cases": cases,
            "occupants": len(occupants),
            "events": plan.events,
            "effective_events": plan.effective_events,
            "occupants_sha256": cases_sha256(occupants),
            "occupant_list": sorted(occupants),
        },
        "precision": {**_finite(asdict(plan)), "reason": plan.reason},
        "cross_validation": {
            **_finite(asdict(cross_validation)),
            "improves": cross_validation.improves,
        },
        "high_tier": "the high tier's threshold applies to the recalibrated probability",
    }
    doc["content_sha256"] = canonical_content_sha256(doc)
    return doc
