"""The house: one-way imports, no cycles, a request path without the offline tools.

The service's rooms (``docs/layout.md``): a feature (``pages``, ``nemsis``, ``jobs``,
``outcomes``, any package of ``service/`` but ``cases``, ``db`` and ``cli``) imports
``cases``, ``db`` and the flat infrastructure, never another feature; the
infrastructure imports no feature; ``cli/`` and ``app`` compose them all;
``service/cases`` (the request path) imports none of ``service/pages``, ``service/jobs``
or ``service/cli``; only
the research commands (``service/cli/research*.py``) import the offline tools; no module
but the app factory imports a router; one enum of impact modes; small modules and
functions.

The import graph is read from the source (every ``import`` and ``from ...
import``, at module level or inside functions, so an import hidden in a
function counts). Rules: the engine (``models``) never imports the service;
the engine never imports the offline tools (``models.offline``); nothing in
the house imports in a circle. And, run for real in a fresh interpreter: the
service's request path (the app, the engine models loaded, one notification
triaged) imports no offline module and none of their heavy libraries.
"""

from __future__ import annotations

import ast
import json
import subprocess
import sys
from pathlib import Path

from tests.paths import ROOT

PACKAGES = ("models", "service")
#: Modules that define HTTP routes: only the app factory mounts them.
ROUTERS = (
    "service.cases.endpoints",
    "service.pages.endpoints",
    "service.nemsis.endpoints",
    "service.outcomes.endpoints",
    "service.outcomes.page_endpoints",
    "service.sign_in",
    "service.health",
)
#: Longest module (lines) in service/ and models/triage/, longest function (lines) in
#: service/ and models/ (the house's standards).
MAX_MODULE_LINES = 800
MAX_FUNCTION_LINES = 150


def _module_name(path: Path) -> str:
    rel = path.relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _modules() -> dict[str, Path]:
    out = {}
    for pkg in PACKAGES:
        for path in (ROOT / pkg).rglob("*.py"):
            if "versions" in path.parts:
                continue
            out[_module_name(path)] = path
    return out


def _resolve(name: str, known: dict[str, Path]) -> str | None:
    """The house module an imported name refers to (a module, or its package)."""
    while name:
        if name in known:
            return name
        name = name.rpartition(".")[0]
    return None


def import_graph() -> dict[str, set[str]]:
    known = _modules()
    graph: dict[str, set[str]] = {m: set() for m in known}
    for module, path in known.items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        package = module if path.name == "__init__.py" else module.rpartition(".")[0]
        for node in ast.walk(tree):
            targets: list[str] = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    up = package.split(".")
                    up = up[: len(up) - (node.level - 1)]
                    base = ".".join([*up, base] if base else up)
                # `from pkg import sub` imports the submodule; `from mod import name`
                # imports the module (a name of a package __init__ is an edge to it)
                targets = [
                    f"{base}.{a.name}" if f"{base}.{a.name}" in known else base for a in node.names
                ]
            for t in targets:
                hit = _resolve(t, known)
                if hit is not None and hit != module:
                    graph[module].add(hit)
    return graph


def _is_offline(module: str) -> bool:
    return module == "models.offline" or module.startswith("models.offline.")


def test_the_engine_never_imports_the_service() -> None:
    bad = {
        (m, d)
        for m, deps in import_graph().items()
        if m.startswith("models")
        for d in deps
        if d.startswith("service")
    }
    assert not bad


def test_the_engine_never_imports_the_offline_tools() -> None:
    bad = {
        (m, d)
        for m, deps in import_graph().items()
        if m.startswith("models") and not _is_offline(m)
        for d in deps
        if _is_offline(d)
    }
    assert not bad, sorted(bad)


def test_no_module_of_the_house_imports_in_a_circle() -> None:
    graph = import_graph()
    # a package's __init__ importing its own submodules is not a cycle of the house;
    # edges to a parent package (a module importing from its package) are kept
    state: dict[str, int] = {}
    cycles: list[list[str]] = []

    def visit(node: str, stack: list[str]) -> None:
        state[node] = 1
        stack.append(node)
        for dep in sorted(graph[node]):
            if state.get(dep) == 1:
                cycles.append(stack[stack.index(dep) :] + [dep])
            elif dep not in state:
                visit(dep, stack)
        stack.pop()
        state[node] = 2

    for node in sorted(graph):
        if node not in state:
            visit(node, [])
    assert not cycles, cycles[:5]


def test_the_graph_sees_imports_hidden_in_functions() -> None:
    """The check can fail: a function-level import is an edge like any other."""
    graph = import_graph()
    # service.cli.research imports the evaluation only inside the `evaluate` command
    assert "models.offline.field.evaluate" in graph["service.cli.research"]
    assert "models.triage" in graph["service.cases.service"]


