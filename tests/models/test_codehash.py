"""The kept code checksums: the same digest as parsing the sources, every time."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from models.codehash import source_tree_sha256
from models.field.risk_children import FEATURE_SET_SOURCES_3
from models.lpm.fingerprint import _MODELS, MODEL_SOURCES
from models.surrogate.evaluate import _EVALUATION_SOURCES
from models.triage.loading import TRIAGE_SOURCES


def _engine_source_lists() -> list[list[Path]]:
    """Every list of sources the engine checksums at load."""
    lists = [
        [_MODELS / rel for rel in MODEL_SOURCES],
        [_MODELS / rel for rel in TRIAGE_SOURCES],
        [_MODELS / "field/measurement.py"],
        [_MODELS / "field/features.py"],
        list(_EVALUATION_SOURCES),
    ]
    lists += [[_MODELS / rel for rel in srcs] for srcs in FEATURE_SET_SOURCES_3.values()]
    return lists


def test_kept_checksums_equal_the_parsed_ones(tmp_path: Path) -> None:
    for paths in _engine_source_lists():
        parsed = source_tree_sha256(paths, use_cache=False)
        assert source_tree_sha256(paths, cache=tmp_path) == parsed  # computed and kept
        assert source_tree_sha256(paths, cache=tmp_path) == parsed  # read back
    entries = sorted(tmp_path.glob("*.sha256"))
    assert len(entries) == len({tuple(p) for p in _engine_source_lists()})
    assert not list(tmp_path.glob(".codehash-*"))  # no temporary file left


def test_the_default_directory_is_under_numbas_cache(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    paths = [_MODELS / rel for rel in TRIAGE_SOURCES]
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    parsed = source_tree_sha256(paths, use_cache=False)
    assert source_tree_sha256(paths) == parsed
    assert len(list((tmp_path / "codehash").glob("*.sha256"))) == 1
    monkeypatch.delenv("NUMBA_CACHE_DIR")
    assert source_tree_sha256(paths) == parsed  # no directory: computed


def test_a_corrupt_entry_is_computed_again_and_rewritten(tmp_path: Path) -> None:
    paths = [_MODELS / rel for rel in MODEL_SOURCES]
    parsed = source_tree_sha256(paths, use_cache=False)
    source_tree_sha256(paths, cache=tmp_path)
    (entry,) = tmp_path.glob("*.sha256")
    for corrupt in (b"0" * 63, b"not a digest", b"\xff\xfe", b""):
        entry.write_bytes(corrupt)
        assert source_tree_sha256(paths, cache=tmp_path) == parsed
        assert entry.read_text().strip() == parsed


def test_an_edited_file_misses_the_cache(tmp_path: Path) -> None:
    source = tmp_path / "module.py"
    source.write_text("def f(x):\n    return x + 1\n")
    kept = tmp_path / "kept"
    first = source_tree_sha256([source], cache=kept)
    source.write_text('def f(x):\n    """Docstring."""\n    return x + 1  # comment\n')
    assert source_tree_sha256([source], cache=kept) == first  # the same tree, a new entry
    source.write_text("def f(x):\n    return x + 2\n")
    changed = source_tree_sha256([source], cache=kept)
    assert changed != first
    assert changed == source_tree_sha256([source], use_cache=False)
    assert len(list(kept.glob("*.sha256"))) == 3


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into a read-only directory")
def test_a_read_only_cache_is_read_and_never_written(tmp_path: Path) -> None:
    paths = [_MODELS / rel for rel in TRIAGE_SOURCES]
    parsed = source_tree_sha256(paths, use_cache=False)
    tmp_path.chmod(0o555)
    try:
        assert source_tree_sha256(paths, cache=tmp_path) == parsed
        assert not list(tmp_path.iterdir())
    finally:
        tmp_path.chmod(0o755)


def test_an_unwritable_cache_path_is_computed(tmp_path: Path) -> None:
    """A cache directory that cannot be made (a file stands in its place)."""
    blocker = tmp_path / "blocker"
    blocker.write_text("a file, not a directory")
    paths = [_MODELS / rel for rel in TRIAGE_SOURCES]
    parsed = source_tree_sha256(paths, use_cache=False)
    assert source_tree_sha256(paths, cache=blocker / "codehash") == parsed
