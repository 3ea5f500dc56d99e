"""Without Chromium the browser tests skip on a developer's machine, and fail where required."""

from __future__ import annotations

import pytest

from tests.service.browser_support import REQUIRE_BROWSER_ENV, _no_browser


def test_no_browser_skips_unless_required(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(REQUIRE_BROWSER_ENV, raising=False)
    with pytest.raises(pytest.skip.Exception, match="no Chromium"):
        _no_browser("no Chromium can be started")
    monkeypatch.setenv(REQUIRE_BROWSER_ENV, "1")
    with pytest.raises(pytest.fail.Exception, match="AACN_REQUIRE_BROWSER=1 but no Chromium"):
        _no_browser("no Chromium can be started")
