"""aacn-triage HTTP and audit shell: FastAPI app, wire schemas, auth, persistence.

Depends on `models` (the engine); the engine never imports this package.
Importing it sets numba's kernel cache directory first (`service.numba_cache`).

Layout, by feature (``docs/layout.md`` has the whole map)::

    app             create_app and its lifespan: settings, database, models, routers
    middleware      body size limit, response headers;  openapi  the document's own parts
    settings        the one settings object (AACN_ prefix)
    context, deps   the loaded state of a process and its FastAPI dependency
    auth            API keys: hashing, roles, dependencies;  key_cache  keys in an outage
    session_secret  the pages' signing secret;  security_headers  /docs policy, HSTS
    problems        RFC 9457 problem+json;  jsonbody  strict JSON bodies
    health          /livez, /readyz, /metrics (a router)
    logs, metrics   JSON logs with request ids; Prometheus metrics
    balance         keep-alive balance over worker processes;  numba_cache
    cases/          POST/GET /v1/cases, the request path: endpoints (router), service
                    (use cases), notification (wire in, to_engine), result (wire out),
                    veds and veds_xml (VEDS XML input), examples
    pages/          the dispatcher's pages: endpoints (router), views, drawing, session
                    (sign-in cookie), session_end (sign-out), templates/, static/
    nemsis/         the case as a NEMSIS v3.5.1 EMS record: endpoints (router), service,
                    mapping, codes, veds_source, validate (xsd/), export and command
    db/             tables, session, migrate, repository (every query), spool (outages)
    jobs/           batch (local pool), dask, io, rescore: never on the request path
    cli/            the aacn-triage command: main, operate, research, common

Imports run one way: cli -> jobs -> cases -> db and the infrastructure; pages -> cases;
nemsis -> cases, and the pages' session (its record opens with the pages' cookie);
only app imports a router; cases imports neither pages, jobs nor cli
(``tests/test_architecture.py``).
"""

from service import numba_cache as _numba_cache

_numba_cache.configure()

__version__ = "0.1.0"
