"""The quality page (HTML, a router): ``GET /v1/quality/report``.

The figures of ``GET /v1/quality`` for a reader (auditor or admin), with the same
filters: the view is ``quality_page.py``, the reliability plot ``reliability.py``, the
template ``templates/quality.html`` in the pages' frame (``service.page_frame``: the
sign-in gate, ``base.html``, the stylesheet). An HTML resource, kept out of the
OpenAPI document.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from fastapi import APIRouter, Request
from fastapi.responses import HTMLResponse, Response

from service.deps import ContextDep
from service.outcomes.quality import AGE_GROUPS, CRASH_MODES, drift_settings_of, quality_report
from service.outcomes.quality_page import filters_from_query, quality_context
from service.page_frame import chrome, form_time, gate, html_response, template_environment

__all__ = ["router"]

router = APIRouter(include_in_schema=False)

#: The quality page's templates (``quality.html`` and its plot's macro).
TEMPLATES_DIR = Path(__file__).resolve().parent / "templates"
#: One environment per process: templates compile once and are cached.
_ENV = template_environment(TEMPLATES_DIR)
#: The page's filters, as ``GET /v1/quality`` takes them.
_FILTERS = ("crash_mode", "age_group", "seat_row", "received_from", "received_before")


@router.get("/v1/quality/report", response_class=HTMLResponse)
def quality_page(request: Request, ctx: ContextDep) -> Response:
    """Triage quality against linked outcomes, with the filters of ``GET /v1/quality``."""
    started = time.perf_counter()
    session = gate(request, ctx)
    if isinstance(session, Response):
        return session
    q = request.query_params
    echo = {k: q.get(k, "") for k in _FILTERS}
    message = ""
    context: dict[str, Any] = {"overall": None, "drift": None, "targets": {}}
    try:
        filters = filters_from_query(echo, form_time)
        found = quality_report(ctx.sessions, filters, drift=drift_settings_of(ctx.settings))
        context = quality_context(found)
    except ValueError as exc:
        message = str(exc)
    context.setdefault("crash_modes", CRASH_MODES)
    context.setdefault("age_groups", AGE_GROUPS)
    context.setdefault("targets", {})
    body = _ENV.get_template("quality.html").render(
        filters=echo,
        message=message,
        **context,
        **chrome(request, ctx, session),
    )
    return html_response(body, 422 if message else 200, started=started)
