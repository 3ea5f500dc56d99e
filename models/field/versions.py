"""Every shipped field model artifact, by version, and loading one whatever its kind.

Two kinds of artifact are shipped under ``models/field/artifacts/``: the MAIS 3+
logistic models (``field_mais3*.json``, :class:`models.field.model.FieldModel`,
versions 1.0.0 withdrawn and 2.0.0) and the ISS 15+ field risk models
(``field_iss15*.json``, :class:`models.field.risk_model.RiskModel`, 3.0.0 on).
The service decides with the shipped ISS 15+ model; the others stay loadable,
byte for byte, for recall reports (``aacn-triage cases rescore --model``).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

from models.field.model import ARTIFACT_SCHEMA as MAIS3_SCHEMA
from models.field.model import FieldModel
from models.field.risk_model import ARTIFACT_SCHEMA as RISK_SCHEMA
from models.field.risk_model import RiskModel, default_artifact_path

__all__ = ["AnyFieldModel", "artifact_for_version", "artifact_versions", "load_field_artifact"]

#: Either kind of field model.
AnyFieldModel = FieldModel | RiskModel


def load_field_artifact(path: str | Path) -> AnyFieldModel:
    """Load and verify a field model artifact of either kind (by its ``schema``).

    Raises
    ------
    ValueError
        Unknown schema, malformed, tampered or stale.
    OSError
        The file cannot be read.
    """
    p = Path(path)
    try:
        schema = json.loads(p.read_text(encoding="utf-8")).get("schema")
    except (UnicodeDecodeError, json.JSONDecodeError, AttributeError) as exc:
        raise ValueError(f"field model artifact {p}: not a JSON object ({exc})") from None
    if schema == RISK_SCHEMA:
        return RiskModel.from_artifact(p)
    if schema == MAIS3_SCHEMA:
        return FieldModel.from_artifact(p)
    raise ValueError(
        f"field model artifact {p}: `schema` must be {RISK_SCHEMA!r} or {MAIS3_SCHEMA!r}"
    )


def artifact_versions(local_dirs: Sequence[Path] = ()) -> dict[str, Path]:
    """Every field model artifact (both kinds) by version: the shipped ones, then those
    in `local_dirs` (a site's recalibrated models, ``aacn-triage outcomes recalibrate``;
    a local file never replaces a shipped version)."""
    out: dict[str, Path] = {}
    shipped = sorted(default_artifact_path().parent.glob("field_*.json"))
    local = [p for d in local_dirs for p in sorted(Path(d).glob("field_*.json"))]
    for path in (*shipped, *local):
        try:
            version = json.loads(path.read_text(encoding="utf-8"))["model"]["version"]
        except (OSError, ValueError, KeyError, TypeError):
            continue
        out.setdefault(str(version), path)
    return out


def artifact_for_version(version: str, local_dirs: Sequence[Path] = ()) -> Path:
    """The artifact of field model `version` (either kind), shipped or in `local_dirs`.

    Raises
    ------
    LookupError
        No artifact of that version (the message lists those known).
    """
    versions = artifact_versions(local_dirs)
    if version not in versions:
        raise LookupError(
            f"no field model artifact of version {version!r}; shipped or local: "
            + ", ".join(sorted(versions))
        )
    return versions[version]
