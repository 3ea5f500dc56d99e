"""Shared dependencies of the routers."""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends, Request

from service.context import ServiceContext

__all__ = ["ContextDep"]


async def _context(request: Request) -> ServiceContext:
    # async: no I/O, so FastAPI calls it on the event loop instead of a worker thread
    ctx: ServiceContext = request.app.state.ctx
    return ctx


ContextDep = Annotated[ServiceContext, Depends(_context)]