_REQUEST_PATH = """
import json, sys
from datetime import UTC, datetime
from fastapi.testclient import TestClient
from service.app import create_app
from service.settings import Settings
from service.auth import Role, create_api_key
from service.cases.examples import EXAMPLE_NOTIFICATIONS

app = create_app(Settings(database_url="sqlite:///" + sys.argv[1]))
with TestClient(app) as client:
    _, key = create_api_key(app.state.ctx.sessions, name="c", role=Role.SUBMITTER)
    body = EXAMPLE_NOTIFICATIONS["summary"]["value"]
    r = client.post("/v1/cases", json=body, headers={"Authorization": "Bearer " + key})
    assert r.status_code == 201, r.text
    assert client.get("/readyz").status_code == 200
print(json.dumps(sorted(sys.modules)))
"""

#: Libraries only the offline tools need (the ``offline`` extra).
OFFLINE_LIBRARIES = ("matplotlib", "sklearn", "statsmodels", "chaospy", "pandas")


def test_the_request_path_imports_no_offline_tool(tmp_path: Path) -> None:
    out = subprocess.run(
        [sys.executable, "-c", _REQUEST_PATH, str(tmp_path / "a.db")],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
        timeout=600,
    )
    loaded = json.loads(out.stdout.strip().splitlines()[-1])
    offline = [m for m in loaded if _is_offline(m)]
    heavy = [m for m in loaded if m.split(".")[0] in OFFLINE_LIBRARIES]
    assert not offline, offline
    assert not heavy, sorted({m.split(".")[0] for m in heavy})
    assert "models.triage" in loaded, "the check ran the engine"
    batch = [m for m in loaded if m.startswith(("service.jobs", "service.cli"))]
    assert not batch, batch


def _in(module: str, package: str) -> bool:
    return module == package or module.startswith(package + ".")


#: The research command line: the only modules of the service that import the lab.
RESEARCH_COMMANDS = ("service.cli.research", "service.cli.research_dask")


def test_only_the_research_commands_import_the_offline_tools() -> None:
    bad = {
        (m, d)
        for m, deps in import_graph().items()
        if _in(m, "service") and m not in RESEARCH_COMMANDS
        for d in deps
        if _is_offline(d)
    }
    assert not bad, sorted(bad)


def test_the_cases_import_neither_the_pages_the_jobs_nor_the_command_line() -> None:
    bad = {
        (m, d)
        for m, deps in import_graph().items()
        if _in(m, "service.cases")
        for d in deps
        if any(_in(d, p) for p in ("service.pages", "service.jobs", "service.cli"))
    }
    assert not bad, sorted(bad)


def test_the_jobs_and_the_command_line_stay_off_the_request_path() -> None:
    """Only the command line (and the jobs themselves) import the jobs; nothing outside
    the command line imports it."""
    bad = {
        (m, d)
        for m, deps in import_graph().items()
        for d in deps
        if (_in(d, "service.jobs") and not (_in(m, "service.cli") or _in(m, "service.jobs")))
        or (_in(d, "service.cli") and not _in(m, "service.cli"))
    }
    assert not bad, sorted(bad)


#: The packages of ``service/`` that are not features: the request path's core
#: (``cases``), the store (``db``) and the command line (``cli``, a composition root).
NOT_FEATURES = ("cases", "db", "cli")
#: The composition roots: they put the features together, so they may import any.
COMPOSITION_ROOTS = ("service.app", "service.cli")
#: Edges between features or from the infrastructure to ``cases`` that stay, and why.
ALLOWED_EDGES = {
    # the OpenAPI document's part for POST /v1/cases: the route reads its body itself
    # (JSON or VEDS XML), so FastAPI cannot see the body's model; the document names it,
    # its examples and the XML media type from the cases
    ("service.openapi", "service.cases"): "the document of the body POST /v1/cases reads",
}


def _service_packages() -> set[str]:
    return {p.name for p in (ROOT / "service").iterdir() if (p / "__init__.py").is_file()}


def _room(module: str, packages: set[str]) -> str:
    """``feature:<name>``, ``cases``, ``db``, ``cli``, ``root`` or ``infrastructure``."""
    parts = module.split(".")
    if module in COMPOSITION_ROOTS or _in(module, "service.cli"):
        return "root"
    if len(parts) >= 2 and parts[1] in packages:
        return parts[1] if parts[1] in NOT_FEATURES else f"feature:{parts[1]}"
    return "infrastructure"


