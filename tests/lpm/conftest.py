"""Shared fixtures of the occupant LPM tests."""

from __future__ import annotations

import pytest

from models.lpm.params import ParameterSet, load_parameter_set


@pytest.fixture(scope="session")
def params() -> ParameterSet:
    """The default compact-sedan parameter set."""
    return load_parameter_set()
