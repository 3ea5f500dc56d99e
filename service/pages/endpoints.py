"""The dispatcher's pages (HTML): the case list and the case page.

- ``GET /v1/cases/{case_id}/report``: the case page (auditor or admin).
- ``GET /v1/reports``: recent cases with the filters of ``GET /v1/cases``.

The pages accept a session cookie (signing in: ``service.sign_in``) or, like the API,
an ``Authorization: Bearer`` key (``service.page_frame.gate``). They are HTML
resources, kept out of the OpenAPI document; the JSON API is unchanged. An
unauthenticated visit gets 401 with the sign-in form and no case data.
"""

from __future__ import annotations

import re
import time
from datetime import UTC, datetime

from fastapi import APIRouter, Request
from fastapi.responses import HTMLResponse, Response

from models.impact_mode import ImpactMode
from models.tiers import Tier
from service.cases import service as cases_service
from service.db.repository import CaseFilters
from service.deps import ContextDep
from service.page_frame import chrome, error_page, form_time, gate, html_response, root_path
from service.pages import views as report
from service.problems import UnprocessableNotification

__all__ = ["router"]

router = APIRouter(include_in_schema=False)


@router.get("/v1/cases/{case_id}/report", response_class=HTMLResponse)
def case_report(case_id: str, request: Request, ctx: ContextDep) -> Response:
    """The case page: drawn from the stored case only."""
    started = time.perf_counter()
    session = gate(request, ctx)
    if isinstance(session, Response):
        return session
    record = cases_service.load_case_record(ctx.sessions, case_id) if len(case_id) <= 64 else None
    if record is None:
        return error_page(
            request, 404, "Not found", f"No case with id {case_id!r}.", signed_in=True
        )
    body = report.case_page(record, now=datetime.now(UTC), chrome=chrome(request, ctx, session))
    return html_response(body, started=started)


def _flag(value: str) -> bool | None:
    v = value.strip().lower()
    if v == "":
        return None
    if v in ("true", "1", "yes"):
        return True
    if v in ("false", "0", "no"):
        return False
    raise ValueError("Decision must be true or false.")


@router.get("/v1/reports", response_class=HTMLResponse)
def case_list(request: Request, ctx: ContextDep) -> Response:
    """Recent cases, newest first, with the filters of ``GET /v1/cases``."""
    started = time.perf_counter()
    session = gate(request, ctx)
    if isinstance(session, Response):
        return session
    q = request.query_params
    settings = ctx.settings
    echo = {
        "iss15_plus": q.get("iss15_plus", ""),
        "tier": q.get("tier", ""),
        "impact_mode": q.get("impact_mode", ""),
        "received_from": q.get("received_from", ""),
        "received_before": q.get("received_before", ""),
        "limit": q.get("limit", ""),
    }
    message = ""
    rows: tuple[report.ListRow, ...] = ()
    next_url = ""
    try:
        impact = echo["impact_mode"].strip()
        if impact and impact not in {m.value for m in ImpactMode}:
            raise ValueError(f"Unknown impact mode {impact!r}.")
        tier = echo["tier"].strip()
        if tier and tier not in {t.value for t in Tier}:
            raise ValueError(f"Unknown risk tier {tier!r}: high, moderate or none.")
        limit_text = echo["limit"].strip()
        # ASCII digits only (str.isdigit takes "²", which int() refuses), a bounded length
        if limit_text and not (re.fullmatch(r"[0-9]{1,9}", limit_text) and int(limit_text) >= 1):
            raise ValueError("Per page must be a whole number of at least 1.")
        page = min(
            int(limit_text) if limit_text else settings.page_default_limit, settings.page_max_limit
        )
        filters = CaseFilters(
            received_from=form_time(echo["received_from"], "Received from"),
            received_before=form_time(echo["received_before"], "Received before"),
            iss15_plus=_flag(echo["iss15_plus"]),
            impact_mode=impact or None,
            tier=Tier(tier) if tier else None,
        )
        listing = cases_service.list_cases(ctx, filters, limit=page, cursor=q.get("cursor") or None)
        rows = report.list_rows(listing.items)
        if listing.next_cursor:
            next_url = f"{root_path(request)}/v1/reports" + report.query_string(
                {**echo, "cursor": listing.next_cursor}
            )
    except (ValueError, UnprocessableNotification) as exc:
        message = exc.detail if isinstance(exc, UnprocessableNotification) else str(exc)
    body = report.render(
        "cases.html",
        rows=rows,
        filters=echo,
        impact_modes=[m.value for m in ImpactMode],
        max_limit=settings.page_max_limit,
        message=message,
        next_url=next_url,
        **chrome(request, ctx, session),
    )
    return html_response(body, 422 if message else 200, started=started)
