"""Fixtures shared by the engine's tests and the offline tools' tests."""

from __future__ import annotations

from pathlib import Path

import pytest

from models.lpm.params import ParameterSet, load_parameter_set
from tests.models.surrogate.tiny import TINY_CONFIG, tiny_spec


@pytest.fixture(scope="session")
def params() -> ParameterSet:
    """The default compact-sedan parameter set."""
    return load_parameter_set()


@pytest.fixture(scope="session")
def tiny_library_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A one-family surrogate library built on the fly (:mod:`tests.models.surrogate.tiny`)."""
    from models.offline.surrogate.build import build_family, write_manifest

    d = tmp_path_factory.mktemp("surrogates")
    build_family(tiny_spec(), d, TINY_CONFIG)
    write_manifest(d, TINY_CONFIG)
    return d
