"""``aacn-triage build-surrogates``: build the families, then the report and the fresh validation.

The orchestration of :mod:`.build` (the families), :mod:`.report` (REPORT.md
and its plots) and :mod:`.validate` (VALIDATION.md); those modules do not
import this one or each other's orchestration.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import replace
from pathlib import Path
from typing import Any

from models.offline.paths import docs_dir
from models.offline.surrogate.build import (
    _checks,
    build_family,
    default_config,
    is_current,
    write_manifest,
)
from models.offline.surrogate.validate import validate_and_write
from models.surrogate.evaluate import SurrogateLibrary, default_artifact_dir
from models.surrogate.spec import FAMILIES
from models.surrogate.store import write_json

__all__ = ["main", "restamp"]


def restamp(directory: Path) -> int:
    """Record the golden cases and parameter checksum anew, when the physics is unchanged.

    For a change that keeps every answer (a refactor, the vehicle interior moved
    from code into the parameter file): the recorded golden cases must still
    hold, except for the parameter-values checksum itself. Any other file of the
    library is left as it is.
    """
    import json

    from models.lpm.params import load_parameter_set
    from models.surrogate.golden import golden_mismatch, golden_record
    from models.surrogate.store import MANIFEST_NAME

    path = directory / MANIFEST_NAME
    manifest = json.loads(path.read_text(encoding="utf-8"))
    golden = manifest.get("golden")
    if not golden:
        sys.stderr.write("the manifest records no golden cases: rebuild the surrogates\n")
        return 2
    params = load_parameter_set()
    check = {**golden, "parameter_values_sha256": params.values_sha256}
    reason = golden_mismatch(check, {s.name: s for s in FAMILIES}, params)
    if reason is not None:
        sys.stderr.write(f"not restamped: {reason}; rebuild the surrogates\n")
        return 1
    built = [s for s in FAMILIES if s.name in manifest["families"]]
    manifest["golden"] = golden_record(built, params)
    write_json(path, manifest)
    sys.stderr.write(f"restamped {path}: the golden cases hold\n")
    return 0


def _worker_init() -> None:
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


def main(argv: Sequence[str] | None = None) -> int:
    """Command line: build (or rebuild) the surrogate families.

    ``--family NAME`` (repeatable) rebuilds only those families; without it,
    the families whose artifact is missing or records another configuration
    or other LPM checksums are built and the others skipped (resumable);
    ``--force`` rebuilds all; ``--workers N`` processes (default: CPU count);
    ``--out DIR`` (default: the shipped artifact directory); ``--n-train``,
    ``--n-holdout``, ``--n-boot``, ``--seed`` override the configuration;
    ``--no-report`` skips REPORT.md, the plots and the fresh validation
    (``VALIDATION.md``, :mod:`models.offline.surrogate.validate`, run when every family
    is present).

    Returns
    -------
    int
        0 on success, 1 when the LPM code or parameters changed during the
        build (stale families; rerun), 2 on an unknown family name.
    """
    from tqdm import tqdm

    ap = argparse.ArgumentParser(
        prog="aacn-triage build-surrogates", description=__doc__.split("\n")[0]
    )
    ap.add_argument(
        "--family", action="append", default=[], help="rebuild this family (repeatable)"
    )
    ap.add_argument("--force", action="store_true", help="rebuild every family")
    ap.add_argument(
        "--restamp",
        action="store_true",
        help="rewrite the manifest's golden cases and parameter checksum after a change that "
        "keeps the physics (refused unless the recorded golden cases still hold)",
    )
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--out", type=Path, default=None, help="artifact directory (the shipped one)")
    ap.add_argument(
        "--report-dir",
        type=Path,
        default=None,
        help="REPORT.md, VALIDATION.md, plots and build timings (default docs/surrogate)",
    )
    d = default_config()
    ap.add_argument(
        "--n-train",
        type=int,
        default=None,
        help=f"design size per delta-V piece for every mode (default {d.n_train}, "
        + ", ".join(f"{m} {n}" for m, n in d.n_train_by_mode)
        + ")",
    )
    ap.add_argument("--n-holdout", type=int, default=d.n_holdout)
    ap.add_argument("--n-boot", type=int, default=d.n_boot)
    ap.add_argument("--seed", type=int, default=d.seed)
    ap.add_argument("--no-report", action="store_true")
    args = ap.parse_args(list(argv) if argv is not None else None)
    if args.restamp:
        return restamp(args.out or default_artifact_dir())
    config = replace(d, n_holdout=args.n_holdout, n_boot=args.n_boot, seed=args.seed)
    if args.n_train is not None:
        config = replace(config, n_train=args.n_train, n_train_by_mode=())
    directory: Path = args.out or default_artifact_dir()
    directory.mkdir(parents=True, exist_ok=True)
    names = {s.name: s for s in FAMILIES}
    unknown = [f for f in args.family if f not in names]
    if unknown:
        sys.stderr.write(f"unknown family {unknown}; known: {', '.join(names)}\n")
        return 2
    checks = _checks()
    if args.family:
        todo = [names[f] for f in dict.fromkeys(args.family)]
    else:
        todo = [
            s
            for s in FAMILIES
            if args.force or not is_current(directory / f"{s.name}.npz", s, config, checks)
        ]
    skipped = len(FAMILIES) - len(todo)
    t0 = time.perf_counter()
    results: list[dict[str, Any]] = []
    with tqdm(total=len(todo), desc="surrogate families", unit="family", file=sys.stderr) as bar:
        if args.family:
            bar.write(f"rebuilding {len(todo)} named families")
        elif skipped:
            bar.write(f"{skipped} families current, skipped")
        if args.workers <= 1:
            for s in todo:
                results.append(build_family(s, directory, config))
                bar.update(1)
        else:
            _worker_init_env()
            with ProcessPoolExecutor(max_workers=args.workers, initializer=_worker_init) as ex:
                futs = [ex.submit(build_family, s, directory, config) for s in todo]
                for fut in as_completed(futs):
                    results.append(fut.result())
                    bar.update(1)
    total = time.perf_counter() - t0
    stale = [
        s.name
        for s in FAMILIES
        if (directory / f"{s.name}.npz").exists()
        and not is_current(directory / f"{s.name}.npz", s, config)
    ]
    if stale and not args.family:
        # the LPM code or parameters changed while building: rerun to rebuild those
        sys.stderr.write(
            "LPM code or parameter set changed during the build; stale families: "
            + ", ".join(stale)
            + "\nrerun the build (it resumes and rebuilds only those)\n"
        )
        return 1
    manifest = write_manifest(directory, config)
    # build timings are machine-dependent: a side file, not part of the manifest.
    # "total_seconds" is the last build that built every family; per-family
    # entries are those of the latest build of each family.
    report_dir: Path = args.report_dir or docs_dir("surrogate")
    tpath = report_dir / "build_timings.json"
    try:
        timings: dict[str, Any] = json.loads(tpath.read_text()) if tpath.exists() else {}
    except ValueError:
        timings = {}
    timings.setdefault("families", {}).update({r["family"]: r for r in results})
    # families that are no longer built (a split or renamed family) drop out
    built = {spec.name for spec in FAMILIES}
    timings["families"] = {k: v for k, v in timings["families"].items() if k in built}
    if len(results) == len(FAMILIES):
        timings["total_seconds"] = total
        timings["workers"] = args.workers
    if results:
        write_json(tpath, timings)
    if not args.no_report:
        from models.offline.surrogate.report import write_report

        t_rep = time.perf_counter()
        write_report(directory, report_dir)
        t_val = time.perf_counter()
        _validate_after_build(directory, report_dir)
        if results:
            timings["report_seconds"] = t_val - t_rep
            timings["validation_seconds"] = time.perf_counter() - t_val
            write_json(tpath, timings)
    sys.stderr.write(
        f"built {len(results)} families in {total:.1f} s; manifest {manifest['version']}\n"
    )
    return 0


def _validate_after_build(directory: Path, report_dir: Path) -> None:
    """Rerun the fresh validation (VALIDATION.md) when the library is complete."""

    try:
        lib = SurrogateLibrary.load(directory)
    except ValueError as exc:
        sys.stderr.write(f"fresh validation skipped: {exc}\n")
        return
    if not validate_and_write(lib, report_dir)["targets_met"]:
        sys.stderr.write("fresh validation: targets not met (VALIDATION.md names them)\n")


def _worker_init_env() -> None:
    # children inherit the environment: single-threaded BLAS in every worker
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")


if __name__ == "__main__":
    raise SystemExit(main())