def feature_violations(graph: dict[str, set[str]], packages: set[str]) -> set[tuple[str, str]]:
    """The edges that break the rooms' rule.

    A feature (a package of ``service/`` other than ``cases``, ``db`` and ``cli``)
    imports ``cases``, ``db`` and the infrastructure (the flat modules of ``service/``),
    never another feature or the command line. The infrastructure imports no feature
    (nor ``cases``). ``cli/`` and ``app`` are the composition roots: they import any.
    An edge of :data:`ALLOWED_EDGES` (by package) stays, with its reason.
    """
    bad = set()
    for m, deps in graph.items():
        if not _in(m, "service") or m == "service":
            continue
        here = _room(m, packages)
        for d in deps:
            if not _in(d, "service") or d == "service":
                continue
            there = _room(d, packages)
            if here == "root" or there == here or there in ("db", "infrastructure"):
                continue
            if there == "cases" and here.startswith("feature:"):
                continue
            if any(_in(m, a) and _in(d, b) for a, b in ALLOWED_EDGES):
                continue
            bad.add((m, d))
    return bad


def test_a_feature_imports_no_other_feature_and_the_infrastructure_none() -> None:
    bad = feature_violations(import_graph(), _service_packages())
    assert not bad, sorted(bad)


def test_the_rooms_rule_can_fail() -> None:
    """A deliberate violation of each kind is caught (the check is not vacuous)."""
    packages = {"cases", "db", "cli", "pages", "nemsis", "jobs", "outcomes"}
    graph = {
        "service.nemsis.endpoints": {"service.pages.views", "service.cases.result"},
        "service.pages.endpoints": {"service.outcomes.quality", "service.page_frame"},
        "service.jobs.batch": {"service.cli.common", "service.db.repository"},
        "service.auth": {"service.pages.endpoints", "service.problems"},
        "service.metrics": {"service.cases.service"},
        "service.cli.main": {"service.nemsis.export", "service.jobs.batch"},
        "service.app": {"service.pages.endpoints"},
    }
    assert feature_violations(graph, packages) == {
        ("service.nemsis.endpoints", "service.pages.views"),
        ("service.pages.endpoints", "service.outcomes.quality"),
        ("service.jobs.batch", "service.cli.common"),
        ("service.auth", "service.pages.endpoints"),
        ("service.metrics", "service.cases.service"),
    }
    assert {"pages", "nemsis", "jobs", "outcomes"} <= _service_packages() - set(NOT_FEATURES)


def test_no_module_but_the_app_imports_a_router() -> None:
    graph = import_graph()
    bad = {(m, d) for m, deps in graph.items() if m != "service.app" for d in deps if d in ROUTERS}
    assert not bad, sorted(bad)
    assert all(r in graph["service.app"] for r in ROUTERS), "the check sees the routers"


def _string_enums() -> dict[str, frozenset[str]]:
    """Every Enum class of the house with its string member values, by qualified name."""
    out = {}
    for module, path in _modules().items():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not isinstance(node, ast.ClassDef):
                continue
            bases = {
                b.id if isinstance(b, ast.Name) else getattr(b, "attr", "") for b in node.bases
            }
            if not bases & {"Enum", "StrEnum"}:
                continue
            out[f"{module}.{node.name}"] = frozenset(
                s.value.value
                for s in node.body
                if isinstance(s, ast.Assign)
                and isinstance(s.value, ast.Constant)
                and isinstance(s.value.value, str)
            )
    return out


def test_one_enum_for_the_impact_modes() -> None:
    """The impact modes are spelled once (models.impact_mode.ImpactMode); the API's
    query-parameter type is derived from it, not a second list. (The field data's
    crash mode, models.field.features.FieldMode, is another thing: it has rollover.)"""
    from models.impact_mode import ImpactMode
    from service.cases.endpoints import ImpactModeFilter

    modes = frozenset(m.value for m in ImpactMode)
    spelled = sorted(name for name, values in _string_enums().items() if values == modes)
    assert spelled == ["models.impact_mode.ImpactMode"]
    assert [m.value for m in ImpactModeFilter] == [m.value for m in ImpactMode]


def test_no_module_is_too_long() -> None:
    long = {
        str(path.relative_to(ROOT)): n
        for module, path in _modules().items()
        if _in(module, "service") or _in(module, "models.triage")
        if (n := len(path.read_text(encoding="utf-8").splitlines())) > MAX_MODULE_LINES
    }
    assert not long, long


def test_no_function_is_too_long() -> None:
    long = {}
    for module, path in _modules().items():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                assert node.end_lineno is not None
                first = min([d.lineno for d in node.decorator_list] + [node.lineno])
                if node.end_lineno - first + 1 > MAX_FUNCTION_LINES:
                    long[f"{module}.{node.name}"] = node.end_lineno - first + 1
    assert not long, long
