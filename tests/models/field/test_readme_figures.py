"""README.md's figures of the decision are the shipped artifact's (issue 32).

`aacn-triage fit-field` writes them (models/offline/field/readme.py); these tests
hold the README to what the shipped artifact renders, and the README's example
answer to the engine's, so that a refit cannot leave stale figures behind.
"""

from __future__ import annotations

import json

import pytest

from models.field.risk_model import default_artifact_path
from models.offline.field.readme import (
    BEGIN,
    END,
    README_EXAMPLE,
    TIER_EXAMPLES,
    example_answer,
    readme_block,
    readme_path,
)
from models.offline.field.risk_measured import CHECK_FILE, load_check
from models.offline.field.risk_report import default_report_dir

DOC = json.loads(default_artifact_path().read_text(encoding="utf-8"))
CHECK = load_check(DOC, default_report_dir() / CHECK_FILE)


@pytest.fixture(scope="module")
def answer() -> dict[str, object]:
    return example_answer(DOC)


def test_the_readme_block_is_the_shipped_artifacts(answer: dict[str, object]) -> None:
    text = readme_path().read_text(encoding="utf-8")
    start, end = text.index(BEGIN), text.index(END) + len(END)
    assert text[start:end] == readme_block(DOC, answer, CHECK)


def test_the_readme_example_is_the_one_in_try_it() -> None:
    """The notification the block answers is the one the README's curl sends."""
    text = readme_path().read_text(encoding="utf-8")
    curl = text[text.index("-d '{") + 4 : text.index("}]}'") + 3]
    assert json.loads(curl) == README_EXAMPLE


def test_the_example_is_answered_by_the_iss15_model(answer: dict[str, object]) -> None:
    """A belted 42-year-old at 40 km/h with the airbag: 1.0.0 answered P(MAIS 3+) 0.23 (it
    read 40 km/h as 40 mph); NHTSA's all-crash MAIS 3+ curve gives 0.05 at 25 mph (40 km/h),
    and ISS 15+ is rarer than MAIS 3+."""
    assert answer["model"] == f"field_iss15@{DOC['model']['version']}"
    assert float(answer["probability"]) < 0.05  # type: ignore[arg-type]


@pytest.mark.parametrize("tier", ["high", "moderate", "none"])
def test_each_tier_example_lands_in_its_tier(answer: dict[str, object], tier: str) -> None:
    """The README shows one notification per tier, chosen for the tier it must show; the
    moderate one is the README's own driver at 60 km/h (its 40 km/h, sent as measured by
    the vehicle, reads as a 31 km/h reconstruction: no telemetry indication)."""
    tiers = answer["tiers"]
    assert isinstance(tiers, dict)
    assert tiers[tier]["tier"] == tier
    assert "Level I" not in tiers[tier]["recommendation"]
    assert TIER_EXAMPLES["moderate"]["occupants"] == README_EXAMPLE["occupants"]
    assert answer["tier"] == "none"
