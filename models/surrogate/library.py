"""The surrogate library: load and verify the artifacts, find a family, say when stale."""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from types import MappingProxyType
from typing import Any

from models.impact_mode import ImpactMode
from models.notification import Body
from models.surrogate.family import SurrogateFamily
from models.surrogate.spec import (
    AIRBAG_MODES,
    FAMILIES,
    family_name,
)
from models.surrogate.store import MANIFEST_NAME, read_artifact, sha256_file


def default_artifact_dir() -> Path:
    """``models/surrogate/artifacts`` of this package."""
    return Path(__file__).resolve().parent / "artifacts"


#: Families already assembled in this process, by the SHA-256 of their artifact
#: file (content-addressed: the same bytes give the same immutable family). A
#: load still reads and checks every file's checksum against the manifest; only
#: the assembly (about 0.1 s and 14 MB per family) is shared, e.g. between the
#: apps a test session creates.
_FAMILY_CACHE: dict[str, SurrogateFamily] = {}


class SurrogateLibrary:
    """The verified set of surrogate families (immutable).

    Attributes
    ----------
    name, version : str
        From the manifest.
    sha256 : str
        SHA-256 of ``manifest.json``.
    lpm_code_sha256, parameter_set_sha256 : str
        Checksums of the LPM code and parameter set the families were built from.
    engine_version : str
    """

    __slots__ = (
        "_families",
        "directory",
        "engine_version",
        "lpm_code_sha256",
        "manifest",
        "name",
        "parameter_set_sha256",
        "sha256",
        "version",
    )

    name: str
    version: str
    sha256: str
    lpm_code_sha256: str
    parameter_set_sha256: str
    engine_version: str
    directory: Path
    manifest: Mapping[str, Any]
    _families: Mapping[str, SurrogateFamily]

    def __setattr__(self, key: str, value: object) -> None:
        if hasattr(self, key):
            raise AttributeError(f"SurrogateLibrary is immutable ({key})")
        object.__setattr__(self, key, value)

    @classmethod
    def load(cls, directory: Path | None = None, *, require_all: bool = True) -> SurrogateLibrary:
        """Load and verify the artifacts of `directory` (default: the shipped ones).

        Parameters
        ----------
        directory : Path, optional
        require_all : bool, optional
            Require every family of :data:`models.surrogate.spec.FAMILIES`
            (False for partial test libraries).

        Raises
        ------
        ValueError
            With the reason: manifest missing or malformed, a file missing, a
            checksum mismatch, an artifact recording other LPM checksums than
            the manifest, or (``require_all``) a family missing.
        """
        d = default_artifact_dir() if directory is None else Path(directory)
        mpath = d / MANIFEST_NAME
        if not mpath.is_file():
            raise ValueError(f"surrogate manifest missing: {mpath}")
        try:
            manifest = json.loads(mpath.read_bytes())
            files: dict[str, str] = dict(manifest["files"])
            keys = ("name", "version", "lpm_code_sha256", "parameter_set_sha256", "engine_version")
            ident = {k: str(manifest[k]) for k in keys}
        except (ValueError, KeyError, TypeError) as exc:
            raise ValueError(f"surrogate manifest malformed: {exc}") from exc
        families: dict[str, SurrogateFamily] = {}
        for fname, digest in sorted(files.items()):
            path = d / fname
            if not path.is_file():
                raise ValueError(f"surrogate artifact missing: {fname}")
            actual = sha256_file(path)
            if actual != digest:
                raise ValueError(
                    f"surrogate artifact checksum mismatch: {fname} "
                    f"(manifest {digest[:12]}..., file {actual[:12]}...)"
                )
            fam = _FAMILY_CACHE.get(actual)
            if fam is None:
                arrays, meta = read_artifact(path)
                fam = SurrogateFamily.from_arrays(arrays, meta)
                _FAMILY_CACHE[actual] = fam
            for k in ("lpm_code_sha256", "parameter_set_sha256", "engine_version"):
                if str(fam.meta.get(k)) != ident[k]:
                    raise ValueError(f"surrogate artifact {fname}: {k} differs from the manifest")
            families[fam.name] = fam
        if require_all:
            missing = [s.name for s in FAMILIES if s.name not in families]
            if missing:
                raise ValueError(f"surrogate families missing: {', '.join(missing)}")
        self = cls.__new__(cls)
        for k, v in ident.items():
            object.__setattr__(self, k, v)
        object.__setattr__(self, "sha256", sha256_file(mpath))
        object.__setattr__(self, "directory", d)
        object.__setattr__(self, "manifest", MappingProxyType(manifest))
        object.__setattr__(self, "_families", MappingProxyType(families))
        return self

    def families(self) -> Mapping[str, SurrogateFamily]:
        """Every loaded family by name (read-only mapping)."""
        return self._families

    @property
    def family_names(self) -> tuple[str, ...]:
        """Names of the loaded families."""
        return tuple(sorted(self._families))

    def family(
        self, mode: ImpactMode, body: Body, belted: bool, airbag_deployed: bool
    ) -> SurrogateFamily:
        """The family for a mode, body and restraint configuration.

        ``airbag_deployed`` is the mode's airbag: the frontal airbag (frontal),
        the side and curtain airbags (near side). Rear and far-side families
        serve every airbag state (no airbag acts in those LPMs; see
        :mod:`models.surrogate.spec`).

        Raises
        ------
        KeyError
            When the family is not in the library.
        """
        mode = ImpactMode(mode)
        bag: bool | None = bool(airbag_deployed) if mode in AIRBAG_MODES else None
        return self._families[family_name(mode, Body(body), bool(belted), bag)]

    def stale_reason(self) -> str | None:
        """Why the library no longer fits the occupant models, or None.

        What the families depend on is checked by running it: the parameter
        values (their checksum) and the golden cases recorded in the manifest
        (:mod:`models.surrogate.golden`), rerun now. A docstring edit, a
        reformat or a refactor that keeps the numbers leaves the library
        current; a change of physics or of a parameter value does not.
        """
        from models import ENGINE_VERSION
        from models.lpm.params import load_parameter_set
        from models.surrogate.golden import golden_mismatch

        golden = self.manifest.get("golden")
        if not golden:
            return "the surrogate manifest records no golden cases; rebuild the surrogates"
        if self.engine_version != ENGINE_VERSION:
            return (
                f"surrogates were built by engine {self.engine_version}, running {ENGINE_VERSION}"
            )
        specs = {s.name: s for s in FAMILIES}
        reason = golden_mismatch(golden, specs, load_parameter_set())
        if reason is not None:
            return reason
        return None
